// Exact solutions of the column-compaction (D 5.4.2) and traction-bar (D 4.6.2, eq. 4.93)
// benchmarks checked against their equations by central finite differences.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "benchmarks/benchmarks.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(ColumnExact, SatisfiesEquilibriumKinematicsAndTheLargeDeformationLaw) {
  const ColumnExact ex{50.0, 1.0, 1e6, -200.0, 0.5};
  const double t = 0.5, b = ex.body_force(t), E = 1e6, rho0 = 1.0, dX = 1e-3;
  EXPECT_DOUBLE_EQ(b, -200.0);
  EXPECT_DOUBLE_EQ(ex.body_force(0.25), -100.0);
  EXPECT_DOUBLE_EQ(ex.body_force(1.0), -200.0);  // held after the ramp
  for (double X : {0.5, 10.0, 25.0, 49.0}) {
    auto s = [&](double x) { return ex(Vec<1>(x), t); };
    const double dsig = (s(X + dX).stress(0, 0) - s(X - dX).stress(0, 0)) / (2 * dX);
    EXPECT_NEAR(dsig + rho0 * b, 0.0, 1e-6);  // dP/dX + rho0 b = 0, P = sigma in 1D
    const double F = 1.0 + (s(X + dX).u[0] - s(X - dX).u[0]) / (2 * dX);
    EXPECT_NEAR(s(X).stress(0, 0), E * (1.0 - 1.0 / F), 1e-5);  // sigma = E (1 - 1/F)
  }
  EXPECT_NEAR(ex(Vec<1>(0.0), t).u[0], 0.0, 1e-14);          // fixed bottom
  EXPECT_NEAR(ex(Vec<1>(50.0), t).stress(0, 0), 0.0, 1e-9);  // free top
  // Published: the top moves by about 0.27 m (D 5.4.2, "maximal strain 0.27 m" = displacement).
  EXPECT_NEAR(ex(Vec<1>(50.0), t).u[0], -0.25, 0.03);
}

TEST(TractionBarExact, SatisfiesTheWaveEquationsAndBoundaryConditions) {
  const double L = 1.0, rho = 100.0, E = 100.0, c = std::sqrt(E / rho), A = 1.0;
  const TractionBarExact ex{L, rho, c, A};
  const double ht = 1e-6, hx = 1e-6;
  for (double t : {0.2, 0.4, 1.3, 2.5, 3.2}) {
    // Traction at the loaded end and fixed end.
    EXPECT_NEAR(ex(Vec<1>(L), t).stress(0, 0), -A * std::sin(std::numbers::pi * c * t / L), 1e-12);
    EXPECT_NEAR(ex(Vec<1>(0.0), t).u[0], 0.0, 1e-12);
    for (double X : {0.13, 0.42, 0.77}) {
      // Skip points on a wave front, where the solution has a kink.
      bool front = false;
      for (double f : {L - X, L + X, 3 * L - X, 3 * L + X}) front |= std::abs(c * t - f) < 1e-3;
      if (front) continue;
      auto s = [&](double x, double tt) { return ex(Vec<1>(x), tt); };
      const double dv_dt = (s(X, t + ht).v[0] - s(X, t - ht).v[0]) / (2 * ht);
      const double du_dt = (s(X, t + ht).u[0] - s(X, t - ht).u[0]) / (2 * ht);
      const double ds_dt = (s(X, t + ht).stress(0, 0) - s(X, t - ht).stress(0, 0)) / (2 * ht);
      const double ds_dx = (s(X + hx, t).stress(0, 0) - s(X - hx, t).stress(0, 0)) / (2 * hx);
      const double dv_dx = (s(X + hx, t).v[0] - s(X - hx, t).v[0]) / (2 * hx);
      EXPECT_NEAR(rho * dv_dt, ds_dx, 1e-5) << "t " << t << " X " << X;
      EXPECT_NEAR(ds_dt, E * dv_dx, 1e-5) << "t " << t << " X " << X;
      EXPECT_NEAR(du_dt, s(X, t).v[0], 1e-6) << "t " << t << " X " << X;
    }
  }
  // Before the wave arrives everything is at rest (eq. 4.93, first case).
  const auto quiet = ex(Vec<1>(0.3), 0.5);
  EXPECT_EQ(quiet.stress(0, 0), 0.0);
  EXPECT_EQ(quiet.v[0], 0.0);
  EXPECT_EQ(quiet.u[0], 0.0);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
