#include "io/output.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <set>
#include <span>
#include <stdexcept>
#include <system_error>
#include <type_traits>
#include <utility>

#include "core/input_file.hpp"

namespace mpm::io {

namespace {

using Buffer = fmt::memory_buffer;

// 17 significant digits: enough for any double to parse back to the same value (IEEE 754
// binary64 needs at most 17, see std::numeric_limits<double>::max_digits10).
void put_num(Buffer& b, double x) {
  fmt::format_to(std::back_inserter(b), "{:.17g}", x);
}
void put_int(Buffer& b, Index i) {
  fmt::format_to(std::back_inserter(b), "{}", i);
}
void put(Buffer& b, std::string_view s) {
  b.append(s.data(), s.data() + s.size());
}

std::string system_error_text(int err) {
  return std::strerror(err);
}

// A RunError with its own exit code: the time loop records it like any failure of a run and
// still tries to write the failed summary (a full disk may have room for it once the
// temporary file is gone).
[[noreturn]] void throw_write_error(const std::filesystem::path& path, std::string_view what,
                                    int err) {
  throw RunError(exit_code::kOutput, fmt::format("cannot write '{}' ({}): {}", path.string(), what,
                                                 system_error_text(err)));
}

// Writes all of text to fd, retrying after signals: 0, or the errno of the write that failed.
int write_all(int fd, std::string_view text) {
  const char* data = text.data();
  std::size_t left = text.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    data += n;
    left -= static_cast<std::size_t>(n);
  }
  return 0;
}

// Escape the five XML special characters for use in attribute values (XML 1.0, section 2.4).
std::string xml_escape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Quote a CSV header field only when it needs it (RFC 4180: fields with commas, quotes or line
// breaks are enclosed in double quotes, embedded quotes doubled).
std::string csv_field(std::string_view s) {
  if (s.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(s);
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

// Check the extra fields against the number of entities (particles or grid nodes) and against
// the names the writer already uses, so that a frame never has two columns/arrays of one name.
void check_fields(const std::vector<ScalarField>& fields, std::size_t n, std::set<std::string> used,
                  std::string_view what) {
  for (const auto& f : fields) {
    if (f.name.empty()) throw std::invalid_argument("output field with an empty name");
    if (f.values == nullptr) {
      throw std::invalid_argument(fmt::format("output field '{}' has no values", f.name));
    }
    if (f.values->size() != n) {
      throw std::invalid_argument(
          fmt::format("output field '{}' has {} values, expected {} (one per {})", f.name,
                      f.values->size(), n, what));
    }
    if (!used.insert(f.name).second) {
      throw std::invalid_argument(fmt::format("output field name '{}' is already used", f.name));
    }
  }
}

template <int Dim>
void check_particles(const Particles<Dim>& p) {
  const auto n = static_cast<std::size_t>(p.size());
  if (p.x0.size() != n || p.v.size() != n || p.mass.size() != n || p.volume.size() != n ||
      p.F.size() != n || p.stress.size() != n || p.state.size() != n) {
    throw std::invalid_argument("particle arrays have inconsistent sizes");
  }
}

// The stable id of the particle at index i (Particles::id; the index where ids were not set).
template <int Dim>
Index particle_id(const Particles<Dim>& p, std::size_t i) {
  return i < p.id.size() ? p.id[i] : static_cast<Index>(i);
}

// ---- VTK XML pieces ----------------------------------------------------------------------

// VTK cell type ids (vtkCellType.h).
constexpr int kVtkVertex = 1;
constexpr int kVtkLine = 3;
constexpr int kVtkTriangle = 5;
constexpr int kVtkQuad = 9;
constexpr int kVtkHexahedron = 12;

// Where a DataArray's values go: inline as ASCII (17 significant digits, a tuple per line), or
// as raw little-endian bytes in the file's <AppendedData> block, each array a UInt64 byte count
// followed by its values (VTK XML format 1.0, header_type="UInt64"), referenced by its offset.
// A 2D frame of 1e6 particles is then 289 MB instead of 466 MB and built 4x faster.
struct VtuData {
  bool binary = false;
  std::string appended;
};

template <class T>
constexpr std::string_view vtk_type() {
  if constexpr (std::is_same_v<T, double>) return "Float64";
  if constexpr (std::is_same_v<T, std::int64_t>) return "Int64";
  if constexpr (std::is_same_v<T, std::uint8_t>) return "UInt8";
}

// values: `components` per tuple, tuples one after the other.
// component_names: one per component (VTK's ComponentName0, ...: ParaView shows "stress_XY"
// instead of "stress_1"), or empty.
template <class T>
void data_array(Buffer& b, VtuData& d, std::string_view name, int components,
                const std::vector<T>& values,
                std::span<const std::string_view> component_names = {}) {
  static_assert(std::endian::native == std::endian::little, "VTK raw data: little endian");
  fmt::format_to(std::back_inserter(b), "        <DataArray type=\"{}\" Name=\"{}\"", vtk_type<T>(),
                 xml_escape(name));
  if (components != 1)
    fmt::format_to(std::back_inserter(b), " NumberOfComponents=\"{}\"", components);
  for (std::size_t k = 0; k < component_names.size(); ++k)
    fmt::format_to(std::back_inserter(b), " ComponentName{}=\"{}\"", k, component_names[k]);
  if (d.binary) {
    fmt::format_to(std::back_inserter(b), " format=\"appended\" offset=\"{}\"/>\n",
                   d.appended.size());
    const std::uint64_t bytes = values.size() * sizeof(T);
    d.appended.append(reinterpret_cast<const char*>(&bytes), sizeof bytes);
    d.appended.append(reinterpret_cast<const char*>(values.data()), bytes);
    return;
  }
  put(b, " format=\"ascii\">\n");
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) put(b, (i % static_cast<std::size_t>(components) == 0) ? "\n" : " ");
    if constexpr (std::is_same_v<T, double>)
      put_num(b, values[i]);
    else
      put_int(b, static_cast<Index>(values[i]));
  }
  put(b, "\n        </DataArray>\n");
}

void scalar_array(Buffer& b, VtuData& d, std::string_view name, const std::vector<double>& values) {
  data_array(b, d, name, 1, values);
}

constexpr std::array<std::string_view, 3> kVectorComponents = {"X", "Y", "Z"};
constexpr std::array<std::string_view, 9> kTensorComponents = {"XX", "XY", "XZ", "YX", "YY",
                                                               "YZ", "ZX", "ZY", "ZZ"};

// A vector field padded with zeros to 3 components (VTK vectors are always 3D).
template <int Dim>
void vector_array(Buffer& b, VtuData& d, std::string_view name,
                  const std::vector<Vec<Dim>>& values) {
  std::vector<double> flat;
  flat.reserve(3 * values.size());
  for (const auto& v : values)
    for (int k = 0; k < 3; ++k) flat.push_back(k < Dim ? v[k] : 0.0);
  data_array(b, d, name, 3, flat, kVectorComponents);
}

// A Dim x Dim tensor embedded in 3x3 (row-major, 9 components); pad is the value on the
// padded diagonal (1 for F: no deformation out of plane; 0 for stress), zz (2D, when given) the
// value at (2, 2) per tensor instead (the plane-strain stress sigma_zz).
template <int Dim>
void tensor_array(Buffer& b, VtuData& d, std::string_view name, const std::vector<Mat<Dim>>& values,
                  double pad, const std::vector<double>* zz = nullptr) {
  std::vector<double> flat;
  flat.reserve(9 * values.size());
  for (std::size_t i = 0; i < values.size(); ++i)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        const double padded = (zz != nullptr && r == 2 && c == 2) ? (*zz)[i] : pad;
        flat.push_back(r < Dim && c < Dim ? values[i](r, c) : (r == c ? padded : 0.0));
      }
  data_array(b, d, name, 9, flat, kTensorComponents);
}

void vtu_header(Buffer& b, const VtuData& d) {
  put(b, "<?xml version=\"1.0\"?>\n");
  put(b, d.binary ? "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                    "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                  : "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
                    "byte_order=\"LittleEndian\">\n");
  put(b, "  <UnstructuredGrid>\n");
}
void vtu_footer(Buffer& b, const VtuData& d) {
  put(b,
      "    </Piece>\n"
      "  </UnstructuredGrid>\n");
  if (d.binary) {
    put(b, "  <AppendedData encoding=\"raw\">\n   _");
    put(b, d.appended);
    put(b, "\n  </AppendedData>\n");
  }
  put(b, "</VTKFile>\n");
}

// <Cells>: connectivity (nodes_per_cell node ids per cell), offsets (end of each cell's
// connectivity, VTK convention), types.
void cells_block(Buffer& b, VtuData& d, const std::vector<Index>& connectivity, Index num_cells,
                 int nodes_per_cell, int cell_type) {
  put(b, "      <Cells>\n");
  // One component: VTK's reader refuses a connectivity array of several ("could not be created
  // with one component") and reads no points at all. (ASCII: one id per line.)
  data_array(b, d, "connectivity", 1,
             std::vector<std::int64_t>(connectivity.begin(), connectivity.end()));
  std::vector<std::int64_t> offsets(static_cast<std::size_t>(num_cells));
  for (Index c = 0; c < num_cells; ++c)
    offsets[static_cast<std::size_t>(c)] = (c + 1) * nodes_per_cell;
  data_array(b, d, "offsets", 1, offsets);
  data_array(b, d, "types", 1,
             std::vector<std::uint8_t>(static_cast<std::size_t>(num_cells),
                                       static_cast<std::uint8_t>(cell_type)));
  put(b, "      </Cells>\n");
}

}  // namespace

