#include <fmt/format.h>
#include <cmath>
#include <numbers>

#include "benchmarks/benchmarks.hpp"
#include "setup/config.hpp"
#include "setup/material_settings.hpp"

namespace mpm {

namespace {
Mat<2> rotation(double a) {
  Mat<2> Q;
  Q << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return Q;
}
}  // namespace

Particles<2> seed_annulus(const Grid<2>& g, double inner, double outer, int per_cell, double rho0,
                          const SeedScope& scope) {
  // Rings at the mid radii of n_r equal radial layers, n_r = ceil((R_o - R_i) / s) with the
  // particle spacing s = h / per_cell; ring k cut into n_k = ceil(2 pi R_k / s) equal sectors,
  // one particle at the sector's mid angle and mid radius carrying the sector's area
  // R_k dR dTheta (exact for an annular sector), so the particles' volumes add up to the
  // annulus's area to round-off and their domains follow both circles.
  using std::numbers::pi;
  const double s = g.h.minCoeff() / per_cell;
  const auto n_r = static_cast<int>(std::ceil((outer - inner) / s - 1e-9));
  const double dR = (outer - inner) / n_r;
  const auto sectors = [&](int k) {
    return static_cast<int>(std::ceil(2.0 * pi * (inner + (k + 0.5) * dR) / s - 1e-9));
  };
  // Numbered ring after ring.
  SeedSink<2> sink(&g, rho0, scope);
  Index total = 0;
  for (int k = 0; k < n_r; ++k) total += sectors(k);
  sink.reserve(total);
  for (int k = 0; k < n_r; ++k) {
    const double R = inner + (k + 0.5) * dR;
    const int n = sectors(k);
    const double dTheta = 2.0 * pi / n;
    for (int j = 0; j < n; ++j) {
      const double th = (j + 0.5) * dTheta;
      sink.add(Vec<2>(R * std::cos(th), R * std::sin(th)), R * dR * dTheta);
    }
  }
  return sink.finish();
}

double Vortex2DExact::g(double t) const {
  return amplitude * std::sin(2.0 * std::numbers::pi * t / period);
}
double Vortex2DExact::g_t(double t) const {
  const double w = 2.0 * std::numbers::pi / period;
  return amplitude * w * std::cos(w * t);
}
double Vortex2DExact::g_tt(double t) const {
  const double w = 2.0 * std::numbers::pi / period;
  return -w * w * g(t);
}

// h = (1 - 4 xi^2)^2, xi = (R - R_m) / w, w = R_o - R_i: h(R_i) = h(R_o) = 0 and
// h'(R_i) = h'(R_o) = 0; zero outside the annulus.
std::array<double, 3> Vortex2DExact::h(double R) const {
  const double w = outer_radius - inner_radius;
  const double xi = (R - 0.5 * (inner_radius + outer_radius)) / w;
  if (4.0 * xi * xi >= 1.0) return {0.0, 0.0, 0.0};
  const double s = 1.0 - 4.0 * xi * xi;
  return {s * s, -16.0 * xi * s / w, -16.0 * (1.0 - 12.0 * xi * xi) / (w * w)};
}

Mat<2> Vortex2DExact::deformation_gradient(const Vec<2>& X, double t) const {
  // x = Q(alpha) X with alpha = alpha(R, t): F = Q (I + R alpha_R E_Theta (x) E_R), the rotation
  // of a simple shear of amount gamma = R alpha_R along the circles (J = 1).
  const double R = X.norm();
  const auto [h0, h1, h2] = h(R);
  const Vec<2> E_R = X / R, E_Theta(-E_R[1], E_R[0]);
  return rotation(g(t) * h0) * (Mat<2>::Identity() + R * g(t) * h1 * E_Theta * E_R.transpose());
}

Mat<2> Vortex2DExact::cauchy_stress(const Mat<2>& F) const {
  // The plane-strain neo-Hookean law of the library (D eq. 2.14); J = 1 here, so
  // sigma = mu (F F^T - I), kept general so that the test compares the same expression.
  const double J = F.determinant();
  return (lambda * std::log(J) / J) * Mat<2>::Identity() +
         (mu / J) * (F * F.transpose() - Mat<2>::Identity());
}

Vec<2> Vortex2DExact::body_force(const Vec<2>& X, double t) const {
  // b = x_tt - Div P / rho0 in the current polar frame (e_r, e_phi), phi = Theta + alpha
  // (derived with sympy in scripts/vortex_mms.py, which checks it against the Cartesian
  // x_tt - Div P / rho0; tests/benchmarks/test_vortex_2d.cpp checks it by finite differences):
  //   b_r = R (mu/rho0 alpha_R^2 - alpha_t^2),  b_phi = R alpha_tt - mu/rho0 (3 alpha_R + R
  //   alpha_RR).
  const double R = X.norm();
  const auto [h0, h1, h2] = h(R);
  const double gt = g(t), a_t = g_t(t) * h0, a_tt = g_tt(t) * h0;
  const double a_R = gt * h1, a_RR = gt * h2, m = mu / density;
  const double b_r = R * (m * a_R * a_R - a_t * a_t);
  const double b_phi = R * a_tt - m * (3.0 * a_R + R * a_RR);
  const Mat<2> Q = rotation(gt * h0);
  const Vec<2> e_r = Q * (X / R), e_phi(-e_r[1], e_r[0]);
  return b_r * e_r + b_phi * e_phi;
}

ExactState<2> Vortex2DExact::operator()(const Vec<2>& X, double t) const {
  const double R = X.norm();
  const double h0 = h(R)[0];
  const Mat<2> Q = rotation(g(t) * h0);
  ExactState<2> s;
  s.u = Q * X - X;
  // v = alpha_t R e_phi = alpha_t (Q X)^perp.
  const Vec<2> x = Q * X;
  s.v = g_t(t) * h0 * Vec<2>(-x[1], x[0]);
  s.stress = cauchy_stress(deformation_gradient(X, t));
  return s;
}

Problem<2> make_vortex_2d(const Config& cfg, const SeedScope& scope) {
  Problem<2> pb;
  pb.benchmark = "vortex_2d";
  pb.materials = material_from_config(cfg, 2);
  const auto* law =
      &require_neo_hookean(cfg, pb.materials.single(), pb.benchmark, "scripts/vortex_mms.py");
  const double rho = cfg.get_real("material.density");
  const Vortex2DExact ex{cfg.get_real("vortex.inner_radius"),
                         cfg.get_real("vortex.outer_radius"),
                         cfg.get_real("vortex.amplitude"),
                         cfg.get_real("vortex.period"),
                         rho,
                         law->p.lambda(),
                         law->p.mu()};
  if (ex.inner_radius >= ex.outer_radius)
    throw InputError(fmt::format(
        "{}: vortex.inner_radius = {} must be below vortex.outer_radius = {} (the annulus "
        "R_i <= R <= R_o)",
        cfg.where("vortex.inner_radius"), ex.inner_radius, ex.outer_radius));
  const double half = cfg.get_real("vortex.half_width");
  if (half < ex.outer_radius)
    throw InputError(fmt::format(
        "{}: vortex.half_width = {} must be at least vortex.outer_radius = {}: the grid "
        "[-half_width, half_width]^2 holds the annulus",
        cfg.where("vortex.half_width"), half, ex.outer_radius));
  const auto cells = static_cast<Index>(cfg.get_int("grid.cells"));
  const Index seeded_before = scope.seeded;
  pb.grid = Grid<2>(Vec<2>(-half, -half), Vec<2>(half, half), IVec<2>{cells, cells});
  if (cfg.get_string("vortex.seeding") == "polar") {
    if (cfg.get_int("particles.per_triangle") != 0)
      throw InputError(fmt::format(
          "{}: particles.per_triangle seeds grid triangles; vortex.seeding = \"polar\" lays "
          "rings of particles.per_cell per cell width (set vortex.seeding = \"cells\" to seed "
          "triangles)",
          cfg.where("particles.per_triangle")));
    pb.particles = seed_annulus(pb.grid, ex.inner_radius, ex.outer_radius,
                                static_cast<int>(cfg.get_int("particles.per_cell")), rho, scope);
  } else {
    // The grid's particles whose centre lies in the annulus, each with its cell's share of the
    // volume: a staircase along both circles.
    pb.particles = seed_body_2d(cfg, pb.grid, pb.grid.origin, pb.grid.upper(), rho, nullptr, scope,
                                [&](const Vec<2>& X) {
                                  const double R = X.norm();
                                  return R > ex.inner_radius && R < ex.outer_radius;
                                });
  }
  // (The body's particles, on every process of a distributed run alike, not those it keeps.)
  if (scope.seeded == seeded_before)
    throw InputError(
        fmt::format("{}: no particle of the {} x {} grid lies in the annulus {} < R < {}",
                    cfg.where("grid.cells"), cells, cells, ex.inner_radius, ex.outer_radius));
  pb.body_min = Vec<2>(-ex.outer_radius, -ex.outer_radius);
  pb.body_max = Vec<2>(ex.outer_radius, ex.outer_radius);
  // No condition: the traction vanishes on both circles (h = h' = 0 there), and the grid's
  // sides are away from the body.
  use_manufactured_solution(pb, ex);
  return pb;
}

}  // namespace mpm
