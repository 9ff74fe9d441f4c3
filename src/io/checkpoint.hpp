#pragma once
// Checkpoints: the complete state of a run (output.checkpoint_every), from which
// `mpm run --restart FILE` continues bit for bit (README "Checkpoints"). A run on one process
// writes one file, checkpoint.bin. A distributed run writes one piece per process
// (checkpoint_s<step>_p<rank>.bin: that process's particles, written by it) and, once every piece
// is on disk, checkpoint.bin as their manifest (the run's state without particles, and each
// piece's size and hash), so that no process gathers the body and a restart reads only the
// pieces it needs.
//
// File layout (all integers little-endian, reals IEEE-754 binary64 little-endian):
//   offset  0  8 bytes  magic "MPMLABCK"
//   offset  8  u32      format version (kCheckpointVersion)
//   offset 12  u64      payload size in bytes
//   offset 20  u64      FNV-1a 64-bit hash of the payload bytes
//   offset 28           payload
// Payload, in this order (str = u64 length + bytes; f64[] = u64 count + values; i64[] likewise):
//   str config (Config::to_toml() of the run), str solver ("mpm" or "ulfem"), i64 dim,
//   i64 step, f64 time,
//   particles: i64 dim, i64 count, then one f64[] per real field of Particles::for_each_field
//     (x, x0, v, mass, volume, volume0, F, stress, body, state, material; vectors Dim values
//     per particle, tensors Dim x Dim column-major, state the materials' internal variables,
//     the columns of every law of the run per particle (version 8), material the index of the
//     particle's material, one value (version 9)), i64[] id (version 3: the stable ids in the
//     stored order, which re-sorting may have changed),
//   i64[] cell of each particle at the last basis evaluation,
//   version 3: i64 re-sorting reference span (-1: none), i64 sorts so far (state/sort.hpp),
//   diagnostics: f64 max_rel_mass_error, f64 max_rel_momentum_error, i64 grid_crossings,
//   u8 FEM state present; if 1: f64[] node x, f64[] node v, f64[] node body, the element
//     particles (as above), f64 time, f64 time_anchor, f64 last_dt, i64 steps,
//     i64 steps_since_anchor,
//   str mapping name, str mapping totals (the bytes the mapping writes of itself, save_totals()
//     of TLS and MLS/IMLS; empty for the other mappings),
//   i64 frames written, f64[] frame times,
//   f64[] basis state (version 2: the tracked corners of CPDI2, 2^Dim x Dim values per particle;
//     empty for the other bases),
//   i64[] distribution (version 10; empty for a run on one process): R processes, the
//     processes along each axis (Dim values, x first; slabs: 1, ..., 1, R), the cuts along each
//     axis (processes + 1 values per axis, axis after axis), then per rank its particle count,
//     re-sorting reference span, sorts and grid crossings (4 R values; the diagnostics above
//     hold the total crossings and sorts),
//   version 10: i64[] layer counts (a distributed run: the particles in each cell layer along
//     each axis, axis after axis, over all processes; empty for one process), u64 pieces, then
//     per piece (rank 0, 1, ...): str file name, u64 file size, u64 payload hash (its header's),
//   version 7: u64 the FNV-1a hash of the bytes of the mesh file (grid.mesh; 0 without one),
//     so that a restart refuses a mesh file that changed.
// A distributed run's manifest holds no particles, cells or basis state (counts 0): its pieces
// do. A piece has the same header with the magic "MPMLABCP" and the payload
//   i64 step, i64 rank, i64 ranks, particles (as above), i64[] cells, f64[] basis state
//   (CPDI2's corners, 2^Dim x Dim values per particle, else empty),
// the particles in that process's order.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "methods/ulfem.hpp"
#include "particles/particles.hpp"
#include "setup/config.hpp"
#include "state/diagnostics.hpp"

