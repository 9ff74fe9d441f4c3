#include <fmt/format.h>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "benchmarks/benchmarks.hpp"
#include "setup/config.hpp"
#include "setup/material_settings.hpp"

namespace mpm {

Mat<2> PlateMms2DExact::deformation_gradient(const Vec<2>& X, double t) const {
  using std::numbers::pi;
  const double k = 2.0 * pi / length, s = std::sin(omega() * t);
  Mat<2> F = Mat<2>::Identity();
  F(0, 0) += amplitude * k * std::cos(k * X[0]) * s;
  F(1, 1) -= amplitude * k * std::cos(k * X[1]) * s;
  return F;
}

Mat<2> PlateMms2DExact::cauchy_stress(const Mat<2>& F) const {
  // 001 eq. 41 (D eq. 2.14), plane strain: F_zz = 1.
  const double J = F.determinant();
  return (lambda * std::log(J) / J) * Mat<2>::Identity() +
         (mu / J) * (F * F.transpose() - Mat<2>::Identity());
}

Mat<2> PlateMms2DExact::piola_stress(const Mat<2>& F) const {
  // 001 eq. 40: P = lambda ln(J) F^-1 + mu F^-1 (F F^T - I) = J sigma F^-T.
  const double J = F.determinant();
  return J * cauchy_stress(F) * F.inverse().transpose();
}

Vec<2> PlateMms2DExact::body_force(const Vec<2>& X, double t) const {
  using std::numbers::pi;
  // b = u_tt - (1/rho0) Div P. F is diagonal with F_xx = F_xx(X, t), F_yy = F_yy(Y, t), so
  // P_xy = 0 and Div P = (dP_xx/dF_xx dF_xx/dX, dP_yy/dF_yy dF_yy/dY) with
  //   P_xx = lambda ln(F_xx F_yy) / F_xx + mu (F_xx - 1/F_xx),
  //   dP_xx/dF_xx = (lambda (1 - ln J) + mu) / F_xx^2 + mu,   dF_xx/dX = -k^2 u_x,
  // and u_tt = -omega^2 u. Hence b_x = u_x [k^2/rho0 dP_xx/dF_xx - omega^2]
  //   = pi^2 u_x / L^2 [4 mu/rho0 - c^2 - 4 (lambda (ln J - 1) - mu) / (rho0 F_xx^2)],
  // which is 001 eq. 42 with its prefactor pi u / L^2 corrected to pi^2 u / L^2 (METHODS.md
  // errata), and the same for y. A test checks it against finite differences of u and P.
  const double k = 2.0 * pi / length, w = omega();
  // u alone (001 eq. 38, the same expressions as operator()): the full exact state would also
  // evaluate the stress, which this per-particle, per-step force does not need.
  const Vec<2> u(amplitude * std::sin(k * X[0]) * std::sin(w * t),
                 -amplitude * std::sin(k * X[1]) * std::sin(w * t));
  const Mat<2> F = deformation_gradient(X, t);
  const double lnJ = std::log(F.determinant());
  Vec<2> b;
  for (int d = 0; d < 2; ++d) {
    const double f = F(d, d);
    const double dPdF = (lambda * (1.0 - lnJ) + mu) / (f * f) + mu;
    b[d] = u[d] * (k * k * dPdF / density - w * w);
  }
  return b;
}

ExactState<2> PlateMms2DExact::operator()(const Vec<2>& X, double t) const {
  using std::numbers::pi;
  const double k = 2.0 * pi / length, w = omega();
  ExactState<2> s;
  // 001 eq. 38-39 (written for L = 1; du/dt carries c pi / L).
  s.u = Vec<2>(amplitude * std::sin(k * X[0]) * std::sin(w * t),
               -amplitude * std::sin(k * X[1]) * std::sin(w * t));
  s.v = Vec<2>(amplitude * w * std::sin(k * X[0]) * std::cos(w * t),
               -amplitude * w * std::sin(k * X[1]) * std::cos(w * t));
  s.stress = cauchy_stress(deformation_gradient(X, t));
  return s;
}

Problem<2> make_plate_mms_2d(const Config& cfg, const SeedScope& scope) {
  Problem<2> pb;
  pb.benchmark = "plate_mms_2d";
  pb.materials = material_from_config(cfg, 2);
  const auto* law = &require_neo_hookean(cfg, pb.materials.single(), pb.benchmark, "001 eq. 40-42");
  const double L = cfg.get_real("plate.length");
  const double rho = cfg.get_real("material.density");
  // 001: c = sqrt(E / rho0) (its "sqrt(E)/gamma", METHODS.md errata), not the P-wave speed.
  const PlateMms2DExact ex{L,
                           rho,
                           law->p.lambda(),
                           law->p.mu(),
                           std::sqrt(cfg.get_real("material.youngs_modulus") / rho),
                           cfg.get_real("mms.amplitude")};
  const auto cells = static_cast<Index>(cfg.get_int("grid.cells"));
  pb.grid = Grid<2>(Vec<2>::Zero(), Vec<2>(L, L), IVec<2>{cells, cells});
  // D Fig. 3.6, 3.9: the plate on an unstructured triangulation of the square (grid.mesh).
  pb.mesh = mesh_from_config(cfg);
  if (pb.mesh) check_mesh_box(cfg, *pb.mesh, pb.grid);
  pb.particles =
      seed_body_2d(cfg, pb.grid, Vec<2>::Zero(), Vec<2>(L, L), rho, pb.mesh.get(), scope);
  pb.body_min = Vec<2>::Zero();
  pb.body_max = Vec<2>(L, L);
  // "Fixed at the entire boundary" fixes the normal component only (rollers): u_x = 0 on X = 0
  // and X = L, u_y = 0 on Y = 0 and Y = L. The tangential components follow the manufactured
  // solution (u_y(0, Y, t) != 0), so fixing both would contradict it.
  pb.fixed_sides = {{0, 0, 1u}, {0, 1, 1u}, {1, 0, 2u}, {1, 1, 2u}};
  use_manufactured_solution(pb, ex);
  // The exact solution is itself unstable at large amplitude: a finite-element linearisation
  // about it (scripts/plate_fem_check.py --floquet) finds perturbations that grow 16-60x a period
  // at nu = 0.3 and A = 0.1 L (001's set-up), and a FEM from the exact initial state stops as the
  // material point runs do (docs/verification.md, "The exact solution at A = 0.1 m is
  // unstable"). A run that stays within one period of the solution (2 L / c) only warns: the
  // perturbations then grow by one Floquet multiplier at most, and the errors are still the
  // method's (the FEM at A = 0.1 L converges at second order to T = 0.02 s, ibid.). A longer one
  // is refused unless mms.allow_unstable (001's set-up, ten periods, is worth reproducing, but its
  // errors after a few periods are that growth). The bound depends on Poisson's ratio; below,
  // the largest amplitude (steps of 0.01 L) at which the linearisation (16 elements, 8 periods)
  // grew less than 1.05x a period (runs at A = 0 and small amplitudes scatter within 0.98-1.03),
  // the next one more. It falls as nu rises, so a ratio between two measured ones takes the
  // bound of the larger.
  struct StableAmplitude {
    double nu, amplitude;  // Poisson's ratio, largest stable amplitude / L
  };
  static constexpr std::array<StableAmplitude, 5> kStable{
      {{0.1, 0.10}, {0.2, 0.09}, {0.3, 0.08}, {0.4, 0.05}, {0.45, 0.03}}};
  const double nu = law->p.poisson_ratio;
  const auto* bound = &kStable.back();
  for (const auto& b : kStable)
    if (b.nu >= nu - 1e-12) {
      bound = &b;
      break;
    }
  if (std::abs(ex.amplitude) > bound->amplitude * L) {
    const std::string at = cfg.where("mms.amplitude");
    std::string unmeasured;  // how the run's ratio relates to the measured ones
    if (nu > bound->nu + 1e-12)
      unmeasured = fmt::format(
          " (material.poisson_ratio = {:g} is above the largest ratio measured: the bound may "
          "be too high)",
          nu);
    else if (nu < bound->nu - 1e-12)
      unmeasured = fmt::format(
          " (material.poisson_ratio = {:g} was not measured: the bound is that of the nearest "
          "larger ratio measured)",
          nu);
    const std::string what = fmt::format(
        "{}mms.amplitude = {:g} m{} is above {:g} plate.length, the largest amplitude at which the "
        "perturbations of this manufactured solution were found not to grow at nu = {:g}{}",
        at == "default" ? "" : at + ": ", ex.amplitude, at == "default" ? " (the default)" : "",
        bound->amplitude, bound->nu, unmeasured);
    constexpr const char* kSection =
        "docs/verification.md, \"The exact solution at A = 0.1 m is unstable\"";
    const double period = 2.0 * std::numbers::pi / ex.omega();  // 2 L / c
    const double end = cfg.get_real("time.end");
    if (end > period * (1.0 + 1e-9) && !cfg.get_bool("mms.allow_unstable"))
      throw InputError(fmt::format(
          "{}, and {}time.end = {:g} s spans {:.3g} of its periods (2 plate.length / c = {:g} s): "
          "its perturbations grow with every period (16-60x a period at nu = 0.3 and "
          "0.1 plate.length), so after a few periods the errors measure that growth, not the "
          "method, and fine grids stop with a non-finite stress ({}). Choose mms.amplitude <= "
          "{:g} m, or time.end <= {:g} s (one period), or set mms.allow_unstable = true to run "
          "it anyway",
          what, cfg.where("time.end") + ": ", end, end / period, period, kSection,
          bound->amplitude * L, period));
    pb.warnings.push_back(fmt::format(
        "{}: after a few periods its errors measure that growth, not the method, and fine grids "
        "may stop with a non-finite stress (at nu = 0.3 and 0.1 plate.length they grow 16-60x a "
        "period; {})",
        what, kSection));
  }
  return pb;
}

}  // namespace mpm
