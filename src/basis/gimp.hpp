#pragma once
// Generalized interpolation material point (GIMP) bases, D 2.6.4 eq. 2.58-2.63 after Bardenhagen
// & Kober (2004). The weighting function of node i and its gradient are averages of the P1 basis
// and of its gradient over the particle domain (piecewise-constant characteristic function, a box
// of side l_d in direction d centred at x_p):
//   w_i  = (1/|Omega_p|) int_{Omega_p} N_i dx           (D eq. 2.61)
//   dw_i = (1/|Omega_p|) int_{Omega_p} grad N_i dx      (D eq. 2.62)
// In 1D both integrals are exact sums over the cells the domain overlaps (N_i is linear on each
// cell); in Dim > 1 the box makes them tensor products of the 1D factors (D 2.6.4).
//   uGIMP:  l_d = l0_d, the initial size at every time level (D 2.6.4, Sadeghirad et al. 2011).
//   cpGIMP: l_d = F_dd l0_d, the size from the diagonal of F (D 2.6.4, Sadeghirad et al. 2011).
// Initial size: l0 = V_p^0 in 1D (a 1D volume is a length). Particles carries no per-direction
// size, so in Dim > 1 the initial domain is taken similar to the grid cell:
//   l0_d = h_d (V_p^0 / |cell|)^(1/Dim),   |cell| = prod_d h_d.
// For particles seeded on a regular lattice with k per cell and direction (seed_particles), the
// domain is the lattice cell h_d / k in every direction, exactly what this gives (V_p^0 =
// prod_d h_d / k^Dim), so the domains tile the body; on square cells it is the cube of side
// (V_p^0)^(1/Dim). It is stateless (from V_p^0, which checkpoints keep), so a restart needs no
// basis state. A body whose extent is not a whole number of lattice spacings per cell gets the
// same-area domain of the cell's aspect ratio instead of the exact lattice spacing.
// Stencil: 4 nodes per direction. A domain of length l spans at most ceil(l/h) + 1 nodes' supports
// in the worst position, so 4 nodes hold any domain with l_d <= 2 h_d, wherever it lies; fits()
// enforces that limit (position-independent, so a run never stops by the luck of a position).
#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>
#include <vector>

#include "basis/basis.hpp"
#include "basis/stencil.hpp"
#include "grid/grid.hpp"
#include "particles/particles.hpp"

namespace mpm {

// Initial side of a particle's domain along d [m] (the file comment): V_p^0 in 1D and
// h_d (V_p^0 / |cell|)^(1/Dim) otherwise. Shared by the GIMP and CPDI bases and by the TLS
// mapping's particle domains (mapping/tls_mapping.cpp, the cpGIMP box).
template <int Dim>
double domain_initial_side(const Grid<Dim>& g, double volume0, int d) {
  if constexpr (Dim == 1) {
    return volume0;
  } else if constexpr (Dim == 2) {
    return g.h[d] * std::sqrt(volume0 / g.cell_volume());
  } else {
    return g.h[d] * std::pow(volume0 / g.cell_volume(), 1.0 / Dim);
  }
}

// The cpGIMP side now, l_d = F_dd l0_d [m] (D eq. 2.63).
template <int Dim>
double cpgimp_side(const Grid<Dim>& g, const Particles<Dim>& P, Index p, int d) {
  const auto i = static_cast<std::size_t>(p);
  return P.F[i](d, d) * domain_initial_side(g, P.volume0[i], d);
}

// Nodes per direction in the GIMP and CPDI stencils.
inline constexpr int kDomainPerDim = 4;

// Cell containing grid coordinate s = (x - origin)/h, clamped to [0, cells - 1]; NaN gives 0. Used
// only where the caller has checked that the point lies in the grid, so the clamp only removes
// round-off and keeps indices valid when that contract is broken.
inline Index clamped_cell(double s, Index cells) {
  if (!(s >= 0.0)) return 0;
  if (s >= static_cast<double>(cells)) return cells - 1;
  return std::min(static_cast<Index>(std::floor(s)), cells - 1);
}

// First node of the 4-node window holding nodes c0 .. c0 + 3, moved back at the upper end so
// the window stays inside the n nodes (n >= 4); with fewer nodes the extra slots repeat the
// last node with zero weight.
inline Index window_first(Index c0, Index n) {
  return std::clamp<Index>(c0, 0, std::max<Index>(n - kDomainPerDim, 0));
}

// Node layout shared by the domain-averaged bases: the DOFs are the grid nodes, as for P1
// (LinearBasis), x fastest, and the stencil has 4 nodes per direction.
template <int Dim>
class NodalDomainBasis {
 public:
  static constexpr int kPerDim = kDomainPerDim;
  using StencilT = Stencil<Dim, ipow(kPerDim, Dim)>;
  // Capabilities (basis/basis.hpp): full stencils of a particle domain that must fit them
  // (fits()); CPDI2 adds its preparation pass and tracked corners.
  static constexpr bool kTensorProduct = false, kParticleDomain = true, kPrepare = false,
                        kNodalSums = false, kTrackedCorners = false, kIterative = false,
                        kTriangleMesh = false;

