#pragma once
// Finite-difference checks of the 2D manufactured solutions (plate_mms_2d, vortex_2d): the
// deformation gradient from the exact displacement and the first Piola-Kirchhoff stress of the
// library's neo-Hookean law, from which a test forms x_tt - Div P / rho0.
#include "core/types.hpp"
#include "material/materials.hpp"

namespace mpm::test {

// F = I + Grad u by central differences (step h) of ex(X, t).u.
template <class Exact>
Mat<2> fd_deformation_gradient(const Exact& ex, const Vec<2>& X, double t, double h = 1e-6) {
  Mat<2> F = Mat<2>::Identity();
  for (int b = 0; b < 2; ++b) {
    Vec<2> e = Vec<2>::Zero();
    e[b] = h;
    F.col(b) += (ex(X + e, t).u - ex(X - e, t).u) / (2.0 * h);
  }
  return F;
}

// P = J sigma F^-T of the library's plane-strain neo-Hookean law.
inline Mat<2> neo_hookean_piola(const ElasticParameters& p, const Mat<2>& F) {
  const NeoHookean law{p};
  Mat<2> sigma = Mat<2>::Zero();
  law.update<2>(sigma, F, Mat<2>::Zero());
  return F.determinant() * sigma * F.inverse().transpose();
}

}  // namespace mpm::test
