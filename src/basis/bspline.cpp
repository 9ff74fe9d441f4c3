// The B-spline basis's explicit stability factor (out of line: the driver asks for it by degree
// without compiling the basis).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "basis/bspline.hpp"
#include "basis/stability.hpp"

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
  return gershgorin_stability_factor(BSplineBasis<1, P>(stability_bar(n)), n, P + 1, [] {});
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
