#include <fmt/format.h>
#include <cmath>
#include <numbers>

#include "benchmarks/benchmarks.hpp"
#include "setup/config.hpp"
#include "setup/material_settings.hpp"

namespace mpm {

const NeoHookean& require_neo_hookean(const Config& cfg, const Material& m,
                                      std::string_view benchmark, std::string_view source) {
  if (const auto* law = std::get_if<NeoHookean>(&m)) return *law;
  throw InputError(fmt::format(
      "{}: the manufactured body force of benchmark \"{}\" is derived for material.model = "
      "\"neo_hookean\" ({}), not \"{}\"",
      cfg.where("material.model"), benchmark, source, material_name(m)));
}

void fill_fixed_bar(Problem<1>& pb, const Config& cfg, double L, double rho, const SeedScope& scope,
                    std::function<Vec<1>(const Vec<1>&)> velocity) {
  const auto cells = static_cast<Index>(cfg.get_int("grid.cells"));
  pb.grid = Grid<1>(Vec<1>(0.0), Vec<1>(L), IVec<1>{cells});
  pb.particles = seed_particles<1>(pb.grid, Vec<1>(0.0), Vec<1>(L),
                                   static_cast<int>(cfg.get_int("particles.per_cell")), rho, scope);
  pb.body_min = Vec<1>(0.0);
  pb.body_max = Vec<1>(L);
  pb.initial_velocity = std::move(velocity);
  for (std::size_t i = 0; i < pb.particles.x.size(); ++i)
    pb.particles.v[i] = pb.initial_velocity(pb.particles.x0[i]);
  pb.fixed_sides = {{0, 0}, {0, 1}};
}

ExactState<1> VibratingBarExact::operator()(const Vec<1>& X, double t) const {
  using std::numbers::pi;
  const double omega = pi * wave_speed / length;
  const double k = pi / length;
  ExactState<1> s;
  s.u[0] = v0 / omega * std::sin(omega * t) * std::sin(k * X[0]);
  s.v[0] = v0 * std::cos(omega * t) * std::sin(k * X[0]);
  s.stress(0, 0) = v0 * density * wave_speed * std::sin(omega * t) * std::cos(k * X[0]);
  return s;
}

Problem<1> make_vibrating_bar(const Config& cfg, bool large, const SeedScope& scope) {
  Problem<1> pb;
  pb.benchmark = large ? "vibrating_bar_large" : "vibrating_bar";
  const double L = cfg.get_real("bar.length");
  const double v0 = cfg.get_real("bar.v0");
  const double rho = cfg.get_real("material.density");
  pb.materials = material_from_config(cfg, 1);
  const std::string model{material_name(pb.materials.single())};
  if (!large && model != "elastic_1d_small" && model != "linear_elastic")
    throw InputError(fmt::format(
        "{}: benchmark \"vibrating_bar\" compares with the small-deformation exact solution, "
        "which holds for material.model = \"elastic_1d_small\" or \"linear_elastic\", not \"{}\"; "
        "use benchmark = \"vibrating_bar_large\" for large deformation",
        cfg.where("material.model"), model));
  fill_fixed_bar(pb, cfg, L, rho, scope, [v0, L](const Vec<1>& X) {
    return Vec<1>(v0 * std::sin(std::numbers::pi * X[0] / L));
  });
  if (!large)
    pb.exact = VibratingBarExact{L, v0, rho, wave_speed(pb.materials.single())};
  else
    pb.fem_reference = true;
  return pb;
}

}  // namespace mpm
