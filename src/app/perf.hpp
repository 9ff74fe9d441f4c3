#pragma once
// `mpm bench`: time per particle-step and memory per particle of the explicit step.
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "core/stage_clock.hpp"
#include "core/types.hpp"

namespace mpm {

struct BenchOptions {
  int dim = 1;
  Index particles = 1000000;
  int per_cell = 0;  // per direction; 0: 4 in 1D, 3 in 2D, 2 in 3D
  int threads = 0;   // OpenMP threads; 0: the OpenMP default (OMP_NUM_THREADS or all cores)
  Index steps = 20;
  int repeats = 3;
  std::string scheme = "musl";
  std::string basis = "linear";
  int degree = 2;
  std::string mapping = "direct";
  std::string solver = "mpm";          // method.solver: mpm, otm or unified (1D)
  std::string mass = "lumped";         // method.mass
  std::string mass_solver = "direct";  // method.mass_solver (consistent mass)
  // 2D and 3D problem: "plate" (2D plate_mms_2d, 3D the cube of cube_mms_3d) or "refkernel"
  // (the problem of the yardstick ../shared/tools/refkernel.cpp, in 3D scripts/refkernel3d.cpp,
  // through the custom benchmark). 1D has its bar only.
  std::string problem = "plate";
  bool shuffle = false;       // start from the particles in random order (RunOptions::shuffle_seed)
  std::string sort = "auto";  // method.sort
  bool messages = false;      // time messages between processes instead (bench_messages)
  bool stages = false;        // time the step's stages too (RunOptions::stage_times; one thread)
};

struct BenchResult {
  Index particles = 0;
  Index cells = 0;
  Index steps = 0;
  int threads = 0;  // OpenMP threads used
  double best_ns_per_particle_step = 0.0;
  double median_ns_per_particle_step = 0.0;
  // The same over the steps after the first (steps >= 2; 0 otherwise), and the first step's wall
  // time per particle, median over the repeats [ns]: the first step allocates and first touches
  // the step's arrays, which a run of thousands of steps pays once.
  double best_ns_after_first = 0.0;
  double median_ns_after_first = 0.0;
  double median_ns_first_step = 0.0;
  double bytes_per_particle = 0.0;  // particle state + cached stencil + grid share
  // Re-sorting (state/sort.hpp): sorts per run, mean wall time of one [ns per particle], and
  // its buffers [bytes per particle] (order, inverse, scratch of the largest field, cursors per
  // cell), allocated by the first sort.
  Index sorts = 0;
  double ns_per_particle_sort = 0.0;
  double sort_bytes_per_particle = 0.0;
  // With BenchOptions::stages: each stage's wall time (core/stage_clock.hpp) and the whole step's,
  // over every step of every repeat [ns per particle-step].
  std::array<double, static_cast<std::size_t>(Stage::kCount)> stage_ns{};
  double mean_ns_per_particle_step = 0.0;
};

// 1D vibrating bar (D Table 3.1 set 2 material) with the given scheme, basis and mapping,
// lumped mass.
BenchResult bench_1d(const BenchOptions& opt);

// 2D, about `particles` particles, per_cell per direction, neo-Hookean (E = 1e7 Pa, nu = 0.3,
// rho = 1000 kg/m^3), lumped mass. problem "plate": the manufactured-solution plate
// (plate_mms_2d, amplitude 1e-3 m, rollers, its body force b(X, t) evaluated every step),
// dt = 0.1 h / c with the P-wave speed c. problem "refkernel": the yardstick's problem, the
// unit square body in a grid padded by two cells per side, v = (0.1 sin(2 pi x),
// -0.1 sin(2 pi y)) m/s, no body force, free sides, dt = 1e-6 s.
BenchResult bench_2d(const BenchOptions& opt);

// 3D, about `particles` particles, per_cell per direction (default 2), the 2D plate's material,
// lumped mass. problem "plate": the cube of cube_mms_3d, amplitude 1e-3 m, rollers,
// its body force every step, dt = 0.1 h / c with the P-wave speed. problem "refkernel": the 2D
// refkernel problem in 3D (scripts/refkernel3d.cpp), the unit cube body in a grid padded by two
// cells per side, v = (0.1 sin(2 pi x), -0.1 sin(2 pi y), 0.1 sin(2 pi z)) m/s, no body force,
// free sides, dt = 1e-6 s.
BenchResult bench_3d(const BenchOptions& opt);

// `mpm bench --messages` under mpirun: the time of one halo exchange (Comm::exchange, each
// process of a pair sending and receiving `bytes` at once, every pair of ranks 2k, 2k + 1 at
// the same time) for message sizes from 8 bytes to 2 MiB (eightfold steps); the slowest pair's
// time, best and median of `repeats`. alpha: the best time of the smallest message [s]; beta: the
// bandwidth between the two largest, (bytes_n - bytes_{n-1}) / (t_n - t_{n-1}) of the medians
// [bytes/s]: the costs of the communication model (BENCHMARKS.md, "Processes").
struct MessageTiming {
  std::size_t bytes = 0;
  double best_seconds = 0.0, median_seconds = 0.0;
};
struct MessageBench {
  int processes = 0;
  std::vector<MessageTiming> sizes;
  double alpha_seconds = 0.0, beta_bytes_per_second = 0.0;
};
class Comm;
// InputError unless the run has an even number of processes, two or more.
MessageBench bench_messages(const Comm& comm, int repeats);

}  // namespace mpm
