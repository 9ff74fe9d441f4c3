#pragma once
// Convected particle domain interpolation (CPDI), D 2.6.4 eq. 2.64-2.65 after Sadeghirad, Brannon
// & Burghardt (2011). The particle domain is the parallelogram (parallelepiped) spanned by the
// initial half-edge vectors r_d^0 = (l0_d / 2) e_d convected by F (D eq. 2.64-2.65):
//   r_d = F r_d^0,   corners x_c = x_p + sum_d s_{c,d} r_d,   s_c in {-1, +1}^Dim.
// Inside the domain the P1 basis N_i is replaced by its multilinear interpolant from the corner
// values, so the GIMP averages (D eq. 2.61-2.62) are exact sums over the 2^Dim corners:
//   w_i  = 2^-Dim sum_c N_i(x_c),
//   dw_i = 2^-Dim J^-T sum_c N_i(x_c) s_c,   J = [r_1 ... r_Dim],
// with x = x_p + J xi mapping the reference cube xi in [-1, 1]^Dim onto the domain.
// In 1D: w_i = (N_i(x_1) + N_i(x_2)) / 2 and dw_i = (N_i(x_2) - N_i(x_1)) / (x_2 - x_1), with
// x_{1,2} = x_p -/+ F_11 l0 / 2 (Sadeghirad et al. 2011, 1D reduction of their eq. for w_ip and
// grad w_ip; in 2D the formula above equals theirs: J^-T s_c / 4 = their corner vectors / V_p).
// Initial size: l0 = V_p^0 in 1D; in Dim > 1 a cube of side (V_p^0)^(1/Dim) (Particles carries no
// per-direction size). Only the 1D case is tested so far.
// Stencil: 4 nodes per direction, enough when the domain's extent along every direction is at
// most 2 h_d (the corners' P1 supports then span at most 4 nodes); fits() enforces that limit.
// Grid ends (1D): a corner that passes a grid end is clipped to it, as GIMP clips its domain,
// so the weights and gradient are those of the part of the domain inside the grid (partition of
// unity and zero gradient sum hold). This happens at fixed ends, where the material boundary
// sits on the grid boundary and the end particle's averaged stretch moves its corner past it.
// In Dim > 1 a corner outside the grid does not fit (clipping a parallelogram is not defined
// by the method).
#include <array>
#include <cmath>
#include <string_view>

#include "basis/gimp.hpp"

namespace mpm {

template <int Dim>
class CpdiBasis : public detail::NodalDomainBasis<Dim> {
  using Base = detail::NodalDomainBasis<Dim>;
  static constexpr int kCorners = ipow(2, Dim);

 public:
  static constexpr std::string_view kName = "cpdi";
  using Base::kPerDim;
  using typename Base::StencilT;

  explicit CpdiBasis(const Grid<Dim>& g) : Base(g) {}

  // Corners x_c of the convected domain (D eq. 2.64-2.65); corner c has s_{c,d} = +1 where bit d
  // of c is set.
  std::array<Vec<Dim>, kCorners> corners(const Particles<Dim>& P, Index p) const {
    const auto i = static_cast<std::size_t>(p);
    const Mat<Dim> J = P.F[i] * (0.5 * Base::initial_length(P, p));
    std::array<Vec<Dim>, kCorners> x;
    for (int c = 0; c < kCorners; ++c) {
      x[static_cast<std::size_t>(c)] = P.x[i];
      for (int d = 0; d < Dim; ++d)
        x[static_cast<std::size_t>(c)] += (((c >> d) & 1) ? 1.0 : -1.0) * J.col(d);
    }
    if constexpr (Dim == 1) {
      const double lo = this->grid_.origin[0], hi = this->grid_.upper()[0];
      for (auto& xc : x) xc[0] = std::clamp(xc[0], lo, hi);
    }
    return x;
  }

