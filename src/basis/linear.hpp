#pragma once
// Piecewise-linear Lagrange (P1) basis on a uniform grid, tensor product in Dim > 1
// (D eq. 2.56-2.57). DOFs are the grid nodes, x fastest.
#include <string_view>
#include <vector>

#include "basis/basis.hpp"
#include "basis/stencil.hpp"
#include "grid/grid.hpp"
#include "particles/particles.hpp"

namespace mpm {

template <int Dim>
class LinearBasis {
 public:
  static constexpr std::string_view kName = "linear";
  static constexpr int kPerDim = 2;
  // Capabilities (basis/basis.hpp): compact tensor-product stencils evaluated from cell
  // coordinates; no particle domain, no preparation pass, no tracked per-particle state.
  static constexpr bool kTensorProduct = true, kParticleDomain = false, kPrepare = false,
                        kNodalSums = false, kTrackedCorners = false, kIterative = false,
                        kTriangleMesh = false;
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

  // The compact form from the position in cell units s = (x - origin) / h and the cell c
  // (cell_of_scaled), which stages::evaluate_basis has already computed for its checks.
  void evaluate_scaled(const Vec<Dim>& s, const IVec<Dim>& c, CachedStencilT& st) const {
    factors_scaled(s, c, st.w, st.dw);
    st.dof0 = 0;
    for (int d = 0; d < Dim; ++d) st.dof0 += c[d] * stride_[d];
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
    Vec<Dim> s;
    for (int d = 0; d < Dim; ++d) {
      s[d] = (x[d] - grid_.origin[d]) / grid_.h[d];
      first[d] = cell_of_scaled(s[d], grid_.cells[d]);
    }
    factors_scaled(s, first, w, dw);
  }
  // The same from s = (x - origin) / h and the cell c = cell_of_scaled(s): xi = s - c lies in
  // [0, 1] exactly (Grid::cell_of's rounding), so no weight is negative from round-off.
  void factors_scaled(const Vec<Dim>& s, const IVec<Dim>& c,
                      std::array<std::array<double, 2>, Dim>& w,
                      std::array<std::array<double, 2>, Dim>& dw) const {
    for (int d = 0; d < Dim; ++d) {
      const double xi = s[d] - static_cast<double>(c[d]);
      w[d] = {1.0 - xi, xi};
      dw[d] = {-inv_h_[d], inv_h_[d]};
    }
  }

  Grid<Dim> grid_;
  IVec<Dim> n_{}, stride_{};
  Vec<Dim> inv_h_;
};

// The basis concept (basis/basis.hpp).
static_assert(Basis<LinearBasis<1>, 1> && Basis<LinearBasis<2>, 2>);

}  // namespace mpm
