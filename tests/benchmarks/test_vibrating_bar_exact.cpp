// The vibrating-bar exact solution satisfies its PDE system (004 eq. 4.45-4.47), the initial
// and boundary conditions, checked by central finite differences.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "benchmarks/benchmarks.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(VibratingBarExact, SatisfiesPdeInitialAndBoundaryConditions) {
  const double L = 1.3, v0 = 0.28, rho = 2000.0, E = 7e6;
  const double c = std::sqrt(E / rho);
  VibratingBarExact ex{L, v0, rho, c};
  const double T = 2.0 * L / c;  // one period
  for (double t : {0.1 * T, 0.37 * T, 0.8 * T}) {
    for (double X : {0.05 * L, 0.3 * L, 0.71 * L}) {
      const double ht = 1e-6 * T, hx = 1e-5 * L;
      auto s = [&](double x, double tt) { return ex(Vec<1>(x), tt); };
      const double dv_dt = (s(X, t + ht).v[0] - s(X, t - ht).v[0]) / (2 * ht);
      const double du_dt = (s(X, t + ht).u[0] - s(X, t - ht).u[0]) / (2 * ht);
      const double ds_dt = (s(X, t + ht).stress(0, 0) - s(X, t - ht).stress(0, 0)) / (2 * ht);
      const double ds_dx = (s(X + hx, t).stress(0, 0) - s(X - hx, t).stress(0, 0)) / (2 * hx);
      const double dv_dx = (s(X + hx, t).v[0] - s(X - hx, t).v[0]) / (2 * hx);
      const double scale_m = rho * v0 * c / L;  // size of the momentum terms
      EXPECT_NEAR(rho * dv_dt, ds_dx, 1e-6 * scale_m);
      EXPECT_NEAR(ds_dt, E * dv_dx, 1e-6 * E * v0 / L);
      EXPECT_NEAR(du_dt, s(X, t).v[0], 1e-6 * v0);
    }
    EXPECT_NEAR(ex(Vec<1>(0.0), t).u[0], 0.0, 1e-15);
    EXPECT_NEAR(ex(Vec<1>(L), t).u[0], 0.0, 1e-12);
  }
  for (double X : {0.1, 0.5, 1.1}) {
    EXPECT_EQ(ex(Vec<1>(X), 0.0).u[0], 0.0);
    EXPECT_EQ(ex(Vec<1>(X), 0.0).stress(0, 0), 0.0);
    EXPECT_NEAR(ex(Vec<1>(X), 0.0).v[0], v0 * std::sin(std::numbers::pi * X / L), 1e-15);
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
