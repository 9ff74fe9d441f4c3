#include "app/perf.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <vector>

#include "core/comm.hpp"
#include "driver/run.hpp"
#include "grid/grid_state.hpp"
#include "particles/particles.hpp"
#include "setup/config.hpp"

namespace mpm {

namespace {

// Functions per direction in a particle's stencil and grid DOFs per direction beyond the cell
// count, by basis name (basis/*.hpp: StencilT and num_dofs()).
int stencil_per_dim(const BenchOptions& opt) {
  if (opt.basis == "linear") return 2;
  if (opt.basis == "bspline") return opt.degree + 1;
  if (opt.basis == "maxent") return 6;  // the node window (basis/maxent.hpp)
  return 4;                             // GIMP, CPDI, DDMPM: nodes c-1 .. c+2
}
Index extra_dofs(const BenchOptions& opt) {
  return opt.basis == "bspline" ? opt.degree : 1;
}

// Particle state + cached stencil + cell index + the grid's share: the GridState arrays and the
// scatter slices of core/parallel.hpp (about one grid of mass and one of vectors). Linear and
// B-spline bases cache the compact TensorStencil (first DOF, K values and K derivatives per
// direction), the others the full Stencil (DOF, value, gradient per entry).
template <int Dim>
double bytes_per_particle(const BenchOptions& opt, Index cells, Index particles) {
  const auto k = static_cast<std::size_t>(stencil_per_dim(opt));
  const auto n = static_cast<std::size_t>(std::pow(stencil_per_dim(opt), Dim));
  const bool tensor = opt.basis == "linear" || opt.basis == "bspline";
  const std::size_t stencil = tensor ? sizeof(Index) + 2 * Dim * k * sizeof(double)
                                     : n * (sizeof(Index) + sizeof(double) + sizeof(Vec<Dim>));
  const double dofs = std::pow(static_cast<double>(cells + extra_dofs(opt)), Dim);
  const double per_dof =
      static_cast<double>(sizeof(double) + 4 * sizeof(Vec<Dim>) + 2 * sizeof(std::uint8_t) +
                          sizeof(double) + sizeof(Vec<Dim>));
  // (The benchmarks' elastic laws carry no internal variables.)
  return static_cast<double>(Particles<Dim>::bytes_per_particle(0) + stencil +
                             sizeof(CompactIndex)) +
         dofs * per_dof / static_cast<double>(particles);
}

// The re-sorting buffers (SortState): order and inverse permutation, the scratch of the largest
// particle field (F or stress), one cursor per cell the particles span (every cell here).
template <int Dim>
double sort_bytes_per_particle(Index cells, Index particles) {
  return static_cast<double>(2 * sizeof(CompactIndex) + sizeof(Mat<Dim>)) +
         static_cast<double>(cells + 1) * static_cast<double>(sizeof(Index)) /
             static_cast<double>(particles);
}

std::string method_toml(const BenchOptions& opt) {
  return fmt::format(
      "[method]\nscheme = \"{}\"\nbasis = \"{}\"\ndegree = {}\nmapping = \"{}\"\nsort = \"{}\"\n"
      "solver = \"{}\"\nmass = \"{}\"\n{}",
      opt.scheme, opt.basis, opt.degree, opt.mapping, opt.sort, opt.solver, opt.mass,
      opt.mass == "consistent" ? fmt::format("mass_solver = \"{}\"\n", opt.mass_solver) : "");
}

void time_runs(const Config& cfg, const BenchOptions& opt, BenchResult& r) {
  if (opt.threads > 0) omp_set_num_threads(opt.threads);
  r.threads = omp_get_max_threads();
  std::vector<double> ns, after, first;
  double sort_seconds = 0.0;
  for (int k = 0; k < opt.repeats; ++k) {
    RunOptions ro;
    ro.quiet = true;
    ro.shuffle_seed = opt.shuffle ? 1 : 0;
    ro.stage_times = opt.stages;
    const RunResult res = run(cfg, ro);
    ns.push_back(res.ns_per_particle_step);
    // Per particle-step of this run, averaged over the repeats below.
    const double per = 1e9 / (static_cast<double>(res.particles) *
                              static_cast<double>(std::max<Index>(res.steps, 1)) *
                              static_cast<double>(opt.repeats));
    for (std::size_t s = 0; s < r.stage_ns.size(); ++s)
      r.stage_ns[s] += res.stages.seconds[s] * per;
    r.mean_ns_per_particle_step += res.ns_per_particle_step / static_cast<double>(opt.repeats);
    // The run's step time split into its first step and the rest (RunResult::first_step_seconds).
    const double n = static_cast<double>(res.particles);
    const double total = res.ns_per_particle_step * static_cast<double>(res.steps) * n;  // [ns]
    first.push_back(1e9 * res.first_step_seconds / n);
    if (res.steps >= 2)
      after.push_back((total - 1e9 * res.first_step_seconds) /
                      (static_cast<double>(res.steps - 1) * n));
    r.sorts = res.sorts;
    sort_seconds += res.sort_seconds;
    r.particles = res.particles;
  }
  if (r.sorts > 0)
    r.ns_per_particle_sort = 1e9 * sort_seconds /
                             (static_cast<double>(r.sorts) * static_cast<double>(opt.repeats) *
                              static_cast<double>(r.particles));
  std::sort(ns.begin(), ns.end());
  r.best_ns_per_particle_step = ns.front();
  r.median_ns_per_particle_step = ns[ns.size() / 2];
  std::sort(first.begin(), first.end());
  r.median_ns_first_step = first[first.size() / 2];
  if (!after.empty()) {
    std::sort(after.begin(), after.end());
    r.best_ns_after_first = after.front();
    r.median_ns_after_first = after[after.size() / 2];
  }
}

// The plate's material in the 2D and 3D benchmarks (001's plate: neo-Hookean, E = 1e7 Pa,
// nu = 0.3, rho0 = 1000 kg/m^3), and its P-wave speed sqrt((lambda + 2 mu) / rho0) [m/s] for
// the stable step dt = 0.1 h / c on the unit square or cube.
constexpr double kBenchE = 1e7, kBenchNu = 0.3, kBenchRho = 1000.0;
const double kBenchWaveSpeed =
    std::sqrt((kBenchE * kBenchNu / ((1.0 + kBenchNu) * (1.0 - 2.0 * kBenchNu)) +
               kBenchE / (1.0 + kBenchNu)) /
              kBenchRho);
std::string bench_material_toml() {
  return fmt::format(
      "[material]\nmodel = \"neo_hookean\"\ndensity = {}\nyoungs_modulus = {}\n"
      "poisson_ratio = {}\n",
      kBenchRho, kBenchE, kBenchNu);
}

}  // namespace

BenchResult bench_1d(const BenchOptions& opt) {
  BenchResult r;
  const int per_cell = opt.per_cell > 0 ? opt.per_cell : 4;
  r.cells = std::max<Index>(1, opt.particles / per_cell);
  r.particles = r.cells * per_cell;
  r.steps = opt.steps;
  // A stable step: dt = 0.1 h / c with c = sqrt(7e6 / 2000) m/s.
  const double h = 1.0 / static_cast<double>(r.cells);
  const double dt = 0.1 * h / std::sqrt(7e6 / 2000.0);
  const std::string toml = fmt::format(
      "benchmark = \"vibrating_bar\"\n"
      "[grid]\ncells = {}\n[particles]\nper_cell = {}\n"
      "[time]\ndt = {:.17g}\nend = {:.17g}\n{}"
      "[material]\ndensity = 2000.0\nyoungs_modulus = 7e6\n[bar]\nv0 = 0.28\n",
      r.cells, per_cell, dt, dt * static_cast<double>(opt.steps), method_toml(opt));
  time_runs(Config::parse(toml, "<bench>"), opt, r);
  r.bytes_per_particle = bytes_per_particle<1>(opt, r.cells, r.particles);
  r.sort_bytes_per_particle = sort_bytes_per_particle<1>(r.cells, r.particles);
  return r;
}

BenchResult bench_2d(const BenchOptions& opt) {
  BenchResult r;
  const int per_cell = opt.per_cell > 0 ? opt.per_cell : 3;  // per direction
  r.cells = std::max<Index>(1, std::llround(std::sqrt(static_cast<double>(opt.particles)) /
                                            static_cast<double>(per_cell)));
  r.particles = r.cells * r.cells * per_cell * per_cell;
  r.steps = opt.steps;
  const std::string material = bench_material_toml();
  std::string toml;
  if (opt.problem == "refkernel") {
    // refkernel.cpp: n x n cells on the unit square plus two padding cells per side, so every
    // particle's span is interior; no body force (the custom problem fills its constant zero
    // once at set-up), no fixed side.
    const double h = 1.0 / static_cast<double>(r.cells), dt = 1e-6;
    toml = fmt::format(
        "benchmark = \"custom\"\n"
        "[grid]\ndimension = 2\ncells = {}\nmin = [{:.17g}, {:.17g}]\nmax = [{:.17g}, {:.17g}]\n"
        "[body]\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n[particles]\nper_cell = {}\n"
        "[initial]\nvelocity = [\"0.1*sin(2*pi*x)\", \"-0.1*sin(2*pi*y)\"]\n"
        "[boundary]\nleft = \"free\"\nright = \"free\"\nbottom = \"free\"\ntop = \"free\"\n"
        "[time]\ndt = {:.17g}\nend = {:.17g}\n{}{}",
        r.cells + 4, -2.0 * h, -2.0 * h, 1.0 + 2.0 * h, 1.0 + 2.0 * h, per_cell, dt,
        dt * static_cast<double>(opt.steps), method_toml(opt), material);
  } else {
    // A stable step: dt = 0.1 h / c with the P-wave speed c = sqrt((lambda + 2 mu) / rho).
    const double dt = 0.1 / static_cast<double>(r.cells) / kBenchWaveSpeed;
    toml = fmt::format(
        "benchmark = \"plate_mms_2d\"\n"
        "[grid]\ncells = {}\n[particles]\nper_cell = {}\n"
        "[time]\ndt = {:.17g}\nend = {:.17g}\n{}{}[mms]\namplitude = 1e-3\n",
        r.cells, per_cell, dt, dt * static_cast<double>(opt.steps), method_toml(opt), material);
  }
  time_runs(Config::parse(toml, "<bench>"), opt, r);
  const Index grid_cells = opt.problem == "refkernel" ? r.cells + 4 : r.cells;
  r.bytes_per_particle = bytes_per_particle<2>(opt, grid_cells, r.particles);
  r.sort_bytes_per_particle = sort_bytes_per_particle<2>(grid_cells * grid_cells, r.particles);
  return r;
}

BenchResult bench_3d(const BenchOptions& opt) {
  BenchResult r;
  const int per_cell = opt.per_cell > 0 ? opt.per_cell : 2;  // per direction
  r.cells = std::max<Index>(1, std::llround(std::cbrt(static_cast<double>(opt.particles)) /
                                            static_cast<double>(per_cell)));
  const Index per = static_cast<Index>(per_cell);
  r.particles = r.cells * r.cells * r.cells * per * per * per;
  r.steps = opt.steps;
  const std::string material = bench_material_toml();
  std::string toml;
  if (opt.problem == "refkernel") {
    // The 2D refkernel problem in 3D (the yardstick scripts/refkernel3d.cpp): n^3 cells on the
    // unit cube plus two padding cells per side, so every particle's span is interior; no body
    // force (the custom problem fills its constant zero once at set-up), no fixed side.
    const double h = 1.0 / static_cast<double>(r.cells), dt = 1e-6;
    toml = fmt::format(
        "benchmark = \"custom\"\n"
        "[grid]\ndimension = 3\ncells = {}\ncells_y = {}\ncells_z = {}\n"
        "min = [{:.17g}, {:.17g}, {:.17g}]\nmax = [{:.17g}, {:.17g}, {:.17g}]\n"
        "[body]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n[particles]\nper_cell = {}\n"
        "[initial]\nvelocity = [\"0.1*sin(2*pi*x)\", \"-0.1*sin(2*pi*y)\", "
        "\"0.1*sin(2*pi*z)\"]\n"
        "[boundary]\nleft = \"free\"\nright = \"free\"\nbottom = \"free\"\ntop = \"free\"\n"
        "back = \"free\"\nfront = \"free\"\n"
        "[time]\ndt = {:.17g}\nend = {:.17g}\n{}{}",
        r.cells + 4, r.cells + 4, r.cells + 4, -2.0 * h, -2.0 * h, -2.0 * h, 1.0 + 2.0 * h,
        1.0 + 2.0 * h, 1.0 + 2.0 * h, per_cell, dt, dt * static_cast<double>(opt.steps),
        method_toml(opt), material);
  } else {
    // The cube of cube_mms_3d, the plate's material, amplitude 1e-3 m (no grid crossing to
    // speak of), its body force every step; dt = 0.1 h / c with the P-wave speed.
    const double dt = 0.1 / static_cast<double>(r.cells) / kBenchWaveSpeed;
    toml = fmt::format(
        "benchmark = \"cube_mms_3d\"\n"
        "[grid]\ncells = {}\n[particles]\nper_cell = {}\n"
        "[time]\ndt = {:.17g}\nend = {:.17g}\n{}{}[mms]\namplitude = 1e-3\n",
        r.cells, per_cell, dt, dt * static_cast<double>(opt.steps), method_toml(opt), material);
  }
  time_runs(Config::parse(toml, "<bench>"), opt, r);
  const Index grid_cells = opt.problem == "refkernel" ? r.cells + 4 : r.cells;
  r.bytes_per_particle = bytes_per_particle<3>(opt, grid_cells, r.particles);
  r.sort_bytes_per_particle =
      sort_bytes_per_particle<3>(grid_cells * grid_cells * grid_cells, r.particles);
  return r;
}

MessageBench bench_messages(const Comm& comm, int repeats) {
  const int n = comm.size();
  if (n < 2 || n % 2 != 0)
    throw InputError(fmt::format(
        "mpm bench --messages times the exchange between pairs of processes: start it under "
        "mpirun with an even number of processes, 2 or more (this run has {})",
        n));
  MessageBench out;
  out.processes = n;
  const std::vector<int> peers{comm.rank() ^ 1};
  for (std::size_t bytes = 8; bytes <= (std::size_t{2} << 20); bytes *= 8) {
    // About 100 MB a repeat (20 ms at 5 GB/s), 20 to 2,000 exchanges.
    const int count =
        static_cast<int>(std::clamp<std::size_t>((std::size_t{100} << 20) / bytes, 20, 2000));
    std::vector<std::vector<std::byte>> send{std::vector<std::byte>(bytes, std::byte{1})};
    comm.exchange(peers, send, 7);  // warm-up: the connection and its buffers
    std::vector<double> t;
    for (int k = 0; k < repeats; ++k) {
      comm.check();  // every pair starts together
      const auto start = std::chrono::steady_clock::now();
      for (int i = 0; i < count; ++i) {
        const auto recv = comm.exchange(peers, send, 7);
        if (recv.size() != 1 || recv[0].size() != bytes)
          throw RunError(exit_code::kInternal, "mpm bench --messages: a message lost bytes");
      }
      const std::chrono::duration<double> wall = std::chrono::steady_clock::now() - start;
      t.push_back(comm.max(wall.count() / count));
    }
    std::sort(t.begin(), t.end());
    out.sizes.push_back({bytes, t.front(), t[t.size() / 2]});
  }
  const auto& a = out.sizes[out.sizes.size() - 2];
  const auto& b = out.sizes.back();
  out.alpha_seconds = out.sizes.front().best_seconds;
  out.beta_bytes_per_second =
      static_cast<double>(b.bytes - a.bytes) / std::max(b.median_seconds - a.median_seconds, 1e-12);
  return out;
}

}  // namespace mpm
