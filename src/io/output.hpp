#pragma once
// Writers for run output: particle frames (CSV, VTK .vtu), the background grid (.vtu), the
// ParaView time series (.pvd) and an atomic file writer for all of them. Every writer returns
// the file content as a string; only write_file_atomic touches the file system, so the
// formatting can be tested without files and a killed run never leaves a half-written frame.
//
// Formats: VTK XML file formats, "VTK File Formats" (VTK User's Guide, Kitware), section
// "XML File Formats"; cell type ids from vtkCellType.h.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "grid/grid.hpp"
#include "grid/triangle_mesh.hpp"
#include "particles/particles.hpp"

namespace mpm::io {

// Write content to path atomically: write "<path>.tmp.<pid>" in the same directory, flush and
// fsync it, then rename it over path (rename is atomic within one file system, POSIX). Readers
// see either the old file or the complete new one. Creates no directories. Throws
// RunError (exit_code::kOutput) naming the path and the system error (strerror) on failure; the
// temporary file is removed in that case.
// A path that exists and is not a regular file is never replaced: a symbolic link keeps its
// place and its target is written (as below); a character device (/dev/null, a terminal) is
// written through; anything else (a directory, a FIFO, a socket, a block device, a link to
// nothing or to such a thing) is refused with RunError (exit_code::kOutput) naming it.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// Where an output at `path` goes: `path` itself when it does not exist or is a regular file
// (replaced by a rename), a symbolic link's target (the link kept), or a character device
// (write_through: written into, never renamed over). RunError (exit_code::kOutput) naming the
// path for anything else.
struct OutputTarget {
  std::filesystem::path path;
  bool write_through = false;
};
OutputTarget output_target(const std::filesystem::path& path);

// Removes the temporaries "<name>.tmp.<pid>" in dir (not its subdirectories) that a process no
// longer running left behind (killed while writing); those of running processes stay. Returns
// how many were removed.
int remove_stale_temporaries(const std::filesystem::path& dir);

// The output directory of one run at a time: holds an exclusive flock(2) on dir/.mpm.lock, with
// the holder's pid in it, for its lifetime (the kernel drops it when the process dies, so a
// killed run leaves no stale lock). A second run into the directory is refused with InputError
// naming the holder's pid. Move-only.
class DirectoryLock {
 public:
  DirectoryLock() = default;
  explicit DirectoryLock(const std::filesystem::path& dir);
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;
  DirectoryLock(DirectoryLock&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}
  DirectoryLock& operator=(DirectoryLock&& o) noexcept;
  ~DirectoryLock();

 private:
  int fd_ = -1;
};

// The files of a run in dir (config.toml, summary.json, history.csv, checkpoint.bin, grid.vtu,
// particles.pvd, particles_NNNNN.csv/.vtu, a distributed run's pieces of frames and
// checkpoints), sorted; other files are not a run's.
std::vector<std::string> run_files(const std::filesystem::path& dir);

// A distributed checkpoint's piece of `rank` at `step` (io/checkpoint.hpp):
// "checkpoint_s<step>_p<rank, 4 digits or more>.bin", and whether a name is one.
std::string checkpoint_piece_name(std::int64_t step, int rank);
bool is_checkpoint_piece_name(std::string_view name);
// Removes the checkpoint pieces in dir that `keep` does not name (those of an earlier
// checkpoint, once the manifest naming the new ones is written); returns how many. Errors are
// ignored: a piece left over takes room but no run reads it.
int remove_checkpoint_pieces(const std::filesystem::path& dir,
                             const std::vector<std::string>& keep);

// A file written as a run goes (history.csv): open() replaces it with `content` atomically, then
// every append() is one write(2) at its end, so the text appended so far survives a killed
// process (the kernel holds it) and the run keeps none of it in memory. Throws
// RunError (exit_code::kOutput) naming the path and the system error on failure. Move-only.
class AppendFile {
 public:
  AppendFile() = default;
  AppendFile(const AppendFile&) = delete;
  AppendFile& operator=(const AppendFile&) = delete;
  AppendFile(AppendFile&& o) noexcept : path_(std::move(o.path_)), fd_(std::exchange(o.fd_, -1)) {}
  AppendFile& operator=(AppendFile&& o) noexcept;
  ~AppendFile();