// ---- AppendFile ----------------------------------------------------------------------------

AppendFile& AppendFile::operator=(AppendFile&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(o.path_);
    fd_ = std::exchange(o.fd_, -1);
  }
  return *this;
}

AppendFile::~AppendFile() {
  if (fd_ >= 0) ::close(fd_);
}

void AppendFile::open(const std::filesystem::path& path, std::string_view content) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  write_file_atomic(path, content);
  path_ = path;
  fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd_ < 0) throw_write_error(path, "open for appending", errno);
}

void AppendFile::append(std::string_view text, std::string_view what) {
  if (fd_ < 0) throw std::logic_error("AppendFile::append before open");
  const off_t before = ::lseek(fd_, 0, SEEK_END);
  if (const int err = write_all(fd_, text)) {
    // (Best effort: a character device has no end to cut back to.)
    if (before >= 0) (void)::ftruncate(fd_, before);
    throw_write_error(path_, fmt::format("write of {}", what), err);
  }
}

// ---- the output directory ------------------------------------------------------------------

DirectoryLock::DirectoryLock(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / ".mpm.lock";
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ < 0) throw_write_error(path, "open", errno);
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    std::string holder(32, '\0');
    const ssize_t n = ::pread(fd_, holder.data(), holder.size(), 0);
    holder.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
    ::close(fd_);
    fd_ = -1;
    if (err != EWOULDBLOCK) throw_write_error(path, "lock", err);
    throw InputError(fmt::format(
        "output directory '{}' is in use by another run (pid {}); wait for it to end or choose "
        "another --out",
        dir.string(), holder.empty() ? "unknown" : holder));
  }
  const std::string pid = std::to_string(static_cast<long long>(::getpid())) + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    throw_write_error(path, "write", err);
  }
}

