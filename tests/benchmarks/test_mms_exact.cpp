// The 1D neo-Hookean manufactured solution (003 eq. 41-47) checked against its definition by
// central finite differences: the body force is the residual u_tt - (1/rho0) dP/dX of the
// manufactured displacement, the stress is the law at F = 1 + du/dX, v = du/dt.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "benchmarks/benchmarks.hpp"
#include "material/materials.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

Mms1DExact make_exact(double A = 0.1) {
  ElasticParameters p;
  p.density = 1000.0;
  p.youngs_modulus = 1.0e7;
  p.poisson_ratio = 0.3;
  return {1.0, p.density, p.lambda(), p.mu(), std::sqrt(p.youngs_modulus / p.density), A};
}

// 1D neo-Hookean law of the library, sigma(F) with J = F.
double law_stress(const Mms1DExact& ex, double F) {
  ElasticParameters p;
  p.density = 1000.0;
  p.youngs_modulus = 1.0e7;
  p.poisson_ratio = 0.3;
  const NeoHookean law{p};
  Mat<1> sigma = Mat<1>::Zero();
  law.update<1>(sigma, {}, Mat<1>::Constant(F), Mat<1>::Zero());
  EXPECT_NEAR(p.lambda(), ex.lambda, 1e-9 * ex.lambda);
  return sigma(0, 0);
}

TEST(Mms1DExact, MaterialConstantsMatch003) {
  const auto ex = make_exact();
  EXPECT_NEAR(ex.mu, 3.85e6, 0.001 * 3.85e6);      // 3.846e6
  EXPECT_NEAR(ex.lambda, 5.77e6, 0.001 * 5.77e6);  // 5.769e6
  EXPECT_DOUBLE_EQ(ex.wave_speed, 100.0);
}

TEST(Mms1DExact, BodyForceIsTheFiniteDifferenceResidual) {
  const auto ex = make_exact();
  const double hx = 1e-4, ht = 1e-6;
  auto u = [&](double X, double t) { return ex(Vec<1>(X), t).u[0]; };
  auto P = [&](double X, double t) { return ex(Vec<1>(X), t).stress(0, 0); };
  for (double t : {0.0013, 0.004, 0.0071, 0.013, 0.019})
    for (double X : {0.07, 0.21, 0.33, 0.47, 0.64, 0.9}) {  // not 0.5, where b = 0
      const double u_tt = (u(X, t + ht) - 2.0 * u(X, t) + u(X, t - ht)) / (ht * ht);
      const double dPdX = (P(X + hx, t) - P(X - hx, t)) / (2.0 * hx);
      const double residual = u_tt - dPdX / ex.density;
      const double b = ex.body_force(X, t);
      EXPECT_NEAR(b, residual, 1e-6 * std::abs(residual)) << "X " << X << " t " << t;
      // 003 eq. 47 with pi^2 u / L^2 (METHODS.md errata) agrees with the derivation.
      using std::numbers::pi;
      const double F = ex.deformation_gradient(X, t), c = ex.wave_speed, L = ex.length;
      const double eq47 = pi * pi * u(X, t) / (L * L) *
                          (4.0 * ex.mu / ex.density - c * c -
                           4.0 * (ex.lambda * (std::log(F) - 1.0) - ex.mu) / (ex.density * F * F));
      EXPECT_NEAR(b, eq47, 1e-10 * std::abs(eq47)) << "X " << X << " t " << t;
    }
}

TEST(Mms1DExact, StressIsTheLawAtTheManufacturedStretch) {
  const auto ex = make_exact();
  const double hx = 1e-6;
  for (double t : {0.003, 0.008, 0.0165})
    for (double X : {0.0, 0.12, 0.5, 0.77, 1.0}) {
      auto u = [&](double x) { return ex(Vec<1>(x), t).u[0]; };
      const double F = 1.0 + (u(X + hx) - u(X - hx)) / (2.0 * hx);
      EXPECT_NEAR(ex.deformation_gradient(X, t), F, 1e-8);
      const double sigma = law_stress(ex, F);
      EXPECT_NEAR(ex(Vec<1>(X), t).stress(0, 0), sigma, 1e-6 * std::abs(sigma) + 1.0)
          << "X " << X << " t " << t;
    }
}

TEST(Mms1DExact, VelocityIsTheTimeDerivative) {
  const auto ex = make_exact();
  const double ht = 1e-7;
  for (double t : {0.0005, 0.006, 0.012, 0.02})
    for (double X : {0.1, 0.4, 0.55, 0.85}) {
      auto u = [&](double tt) { return ex(Vec<1>(X), tt).u[0]; };
      const double v = (u(t + ht) - u(t - ht)) / (2.0 * ht);
      EXPECT_NEAR(ex(Vec<1>(X), t).v[0], v, 1e-6 * std::abs(v) + 1e-9) << "X " << X << " t " << t;
    }
}

TEST(Mms1DExact, BoundaryAndInitialConditions) {
  using std::numbers::pi;
  const auto ex = make_exact();
  for (double t : {0.0, 0.003, 0.01, 0.02}) {
    EXPECT_NEAR(ex(Vec<1>(0.0), t).u[0], 0.0, 1e-15);
    EXPECT_NEAR(ex(Vec<1>(1.0), t).u[0], 0.0, 1e-15);
    EXPECT_NEAR(ex(Vec<1>(0.0), t).v[0], 0.0, 1e-13);
    EXPECT_NEAR(ex(Vec<1>(1.0), t).v[0], 0.0, 1e-12);
    EXPECT_NEAR(ex.body_force(0.0, t), 0.0, 1e-9);
    EXPECT_NEAR(ex.body_force(1.0, t), 0.0, 1e-6);
  }
  for (double X : {0.1, 0.25, 0.6, 0.9}) {
    const auto s = ex(Vec<1>(X), 0.0);
    EXPECT_EQ(s.u[0], 0.0);
    EXPECT_EQ(s.stress(0, 0), 0.0);
    EXPECT_DOUBLE_EQ(ex.deformation_gradient(X, 0.0), 1.0);
    EXPECT_NEAR(s.v[0], 0.1 * 100.0 * pi * std::sin(2.0 * pi * X), 1e-12);
    EXPECT_EQ(ex.body_force(X, 0.0), 0.0);
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
