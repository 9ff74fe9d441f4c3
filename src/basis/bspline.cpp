// The B-spline basis's explicit stability factor (out of line: the driver asks for it by degree
// without compiling the basis).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "basis/bspline.hpp"
#include "mapping/quadrature.hpp"

namespace mpm {

namespace {

// Explicit stability (Euler-Cromer, lumped mass): dt <= 2 / omega_max, omega_max^2 bounded by
// Gershgorin's theorem on M_L^-1 K of a uniform 1D bar (E = rho = h = 1), so
// dt_crit = factor h / c. P1: factor 1 exactly (h / c). B-splines of degree p: computed from
// exact Gauss integrals of their stiffness and lumped mass over a grid of 4p + 4 cells (the
// small end functions of the open knot vector set the bound).
template <int P>
double stability_factor() {
  const Index n = 4 * P + 4;
  const Grid<1> g(Vec<1>(0.0), Vec<1>(static_cast<double>(n)), IVec<1>{n});
  const BSplineBasis<1, P> basis(g);
  const auto nd = static_cast<std::size_t>(basis.num_dofs());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(static_cast<Index>(nd), static_cast<Index>(nd));
  Eigen::VectorXd m = Eigen::VectorXd::Zero(static_cast<Index>(nd));
  const GaussRule rule = gauss_legendre(P + 1);
  typename BSplineBasis<1, P>::StencilT st;
  for (Index c = 0; c < n; ++c)
    for (std::size_t k = 0; k < rule.xi.size(); ++k) {
      basis.evaluate_point(Vec<1>(static_cast<double>(c) + 0.5 + 0.5 * rule.xi[k]), st);
      const double w = 0.5 * rule.w[k];
      for (int a = 0; a < st.kSize; ++a) {
        m[st.dof[a]] += w * st.w[a];
        for (int b = 0; b < st.kSize; ++b)
          K(st.dof[a], st.dof[b]) += w * st.grad[a][0] * st.grad[b][0];
      }
    }
  double omega2 = 0.0;
  for (Index i = 0; i < K.rows(); ++i) omega2 = std::max(omega2, K.row(i).cwiseAbs().sum() / m[i]);
  return 2.0 / std::sqrt(omega2);
}

}  // namespace

double bspline_stability_factor(int degree) {
  switch (degree) {
    case 1:
      return stability_factor<1>();
    case 2:
      return stability_factor<2>();
    case 3:
      return stability_factor<3>();
    case 4:
      return stability_factor<4>();
    case 5:
      return stability_factor<5>();
    default:
      throw std::invalid_argument("bspline_stability_factor: degree 1 to 5");
  }
}

}  // namespace mpm
