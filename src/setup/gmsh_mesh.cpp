#include "setup/gmsh_mesh.hpp"

#include <dlfcn.h>
#include <fmt/format.h>
#include <gmshc.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <unordered_map>
#include <vector>

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

}  // namespace

TriangleMesh read_gmsh_mesh(const std::string& path) {
  const std::string where = fmt::format("mesh file \"{}\"", path);
  if (!std::ifstream(path).good())
    throw InputError(fmt::format("{}: cannot be opened for reading", where));
  const GmshLibrary& lib = GmshLibrary::get();
  std::lock_guard<std::mutex> lock(gmsh_mutex);
  const GmshSession g(lib);
  int ierr = 0;
  lib.open(path.c_str(), &ierr);
  g.check(ierr, where + ": Gmsh could not read it");
  auto [tri_tags, tri_nodes] = g.elements(2, -1, where);
  if (tri_tags.empty()) {
    int* types = nullptr;
    std::size_t nt = 0;
    lib.element_types(&types, &nt, 2, -1, &ierr);
    std::string found;
    for (int t : g.take(types, nt)) found += (found.empty() ? "" : ", ") + g.element_name(t);
    throw InputError(fmt::format(
        "{}: no 3-node triangles (Gmsh element type 2){}; mpm reads linear triangles: mesh with "
        "Mesh.ElementOrder = 1 and without recombination into quadrilaterals",
        where,
        found.empty() ? std::string(" and no other surface elements") : "; it holds " + found));
  }
  // The triangles' nodes, numbered by ascending Gmsh tag.
  std::vector<std::size_t> used(tri_nodes);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::unordered_map<std::size_t, Index> index;
  for (std::size_t k = 0; k < used.size(); ++k) index.emplace(used[k], static_cast<Index>(k));
  std::size_t *tags_p = nullptr, ntags = 0, ncoord = 0, nparam = 0;
  double *coord_p = nullptr, *param_p = nullptr;
  lib.nodes(&tags_p, &ntags, &coord_p, &ncoord, &param_p, &nparam, -1, -1, 1, 0, &ierr);
  const auto node_tags = g.take(tags_p, ntags);
  const auto coord = g.take(coord_p, ncoord);
  g.take(param_p, nparam);
  g.check(ierr, where);
  std::vector<Vec<2>> vertices(used.size(), Vec<2>::Zero());
  std::vector<char> seen(used.size(), 0);
  double extent = 0.0;
  for (std::size_t k = 0; k < node_tags.size(); ++k) {
    const auto it = index.find(node_tags[k]);
    if (it == index.end()) continue;
    const auto v = static_cast<std::size_t>(it->second);
    vertices[v] = Vec<2>(coord[3 * k], coord[3 * k + 1]);
    seen[v] = 1;
    extent = std::max({extent, std::abs(coord[3 * k]), std::abs(coord[3 * k + 1])});
  }
  for (std::size_t k = 0; k < node_tags.size(); ++k)
    if (index.count(node_tags[k]) != 0 &&
        !(std::abs(coord[3 * k + 2]) <= 1e-12 * std::max(extent, 1.0)))
      throw InputError(fmt::format("{}: node {} has z = {}; mpm reads planar meshes in z = 0",
                                   where, node_tags[k], coord[3 * k + 2]));
  for (std::size_t v = 0; v < used.size(); ++v)
    if (!seen[v])
      throw InputError(fmt::format(
          "{}: a triangle refers to node {}, which the file does not define", where, used[v]));
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

}  // namespace mpm
