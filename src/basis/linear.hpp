#pragma once
// Piecewise-linear Lagrange (P1) basis on a uniform grid, tensor product in Dim > 1
// (D eq. 2.56-2.57). DOFs are the grid nodes, x fastest.
#include <string_view>
#include <vector>

#include "basis/stencil.hpp"
#include "grid/grid.hpp"
#include "particles/particles.hpp"

namespace mpm {

template <int Dim>
class LinearBasis {
 public:
  static constexpr std::string_view kName = "linear";
  static constexpr int kPerDim = 2;
  using StencilT = Stencil<Dim, ipow(kPerDim, Dim)>;
  using CachedStencilT = TensorStencil<Dim, kPerDim>;

  explicit LinearBasis(const Grid<Dim>& g) : grid_(g) {
    for (int d = 0; d < Dim; ++d) {
      n_[d] = g.cells[d] + 1;
      inv_h_[d] = 1.0 / g.h[d];
    }
    stride_ = dof_strides<Dim>(n_);
  }

  const Grid<Dim>& grid() const { return grid_; }
  IVec<Dim> dofs_per_dim() const { return n_; }
  Index num_dofs() const { return dof_count<Dim>(n_); }
  // Position of a DOF (the node), for output and boundary conditions.
  Vec<Dim> dof_position(Index i) const { return node_position<Dim>(grid_.origin, grid_.h, n_, i); }
  // DOFs prescribed by a Dirichlet condition on the grid side `side` (0 lower, 1 upper) normal
  // to direction d: the nodes on that side (P1 is interpolatory there).
  std::vector<Index> boundary_dofs(int d, int side) const { return side_dofs<Dim>(n_, d, side); }

  // Requires grid().inside(P.x[p]); the caller checks.
  void evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
    evaluate_point(P.x[static_cast<std::size_t>(p)], s);
  }
  // The compact form cached per particle (basis/stencil.hpp, TensorStencil).
  void evaluate(const Particles<Dim>& P, Index p, CachedStencilT& s) const {
    IVec<Dim> first;
    factors(P.x[static_cast<std::size_t>(p)], first, s.w, s.dw);
    s.dof0 = 0;
    for (int d = 0; d < Dim; ++d) s.dof0 += first[d] * stride_[d];
  }

  // The basis at any point inside the grid (tractions, quadrature points).
  void evaluate_point(const Vec<Dim>& x, StencilT& s) const {
    IVec<Dim> first;
    std::array<std::array<double, 2>, Dim> w, dw;
    factors(x, first, w, dw);
    tensor_product<Dim, 2>(first, w, dw, n_, s);
  }

 private:
  // The 1D factors at x: the first node per direction, values and derivatives [1/m].
  void factors(const Vec<Dim>& x, IVec<Dim>& first, std::array<std::array<double, 2>, Dim>& w,
               std::array<std::array<double, 2>, Dim>& dw) const {
    for (int d = 0; d < Dim; ++d) {
      // Same rounding as Grid::cell_of, so xi = s - c lies in [0, 1] exactly (no negative
      // weights from round-off at the nodes).
      const double s_d = (x[d] - grid_.origin[d]) / grid_.h[d];
      const Index c = grid_.cell_of(x[d], d);
      const double xi = s_d - static_cast<double>(c);
      first[d] = c;
      w[d] = {1.0 - xi, xi};
      dw[d] = {-inv_h_[d], inv_h_[d]};
    }
  }

  Grid<Dim> grid_;
  IVec<Dim> n_{}, stride_{};
  Vec<Dim> inv_h_;
};

}  // namespace mpm
