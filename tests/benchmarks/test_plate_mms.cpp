// The 2D axis-aligned vibration (001 eq. 38-42, D 3.4.1) checked against its definition by
// central finite differences: v = du/dt, F = I + Grad u, the stress is the library's plane-strain
// neo-Hookean law at that F, and the body force is the residual u_tt - Div P / rho0.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "../support/mms.hpp"
#include "benchmarks/benchmarks.hpp"
#include "material/materials.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

ElasticParameters params() {
  return test::plate_material();
}

PlateMms2DExact make_exact(double A = 0.1) {
  const auto p = params();
  return {1.0, p.density, p.lambda(), p.mu(), std::sqrt(p.youngs_modulus / p.density), A};
}

using test::fd_deformation_gradient;

Mat<2> law_piola(const Mat<2>& F) {
  return test::neo_hookean_piola(params(), F);
}

TEST(PlateMms2DExact, VelocityDeformationAndStressFromTheDisplacement) {
  const auto ex = make_exact();
  const double ht = 1e-7;
  for (double t : {0.0013, 0.0047, 0.011, 0.019})
    for (const Vec<2>& X : {Vec<2>(0.1, 0.2), Vec<2>(0.37, 0.81), Vec<2>(0.66, 0.45)}) {
      const auto s = ex(X, t);
      const Vec<2> v = (ex(X, t + ht).u - ex(X, t - ht).u) / (2.0 * ht);
      EXPECT_LT((s.v - v).norm(), 1e-6 * s.v.norm() + 1e-9);
      const Mat<2> F = fd_deformation_gradient(ex, X, t);
      EXPECT_LT((ex.deformation_gradient(X, t) - F).norm(), 1e-7);
      const NeoHookean law{params()};
      Mat<2> sigma = Mat<2>::Zero();
      law.update<2>(sigma, {}, ex.deformation_gradient(X, t), Mat<2>::Zero());
      EXPECT_LT((s.stress - sigma).norm(), 1e-9 * sigma.norm());
      // u_y carries sin(omega t + pi) (001 eq. 38).
      using std::numbers::pi;
      EXPECT_NEAR(s.u[1], 0.1 * std::sin(2 * pi * X[1]) * std::sin(ex.omega() * t + pi), 1e-15);
    }
}

TEST(PlateMms2DExact, BodyForceIsTheFiniteDifferenceResidual) {
  const auto ex = make_exact();
  const double hx = 1e-4, ht = 1e-6;
  for (double t : {0.0013, 0.0047, 0.011, 0.019})
    for (const Vec<2>& X :
         {Vec<2>(0.07, 0.13), Vec<2>(0.21, 0.64), Vec<2>(0.47, 0.33), Vec<2>(0.9, 0.71)}) {
      const Vec<2> u_tt = (ex(X, t + ht).u - 2.0 * ex(X, t).u + ex(X, t - ht).u) / (ht * ht);
      // Div P: (Div P)_a = sum_b dP_ab / dX_b, P from the FD deformation gradient.
      Vec<2> div = Vec<2>::Zero();
      for (int b = 0; b < 2; ++b) {
        Vec<2> e = Vec<2>::Zero();
        e[b] = hx;
        const Mat<2> dP = (law_piola(fd_deformation_gradient(ex, X + e, t)) -
                           law_piola(fd_deformation_gradient(ex, X - e, t))) /
                          (2.0 * hx);
        div += dP.col(b);
      }
      const Vec<2> residual = u_tt - div / ex.density;
      const Vec<2> b = ex.body_force(X, t);
      EXPECT_LT((b - residual).norm(), 1e-5 * residual.norm())
          << "X " << X.transpose() << " t " << t;
      // 001 eq. 42 with pi^2 u / L^2 (METHODS.md errata) agrees with the derivation.
      using std::numbers::pi;
      const Mat<2> F = ex.deformation_gradient(X, t);
      const double lnJ = std::log(F.determinant()), c = ex.wave_speed;
      const auto u = ex(X, t).u;
      for (int d = 0; d < 2; ++d) {
        const double eq42 =
            pi * pi * u[d] *
            (4.0 * ex.mu / ex.density - c * c -
             4.0 * (ex.lambda * (lnJ - 1.0) - ex.mu) / (ex.density * F(d, d) * F(d, d)));
        EXPECT_NEAR(b[d], eq42, 1e-9 * std::abs(eq42) + 1e-9);
      }
    }
}

TEST(PlateMms2DExact, NormalComponentVanishesOnEverySide) {
  // The roller conditions of the benchmark hold for the exact solution; the tangential
  // component does not vanish (so fixing it would contradict the solution).
  const auto ex = make_exact();
  for (double t : {0.003, 0.011})
    for (double s : {0.1, 0.3, 0.6}) {
      EXPECT_NEAR(ex(Vec<2>(0.0, s), t).u[0], 0.0, 1e-15);
      EXPECT_NEAR(ex(Vec<2>(1.0, s), t).u[0], 0.0, 1e-15);
      EXPECT_NEAR(ex(Vec<2>(s, 0.0), t).u[1], 0.0, 1e-15);
      EXPECT_NEAR(ex(Vec<2>(s, 1.0), t).u[1], 0.0, 1e-15);
      EXPECT_GT(std::abs(ex(Vec<2>(0.0, s), t).u[1]), 1e-3);
    }
}

