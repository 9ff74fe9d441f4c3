#pragma once
// Gauss-Legendre quadrature (D 3.2.2): the rules of the reconstructions' element integrals, the
// B-spline matrices and the stability factors.
#include <vector>

namespace mpm {

// n-point Gauss-Legendre rule on [-1, 1], exact for polynomials of degree 2n - 1, from the
// Golub-Welsch eigenvalue problem of the Jacobi matrix (nodes ascending).
struct GaussRule {
  std::vector<double> xi, w;
};

GaussRule gauss_legendre(int n);  // gauss_legendre.cpp

}  // namespace mpm
