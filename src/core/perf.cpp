#include "core/perf.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <vector>

#include "basis/linear.hpp"
#include "core/run.hpp"
#include "grid/grid_state.hpp"
#include "io/config.hpp"
#include "particles/particles.hpp"

namespace mpm {

BenchResult bench_1d(const BenchOptions& opt) {
  BenchResult r;
  r.cells = std::max<Index>(1, opt.particles / opt.per_cell);
  r.particles = r.cells * opt.per_cell;
  r.steps = opt.steps;
  // A stable step: dt = 0.1 h / c with c = sqrt(7e6 / 2000) m/s.
  const double h = 1.0 / static_cast<double>(r.cells);
  const double dt = 0.1 * h / std::sqrt(7e6 / 2000.0);
  const std::string toml = fmt::format(
      "benchmark = \"vibrating_bar\"\n"
      "[grid]\ncells = {}\n[particles]\nper_cell = {}\n"
      "[time]\ndt = {:.17g}\nend = {:.17g}\n"
      "[method]\nscheme = \"{}\"\nbasis = \"{}\"\ndegree = {}\nmapping = \"{}\"\n"
      "[material]\ndensity = 2000.0\nyoungs_modulus = 7e6\n[bar]\nv0 = 0.28\n",
      r.cells, opt.per_cell, dt, dt * static_cast<double>(opt.steps), opt.scheme, opt.basis,
      opt.degree, opt.mapping);
  const Config cfg = Config::parse(toml, "<bench>");
  std::vector<double> ns;
  for (int k = 0; k < opt.repeats; ++k) {
    RunOptions ro;
    ro.quiet = true;
    ns.push_back(run(cfg, ro).ns_per_particle_step);
  }
  std::sort(ns.begin(), ns.end());
  r.best_ns_per_particle_step = ns.front();
  r.median_ns_per_particle_step = ns[ns.size() / 2];
  const double dofs = static_cast<double>(r.cells + 1);
  const double grid_bytes = dofs * (sizeof(double) + 4 * sizeof(Vec<1>) + 2 * sizeof(std::uint8_t));
  r.bytes_per_particle = static_cast<double>(Particles<1>::bytes_per_particle() +
                                             sizeof(LinearBasis<1>::StencilT) + sizeof(Index)) +
                         grid_bytes / static_cast<double>(r.particles);
  return r;
}

}  // namespace mpm