  void open(const std::filesystem::path& path, std::string_view content);
  // `what` names the text in the error ("row 12"). A write that fails part-way is cut off again
  // (the file keeps whole appends only, e.g. no partial history row on a full disk).
  void append(std::string_view text, std::string_view what = "append");
  bool is_open() const { return fd_ >= 0; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

// An extra per-particle (or per-grid-node) scalar field to add to a frame, e.g. the exact
// solution or the error. values must outlive the writer call and hold one value per particle
// (or node); the writers throw std::invalid_argument otherwise.
struct ScalarField {
  std::string name;
  const std::vector<double>* values = nullptr;
};

// An extra per-particle vector field (e.g. the exact displacement), written to a VTU as a
// 3-component array like u and v (zero padded), so that an error field is one calculator line.
template <int Dim>
struct VectorField {
  std::string name;
  const std::vector<Vec<Dim>>* values = nullptr;
};

// CSV of the particle state: a header line, then one row per particle. Columns:
// id, x0_1..x0_D, x_1..x_D, u_1..u_D, v_1..v_D, mass, volume, density, F_11..F_DD (row-major),
// stress_11..stress_DD (row-major), the material's internal variables (Particles::state, by
// their names; none for an elastic law), then each extra field. id is the particle's stable id
// (Particles::id); rows are in the order of p (the run writes its particles in id order).
// Numbers are printed with 17 significant digits, so they parse back to the same double.
// header = false: the rows alone (a distributed frame's part after the first process's).
template <int Dim>
std::string particles_csv(const Particles<Dim>& p, const std::vector<ScalarField>& extra = {},
                          bool header = true);

// VTK XML UnstructuredGrid (.vtu; ASCII, or with binary = true the arrays as raw little-endian
// bytes in an <AppendedData> block, VTK format 1.0 with UInt64 headers, which ParaView and
// meshio read) with one VTK_VERTEX cell per particle at its current
// position (padded to 3 components). PointData: id (Int64, Particles::id), x0, u, v (3 components,
// zero padded), mass, volume, density, F and stress (9 components, row-major: the Dim x Dim tensor
// embedded in 3x3 with identity padding for F and zero padding for stress; in 2D stress_zz, when
// given, is the stress normal to the plane, sigma_zz, of each particle), the material's internal
// variables (one scalar each, by name), then the extra vectors and scalars. Vectors and tensors
// name their components (ComponentName0 ...: X, Y, Z; XX, XY,
// ..., ZZ). The time [s] is stored in FieldData as "TimeValue", which ParaView reads.
template <int Dim>
std::string particles_vtu(const Particles<Dim>& p, double time,
                          const std::vector<ScalarField>& extra = {}, bool binary = false,
                          const std::vector<VectorField<Dim>>& vectors = {},
                          const std::vector<double>* stress_zz = nullptr);

// A .pvtu (VTK's parallel unstructured grid) over the pieces `sources` (file names relative to
// it) of one frame of a distributed run, one piece per process: its PPointData and PPoints are
// those of `piece`, the .vtu text of any one piece (every piece has the same arrays), so the
// two cannot disagree. ParaView opens it as one data set.
std::string particles_pvtu(std::string_view piece, const std::vector<std::string>& sources);

// The background grid as a .vtu: points at the cell corners (x fastest, then y, then z), cells
// VTK_LINE in 1D, VTK_QUAD in 2D, VTK_HEXAHEDRON in 3D (linear cell index x fastest, like
// Grid::cell_index). node_fields are PointData scalars with one value per corner node.
template <int Dim>
std::string grid_vtu(const Grid<Dim>& g, const std::vector<ScalarField>& node_fields = {},
                     bool binary = false);

// A triangular mesh as a .vtu: its vertices (z = 0) and VTK_TRIANGLE cells in the mesh's
// order; node_fields one value per vertex, cell_fields one per triangle.
std::string triangle_mesh_vtu(const TriangleMesh& m,
                              const std::vector<ScalarField>& node_fields = {},
                              const std::vector<ScalarField>& cell_fields = {},
                              bool binary = false);

// A ParaView .pvd collection: one DataSet entry per frame, in the order added.
class PvdSeries {
 public:
  // file is written as given; it should be relative to the .pvd file's directory.
  void add(double time, const std::string& file);
  std::string str() const;
  std::size_t size() const { return entries_.size(); }

 private:
  std::vector<std::pair<double, std::string>> entries_;
};

}  // namespace mpm::io
