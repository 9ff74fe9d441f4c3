// The 3D vibrating cube (cube_mms_3d, issue 20) checked against its definition by central finite
// differences: v = du/dt, F = I + Grad u, the stress is the library's 3D neo-Hookean law at that
// F, and the body force is the residual u_tt - Div P / rho0 (scripts/cube_mms.py derives the
// closed form symbolically; this checks the C++ that evaluates it).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "../support/mms.hpp"
#include "benchmarks/benchmarks.hpp"
#include "material/materials.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

ElasticParameters params() {
  return test::plate_material();
}

CubeMms3DExact make_exact(double A = 0.05, double L = 1.3) {
  const auto p = params();
  return {L, p.density, p.lambda(), p.mu(), std::sqrt(p.youngs_modulus / p.density), A};
}

TEST(CubeMmsExact, VelocityDeformationAndStressFromTheDisplacement) {
  const auto ex = make_exact();
  const double ht = 1e-7;
  for (double t : {0.0013, 0.0047, 0.019})
    for (const Vec<3>& X :
         {Vec<3>(0.1, 0.2, 0.3), Vec<3>(0.37, 0.81, 1.1), Vec<3>(1.2, 0.45, 0.6)}) {
      const auto s = ex(X, t);
      const Vec<3> v = (ex(X, t + ht).u - ex(X, t - ht).u) / (2.0 * ht);
      EXPECT_LT((s.v - v).norm(), 1e-6 * s.v.norm() + 1e-9);
      const Mat<3> F = test::fd_deformation_gradient(ex, X, t);
      EXPECT_LT((ex.deformation_gradient(X, t) - F).norm(), 1e-7);
      const NeoHookean law{params()};
      Mat<3> sigma = Mat<3>::Zero();
      law.update<3>(sigma, {}, ex.deformation_gradient(X, t), Mat<3>::Zero());
      EXPECT_LT((s.stress - sigma).norm(), 1e-9 * sigma.norm());
      EXPECT_LT((ex.piola_stress(F) - test::neo_hookean_piola<3>(params(), F)).norm(),
                1e-9 * sigma.norm());
      // Every component carries + A sin(2 pi X_i / L) sin(omega t) (the form).
      using std::numbers::pi;
      for (int d = 0; d < 3; ++d)
        EXPECT_NEAR(s.u[d], 0.05 * std::sin(2 * pi * X[d] / 1.3) * std::sin(ex.omega() * t), 1e-15);
    }
}

TEST(CubeMmsExact, BodyForceIsTheFiniteDifferenceResidual) {
  for (double A : {0.05, 0.15}) {
    const auto ex = make_exact(A);
    const double hx = 1e-4, ht = 1e-6;
    for (double t : {0.0013, 0.0047, 0.011, 0.019})
      for (const Vec<3>& X : {Vec<3>(0.07, 0.13, 0.5), Vec<3>(0.21, 0.64, 1.2),
                              Vec<3>(0.47, 0.33, 0.05), Vec<3>(0.9, 0.71, 0.88)}) {
        const Vec<3> u_tt = (ex(X, t + ht).u - 2.0 * ex(X, t).u + ex(X, t - ht).u) / (ht * ht);
        // (Div P)_a = sum_b dP_ab / dX_b, P from the FD deformation gradient.
        Vec<3> div = Vec<3>::Zero();
        for (int b = 0; b < 3; ++b) {
          Vec<3> e = Vec<3>::Zero();
          e[b] = hx;
          const Mat<3> dP =
              (test::neo_hookean_piola<3>(params(), test::fd_deformation_gradient(ex, X + e, t)) -
               test::neo_hookean_piola<3>(params(), test::fd_deformation_gradient(ex, X - e, t))) /
              (2.0 * hx);
          div += dP.col(b);
        }
        const Vec<3> residual = u_tt - div / ex.density;
        EXPECT_LT((ex.body_force(X, t) - residual).norm(), 1e-5 * residual.norm())
            << "A " << A << " X " << X.transpose() << " t " << t;
      }
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
