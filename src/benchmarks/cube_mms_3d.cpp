#include <cmath>
#include <numbers>

#include "benchmarks/benchmarks.hpp"
#include "setup/config.hpp"
#include "setup/material_settings.hpp"

namespace mpm {

Mat<3> CubeMms3DExact::deformation_gradient(const Vec<3>& X, double t) const {
  const double k = 2.0 * std::numbers::pi / length, s = std::sin(omega() * t);
  Mat<3> F = Mat<3>::Identity();
  for (int d = 0; d < 3; ++d) F(d, d) += amplitude * k * std::cos(k * X[d]) * s;
  return F;
}

Mat<3> CubeMms3DExact::cauchy_stress(const Mat<3>& F) const {
  // D eq. 2.14, the law of the run (materials.hpp, NeoHookean).
  const double J = F.determinant();
  return (lambda * std::log(J) / J) * Mat<3>::Identity() +
         (mu / J) * (F * F.transpose() - Mat<3>::Identity());
}

Mat<3> CubeMms3DExact::piola_stress(const Mat<3>& F) const {
  // P = J sigma F^-T = lambda ln(J) F^-T + mu (F - F^-T).
  return F.determinant() * cauchy_stress(F) * F.inverse().transpose();
}

Vec<3> CubeMms3DExact::body_force(const Vec<3>& X, double t) const {
  // b = u_tt - (1/rho0) Div P (scripts/cube_mms.py derives it with sympy and checks this form).
  // F is diagonal with F_ii depending on X_i alone, so (Div P)_i = dP_ii/dF_ii dF_ii/dX_i with
  //   P_ii = lambda ln(J) / F_ii + mu (F_ii - 1/F_ii),  J = F_11 F_22 F_33,
  //   dP_ii/dF_ii = (lambda (1 - ln J) + mu) / F_ii^2 + mu,  dF_ii/dX_i = -k^2 u_i,
  // and u_tt = -omega^2 u: b_i = u_i (k^2 / rho0 dP_ii/dF_ii - omega^2), the plate's form
  // (001 eq. 42 with pi^2 u / L^2) in each direction.
  const double k = 2.0 * std::numbers::pi / length, w = omega(), s = std::sin(w * t);
  const Mat<3> F = deformation_gradient(X, t);
  const double lnJ = std::log(F(0, 0) * F(1, 1) * F(2, 2));
  Vec<3> b;
  for (int d = 0; d < 3; ++d) {
    const double u = amplitude * std::sin(k * X[d]) * s, f = F(d, d);
    const double dPdF = (lambda * (1.0 - lnJ) + mu) / (f * f) + mu;
    b[d] = u * (k * k * dPdF / density - w * w);
  }
  return b;
}

ExactState<3> CubeMms3DExact::operator()(const Vec<3>& X, double t) const {
  const double k = 2.0 * std::numbers::pi / length, w = omega();
  ExactState<3> e;
  for (int d = 0; d < 3; ++d) {
    e.u[d] = amplitude * std::sin(k * X[d]) * std::sin(w * t);
    e.v[d] = amplitude * w * std::sin(k * X[d]) * std::cos(w * t);
  }
  e.stress = cauchy_stress(deformation_gradient(X, t));
  return e;
}

Problem<3> make_cube_mms_3d(const Config& cfg, const SeedScope& scope) {
  Problem<3> pb;
  pb.benchmark = "cube_mms_3d";
  pb.materials = material_from_config(cfg, 3);
  const auto* law =
      &require_neo_hookean(cfg, pb.materials.single(), pb.benchmark, "scripts/cube_mms.py");
  const double L = cfg.get_real("cube.length");
  const double rho = cfg.get_real("material.density");
  // c = sqrt(E / rho0), as the plate of 001 (not the P-wave speed).
  const CubeMms3DExact ex{L,
                          rho,
                          law->p.lambda(),
                          law->p.mu(),
                          std::sqrt(cfg.get_real("material.youngs_modulus") / rho),
                          cfg.get_real("mms.amplitude")};
  const auto n = static_cast<Index>(cfg.get_int("grid.cells"));
  pb.grid = Grid<3>(Vec<3>::Zero(), Vec<3>::Constant(L), IVec<3>{n, n, n});
  pb.particles = seed_particles<3>(pb.grid, Vec<3>::Zero(), Vec<3>::Constant(L),
                                   static_cast<int>(cfg.get_int("particles.per_cell")), rho, scope);
  pb.body_min = Vec<3>::Zero();
  pb.body_max = Vec<3>::Constant(L);
  // Rollers on the six faces: u_i = 0 on X_i = 0 and X_i = L; the tangential components follow
  // the manufactured solution.
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) pb.fixed_sides.push_back({d, side, 1u << d});
  use_manufactured_solution(pb, ex);
  return pb;
}

}  // namespace mpm