DirectoryLock& DirectoryLock::operator=(DirectoryLock&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(o.fd_, -1);
  }
  return *this;
}

// Closing the descriptor releases the lock; the file stays (removing it could let a waiting
// process and a new one each lock a different file).
DirectoryLock::~DirectoryLock() {
  if (fd_ >= 0) ::close(fd_);
}

std::vector<std::string> run_files(const std::filesystem::path& dir) {
  static const std::set<std::string> kFixed = {"config.toml",    "summary.json", "history.csv",
                                               "checkpoint.bin", "grid.vtu",     "particles.pvd"};
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const auto digits = [&](std::size_t at, std::size_t n) {
      return name.size() >= at + n &&
             name.substr(at, n).find_first_not_of("0123456789") == std::string::npos;
    };
    // particles_NNNNN.csv / .vtu / .pvtu, and a distributed run's pieces particles_NNNNN_pR.vtu
    // (R: the rank, at least 4 digits).
    const bool numbered = name.starts_with("particles_") && digits(10, 5);
    const bool frame =
        numbered && ((name.size() == 19 && (name.ends_with(".csv") || name.ends_with(".vtu"))) ||
                     (name.size() == 20 && name.ends_with(".pvtu")) ||
                     (name.size() >= 25 && name.substr(15, 2) == "_p" && name.ends_with(".vtu") &&
                      digits(17, name.size() - 21)));
    if (kFixed.contains(name) || frame || is_checkpoint_piece_name(name)) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string checkpoint_piece_name(std::int64_t step, int rank) {
  return fmt::format("checkpoint_s{}_p{:04d}.bin", step, rank);
}

bool is_checkpoint_piece_name(std::string_view name) {
  // checkpoint_s<digits>_p<4 or more digits>.bin
  constexpr std::string_view kStart = "checkpoint_s", kEnd = ".bin";
  if (!name.starts_with(kStart) || !name.ends_with(kEnd)) return false;
  const std::string_view mid =
      name.substr(kStart.size(), name.size() - kStart.size() - kEnd.size());
  const auto p = mid.find("_p");
  const auto digits = [](std::string_view d) {
    return !d.empty() && d.find_first_not_of("0123456789") == std::string_view::npos;
  };
  return p != std::string_view::npos && digits(mid.substr(0, p)) && mid.size() - p - 2 >= 4 &&
         digits(mid.substr(p + 2));
}

int remove_checkpoint_pieces(const std::filesystem::path& dir,
                             const std::vector<std::string>& keep) {
  int removed = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (!is_checkpoint_piece_name(name) || std::find(keep.begin(), keep.end(), name) != keep.end())
      continue;
    std::error_code rm;
    if (std::filesystem::remove(entry.path(), rm)) ++removed;
  }
  return removed;
}

