#include "setup/gmsh_mesh.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <gmshc.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "core/input_file.hpp"

namespace mpm {

namespace {

// Gmsh's library is loaded when the first mesh file is read, not linked: it pulls in about 90
// shared libraries (OpenCASCADE, FLTK, ...) whose loading costs about 80 ms, which every run of
// mpm and every test process would pay otherwise. Its C API (gmshc.h) is used, whose functions
// report failure through ierr and keep the message for gmshLoggerGetLastError.
struct GmshLibrary {
  void* handle = nullptr;
  decltype(&gmshInitialize) initialize = nullptr;
  decltype(&gmshFinalize) finalize = nullptr;
  decltype(&gmshOpen) open = nullptr;
  decltype(&gmshOptionSetNumber) set_number = nullptr;
  decltype(&gmshFree) free = nullptr;
  decltype(&gmshLoggerGetLastError) last_error = nullptr;
  decltype(&gmshModelMeshGetElementsByType) elements_by_type = nullptr;
  decltype(&gmshModelMeshGetElementTypes) element_types = nullptr;
  decltype(&gmshModelMeshGetElementProperties) element_properties = nullptr;
  decltype(&gmshModelMeshGetNodes) nodes = nullptr;
  decltype(&gmshModelGetPhysicalGroups) physical_groups = nullptr;
  decltype(&gmshModelGetPhysicalName) physical_name = nullptr;
  decltype(&gmshModelGetEntitiesForPhysicalGroup) group_entities = nullptr;

  // Loads the library once; InputError when it is missing (the reason from dlopen).
  static const GmshLibrary& get() {
    static const GmshLibrary lib = load();
    if (lib.handle == nullptr)
      throw InputError(fmt::format(
          "reading Gmsh meshes needs Gmsh's library (Debian package libgmsh-dev, installed by "
          "scripts/deps.sh): {}",
          load_error()));
    return lib;
  }

 private:
  static std::string& load_error() {
    static std::string e;
    return e;
  }
  template <class F>
  static void bind(void* h, F& f, const char* name) {
    f = reinterpret_cast<F>(dlsym(h, name));
    if (f == nullptr) throw std::runtime_error(fmt::format("symbol {} not found", name));
  }
  static GmshLibrary load() {
    GmshLibrary lib;
    void* h = nullptr;
    for (const char* name : {"libgmsh.so", "libgmsh.so.4.8"}) {
      h = dlopen(name, RTLD_NOW | RTLD_LOCAL);
      if (h != nullptr) break;
      const char* e = dlerror();
      load_error() = e != nullptr ? e : "dlopen failed";
    }
    if (h == nullptr) return lib;
    try {
      bind(h, lib.initialize, "gmshInitialize");
      bind(h, lib.finalize, "gmshFinalize");
      bind(h, lib.open, "gmshOpen");
      bind(h, lib.set_number, "gmshOptionSetNumber");
      bind(h, lib.free, "gmshFree");
      bind(h, lib.last_error, "gmshLoggerGetLastError");
      bind(h, lib.elements_by_type, "gmshModelMeshGetElementsByType");
      bind(h, lib.element_types, "gmshModelMeshGetElementTypes");
      bind(h, lib.element_properties, "gmshModelMeshGetElementProperties");
      bind(h, lib.nodes, "gmshModelMeshGetNodes");
      bind(h, lib.physical_groups, "gmshModelGetPhysicalGroups");
      bind(h, lib.physical_name, "gmshModelGetPhysicalName");
      bind(h, lib.group_entities, "gmshModelGetEntitiesForPhysicalGroup");
    } catch (const std::exception& e) {
      load_error() = e.what();
      dlclose(h);
      return lib;
    }
    lib.handle = h;
    return lib;
  }
};

// Gmsh's API is one global state: one reader at a time, initialised and finalised around each
// file (a failed parse leaves the state unusable for the next one otherwise).
std::mutex gmsh_mutex;

class GmshSession {
 public:
  explicit GmshSession(const GmshLibrary& lib) : lib_(lib) {
    int ierr = 0;
    lib_.initialize(0, nullptr, 0, &ierr);
    check(ierr, "initialising Gmsh");
    lib_.set_number("General.Terminal", 0, &ierr);
    lib_.set_number("General.Verbosity", 0, &ierr);
  }
  ~GmshSession() {
    int ierr = 0;
    lib_.finalize(&ierr);
  }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  // InputError with Gmsh's last message when ierr is set.
  void check(int ierr, const std::string& what) const {
    if (ierr == 0) return;
    char* msg = nullptr;
    int e2 = 0;
    lib_.last_error(&msg, &e2);
    std::string text = msg != nullptr && *msg != '\0' ? msg : "no message";
    if (msg != nullptr) lib_.free(msg);
    throw InputError(fmt::format("{}: {}", what, text));
  }
  // A Gmsh-allocated array as a vector (the array freed).
  template <class T>
  std::vector<T> take(T* p, std::size_t n) const {
    std::vector<T> v(p, p + n);
    if (p != nullptr) lib_.free(p);
    return v;
  }
  std::string take(char* s) const {
    std::string out = s != nullptr ? s : "";
    if (s != nullptr) lib_.free(s);
    return out;
  }
  // Element tags and node tags of the elements of `type` on entity `tag` (-1: all).
  std::pair<std::vector<std::size_t>, std::vector<std::size_t>> elements(
      int type, int tag, const std::string& where) const {
    std::size_t *et = nullptr, *nt = nullptr, ne = 0, nn = 0;
    int ierr = 0;
    lib_.elements_by_type(type, &et, &ne, &nt, &nn, tag, 0, 1, &ierr);
    auto e = take(et, ne);
    auto n = take(nt, nn);
    check(ierr, where);
    return {std::move(e), std::move(n)};
  }
  std::string element_name(int type) const {
    char* name = nullptr;
    double* local = nullptr;
    std::size_t nl = 0;
    int dim = 0, order = 0, nodes = 0, primary = 0, ierr = 0;
    lib_.element_properties(type, &name, &dim, &order, &nodes, &local, &nl, &primary, &ierr);
    take(local, nl);
    return fmt::format("{} (Gmsh type {})", take(name), type);
  }