  explicit NodalDomainBasis(const Grid<Dim>& g) : grid_(g) {
    for (int d = 0; d < Dim; ++d) {
      n_[d] = g.cells[d] + 1;
      inv_h_[d] = 1.0 / g.h[d];
    }
  }

  const Grid<Dim>& grid() const { return grid_; }
  IVec<Dim> dofs_per_dim() const { return n_; }
  Index num_dofs() const { return dof_count<Dim>(n_); }
  Vec<Dim> dof_position(Index i) const { return node_position<Dim>(grid_.origin, grid_.h, n_, i); }
  // The nodes on grid side `side` (0 lower, 1 upper) normal to direction d, as for P1.
  std::vector<Index> boundary_dofs(int d, int side) const { return side_dofs<Dim>(n_, d, side); }

  // The plain P1 basis at a point of the grid (tractions), in this basis' stencil (D eq. 2.56).
  void evaluate_point(const Vec<Dim>& x, StencilT& s) const {
    IVec<Dim> first;
    std::array<std::array<double, kPerDim>, Dim> w{}, dw{};
    for (int d = 0; d < Dim; ++d) {
      const double sd = (x[d] - grid_.origin[d]) * inv_h_[d];
      const Index c = clamped_cell(sd, grid_.cells[d]);
      first[d] = window_first(c, n_[d]);
      const auto k = static_cast<std::size_t>(c - first[d]);
      const double xi = std::clamp(sd - static_cast<double>(c), 0.0, 1.0);
      w[d][k] = 1.0 - xi;
      w[d][k + 1] = xi;
      dw[d][k] = -inv_h_[d];
      dw[d][k + 1] = inv_h_[d];
    }
    assemble(first, w, dw, s);
  }

 protected:
  // DOF of slot k (0..3) along direction d; slots past the last node (grids of fewer than 3
  // cells) repeat it, always with zero weight, so every index stays valid.
  Index slot_node(const IVec<Dim>& first, int d, int k) const {
    return std::min<Index>(first[d] + k, n_[d] - 1);
  }
  Index slot_dof(const IVec<Dim>& first, int n) const {
    Index dof = 0, stride = 1;
    for (int d = 0; d < Dim; ++d) {
      dof += slot_node(first, d, n % kPerDim) * stride;
      n /= kPerDim;
      stride *= n_[d];
    }
    return dof;
  }