// ---- write_file_atomic ---------------------------------------------------------------------

int remove_stale_temporaries(const std::filesystem::path& dir) {
  int removed = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const auto at = name.rfind(".tmp.");
    if (at == std::string::npos || at + 5 == name.size()) continue;
    const std::string digits = name.substr(at + 5);
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    // ESRCH: no such process. EPERM (another user's live process) and our own pid are kept.
    if (pid == ::getpid() || ::kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code rm;
    if (entry.is_regular_file(rm) && std::filesystem::remove(entry.path(), rm)) ++removed;
  }
  return removed;
}

OutputTarget output_target(const std::filesystem::path& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return {path, false};  // (a new file)
  if (S_ISREG(st.st_mode)) return {path, false};
  if (S_ISLNK(st.st_mode)) {
    // The link stays and its target is written: the target itself must be replaceable.
    std::error_code ec;
    const std::filesystem::path target = std::filesystem::canonical(path, ec);
    if (ec)
      throw RunError(exit_code::kOutput,
                     fmt::format("cannot write '{}': it is a symbolic link to nothing ({})",
                                 path.string(), ec.message()));
    struct stat t {};
    if (::stat(target.c_str(), &t) == 0 && !S_ISREG(t.st_mode) && !S_ISCHR(t.st_mode))
      throw RunError(exit_code::kOutput,
                     fmt::format("cannot write '{}': it links to '{}', which is {}, not a regular "
                                 "file; mpm replaces only regular files",
                                 path.string(), target.string(), file_type_name(t.st_mode)));
    return {target, S_ISCHR(t.st_mode)};
  }
  if (S_ISCHR(st.st_mode)) return {path, true};
  throw RunError(exit_code::kOutput,
                 fmt::format("cannot write '{}': it is {}, not a regular file; mpm replaces only "
                             "regular files (choose another path, or remove it)",
                             path.string(), file_type_name(st.st_mode)));
}