  // Whether the stencil can hold the domain: extent <= 2 h_d along every direction, every corner
  // in the grid, and a non-degenerate, non-inverted domain (det J > 0). False for NaN. No
  // allocation, no exceptions.
  bool fits(const Particles<Dim>& P, Index p) const {
    const auto i = static_cast<std::size_t>(p);
    // Extent along d is 2 sum_e |J_de|, taken from J rather than from corner differences so
    // that the limit does not depend on the position by round-off.
    const Mat<Dim> J = P.F[i] * (0.5 * Base::initial_length(P, p));
    for (int d = 0; d < Dim; ++d)
      if (!(J.row(d).cwiseAbs().sum() <= this->grid_.h[d])) return false;
    if (!this->grid_.inside(P.x[i])) return false;
    const auto x = corners(P, p);
    for (const auto& xc : x)
      if (!this->grid_.inside(xc)) return false;  // never in 1D (clipped) unless NaN
    // In 1D the gradient divides by x_2 - x_1, so the corners must differ after round-off too.
    if constexpr (Dim == 1) {
      return x[1][0] > x[0][0];
    } else {
      const double det = J.determinant();
      return det > 0.0 && std::isfinite(det);
    }
  }

  // Requires fits(P, p); the caller checks. (If it is broken, contributions that fall outside the
  // stencil are dropped so memory stays safe, but the result is meaningless.)
  void evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
    const auto x = corners(P, p);
    const Grid<Dim>& g = this->grid_;

    // Grid coordinates and P1 cells of the corners; the stencil window starts at the lowest.
    std::array<Vec<Dim>, kCorners> xi;
    std::array<IVec<Dim>, kCorners> cell;
    IVec<Dim> first;
    for (int d = 0; d < Dim; ++d) {
      Index c_min = g.cells[d];
      for (std::size_t c = 0; c < x.size(); ++c) {
        const double sd = (x[c][d] - g.origin[d]) * this->inv_h_[d];
        cell[c][d] = detail::clamped_cell(sd, g.cells[d]);
        xi[c][d] = std::clamp(sd - static_cast<double>(cell[c][d]), 0.0, 1.0);
        c_min = std::min(c_min, cell[c][d]);
      }
      first[d] = detail::window_first(c_min, this->n_[d]);
    }

    // 2^-Dim J^-T s_c: in 1D from the computed corners, 1 / (x_2 - x_1) each way, so that
    // sum_i dw_i x_i = 1 to round-off.
    Mat<Dim> JinvT;
    if constexpr (Dim == 1) {
      JinvT(0, 0) = 2.0 / (x[1][0] - x[0][0]);
    } else {
      const auto i = static_cast<std::size_t>(p);
      JinvT = (P.F[i] * (0.5 * Base::initial_length(P, p))).inverse().transpose();
    }
    constexpr double kAvg = 1.0 / kCorners;

    for (int n = 0; n < StencilT::kSize; ++n) {
      s.dof[static_cast<std::size_t>(n)] = this->slot_dof(first, n);
      s.w[static_cast<std::size_t>(n)] = 0.0;
      s.grad[static_cast<std::size_t>(n)] = Vec<Dim>::Zero();
    }
    for (int c = 0; c < kCorners; ++c) {
      const auto cu = static_cast<std::size_t>(c);
      Vec<Dim> sc;
      for (int d = 0; d < Dim; ++d) sc[d] = ((c >> d) & 1) ? 1.0 : -1.0;
      const Vec<Dim> gc = kAvg * (JinvT * sc);
      // The 2^Dim P1 nodes of the corner's cell (D eq. 2.56), tensor product.
      for (int b = 0; b < kCorners; ++b) {
        int slot = 0, stride = 1;
        double N = 1.0;
        bool inside = true;
        for (int d = 0; d < Dim; ++d) {
          const int bd = (b >> d) & 1;
          const Index k = cell[cu][d] + bd - first[d];
          if (k < 0 || k >= kPerDim) inside = false;
          slot += static_cast<int>(k) * stride;
          stride *= kPerDim;
          N *= bd ? xi[cu][d] : 1.0 - xi[cu][d];
        }
        if (!inside) continue;
        s.w[static_cast<std::size_t>(slot)] += kAvg * N;
        s.grad[static_cast<std::size_t>(slot)] += N * gc;
      }
    }
  }
};

}  // namespace mpm
