#include <fmt/format.h>
#include <cmath>
#include <numbers>

#include "benchmarks/benchmarks.hpp"
#include "setup/config.hpp"
#include "setup/material_settings.hpp"

namespace mpm {

ExactState<1> TractionBarExact::operator()(const Vec<1>& X, double t) const {
  const double L = length, c = wave_speed, A = amplitude, x = X[0];
  const double w = std::numbers::pi / L;  // omega [1/m]
  const double ct = c * t;
  const double scale = A / (density * c * c * w);  // displacement amplitude [m]
  ExactState<1> e;
  e.stress(0, 0) = 0.0;
  e.v[0] = 0.0;
  e.u[0] = 0.0;
  // Left-going wave from the loaded end, active for ct in [L - x, 3L - x) (eq. 4.93 terms 2-3):
  // sigma = A sin(w (ct + x)), v = sigma / (rho c).
  if (ct >= L - x) {
    const double te = std::min(ct, 3.0 * L - x);
    if (ct < 3.0 * L - x) {
      e.stress(0, 0) += A * std::sin(w * (ct + x));
      e.v[0] += A * std::sin(w * (ct + x)) / (density * c);
    }
    e.u[0] += scale * (-std::cos(w * (te + x)) - 1.0);
  }
  // Its reflection from the fixed end, right-going, active for ct in [L + x, 3L + x):
  // sigma = A sin(w (ct - x)), v = -sigma / (rho c).
  if (ct >= L + x) {
    const double te = std::min(ct, 3.0 * L + x);
    if (ct < 3.0 * L + x) {
      e.stress(0, 0) += A * std::sin(w * (ct - x));
      e.v[0] -= A * std::sin(w * (ct - x)) / (density * c);
    }
    e.u[0] += scale * (std::cos(w * (te - x)) + 1.0);
  }
  return e;
}

Problem<1> make_traction_bar(const Config& cfg, const SeedScope& scope) {
  Problem<1> pb;
  pb.benchmark = "traction_bar";
  pb.materials = material_from_config(cfg, 1);
  const double L = cfg.get_real("bar.length");
  const double g0 = cfg.get_real("grid.min"), g1 = cfg.get_real("grid.max");
  if (g0 != 0.0 || !(g1 > L))
    throw InputError(fmt::format(
        "{}: the traction bar occupies [0, bar.length = {}] and needs a grid [0, grid.max] "
        "longer than the bar (D 4.6.2: 1.25 m for a 1 m bar); got [{}, {}]",
        cfg.where(g0 != 0.0 ? "grid.min" : "grid.max"), L, g0, g1));
  const double rho = cfg.get_real("material.density");
  const auto cells = static_cast<Index>(cfg.get_int("grid.cells"));
  pb.grid = Grid<1>(Vec<1>(g0), Vec<1>(g1), IVec<1>{cells});
  const auto per_cell = static_cast<int>(cfg.get_int("particles.per_cell"));
  pb.particles = seed_particles<1>(pb.grid, Vec<1>(0.0), Vec<1>(L), per_cell, rho, scope);
  pb.body_min = Vec<1>(0.0);
  pb.body_max = Vec<1>(L);
  pb.initial_velocity = [](const Vec<1>&) { return Vec<1>(0.0); };
  pb.fixed_sides = {{0, 0}};
  const TractionBarExact ex{L, rho, wave_speed(pb.materials.single()),
                            cfg.get_real("traction.amplitude")};
  // The end particle's outer edge x_p + V_p / 2 at X = L (Traction, D 4.6.2).
  const auto tr =
      body_face_traction<1>(pb.grid, Vec<1>(0.0), Vec<1>(L), per_cell, 0, +1, [ex](double t) {
        return Vec<1>(-ex.amplitude * std::sin(std::numbers::pi * ex.wave_speed * t / ex.length));
      });
  pb.tractions.push_back(tr);
  pb.exact = ex;
  return pb;
}

}  // namespace mpm