void write_file_atomic(const std::filesystem::path& requested, std::string_view content) {
  const OutputTarget target = output_target(requested);
  const std::filesystem::path& path = target.path;
  if (target.write_through) {
    // A character device (/dev/null, a terminal): written into, never replaced.
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw_write_error(requested, "open", errno);
    const int err = write_all(fd, content);
    const int closed = ::close(fd) != 0 ? errno : 0;
    if (err != 0) throw_write_error(requested, "write", err);
    if (closed != 0) throw_write_error(requested, "close", closed);
    return;
  }
  std::filesystem::path tmp = path;
  tmp += ".tmp." + std::to_string(static_cast<long long>(::getpid()));

  // 0666 & ~umask, the same permissions std::ofstream would give the file.
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw_write_error(path, "open " + tmp.string(), errno);

  const auto fail = [&](std::string_view what, int err) {
    ::close(fd);  // only used while fd is open; the close() failure is handled below
    ::unlink(tmp.c_str());
    throw_write_error(path, what, err);
  };

  if (const int err = write_all(fd, content)) fail("write", err);
  // fsync before rename: otherwise a crash after the rename can leave an empty or partial file
  // under the final name on file systems that reorder metadata and data writes (ext4, xfs).
  if (::fsync(fd) != 0) fail("fsync", errno);
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw_write_error(path, "close", err);
  }

  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    ::unlink(tmp.c_str());
    throw_write_error(path, "rename from " + tmp.string(), ec.value());
  }

  // Make the rename itself durable. Best effort: some file systems refuse fsync on a
  // directory, and the data is already complete either way.
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    (void)::fsync(dfd);
    ::close(dfd);
  }
}

// ---- particles -----------------------------------------------------------------------------

template <int Dim>
std::string particles_csv(const Particles<Dim>& p, const std::vector<ScalarField>& extra,
                          bool header_line) {
  static_assert(Dim >= 1 && Dim <= 3);
  check_particles(p);
  const auto n = static_cast<std::size_t>(p.size());

  std::vector<std::string> header = {"id"};
  for (const char* v : {"x0", "x", "u", "v"}) {
    for (int d = 1; d <= Dim; ++d) header.push_back(fmt::format("{}_{}", v, d));
  }
  for (const char* s : {"mass", "volume", "density"}) header.emplace_back(s);
  for (const char* t : {"F", "stress"}) {
    for (int r = 1; r <= Dim; ++r) {
      for (int c = 1; c <= Dim; ++c) header.push_back(fmt::format("{}_{}{}", t, r, c));
    }
  }
  for (const auto name : p.state.names()) header.emplace_back(name);
  check_fields(extra, n, std::set<std::string>(header.begin(), header.end()), "particle");

  Buffer b;
  if (header_line) {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (i > 0) put(b, ",");
      put(b, header[i]);
    }
    for (const auto& f : extra) {
      put(b, ",");
      put(b, csv_field(f.name));
    }
    put(b, "\n");
  }

  for (std::size_t i = 0; i < n; ++i) {
    put_int(b, particle_id(p, i));
    const auto vec = [&](const Vec<Dim>& a) {
      for (int d = 0; d < Dim; ++d) {
        put(b, ",");
        put_num(b, a[d]);
      }
    };
    const auto mat = [&](const Mat<Dim>& a) {
      for (int r = 0; r < Dim; ++r) {
        for (int c = 0; c < Dim; ++c) {
          put(b, ",");
          put_num(b, a(r, c));
        }
      }
    };
    vec(p.x0[i]);
    vec(p.x[i]);
    vec(p.displacement(i));
    vec(p.v[i]);
    for (const double s : {p.mass[i], p.volume[i], p.density(i)}) {
      put(b, ",");
      put_num(b, s);
    }
    mat(p.F[i]);
    mat(p.stress[i]);
    for (const double s : p.state[i]) {
      put(b, ",");
      put_num(b, s);
    }
    for (const auto& f : extra) {
      put(b, ",");
      put_num(b, (*f.values)[i]);
    }
    put(b, "\n");
  }
  return fmt::to_string(b);
}

