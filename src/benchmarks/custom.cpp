#include <fmt/format.h>

#include "benchmarks/benchmarks.hpp"
#include "io/config.hpp"
#include "io/expression.hpp"

namespace mpm {

Problem<1> make_custom_1d(const Config& cfg) {
  Problem<1> pb;
  pb.benchmark = "custom";
  const double g0 = cfg.get_real("grid.min"), g1 = cfg.get_real("grid.max");
  const double b0 = cfg.get_real("body.min"), b1 = cfg.get_real("body.max");
  if (!(g1 > g0))
    throw InputError(
        fmt::format("{}: grid.max = {} must exceed grid.min = {}", cfg.where("grid.max"), g1, g0));
  if (!(b1 > b0))
    throw InputError(
        fmt::format("{}: body.max = {} must exceed body.min = {}", cfg.where("body.max"), b1, b0));
  if (b0 < g0 || b1 > g1)
    throw InputError(
        fmt::format("{}: the body [{}, {}] must lie inside the grid [{}, {}] (grid.min, grid.max)",
                    cfg.where(b0 < g0 ? "body.min" : "body.max"), b0, b1, g0, g1));
  pb.material = material_from_config(cfg, 1);
  const double rho = cfg.get_real("material.density");
  const auto cells = static_cast<Index>(cfg.get_int("grid.cells"));
  pb.grid = Grid<1>(Vec<1>(g0), Vec<1>(g1), IVec<1>{cells});
  pb.particles = seed_particles<1>(pb.grid, Vec<1>(b0), Vec<1>(b1),
                                   static_cast<int>(cfg.get_int("particles.per_cell")), rho);

  const auto& constants = cfg.constants();
  const Expression v0(cfg.get_string("initial.velocity"), constants);
  const Expression s0(cfg.get_string("initial.stress"), constants);
  pb.body_min = Vec<1>(b0);
  pb.body_max = Vec<1>(b1);
  pb.initial_velocity = [v0](const Vec<1>& X) { return Vec<1>(v0(X[0])); };
  pb.initial_stress = [s0](const Vec<1>& X) {
    Mat<1> m;
    m(0, 0) = s0(X[0]);
    return m;
  };
  const bool incremental_law = std::holds_alternative<Elastic1DSmall>(pb.material) ||
                               std::holds_alternative<Elastic1DLarge>(pb.material);
  auto& P = pb.particles;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    P.v[i][0] = v0(P.x0[i][0]);
    P.stress[i](0, 0) = s0(P.x0[i][0]);
    if (P.stress[i](0, 0) != 0.0 && !incremental_law)
      throw InputError(
          fmt::format("{}: an initial stress needs an incremental law (elastic_1d_small or "
                      "elastic_1d_large); material.model = \"{}\" computes the stress from F = I",
                      cfg.where("initial.stress"), material_name(pb.material)));
  }

  const Expression b(cfg.get_string("loading.body_force"), constants);
  pb.body_force.time_dependent = b.uses_time();
  pb.body_force.position_dependent = b.uses_position();
  pb.body_force.fill = [b](const Particles<1>& P, double t, std::vector<Vec<1>>& out) {
    if (!b.uses_position()) {
      const double value = b(0.0, 0.0, 0.0, t);
      for (auto& o : out) o[0] = value;
      return;
    }
    for (std::size_t i = 0; i < P.x.size(); ++i) out[i][0] = b(P.x[i][0], 0.0, 0.0, t);
  };

  if (cfg.get_string("boundary.left") == "fixed") pb.fixed_sides.push_back({0, 0});
  if (cfg.get_string("boundary.right") == "fixed") pb.fixed_sides.push_back({0, 1});
  return pb;
}

}  // namespace mpm
