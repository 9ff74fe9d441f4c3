#include "basis/gauss_legendre.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace mpm {

// Out of line: the eigen-solver's instantiation is a large share of the compile time of every
// unit that includes quadrature.hpp.
GaussRule gauss_legendre(int n) {
  GaussRule r;
  if (n == 1) {
    r.xi = {0.0};
    r.w = {2.0};
    return r;
  }
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k < n; ++k) {
    const double b = k / std::sqrt(4.0 * k * k - 1.0);
    J(k - 1, k) = J(k, k - 1) = b;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(J);
  for (int k = 0; k < n; ++k) {
    r.xi.push_back(es.eigenvalues()[k]);
    const double v0 = es.eigenvectors()(0, k);
    r.w.push_back(2.0 * v0 * v0);
  }
  return r;
}

}  // namespace mpm