  const GmshLibrary& lib_;
};

// The version line of a Gmsh mesh file: the first line that is not blank must be $MeshFormat,
// the next "2.2 T 8" or "4.1 T 8" (T: 0 ASCII, 1 binary). Gmsh reads a file without this header
// as a .geo script, whose commands (SystemCall, Shell, ...) it would run: a mesh is data, so
// nothing else reaches Gmsh. InputError naming the file and what its start holds.
struct MshFormat {
  bool v41 = false;  // else 2.2
  bool binary = false;
};
MshFormat check_msh_header(const std::string& bytes, const std::string& where) {
  std::size_t at = 0;
  const auto line = [&]() {
    const std::size_t end = bytes.find('\n', at);
    std::string l = bytes.substr(at, end == std::string::npos ? std::string::npos : end - at);
    at = end == std::string::npos ? bytes.size() : end + 1;
    while (!l.empty() && (l.back() == '\r' || l.back() == ' ' || l.back() == '\t')) l.pop_back();
    return l;
  };
  const auto shown = [](const std::string& l) {
    std::string out;
    for (char c : l.substr(0, 40)) out += (c >= 32 && c < 127) ? c : '?';
    return l.size() > 40 ? out + "..." : out;
  };
  std::string first;
  while (at < bytes.size() && first.find_first_not_of(" \t") == std::string::npos) first = line();
  if (first.find_first_not_of(" \t") != std::string::npos)
    first = first.substr(first.find_first_not_of(" \t"));
  if (first != "$MeshFormat")
    throw InputError(fmt::format(
        "{}: not a Gmsh mesh file: it must start with the line $MeshFormat (MSH 2.2 or 4.1, "
        "ASCII or binary), and starts with \"{}\"; mpm reads meshes, never scripts (.geo): "
        "mesh it with gmsh -2 -format msh41 first",
        where, bytes.empty() ? std::string() : shown(first)));
  const std::string version = line();
  std::istringstream in(version);
  std::string number;
  int file_type = -1, data_size = -1;
  in >> number >> file_type >> data_size;
  if (!in || (number != "2.2" && number != "4.1") || (file_type != 0 && file_type != 1) ||
      data_size != 8)
    throw InputError(fmt::format(
        "{}: the format line after $MeshFormat is \"{}\"; mpm reads MSH 2.2 and 4.1, ASCII or "
        "binary (\"4.1 0 8\", \"4.1 1 8\", \"2.2 0 8\" or \"2.2 1 8\")",
        where, shown(version)));
  return {number == "4.1", file_type == 1};
}

// The node ids of the file's $Nodes section in file order, read from the bytes (Gmsh keeps one
// of two definitions of an id without a word): MSH 2.2 "count" then "id x y z" per node (binary:
// int id, 3 doubles); MSH 4.1 "numEntityBlocks numNodes minTag maxTag", then per block
// "entityDim entityTag parametric numNodesInBlock", its tags, then its coordinates (binary: the
// same as 8-byte size_t and 4-byte int fields). Nothing when the section is not found or not read
// (Gmsh's own reader then says what is wrong).
std::optional<std::vector<std::uint64_t>> node_ids(const std::string& bytes, MshFormat f) {
  const std::size_t at = bytes.find("$Nodes");
  if (at == std::string::npos) return std::nullopt;
  std::size_t pos = bytes.find('\n', at);
  if (pos == std::string::npos) return std::nullopt;
  ++pos;
  std::vector<std::uint64_t> ids;
  const auto raw = [&](auto& v) {  // a little-endian binary field (as the header checked)
    if (pos + sizeof v > bytes.size()) return false;
    std::memcpy(&v, bytes.data() + pos, sizeof v);
    pos += sizeof v;
    return true;
  };
  if (!f.binary || !f.v41) {
    // The count (2.2) or the section's header line (4.1 ASCII) is text.
    std::istringstream in(bytes.substr(pos, bytes.find("$EndNodes", pos) - pos));
    if (!f.v41) {
      std::uint64_t n = 0;
      if (!(in >> n)) return std::nullopt;
      if (f.binary) {
        const std::size_t eol = bytes.find('\n', pos);
        if (eol == std::string::npos) return std::nullopt;
        pos = eol + 1;
        for (std::uint64_t k = 0; k < n; ++k) {
          std::int32_t id = 0;
          double xyz[3];
          if (!raw(id) || !raw(xyz)) return std::nullopt;
          ids.push_back(static_cast<std::uint64_t>(id));
        }
        return ids;
      }
      for (std::uint64_t k = 0; k < n; ++k) {
        std::uint64_t id = 0;
        double x = 0, y = 0, z = 0;
        if (!(in >> id >> x >> y >> z)) return std::nullopt;
        ids.push_back(id);
      }
      return ids;
    }
    std::uint64_t blocks = 0, n = 0, lo = 0, hi = 0;
    if (!(in >> blocks >> n >> lo >> hi)) return std::nullopt;
    for (std::uint64_t b = 0; b < blocks; ++b) {
      int dim = 0, tag = 0, parametric = 0;
      std::uint64_t count = 0;
      if (!(in >> dim >> tag >> parametric >> count)) return std::nullopt;
      for (std::uint64_t k = 0; k < count; ++k) {
        std::uint64_t id = 0;
        if (!(in >> id)) return std::nullopt;
        ids.push_back(id);
      }
      const std::uint64_t values = count * (3 + (parametric != 0 ? static_cast<unsigned>(dim) : 0));
      for (std::uint64_t k = 0; k < values; ++k) {
        double v = 0;
        if (!(in >> v)) return std::nullopt;
      }
    }
    return ids;
  }
  std::uint64_t blocks = 0, n = 0, lo = 0, hi = 0;
  if (!raw(blocks) || !raw(n) || !raw(lo) || !raw(hi)) return std::nullopt;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    std::int32_t dim = 0, tag = 0, parametric = 0;
    std::uint64_t count = 0;
    if (!raw(dim) || !raw(tag) || !raw(parametric) || !raw(count)) return std::nullopt;
    if (count > bytes.size()) return std::nullopt;
    for (std::uint64_t k = 0; k < count; ++k) {
      std::uint64_t id = 0;
      if (!raw(id)) return std::nullopt;
      ids.push_back(id);
    }
    const std::uint64_t skip =
        count * 8 * (3 + (parametric != 0 ? static_cast<std::uint64_t>(dim) : 0));
    if (pos + skip > bytes.size()) return std::nullopt;
    pos += skip;
  }
  return ids;
}

// A private directory holding a copy of the mesh for Gmsh to open, removed with it: Gmsh also
// merges a file "NAME.opt" next to the file it opens, whose options and commands it would run,
// and the copy has no such neighbour. Reading the copy also means Gmsh parses the very bytes
// whose header was checked.
class PrivateCopy {
 public:
  PrivateCopy(const std::string& bytes, const std::string& where) {
    std::error_code ec;
    std::filesystem::path base = std::filesystem::temp_directory_path(ec);
    if (ec) base = "/tmp";
    std::string tmpl = (base / "mpm-mesh-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr)
      throw InputError(fmt::format("{}: cannot make a private directory under {} for Gmsh: {}",
                                   where, base.string(), std::strerror(errno)));
    dir_ = tmpl;
    file_ = dir_ / "mesh.msh";
    const int fd = ::open(file_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    bool ok = fd >= 0;
    int err = errno;
    for (std::size_t done = 0; ok && done < bytes.size();) {
      const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        ok = false;
        err = errno;
        break;
      }
      done += static_cast<std::size_t>(n);
    }
    if (fd >= 0 && ::close(fd) != 0 && ok) {
      ok = false;
      err = errno;
    }
    if (!ok) {
      std::filesystem::remove_all(dir_, ec);
      throw InputError(fmt::format("{}: cannot copy it into {} for Gmsh: {}", where, dir_.string(),
                                   std::strerror(err)));
    }
  }
  ~PrivateCopy() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  PrivateCopy(const PrivateCopy&) = delete;
  PrivateCopy& operator=(const PrivateCopy&) = delete;
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path dir_, file_;
};

// Reads the file at `path` (checked as above: a regular file, a MSH header) into Gmsh through a
// private copy and returns f(session, where, bytes, format) with the model loaded; `where` names
// the file in messages.
template <class F>
auto with_gmsh_file(const std::string& path, F&& f) {
  const std::string where = fmt::format("mesh file \"{}\"", path);
  // Refuses FIFOs and devices (which would block or never end) before anything else.
  const std::string bytes = read_input_file(path, "mesh file");
  const MshFormat format = check_msh_header(bytes, where);
  const GmshLibrary& lib = GmshLibrary::get();
  std::lock_guard<std::mutex> lock(gmsh_mutex);
  const PrivateCopy copy(bytes, where);
  const GmshSession g(lib);
  int ierr = 0;
  lib.open(copy.file().c_str(), &ierr);
  g.check(ierr, where + ": Gmsh could not read it");
  return f(g, where, bytes, format);
}

// The coordinates (x, y, z) of the nodes `used` (Gmsh tags, sorted and unique: the nodes of the
// elements read), in that order. InputError for a node defined twice or a used node the file
// does not define.
std::vector<Vec<3>> node_coordinates(const GmshSession& g, const std::vector<std::size_t>& used,
                                     const std::string& where, const std::string& bytes,
                                     MshFormat format) {
  const GmshLibrary& lib = g.lib_;
  std::unordered_map<std::size_t, std::size_t> index;
  for (std::size_t k = 0; k < used.size(); ++k) index.emplace(used[k], k);
  std::size_t *tags_p = nullptr, ntags = 0, ncoord = 0, nparam = 0;
  double *coord_p = nullptr, *param_p = nullptr;
  int ierr = 0;
  // (Every node once: each is classified on one entity, and boundaries are not included.)
  lib.nodes(&tags_p, &ntags, &coord_p, &ncoord, &param_p, &nparam, -1, -1, 0, 0, &ierr);
  const auto node_tags = g.take(tags_p, ntags);
  const auto coord = g.take(coord_p, ncoord);
  g.take(param_p, nparam);
  g.check(ierr, where);
  {
    // A node defined twice (two coordinates for one id) leaves it open which one an element
    // means: refused, not resolved by whichever Gmsh keeps.
    std::vector<std::size_t> sorted(node_tags);
    std::sort(sorted.begin(), sorted.end());
    const auto twice = std::adjacent_find(sorted.begin(), sorted.end());
    if (twice != sorted.end())
      throw InputError(fmt::format("{}: node {} is defined twice", where, *twice));
    // Gmsh keeps one of two definitions of an id in silence: the file's own ids say.
    if (auto ids = node_ids(bytes, format)) {
      std::sort(ids->begin(), ids->end());
      const auto again = std::adjacent_find(ids->begin(), ids->end());
      if (again != ids->end())
        throw InputError(fmt::format("{}: node {} is defined twice in $Nodes", where, *again));
    }
  }
  std::vector<Vec<3>> x(used.size(), Vec<3>::Zero());
  std::vector<char> seen(used.size(), 0);
  for (std::size_t k = 0; k < node_tags.size(); ++k) {
    const auto it = index.find(node_tags[k]);
    if (it == index.end()) continue;
    x[it->second] = Vec<3>(coord[3 * k], coord[3 * k + 1], coord[3 * k + 2]);
    seen[it->second] = 1;
  }
  for (std::size_t v = 0; v < used.size(); ++v)
    if (!seen[v])
      throw InputError(fmt::format(
          "{}: an element refers to node {}, which the file does not define", where, used[v]));
  return x;
}

// The sorted, unique node tags of `node_tags` (the nodes of the elements read).
std::vector<std::size_t> used_nodes(std::vector<std::size_t> node_tags) {
  std::sort(node_tags.begin(), node_tags.end());
  node_tags.erase(std::unique(node_tags.begin(), node_tags.end()), node_tags.end());
  return node_tags;
}

// InputError unless every vertex lies in the plane z = 0 (to 1e-12 of the largest coordinate).
void check_planar(const std::vector<Vec<3>>& x, const std::vector<std::size_t>& tags,
                  const std::string& where) {
  double extent = 0.0;
  for (const auto& p : x) extent = std::max({extent, std::abs(p[0]), std::abs(p[1])});
  for (std::size_t k = 0; k < x.size(); ++k)
    if (!(std::abs(x[k][2]) <= 1e-12 * std::max(extent, 1.0)))
      throw InputError(fmt::format("{}: node {} has z = {}; mpm reads planar meshes in z = 0",
                                   where, tags[k], x[k][2]));
}

// The element types of dimension `dim` in the file other than `wanted`, named ("" when none).
std::string other_types(const GmshSession& g, int dim, int wanted, const std::string& where,
                        bool* has_wanted) {
  int* types = nullptr;
  std::size_t nt = 0;
  int ierr = 0;
  g.lib_.element_types(&types, &nt, dim, -1, &ierr);
  const auto found = g.take(types, nt);
  g.check(ierr, where);
  std::string others;
  for (int t : found)
    if (t != wanted) others += (others.empty() ? "" : ", ") + g.element_name(t);
  *has_wanted = std::find(found.begin(), found.end(), wanted) != found.end();
  return others;
}

// The file's linear triangles as a TriangleMesh, with its physical groups of dimension 1 as
// named boundaries.
TriangleMesh triangle_mesh_of(const GmshSession& g, const std::string& where,
                              const std::string& bytes, MshFormat format) {
  const GmshLibrary& lib = g.lib_;
  int ierr = 0;
  // Only linear triangles: a mesh that mixes them with quadrilaterals (or other surface
  // elements) is refused whole, never read in part.
  bool has_triangles = false;
  const std::string others = other_types(g, 2, 2, where, &has_triangles);
  if (has_triangles && !others.empty())
    throw InputError(fmt::format(
        "{}: it mixes 3-node triangles with other surface elements ({}); mpm reads meshes of "
        "linear triangles only: mesh with Mesh.ElementOrder = 1 and without recombination "
        "into quadrilaterals",
        where, others));
  auto [tri_tags, tri_nodes] = g.elements(2, -1, where);
  if (tri_tags.empty())
    throw InputError(fmt::format(
        "{}: no 3-node triangles (Gmsh element type 2){}; mpm reads linear triangles: mesh with "
        "Mesh.ElementOrder = 1 and without recombination into quadrilaterals",
        where,
        others.empty() ? std::string(" and no other surface elements") : "; it holds " + others));
  // The triangles' nodes, numbered by ascending Gmsh tag.
  const std::vector<std::size_t> used = used_nodes(tri_nodes);
  std::unordered_map<std::size_t, Index> index;
  for (std::size_t k = 0; k < used.size(); ++k) index.emplace(used[k], static_cast<Index>(k));
  const std::vector<Vec<3>> x = node_coordinates(g, used, where, bytes, format);
  check_planar(x, used, where);
  std::vector<Vec<2>> vertices(used.size());
  for (std::size_t v = 0; v < used.size(); ++v) vertices[v] = x[v].head<2>();
  std::vector<TriangleMesh::Triangle> triangles(tri_tags.size());
  for (std::size_t e = 0; e < tri_tags.size(); ++e)
    for (std::size_t a = 0; a < 3; ++a) triangles[e][a] = index.at(tri_nodes[3 * e + a]);
  // Physical groups of dimension 1: named boundaries from their 2-node lines.
  std::map<std::string, std::vector<TriangleMesh::Edge>> boundaries;
  int* groups_p = nullptr;
  std::size_t ngroups = 0;
  lib.physical_groups(&groups_p, &ngroups, 1, &ierr);
  const auto groups = g.take(groups_p, ngroups);  // (dim, tag) pairs
  g.check(ierr, where);
  for (std::size_t k = 0; k + 1 < groups.size(); k += 2) {
    const int dim = groups[k], tag = groups[k + 1];
    char* name_p = nullptr;
    lib.physical_name(dim, tag, &name_p, &ierr);
    std::string name = g.take(name_p);
    if (name.empty()) name = std::to_string(tag);
    auto& edges = boundaries[name];
    int* ent_p = nullptr;
    std::size_t nent = 0;
    lib.group_entities(dim, tag, &ent_p, &nent, &ierr);
    for (int entity : g.take(ent_p, nent)) {
      const auto [line_tags, line_nodes] = g.elements(1, entity, where);
      for (std::size_t e = 0; e < line_tags.size(); ++e) {
        const auto a = index.find(line_nodes[2 * e]), b = index.find(line_nodes[2 * e + 1]);
        if (a == index.end() || b == index.end())
          throw InputError(fmt::format(
              "{}: boundary \"{}\" has an edge whose nodes ({}, {}) belong to no triangle", where,
              name, line_nodes[2 * e], line_nodes[2 * e + 1]));
        edges.push_back({a->second, b->second});
      }
    }
    if (edges.empty())
      throw InputError(fmt::format(
          "{}: boundary \"{}\" (physical group {} of dimension 1) has no 2-node line elements",
          where, name, tag));
  }
  return TriangleMesh(std::move(vertices), std::move(triangles), std::move(boundaries), where);
}

// The file's linear triangles (Dim 2) or tetrahedra (Dim 3) as a body, each element in the
// physical group of dimension Dim that holds it.
template <int Dim>
BodyMesh<Dim> body_mesh_of(const GmshSession& g, const std::string& where, const std::string& bytes,
                           MshFormat format) {
  const GmshLibrary& lib = g.lib_;
  constexpr int kType = Dim == 2 ? 2 : 4;  // Gmsh: 3-node triangle, 4-node tetrahedron
  const char* kinds = Dim == 2 ? "3-node triangles" : "4-node tetrahedra";
  bool has = false;
  const std::string others = other_types(g, Dim, kType, where, &has);
  if (!others.empty())
    throw InputError(fmt::format(
        "{}: {} {}; a {}D body mesh is made of {} only: mesh with Mesh.ElementOrder = 1{}", where,
        has ? fmt::format("it mixes {} with", kinds) : "it holds", others, Dim, kinds,
        Dim == 2 ? " and without recombination into quadrilaterals"
                 : ", without recombination or extrusion into hexahedra and prisms"));
  auto [tags, nodes] = g.elements(kType, -1, where);
  if (tags.empty())
    throw InputError(fmt::format(
        "{}: no {} (Gmsh element type {}){}", where, kinds, kType,
        Dim == 3 ? "; a 3D body needs a volume mesh (gmsh -3), and a mesh of triangles is a 2D "
                   "body (grid.dimension = 2)"
                 : "; a 2D body needs a surface mesh of the plane z = 0 (gmsh -2)"));
  const std::vector<std::size_t> used = used_nodes(nodes);
  std::unordered_map<std::size_t, Index> index;
  for (std::size_t k = 0; k < used.size(); ++k) index.emplace(used[k], static_cast<Index>(k));
  const std::vector<Vec<3>> x = node_coordinates(g, used, where, bytes, format);
  if constexpr (Dim == 2) check_planar(x, used, where);
  std::vector<Vec<Dim>> vertices(used.size());
  for (std::size_t v = 0; v < used.size(); ++v) vertices[v] = x[v].template head<Dim>();
  std::vector<typename BodyMesh<Dim>::Element> elements(tags.size());
  std::unordered_map<std::size_t, std::size_t> position;  // element tag -> index
  for (std::size_t e = 0; e < tags.size(); ++e) {
    for (std::size_t a = 0; a <= Dim; ++a) elements[e][a] = index.at(nodes[(Dim + 1) * e + a]);
    if (!position.emplace(tags[e], e).second)
      throw InputError(fmt::format("{}: element {} is defined twice", where, tags[e]));
  }
  // Physical groups of dimension Dim: the body's named parts. An element in two of them would
  // belong to two parts at once: refused, naming both.
  std::vector<int> group(tags.size(), -1);
  std::vector<std::string> names;
  int ierr = 0;
  int* groups_p = nullptr;
  std::size_t ngroups = 0;
  lib.physical_groups(&groups_p, &ngroups, Dim, &ierr);
  const auto groups = g.take(groups_p, ngroups);  // (dim, tag) pairs
  g.check(ierr, where);
  for (std::size_t k = 0; k + 1 < groups.size(); k += 2) {
    const int dim = groups[k], tag = groups[k + 1];
    char* name_p = nullptr;
    lib.physical_name(dim, tag, &name_p, &ierr);
    std::string name = g.take(name_p);
    if (name.empty()) name = std::to_string(tag);
    const int id = static_cast<int>(names.size());
    names.push_back(name);
    int* ent_p = nullptr;
    std::size_t nent = 0;
    lib.group_entities(dim, tag, &ent_p, &nent, &ierr);
    for (int entity : g.take(ent_p, nent)) {
      const auto [own, own_nodes] = g.elements(kType, entity, where);
      for (std::size_t t : own) {
        const std::size_t e = position.at(t);
        if (group[e] >= 0 && group[e] != id)
          throw InputError(fmt::format(
              "{}: element {} is in the physical groups \"{}\" and \"{}\"; each part of a body "
              "is one group",
              where, t, names[static_cast<std::size_t>(group[e])], name));
        group[e] = id;
      }
    }
  }
  return BodyMesh<Dim>(std::move(vertices), std::move(elements), std::move(tags), std::move(group),
                       std::move(names), where);
}

}  // namespace

TriangleMesh read_gmsh_mesh(const std::string& path) {
  return with_gmsh_file(path,
                        [](const GmshSession& g, const std::string& where, const std::string& bytes,
                           MshFormat format) { return triangle_mesh_of(g, where, bytes, format); });
}

template <int Dim>
BodyMesh<Dim> read_gmsh_body(const std::string& path) {
  return with_gmsh_file(
      path, [](const GmshSession& g, const std::string& where, const std::string& bytes,
               MshFormat format) { return body_mesh_of<Dim>(g, where, bytes, format); });
}

template BodyMesh<2> read_gmsh_body<2>(const std::string&);
template BodyMesh<3> read_gmsh_body<3>(const std::string&);

int gmsh_mesh_dimension(const std::string& path) {
  return with_gmsh_file(
      path, [](const GmshSession& g, const std::string& where, const std::string&, MshFormat) {
        bool tets = false;
        const bool volumes = !other_types(g, 3, 4, where, &tets).empty() || tets;
        return volumes ? 3 : 2;
      });
}

}  // namespace mpm
