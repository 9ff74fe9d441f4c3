#include <fmt/format.h>
#include <algorithm>
#include <cmath>

#include "benchmarks/benchmarks.hpp"
#include "setup/config.hpp"
#include "setup/material_settings.hpp"

namespace mpm {

double ColumnExact::body_force(double t) const {
  return body_force_max * std::min(t / ramp_time, 1.0);
}

ExactState<1> ColumnExact::operator()(const Vec<1>& X, double t) const {
  const double b = body_force(t);
  const double k = density * b / youngs_modulus;   // [1/m]
  const double s = density * b * (height - X[0]);  // sigma(X) [Pa]
  ExactState<1> e;
  e.stress(0, 0) = s;
  // u(X) = int_0^X (1 / (1 - k (H - X')) - 1) dX'; the series form avoids 0/0 when k -> 0.
  if (std::abs(k * height) < 1e-12)
    e.u[0] = 0.5 * k * (2.0 * height * X[0] - X[0] * X[0]);
  else
    e.u[0] = std::log1p(k * X[0] / (1.0 - k * height)) / k - X[0];  // log1p: no cancellation
  e.v[0] = 0.0;                                                     // quasi-static
  return e;
}

Problem<1> make_column_compaction(const Config& cfg, const SeedScope& scope) {
  Problem<1> pb;
  pb.benchmark = "column_compaction";
  pb.materials = material_from_config(cfg, 1);
  if (!std::holds_alternative<Elastic1DLarge>(pb.materials.single()))
    throw InputError(
        fmt::format("{}: the column-compaction exact solution is that of material.model = "
                    "\"elastic_1d_large\" (D 5.4.2), not \"{}\"",
                    cfg.where("material.model"), material_name(pb.materials.single())));
  ColumnExact ex{cfg.get_real("column.height"), cfg.get_real("material.density"),
                 cfg.get_real("material.youngs_modulus"), cfg.get_real("column.body_force"),
                 cfg.get_real("column.ramp_time")};
  const auto cells = static_cast<Index>(cfg.get_int("grid.cells"));
  const double h = ex.height / static_cast<double>(cells);
  pb.grid = Grid<1>(Vec<1>(0.0), Vec<1>(ex.height + h), IVec<1>{cells + 1});
  pb.particles =
      seed_particles<1>(pb.grid, Vec<1>(0.0), Vec<1>(ex.height),
                        static_cast<int>(cfg.get_int("particles.per_cell")), ex.density, scope);
  pb.body_min = Vec<1>(0.0);
  pb.body_max = Vec<1>(ex.height);
  pb.initial_velocity = [](const Vec<1>&) { return Vec<1>(0.0); };
  pb.fixed_sides = {{0, 0}};
  pb.body_force.time_dependent = true;
  pb.body_force.fill = [ex](const Particles<1>&, double t, std::vector<Vec<1>>& b) {
    const double value = ex.body_force(t);
    for (auto& bi : b) bi[0] = value;
  };
  pb.exact = ex;
  return pb;
}

}  // namespace mpm