template <int Dim>
std::string particles_vtu(const Particles<Dim>& p, double time,
                          const std::vector<ScalarField>& extra, bool binary,
                          const std::vector<VectorField<Dim>>& vectors,
                          const std::vector<double>* stress_zz) {
  static_assert(Dim >= 1 && Dim <= 3);
  check_particles(p);
  const auto n = static_cast<std::size_t>(p.size());
  // The frame's own arrays, whose names no extra field may take.
  std::set<std::string> own = {"id", "x0", "u", "v", "mass", "volume", "density", "F", "stress"};
  for (const auto name : p.state.names()) own.emplace(name);
  check_fields(extra, n, own, "particle");
  {
    std::set<std::string> used = own;
    for (const auto& f : extra) used.insert(f.name);
    for (const auto& v : vectors) {
      if (v.values == nullptr || v.values->size() != n || v.name.empty() ||
          !used.insert(v.name).second)
        throw std::invalid_argument(fmt::format(
            "particle vector field '{}': no name, no values, not one per particle, or a name "
            "already used",
            v.name));
    }
    if (stress_zz != nullptr && (Dim != 2 || stress_zz->size() != n))
      throw std::invalid_argument(
          "particles_vtu: stress_zz needs a 2D frame and a value per particle");
  }

  Buffer b;
  VtuData d;
  d.binary = binary;
  vtu_header(b, d);
  // TimeValue in FieldData is what ParaView reads as the data set's time (ASCII in either form).
  put(b, "    <FieldData>\n");
  put(b,
      "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
      "format=\"ascii\">\n");
  put_num(b, time);
  put(b, "\n      </DataArray>\n    </FieldData>\n");
  fmt::format_to(std::back_inserter(b), "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
                 n, n);

  put(b, "      <PointData>\n");
  std::vector<std::int64_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = particle_id(p, i);
  data_array(b, d, "id", 1, ids);
  // The derived fields (Particles::displacement, density), formed for the output only.
  std::vector<Vec<Dim>> u(n);
  std::vector<double> rho(n);
  for (std::size_t i = 0; i < n; ++i) {
    u[i] = p.displacement(i);
    rho[i] = p.density(i);
  }
  vector_array<Dim>(b, d, "x0", p.x0);
  vector_array<Dim>(b, d, "u", u);
  vector_array<Dim>(b, d, "v", p.v);
  scalar_array(b, d, "mass", p.mass);
  scalar_array(b, d, "volume", p.volume);
  scalar_array(b, d, "density", rho);
  tensor_array<Dim>(b, d, "F", p.F, 1.0);
  tensor_array<Dim>(b, d, "stress", p.stress, 0.0, stress_zz);
  // The material's internal variables, one scalar array each.
  {
    std::vector<double> column(n);
    for (std::size_t k = 0; k < p.state.width(); ++k) {
      for (std::size_t i = 0; i < n; ++i) column[i] = p.state[i][k];
      scalar_array(b, d, p.state.names()[k], column);
    }
  }
  for (const auto& f : vectors) vector_array<Dim>(b, d, f.name, *f.values);
  for (const auto& f : extra) scalar_array(b, d, f.name, *f.values);
  put(b, "      </PointData>\n");

  put(b, "      <Points>\n");
  vector_array<Dim>(b, d, "Points", p.x);
  put(b, "      </Points>\n");

  std::vector<Index> conn(n);
  for (std::size_t i = 0; i < n; ++i) conn[i] = static_cast<Index>(i);
  cells_block(b, d, conn, static_cast<Index>(n), 1, kVtkVertex);
  vtu_footer(b, d);
  return fmt::to_string(b);
}

// ---- grid ----------------------------------------------------------------------------------