// The plate's problem on 4 x 4 cells (E = 1e7 Pa, rho0 = 1000 kg/m^3: c = 100 m/s, one period of
// the exact solution 2 L / c = 0.02 s at L = 1 m).
Problem<2> small_plate(double A, double L, double nu, double end, std::string extra = "") {
  const std::string toml = fmt::format(
      "benchmark = \"plate_mms_2d\"\n[grid]\ncells = 4\n[plate]\nlength = {}\n"
      "[mms]\namplitude = {}\n{}[time]\ndt = 1e-5\nend = {}\n[material]\n"
      "model = \"neo_hookean\"\ndensity = 1000.0\nyoungs_modulus = 1e7\npoisson_ratio = {}\n",
      L, A, extra, end, nu);
  return std::get<Problem<2>>(make_problem(Config::parse(toml, "plate.toml")));
}

TEST(PlateMms2D, WarnsAboveTheAmplitudeWhereItsExactSolutionIsUnstable) {
  // docs/verification.md, "The exact solution at A = 0.1 m is unstable": perturbations of the
  // exact solution grow above an amplitude that falls as Poisson's ratio rises (0.08 L at
  // nu = 0.3; scripts/plate_fem_check.py --floquet). Within one period the run says so, naming
  // the key and its line (the next test: longer runs are refused).
  auto warnings = [](double A, double L, double nu) {
    return small_plate(A, L, nu, 1e-4).warnings;
  };
  EXPECT_TRUE(warnings(0.05, 1.0, 0.3).empty());
  EXPECT_TRUE(warnings(0.08, 1.0, 0.3).empty());
  EXPECT_TRUE(warnings(0.1, 2.0, 0.3).empty());  // the bound is relative to the plate's length
  const auto w = warnings(0.1, 1.0, 0.3);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("plate.toml:7"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("mms.amplitude = 0.1 m is above 0.08 plate.length"), std::string::npos)
      << w[0];
  EXPECT_EQ(w[0].find("not measured"), std::string::npos) << w[0];
  EXPECT_EQ(warnings(-0.1, 1.0, 0.3).size(), 1u);
  // By Poisson's ratio: 0.1 L is stable at nu = 0.1, 0.06 L is not at nu = 0.4; a ratio between
  // two measured ones takes the bound of the larger, one above them all says so.
  EXPECT_TRUE(warnings(0.1, 1.0, 0.1).empty());
  EXPECT_EQ(warnings(0.06, 1.0, 0.4).size(), 1u);
  const auto between = warnings(0.085, 1.0, 0.25);
  ASSERT_EQ(between.size(), 1u);
  EXPECT_NE(between[0].find("above 0.08 plate.length"), std::string::npos) << between[0];
  EXPECT_NE(between[0].find("0.25 was not measured"), std::string::npos) << between[0];
  const auto above = warnings(0.04, 1.0, 0.49);
  ASSERT_EQ(above.size(), 1u);
  EXPECT_NE(above[0].find("above the largest ratio measured"), std::string::npos) << above[0];
}

TEST(PlateMms2D, RefusesMoreThanAPeriodAboveTheStableAmplitudeUnlessAllowed) {
  // Over more than one period the perturbations compound (16-60x a period at A = 0.1 L): 001's
  // set-up (A = 0.1 m, T = 0.2 s, ten periods) is refused up front with the reason, the lines
  // of both keys and the ways out; mms.allow_unstable runs it with the warning.
  try {
    (void)small_plate(0.1, 1.0, 0.3, 0.2);
    ADD_FAILURE() << "001's set-up was not refused";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("plate.toml:7"), std::string::npos) << m;   // mms.amplitude
    EXPECT_NE(m.find("plate.toml:10"), std::string::npos) << m;  // time.end
    EXPECT_NE(m.find("time.end = 0.2 s spans 10 of its periods"), std::string::npos) << m;
    EXPECT_NE(m.find("mms.amplitude <= 0.08 m, or time.end <= 0.02 s"), std::string::npos) << m;
    EXPECT_NE(m.find("mms.allow_unstable = true"), std::string::npos) << m;
  }
  EXPECT_THROW((void)small_plate(-0.1, 1.0, 0.3, 0.021), InputError);
  // One period exactly, a stable amplitude, a longer plate (period 0.04 s, bound 0.16 m) and
  // the opt-in all run; the opt-in still warns.
  EXPECT_EQ(small_plate(0.1, 1.0, 0.3, 0.02).warnings.size(), 1u);
  EXPECT_TRUE(small_plate(0.05, 1.0, 0.3, 0.2).warnings.empty());
  EXPECT_TRUE(small_plate(0.1, 2.0, 0.3, 0.2).warnings.empty());
  EXPECT_THROW((void)small_plate(0.2, 2.0, 0.3, 0.041), InputError);
  EXPECT_EQ(small_plate(0.1, 1.0, 0.3, 0.2, "allow_unstable = true\n").warnings.size(), 1u);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
