#pragma once
// Running one configuration: build the problem, choose the variants once, step, write outputs.
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "core/stage_clock.hpp"
#include "core/types.hpp"
#include "state/simulation.hpp"

namespace mpm {

class Config;
namespace io {
struct Checkpoint;
}

struct RunOptions {
  std::string out_dir;  // empty: write nothing
  bool quiet = false;   // no progress line
  // Keep history.csv's rows in memory too, with or without out_dir (driver/session.hpp).
  bool keep_history = false;
  // out_dir holds an earlier run's files (io::run_files): false refuses the run (InputError),
  // true removes them before the first write. A restart keeps what it continues.
  bool overwrite = false;
  // Continue from this checkpoint (io::read_checkpoint) instead of the initial state; the
  // configuration passed to run() must be io::restart_config()'s. restart_name (the file)
  // names it in error messages; a distributed checkpoint's pieces are read next to it.
  std::shared_ptr<const io::Checkpoint> restart;
  std::string restart_name;
  // Non-zero: start from the particles in a random order drawn with this seed
  // (shuffle_particles; tests and `mpm bench --shuffle` of the re-sorting). Ignored on restart.
  std::uint64_t shuffle_seed = 0;
  // OpenMP threads of the run: -1 leaves OpenMP's setting as it is (the library's default:
  // tests and `mpm bench` set it themselves); 0 takes OpenMP's count capped by the problem size,
  // one thread per kMinParticlesPerThread particles (`mpm run` and `mpm study` unless
  // --threads or OMP_NUM_THREADS says otherwise); n > 0 runs n threads. The results do not
  // depend on it (core/parallel.hpp).
  int threads = -1;
  // The processes of a distributed run (mpirun; core/comm.hpp), or null: one process. Every
  // process calls run() with the same configuration and options.
  const Comm* comm = nullptr;
  // The FNV-1a hash of the mesh file's bytes (grid.mesh; 0 without one), which checkpoints
  // store; run() sets it.
  std::uint64_t mesh_hash = 0;
  // Time the step's stages (RunResult::stages; `mpm bench --stages`): one thread only, since the
  // material laws are timed inside the particle loop.
  bool stage_times = false;
};

// Below this many particles per thread a second thread costs more than it saves: measured with
// `mpm bench --threads 1|2`, passive waiting, on 2 cores (BENCHMARKS.md,
// "Threads"): 2D quadratic B-splines gain 1.2x at 8000 particles and lose at 4000; 1D P1 breaks
// even at 64000 and gains 1.35x at 128000.
inline constexpr Index kMinParticlesPerThread[4] = {0, 50000, 5000, 5000};

// The thread count RunOptions::threads asks for, for a problem of `particles` in `dim`
// dimensions, given OpenMP's current maximum.
int run_threads(int requested, Index particles, int dim, int available);

// Particle error norms at the final time (D eq. 4.92); empty when there is no exact solution.
struct ErrorNorms {
  std::optional<double> displacement_rms;      // RMS of u(X_p, T) - u_p
  std::optional<double> velocity_rms;          // RMS of v(X_p, T) - v_p
  std::optional<double> velocity_rms_midstep;  // RMS of v(X_p, T - dt/2) - v_p (leapfrog time)
  // RMS of v(X_p, T + c dt) - v_p with c the scheme's velocity time (-1/2 USL/MUSL, +1/2 USF,
  // 0 USAVG): the comparison in which every scheme is second-order consistent in time.
  std::optional<double> velocity_rms_scheme_time;
  std::optional<double> stress_rms;     // RMS of |sigma(X_p, T) - sigma_p|
  std::optional<double> stress_rel_l2;  // (sum V0 |err|^2 / sum V0 |sigma|^2)^(1/2)
  // The same RMS norms over the interior particles only: those whose initial position is not
  // in the first or last cell of the body, or the first or last p cells for B-splines of degree
  // p (boundary errors of BSMPM, D Fig. 5.10).
  std::optional<double> displacement_rms_interior;
  std::optional<double> velocity_rms_scheme_time_interior;
  std::optional<double> stress_rms_interior;
};

struct RunResult {
  int exit_code = exit_code::kOk;
  std::string failure;  // the diagnosis when exit_code != 0
  std::string benchmark;
  int dim = 1;
  Index cells = 0;
  double h = 0.0;                 // the largest cell size over the directions [m]
  std::vector<double> cell_size;  // per direction [m] (summary.json in more than 1D)
  Index particles = 0;
  Index steps = 0;
  double wall_seconds = 0.0;
  double ns_per_particle_step = 0.0;
  // Wall time of the first step the run took [s], part of ns_per_particle_step: it allocates and
  // first touches the step's arrays (a TLS first step costs about five later ones, BENCHMARKS.md),
  // so `mpm bench` reports the steps after it separately.
  double first_step_seconds = 0.0;
  Index sorts = 0;            // re-sorts by cell over the run (state/sort.hpp; MPM only)
  double sort_seconds = 0.0;  // their wall time, part of ns_per_particle_step [s]
  StageClock stages;          // the stages' wall times over the run (RunOptions::stage_times)
  ErrorNorms errors;
  Diagnostics diag;
  nlohmann::ordered_json summary;     // what summary.json holds
  std::vector<std::string> warnings;  // the problem's (Problem::warnings)
  std::vector<BodyRange> bodies;      // the problem's (Problem::bodies: several bodies)
};

// Runs `cfg`; input errors throw InputError before the first step, numerical failures are
// reported in the result (exit_code, failure) after the last good state has been written.
RunResult run(const Config& cfg, const RunOptions& opt);

}  // namespace mpm