  // Tensor product of 1D factors (D 2.5), like tensor_product() but with the DOF indices
  // clamped as in slot_node().
  void assemble(const IVec<Dim>& first, const std::array<std::array<double, kPerDim>, Dim>& w,
                const std::array<std::array<double, kPerDim>, Dim>& dw, StencilT& s) const {
    for (int n = 0; n < StencilT::kSize; ++n) {
      std::array<int, Dim> k{};
      int rem = n;
      for (int d = 0; d < Dim; ++d) {
        k[d] = rem % kPerDim;
        rem /= kPerDim;
      }
      double value = 1.0;
      for (int d = 0; d < Dim; ++d) value *= w[d][static_cast<std::size_t>(k[d])];
      Vec<Dim> g;
      for (int d = 0; d < Dim; ++d) {
        double gd = dw[d][static_cast<std::size_t>(k[d])];
        for (int e = 0; e < Dim; ++e)
          if (e != d) gd *= w[e][static_cast<std::size_t>(k[e])];
        g[d] = gd;
      }
      s.dof[static_cast<std::size_t>(n)] = slot_dof(first, n);
      s.w[static_cast<std::size_t>(n)] = value;
      s.grad[static_cast<std::size_t>(n)] = g;
    }
  }

  // Initial particle side length along direction d [m]: V_p^0 in 1D, h_d (V_p^0/|cell|)^(1/Dim)
  // in Dim > 1 (the domain is similar to the grid cell; see the file comment).
  double initial_length(const Particles<Dim>& P, Index p, int d) const {
    return domain_initial_side(grid_, P.volume0[static_cast<std::size_t>(p)], d);
  }

  // Matrix of the initial half-edge vectors convected by F (D eq. 2.64-2.65): column d is
  // r_d = F r_d^0 with r_d^0 = (l0_d / 2) e_d, i.e. J = F diag(l0 / 2) [m].
  Mat<Dim> half_edges(const Particles<Dim>& P, Index p) const {
    const Mat<Dim>& F = P.F[static_cast<std::size_t>(p)];
    Mat<Dim> J;
    for (int d = 0; d < Dim; ++d) J.col(d) = F.col(d) * (0.5 * initial_length(P, p, d));
    return J;
  }

  Grid<Dim> grid_;
  IVec<Dim> n_{};
  Vec<Dim> inv_h_;
};

namespace detail {

// 1D GIMP factors for the domain [s_lo, s_hi] in grid units (s = (x - origin)/h), already clipped
// to [0, cells]: exact integrals of the hat functions, cell by cell (D eq. 2.61-2.62). On a cell
// with local coordinates xi1 <= xi2 in [0, 1], the left node's hat is 1 - xi and the right one's
// is xi, so (times h) int N_left = (xi2 - xi1)(1 - (xi1 + xi2)/2) >= 0,
// int N_right = (xi2 - xi1)(xi1 + xi2)/2 >= 0, and int N' = -/+ (xi2 - xi1). Both are divided by
// the integrated length, so the weights sum to one and the gradients to zero to round-off even
// when the domain was clipped at a grid end. At most 3 cells are visited (l <= 2h, fits()); a
// domain on the limit may reach a 4th cell by round-off, whose O(eps h) piece is left out.
// A domain of zero length (l -> 0) gives the P1 basis at s_lo, the limit of the formulas.
inline void gimp_factors_1d(double s_lo, double s_hi, Index cells, double inv_h, Index& first,
                            std::array<double, kDomainPerDim>& w,
                            std::array<double, kDomainPerDim>& dw) {
  w.fill(0.0);
  dw.fill(0.0);
  const Index c_lo = clamped_cell(s_lo, cells);
  first = window_first(c_lo, cells + 1);
  const Index c_end = std::min(c_lo + 2, cells - 1);
  double len = 0.0;  // integrated length in cells
  for (Index c = c_lo; c <= c_end; ++c) {
    const double cd = static_cast<double>(c);
    const double xi1 = std::max(s_lo - cd, 0.0);
    const double xi2 = std::min(s_hi - cd, 1.0);
    if (!(xi2 > xi1)) continue;
    const double piece = xi2 - xi1, mid = 0.5 * (xi1 + xi2);
    const auto k = static_cast<std::size_t>(c - first);
    w[k] += piece * (1.0 - mid);
    w[k + 1] += piece * mid;
    dw[k] -= piece;
    dw[k + 1] += piece;
    len += piece;
  }
  if (len > 0.0) {
    const double inv_len = 1.0 / len;
    for (std::size_t k = 0; k < w.size(); ++k) {
      w[k] *= inv_len;
      dw[k] *= inv_len * inv_h;  // (1/l) (N_i(b) - N_i(a)) [1/m]
    }
    return;
  }
  // Zero-length domain: P1 at s_lo (D eq. 2.56).
  const auto k = static_cast<std::size_t>(c_lo - first);
  const double xi = std::clamp(s_lo - static_cast<double>(c_lo), 0.0, 1.0);
  w[k] = 1.0 - xi;
  w[k + 1] = xi;
  dw[k] = -inv_h;
  dw[k + 1] = inv_h;
}

// GIMP with the particle size chosen by the derived class (uGIMP, cpGIMP).
template <int Dim, bool kSizeFromF>
class GimpBasis : public NodalDomainBasis<Dim> {
  using Base = NodalDomainBasis<Dim>;