template <int Dim>
std::string grid_vtu(const Grid<Dim>& g, const std::vector<ScalarField>& node_fields, bool binary) {
  static_assert(Dim >= 1 && Dim <= 3);
  std::array<Index, 3> nodes{1, 1, 1};  // corner nodes per direction, 1 in unused directions
  std::array<Index, 3> cells{1, 1, 1};
  for (int d = 0; d < Dim; ++d) {
    if (g.cells[d] < 1) throw std::invalid_argument("grid_vtu: grid has no cells");
    cells[d] = g.cells[d];
    nodes[d] = g.cells[d] + 1;
  }
  const Index num_nodes = nodes[0] * nodes[1] * nodes[2];
  const Index num_cells = g.num_cells();
  check_fields(node_fields, static_cast<std::size_t>(num_nodes), {}, "grid node");

  Buffer b;
  VtuData d;
  d.binary = binary;
  vtu_header(b, d);
  fmt::format_to(std::back_inserter(b), "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
                 num_nodes, num_cells);
  if (!node_fields.empty()) {
    put(b, "      <PointData>\n");
    for (const auto& f : node_fields) scalar_array(b, d, f.name, *f.values);
    put(b, "      </PointData>\n");
  }

  put(b, "      <Points>\n");
  std::vector<double> pts;
  pts.reserve(static_cast<std::size_t>(3 * num_nodes));
  for (Index k = 0; k < nodes[2]; ++k)
    for (Index j = 0; j < nodes[1]; ++j)
      for (Index i = 0; i < nodes[0]; ++i) {
        const std::array<Index, 3> ijk{i, j, k};
        // origin + i h rather than accumulating h, so rounding does not grow along the grid.
        for (int dd = 0; dd < 3; ++dd)
          pts.push_back(dd < Dim ? g.origin[dd] + g.h[dd] * static_cast<double>(ijk[dd]) : 0.0);
      }
  data_array(b, d, "Points", 3, pts);
  put(b, "      </Points>\n");

  // VTK corner order (vtkCellType.h / VTK file format figures): counter-clockwise around the
  // bottom face, then the same around the top face. Bits: 1 = +x, 2 = +y, 4 = +z. The first
  // 2^Dim entries give the line, quad and hexahedron orderings.
  constexpr std::array<int, 8> kCorner{0, 1, 3, 2, 4, 5, 7, 6};
  constexpr int kNodesPerCell = ipow(2, Dim);
  constexpr int kType = Dim == 1 ? kVtkLine : (Dim == 2 ? kVtkQuad : kVtkHexahedron);
  std::vector<Index> conn;
  conn.reserve(static_cast<std::size_t>(num_cells * kNodesPerCell));
  for (Index k = 0; k < cells[2]; ++k) {
    for (Index j = 0; j < cells[1]; ++j) {
      for (Index i = 0; i < cells[0]; ++i) {
        for (int c = 0; c < kNodesPerCell; ++c) {
          const int bits = kCorner[static_cast<std::size_t>(c)];
          const Index ci = i + (bits & 1), cj = j + ((bits >> 1) & 1), ck = k + ((bits >> 2) & 1);
          conn.push_back(ci + nodes[0] * (cj + nodes[1] * ck));
        }
      }
    }
  }
  cells_block(b, d, conn, num_cells, kNodesPerCell, kType);
  vtu_footer(b, d);
  return fmt::to_string(b);
}

// ---- pvd -----------------------------------------------------------------------------------

std::string particles_pvtu(std::string_view piece, const std::vector<std::string>& sources) {
  // The DataArray tags of a section of the piece, as PDataArray tags (type, name, components).
  const auto declared = [&](std::string_view open, std::string_view close) {
    std::string out;
    const auto b = piece.find(open), e = piece.find(close);
    if (b == std::string_view::npos || e == std::string_view::npos || e < b)
      throw std::logic_error("particles_pvtu: the piece has no " + std::string(open));
    std::string_view section = piece.substr(b, e - b);
    for (auto at = section.find("<DataArray"); at != std::string_view::npos;
         at = section.find("<DataArray", at + 1)) {
      const auto tag = section.substr(at, section.find('>', at) - at);
      std::string attrs;
      for (const char* key :
           {"type", "Name", "NumberOfComponents", "ComponentName0", "ComponentName1",
            "ComponentName2", "ComponentName3", "ComponentName4", "ComponentName5",
            "ComponentName6", "ComponentName7", "ComponentName8"}) {
        const std::string k = std::string(" ") + key + "=\"";
        const auto v = tag.find(k);
        if (v == std::string_view::npos) continue;
        const auto start = v + k.size();
        attrs += fmt::format(" {}=\"{}\"", key, tag.substr(start, tag.find('"', start) - start));
      }
      out += fmt::format("      <PDataArray{}/>\n", attrs);
    }
    return out;
  };
  std::string out =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <PUnstructuredGrid GhostLevel=\"0\">\n"
      "    <PPointData>\n";
  out += declared("<PointData>", "</PointData>");
  out += "    </PPointData>\n    <PPoints>\n";
  out += declared("<Points>", "</Points>");
  out += "    </PPoints>\n";
  for (const auto& src : sources)
    out += fmt::format("    <Piece Source=\"{}\"/>\n", xml_escape(src));
  out += "  </PUnstructuredGrid>\n</VTKFile>\n";
  return out;
}

