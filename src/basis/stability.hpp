#pragma once
// The explicit stability factor of a basis (dt <= factor h / c with lumped mass, Euler-Cromer):
// dt <= 2 / omega_max, with omega_max^2 bounded by Gershgorin's theorem on M_L^-1 K of a uniform
// 1D bar with E = rho = h = 1 on `cells` cells, the integrals by Gauss quadrature of
// `gauss_points` points per cell. Shared by the B-spline (exact quadrature, basis/bspline.cpp)
// and max-ent (basis/maxent.cpp) factors.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "basis/gauss_legendre.hpp"
#include "grid/grid.hpp"

namespace mpm {

// basis: a 1D basis on Grid<1>(0, cells, cells) with evaluate_point; `after` runs after the
// evaluations (an iterative basis's failure check).
template <class Basis, class After>
double gershgorin_stability_factor(const Basis& basis, Index cells, int gauss_points,
                                   After&& after) {
  const Index nd = basis.num_dofs();
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nd, nd);
  Eigen::VectorXd m = Eigen::VectorXd::Zero(nd);
  const GaussRule rule = gauss_legendre(gauss_points);
  typename Basis::StencilT st;
  for (Index c = 0; c < cells; ++c)
    for (std::size_t k = 0; k < rule.xi.size(); ++k) {
      basis.evaluate_point(Vec<1>(static_cast<double>(c) + 0.5 + 0.5 * rule.xi[k]), st);
      const double w = 0.5 * rule.w[k];
      for (int a = 0; a < st.kSize; ++a) {
        m[st.dof[a]] += w * st.w[a];
        for (int b = 0; b < st.kSize; ++b)
          K(st.dof[a], st.dof[b]) += w * st.grad[a][0] * st.grad[b][0];
      }
    }
  after();
  double omega2 = 0.0;
  for (Index i = 0; i < K.rows(); ++i) omega2 = std::max(omega2, K.row(i).cwiseAbs().sum() / m[i]);
  return 2.0 / std::sqrt(omega2);
}

// The unit bar of `cells` cells the factors are computed on.
inline Grid<1> stability_bar(Index cells) {
  return Grid<1>(Vec<1>(0.0), Vec<1>(static_cast<double>(cells)), IVec<1>{cells});
}

}  // namespace mpm