 public:
  using Base::kPerDim;
  using typename Base::StencilT;

  explicit GimpBasis(const Grid<Dim>& g) : Base(g) {}

  // Side length of the particle domain along d [m] (D eq. 2.63: l_p).
  double length(const Particles<Dim>& P, Index p, int d) const {
    if constexpr (kSizeFromF) {
      return cpgimp_side(this->grid_, P, p, d);
    } else {
      return this->initial_length(P, p, d);
    }
  }

  // Whether the stencil can hold the domain: 0 < l_d <= 2 h_d (also false for NaN) and x_p in
  // the grid. No allocation, no exceptions.
  bool fits(const Particles<Dim>& P, Index p) const {
    if (!this->grid_.inside(P.x[static_cast<std::size_t>(p)])) return false;
    for (int d = 0; d < Dim; ++d) {
      const double l = length(P, p, d);
      if (!(l > 0.0 && l <= 2.0 * this->grid_.h[d])) return false;
    }
    return true;
  }

  // Requires fits(P, p); the caller checks. A domain reaching past a grid end is clipped to the
  // grid and the averages are taken over the clipped part, so partition of unity still holds
  // (there are no basis functions outside the grid to carry the rest).
  void evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
    const Vec<Dim>& x = P.x[static_cast<std::size_t>(p)];
    IVec<Dim> first;
    std::array<std::array<double, kPerDim>, Dim> w, dw;
    for (int d = 0; d < Dim; ++d) {
      const auto cells = static_cast<double>(this->grid_.cells[d]);
      const double sp = (x[d] - this->grid_.origin[d]) * this->inv_h_[d];
      const double half = 0.5 * length(P, p, d) * this->inv_h_[d];
      const double s_lo = std::clamp(sp - half, 0.0, cells);
      const double s_hi = std::clamp(sp + half, 0.0, cells);
      gimp_factors_1d(s_lo, s_hi, this->grid_.cells[d], this->inv_h_[d], first[d],
                      w[static_cast<std::size_t>(d)], dw[static_cast<std::size_t>(d)]);
    }
    this->assemble(first, w, dw, s);
  }
};

}  // namespace detail

// Uniform GIMP: the initial particle size at every time level (D 2.6.4).
template <int Dim>
class UGimpBasis : public detail::GimpBasis<Dim, false> {
 public:
  static constexpr std::string_view kName = "ugimp";
  using detail::GimpBasis<Dim, false>::GimpBasis;
};

// Contiguous-particle GIMP: size l_d = F_dd l0_d from the diagonal of F (D 2.6.4).
template <int Dim>
class CpGimpBasis : public detail::GimpBasis<Dim, true> {
 public:
  static constexpr std::string_view kName = "cpgimp";
  using detail::GimpBasis<Dim, true>::GimpBasis;
};

// The basis concept (basis/basis.hpp).
static_assert(Basis<UGimpBasis<1>, 1> && Basis<UGimpBasis<2>, 2>);
static_assert(Basis<CpGimpBasis<1>, 1> && Basis<CpGimpBasis<2>, 2>);

}  // namespace mpm