namespace mpm::io {

inline constexpr std::string_view kCheckpointMagic = "MPMLABCK";
// A file of another version is refused by its version: the layout above is version 10's (the
// displacement and density derived, not stored; a distributed run's pieces and manifest, its
// process grid of blocks; the mesh file's hash; the materials' internal variables; each
// particle's material).
inline constexpr std::uint32_t kCheckpointVersion = 10;
inline constexpr std::string_view kPieceMagic = "MPMLABCP";
inline constexpr std::size_t kCheckpointHeaderBytes = 28;
inline constexpr const char* kCheckpointFile = "checkpoint.bin";

// FNV-1a, 64-bit (offset basis 14695981039346656037, prime 1099511628211).
std::uint64_t fnv1a64(std::string_view bytes);

// The names of the real particle fields, in the order of Particles::for_each_named_field ("x",
// "x0", ..., "body", "state").
const std::vector<std::string>& particle_field_names();

// Particle arrays of any dimension, flattened (Dim or Dim^2 doubles per particle): one array per
// real field (particle_field_names(); empty ones when there are no particles, as for the ULFEM
// solver), then the ids.
struct ParticleArrays {
  std::int64_t dim = 0;
  std::int64_t count = 0;
  std::vector<std::vector<double>> reals =
      std::vector<std::vector<double>>(particle_field_names().size());
  std::vector<std::int64_t> id;
};

template <int Dim>
ParticleArrays pack_particles(const Particles<Dim>& p);
// Throws InputError (naming `what`) when the dimension or a size does not match. The material
// state's rows come unnamed (MaterialState::set_raw): the run's material names them and checks
// their width (MaterialState::set_names).
template <int Dim>
Particles<Dim> unpack_particles(const ParticleArrays& a, const std::string& what);

struct FemArrays {
  std::vector<double> x, v, body;
  ParticleArrays elements;
  double time = 0.0, time_anchor = 0.0, last_dt = 0.0;
  std::int64_t steps = 0, steps_since_anchor = 0;
};
FemArrays pack_fem(const Ulfem1D::State& s);
Ulfem1D::State unpack_fem(const FemArrays& a, const std::string& what);

struct Checkpoint {
  std::string config;  // Config::to_toml() of the run that wrote it
  std::string solver;  // "mpm" or "ulfem"
  std::int64_t dim = 1;
  std::int64_t step = 0;     // steps taken
  double time = 0.0;         // [s]
  ParticleArrays particles;  // MPM particles (empty for solver "ulfem")
  std::vector<std::int64_t> cells;
  std::int64_t sort_reference = -1;  // SortState::reference
  std::int64_t sorts = 0;            // SortState::sorts
  Diagnostics diag;
  std::optional<FemArrays> fem;  // the FEM reference alongside MPM, or the ULFEM solver
  std::string mapping;           // method.mapping
  std::string mapping_totals;    // encode_totals() of TLS/MLS, else empty
  std::int64_t frames = 0;       // particle frames written so far
  std::vector<double> frame_times;
  std::vector<double> basis_state;  // state a basis carries between steps (CPDI2 corners)
  // A run on several processes (the layout above); empty for one process.
  std::vector<std::int64_t> distribution;
  std::vector<std::int64_t> layer_counts;  // a distributed run: particles per layer, per axis
  // A distributed run's pieces, rank after rank (their particles are not in `particles`).
  struct Piece {
    std::string file;         // its name, in the manifest's directory
    std::uint64_t bytes = 0;  // the file's size
    std::uint64_t hash = 0;   // the FNV-1a hash of its payload (its header's)
  };
  std::vector<Piece> pieces;
  // fnv1a64 of the bytes of the files of kHashedInputKeys (one file: its hash; several: each
  // next one's hash folded in, fnv1a64 of the two as 16 hex digits each); 0: no such file.
  std::uint64_t mesh_hash = 0;
};

// The keys that name input files a run reads besides its configuration: stored by their
// absolute paths, hashed into Checkpoint::mesh_hash (driver/run.cpp), the same file named from
// another directory the same key (restart_config).
inline constexpr const char* kHashedInputKeys[] = {"grid.mesh", "body.mesh", "body.particles"};
// Those keys, and the files of the named bodies of `cfg` (body.NAME.mesh, body.NAME.particles).
std::vector<std::string> hashed_input_keys(const Config& cfg);

// One process's share of a distributed checkpoint: its particles in its order, each one's cell
// at the last basis evaluation and the basis's carried state (basis_state, as Checkpoint's).
struct CheckpointPiece {
  std::int64_t step = 0, rank = 0, ranks = 0;
  ParticleArrays particles;
  std::vector<std::int64_t> cells;
  std::vector<double> basis_state;
};
std::string encode_piece(const CheckpointPiece& p);
// The same bytes straight from a process's particles, their cells and the basis's carried state
// (no flattened copy of the particles: a distributed run writes its piece with this).
template <int Dim>
std::string encode_piece(std::int64_t step, std::int64_t rank, std::int64_t ranks,
                         const Particles<Dim>& particles, std::span<const CompactIndex> cells,
                         const std::vector<double>& basis_state);
// InputError naming `name` when the bytes are not a piece, truncated or corrupted.
CheckpointPiece decode_piece(std::string_view bytes, const std::string& name);
// The manifest's entry for a piece's encoded bytes: its size and payload hash.
Checkpoint::Piece describe_piece(const std::string& file, std::string_view bytes);

// A distributed checkpoint (c.pieces not empty; `manifest` its file): the pieces `take` chooses
// (by rank) read from the manifest's directory, each checked against the manifest (name, size,
// hash) and the manifest's step and process count, and appended in rank order to c.particles,
// c.cells and c.basis_state: all of them give the state a run on one process would have stored.
// Returns each chosen piece's particle count (in rank order). InputError naming the piece.
std::vector<std::int64_t> join_pieces(Checkpoint& c, const std::filesystem::path& manifest,
                                      const std::vector<bool>& take);

std::string encode_checkpoint(const Checkpoint& c);
// `name` (the file name) is used in error messages. Throws InputError when the bytes are not a
// checkpoint, are truncated, corrupted (checksum) or of another format version.
Checkpoint decode_checkpoint(std::string_view bytes, const std::string& name);

// write_file_atomic(path, encode_checkpoint(c)).
void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c);
// Reads and decodes; InputError naming the file when it cannot be read or decoded. A distributed
// checkpoint is read as its manifest (no particles): join_pieces adds them.
Checkpoint read_checkpoint(const std::filesystem::path& path);
// read_checkpoint with every piece joined: the whole state, for a reader on one process.
Checkpoint read_whole_checkpoint(const std::filesystem::path& path);

// The configuration of a restarted run. The checkpoint's stored configuration is parsed (source
// "<name> (stored configuration)"); `given` (CONFIG of `mpm run CONFIG --restart FILE`, --set
// applied) or, when absent, the stored one with `overrides` applied must agree with it in every
// key and constant except output.*, parallel.* and time.end, else InputError listing the
// differing keys with both values. Returns the configuration to run with.
Config restart_config(const Checkpoint& c, const std::string& name, const Config* given,
                      const std::vector<std::string>& overrides = {});

}  // namespace mpm::io
