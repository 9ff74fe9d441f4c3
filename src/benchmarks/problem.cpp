#include "benchmarks/problem.hpp"

#include <fmt/format.h>
#include <cmath>

#include "benchmarks/benchmarks.hpp"
#include "io/config.hpp"

namespace mpm {

template <int Dim>
Particles<Dim> seed_particles(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi,
                              int per_cell, double rho0) {
  IVec<Dim> n{};
  Index total = 1;
  for (int d = 0; d < Dim; ++d) {
    n[d] = std::max<Index>(1, std::llround((hi[d] - lo[d]) / g.h[d] * per_cell));
    total *= n[d];
  }
  Particles<Dim> P;
  P.resize(total);
  const double vol = (hi - lo).prod() / static_cast<double>(total);
  for (Index p = 0; p < total; ++p) {
    Index rem = p;
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) {
      const Index k = rem % n[d];
      rem /= n[d];
      x[d] = lo[d] + (hi[d] - lo[d]) * (static_cast<double>(k) + 0.5) / static_cast<double>(n[d]);
    }
    const auto i = static_cast<std::size_t>(p);
    P.x[i] = P.x0[i] = x;
    P.volume[i] = P.volume0[i] = vol;
    P.density[i] = rho0;
    P.mass[i] = rho0 * vol;
  }
  return P;
}

template Particles<1> seed_particles<1>(const Grid<1>&, const Vec<1>&, const Vec<1>&, int, double);
template Particles<2> seed_particles<2>(const Grid<2>&, const Vec<2>&, const Vec<2>&, int, double);
template Particles<3> seed_particles<3>(const Grid<3>&, const Vec<3>&, const Vec<3>&, int, double);

AnyProblem make_problem(const Config& cfg) {
  const std::string name = cfg.get_string("benchmark");
  if (name == "vibrating_bar") return make_vibrating_bar(cfg, /*large=*/false);
  if (name == "vibrating_bar_large") return make_vibrating_bar(cfg, /*large=*/true);
  if (name == "column_compaction") return make_column_compaction(cfg);
  if (name == "traction_bar") return make_traction_bar(cfg);
  if (name == "mms_1d") return make_mms_1d(cfg);
  if (name == "custom") return make_custom_1d(cfg);
  if (name == "plate_mms_2d") return make_plate_mms_2d(cfg);
  throw InputError(
      fmt::format("{}: benchmark \"{}\" is not implemented", cfg.where("benchmark"), name));
}

}  // namespace mpm
