#pragma once
// Finite-difference checks of the manufactured solutions (plate_mms_2d, vortex_2d, cube_mms_3d):
// the deformation gradient from the exact displacement and the first Piola-Kirchhoff stress of the
// library's neo-Hookean law, from which a test forms x_tt - Div P / rho0.
#include "core/types.hpp"
#include "material/materials.hpp"

namespace mpm::test {

// The material of examples/plate_mms_2d.toml and cube_mms_3d.toml (001's plate).
inline ElasticParameters plate_material() {
  ElasticParameters p;
  p.density = 1000.0;
  p.youngs_modulus = 1.0e7;
  p.poisson_ratio = 0.3;
  return p;
}

// F = I + Grad u by central differences (step h) of ex(X, t).u.
// (X may be an Eigen expression such as X + e.)
template <class Exact, class Point>
auto fd_deformation_gradient(const Exact& ex, const Point& Xp, double t, double h = 1e-6) {
  constexpr int Dim = Point::RowsAtCompileTime;
  const Vec<Dim> X = Xp;
  Mat<Dim> F = Mat<Dim>::Identity();
  for (int b = 0; b < Dim; ++b) {
    Vec<Dim> e = Vec<Dim>::Zero();
    e[b] = h;
    F.col(b) += (ex(X + e, t).u - ex(X - e, t).u) / (2.0 * h);
  }
  return F;
}

// P = J sigma F^-T of the library's neo-Hookean law (plane strain in 2D).
template <int Dim>
Mat<Dim> neo_hookean_piola(const ElasticParameters& p, const Mat<Dim>& F) {
  const NeoHookean law{p};
  Mat<Dim> sigma = Mat<Dim>::Zero();
  law.update<Dim>(sigma, {}, F, Mat<Dim>::Zero());
  return F.determinant() * sigma * F.inverse().transpose();
}

}  // namespace mpm::test