void PvdSeries::add(double time, const std::string& file) {
  entries_.emplace_back(time, file);
}

std::string PvdSeries::str() const {
  Buffer b;
  put(b,
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n");
  for (const auto& [time, file] : entries_) {
    fmt::format_to(std::back_inserter(b),
                   "    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", time,
                   xml_escape(file));
  }
  put(b,
      "  </Collection>\n"
      "</VTKFile>\n");
  return fmt::to_string(b);
}

// ---- explicit instantiations -----------------------------------------------------------------

std::string triangle_mesh_vtu(const TriangleMesh& m, const std::vector<ScalarField>& node_fields,
                              const std::vector<ScalarField>& cell_fields, bool binary) {
  const Index nv = m.num_vertices(), nc = m.num_cells();
  check_fields(node_fields, static_cast<std::size_t>(nv), {}, "mesh vertex");
  check_fields(cell_fields, static_cast<std::size_t>(nc), {}, "mesh cell");
  Buffer b;
  VtuData d;
  d.binary = binary;
  vtu_header(b, d);
  fmt::format_to(std::back_inserter(b), "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
                 nv, nc);
  if (!node_fields.empty()) {
    put(b, "      <PointData>\n");
    for (const auto& f : node_fields) scalar_array(b, d, f.name, *f.values);
    put(b, "      </PointData>\n");
  }
  if (!cell_fields.empty()) {
    put(b, "      <CellData>\n");
    for (const auto& f : cell_fields) scalar_array(b, d, f.name, *f.values);
    put(b, "      </CellData>\n");
  }
  put(b, "      <Points>\n");
  std::vector<double> pts;
  pts.reserve(static_cast<std::size_t>(3 * nv));
  for (Index v = 0; v < nv; ++v) {
    pts.push_back(m.vertex(v)[0]);
    pts.push_back(m.vertex(v)[1]);
    pts.push_back(0.0);
  }
  data_array(b, d, "Points", 3, pts);
  put(b, "      </Points>\n");
  std::vector<Index> conn;
  conn.reserve(static_cast<std::size_t>(3 * nc));
  for (Index c = 0; c < nc; ++c)
    for (Index v : m.cell_vertices(c)) conn.push_back(v);  // counter-clockwise, as VTK expects
  cells_block(b, d, conn, nc, 3, kVtkTriangle);
  vtu_footer(b, d);
  return fmt::to_string(b);
}

#define MPM_IO_INSTANTIATE(D)                                                                 \
  template std::string particles_csv<D>(const Particles<D>&, const std::vector<ScalarField>&, \
                                        bool);                                                \
  template std::string particles_vtu<D>(                                                      \
      const Particles<D>&, double, const std::vector<ScalarField>&, bool,                     \
      const std::vector<VectorField<D>>&, const std::vector<double>*);                        \
  template std::string grid_vtu<D>(const Grid<D>&, const std::vector<ScalarField>&, bool);
MPM_IO_INSTANTIATE(1)
MPM_IO_INSTANTIATE(2)
MPM_IO_INSTANTIATE(3)
#undef MPM_IO_INSTANTIATE

}  // namespace mpm::io
