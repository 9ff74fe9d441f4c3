#pragma once
// A particle's view of the grid basis: the degrees of freedom whose functions do not vanish at
// the particle, with values and gradients. Fixed size per basis, so stages never allocate.
#include <algorithm>
#include <array>
#include <type_traits>
#include <vector>

#include "core/types.hpp"

namespace mpm {

template <int Dim, int N>
struct Stencil {
  static constexpr int kSize = N;
  std::array<Index, N> dof;      // linear DOF indices
  std::array<double, N> w;       // phi_i(x_p)
  std::array<Vec<Dim>, N> grad;  // grad phi_i(x_p) [1/m]
};

// Tensor-product assembly from 1D factors: K functions per direction starting at first[d].
// dofs_per_dim gives the DOF layout (x fastest). D 2.5: multivariate bases as tensor products.
template <int Dim, int K>
inline void tensor_product(const IVec<Dim>& first, const std::array<std::array<double, K>, Dim>& w,
                           const std::array<std::array<double, K>, Dim>& dw,
                           const IVec<Dim>& dofs_per_dim, Stencil<Dim, ipow(K, Dim)>& s) {
  constexpr int N = ipow(K, Dim);
  for (int n = 0; n < N; ++n) {
    int rem = n;
    Index dof = 0, stride = 1;
    std::array<int, Dim> k{};
    for (int d = 0; d < Dim; ++d) {
      k[d] = rem % K;
      rem /= K;
      dof += (first[d] + k[d]) * stride;
      stride *= dofs_per_dim[d];
    }
    double value = 1.0;
    for (int d = 0; d < Dim; ++d) value *= w[d][k[d]];
    Vec<Dim> g;
    for (int d = 0; d < Dim; ++d) {
      double gd = dw[d][k[d]];
      for (int e = 0; e < Dim; ++e)
        if (e != d) gd *= w[e][k[e]];
      g[d] = gd;
    }
    s.dof[n] = dof;
    s.w[n] = value;
    s.grad[n] = g;
  }
}

// Grid::cell_of from the position in cell units s = (x - origin) / h, already computed, of a
// point inside the grid (s in [0, cells]): the same cell (the upper end belongs to the last
// cell) without a second division.
// s >= 0, so truncation is the floor (and needs no libm call without SSE4.1).
inline Index cell_of_scaled(double s, Index cells) {
  const auto c = static_cast<Index>(s);
  return c < cells ? c : cells - 1;
}

// The compact cached form of a tensor-product stencil (linear, B-spline bases): the first DOF
// and the K 1D values and derivatives per direction, expanded on use by for_each_entry. The
// expansion forms the same products in the same order as tensor_product, so every value and
// gradient is bitwise the one a full Stencil would hold, for a quarter to a third of the bytes
// (quadratic 2D: 8 + 2 x 2 x 3 x 8 = 104 bytes instead of 9 x (8 + 8 + 16) = 288).
template <int Dim, int K>
struct TensorStencil {
  static constexpr int kSize = ipow(K, Dim);
  Index dof0;                                 // DOF of the first function in every direction
  std::array<std::array<double, K>, Dim> w;   // 1D values per direction
  std::array<std::array<double, K>, Dim> dw;  // 1D derivatives per direction [1/m]
};

// DOF strides of a tensor-product layout with n[d] functions per direction, x fastest.
template <int Dim>
IVec<Dim> dof_strides(const IVec<Dim>& n) {
  IVec<Dim> s;
  s[0] = 1;
  for (int d = 1; d < Dim; ++d) s[d] = s[d - 1] * n[d - 1];
  return s;
}

// f(dof, phi, grad phi) for every entry of a stencil, in entry order (x fastest). `stride`
// (dof_strides of the basis) is used by the compact form only.
template <int Dim, int N, class F>
inline void for_each_entry(const Stencil<Dim, N>& s,
                           const std::type_identity_t<IVec<Dim>>& /*stride*/, F&& f) {
  for (int a = 0; a < N; ++a) f(s.dof[a], s.w[a], s.grad[a]);
}

template <int Dim, int K, class F>
inline void for_each_entry(const TensorStencil<Dim, K>& s,
                           const std::type_identity_t<IVec<Dim>>& stride, F&& f) {
  // tensor_product: value = 1 * w_0 * w_1 * ..., gradient d = dw_d * w_e (e != d, ascending).
  if constexpr (Dim == 1) {
    for (int i = 0; i < K; ++i) f(s.dof0 + i, s.w[0][i], Vec<1>(s.dw[0][i]));
  } else if constexpr (Dim == 2) {
    for (int j = 0; j < K; ++j)
      for (int i = 0; i < K; ++i)
        f(s.dof0 + i + j * stride[1], s.w[0][i] * s.w[1][j],
          Vec<2>(s.dw[0][i] * s.w[1][j], s.dw[1][j] * s.w[0][i]));
  } else {
    static_assert(Dim == 3, "dimensions 1-3");
    for (int k = 0; k < K; ++k)
      for (int j = 0; j < K; ++j)
        for (int i = 0; i < K; ++i)
          f(s.dof0 + i + j * stride[1] + k * stride[2], s.w[0][i] * s.w[1][j] * s.w[2][k],
            Vec<3>(s.dw[0][i] * s.w[1][j] * s.w[2][k], s.dw[1][j] * s.w[0][i] * s.w[2][k],
                   s.dw[2][k] * s.w[0][i] * s.w[1][j]));
  }
}

// The smallest and largest DOF of a stencil.
template <int Dim, int N>
inline std::array<Index, 2> dof_bounds(const Stencil<Dim, N>& s,
                                       const std::type_identity_t<IVec<Dim>>& /*stride*/) {
  Index lo = s.dof[0], hi = s.dof[0];
  for (int a = 1; a < N; ++a) {
    lo = std::min(lo, s.dof[a]);
    hi = std::max(hi, s.dof[a]);
  }
  return {lo, hi};
}

template <int Dim, int K>
inline std::array<Index, 2> dof_bounds(const TensorStencil<Dim, K>& s,
                                       const std::type_identity_t<IVec<Dim>>& stride) {
  Index hi = s.dof0;
  for (int d = 0; d < Dim; ++d) hi += (K - 1) * stride[d];
  return {s.dof0, hi};
}

// The coordinates per direction of DOF `dof` in a layout with strides `stride` (dof_strides, x
// fastest). Layouts that are one row of DOFs (triangle bases: strides {1, n}) give {dof, 0}.
template <int Dim>
inline IVec<Dim> dof_coords(Index dof, const IVec<Dim>& stride) {
  IVec<Dim> c;
  for (int d = Dim - 1; d > 0; --d) {
    c[d] = dof / stride[d];
    dof -= c[d] * stride[d];
  }
  c[0] = dof;
  return c;
}

// Extends the box [lo, hi] of DOF coordinates (per direction, both ends held) by a stencil's
// DOFs: the box a process's stencils touch, whose intersection with a neighbour's is what the
// two share (state/dof_sharing.hpp).
template <int Dim, int N>
inline void extend_dof_box(const Stencil<Dim, N>& s, const std::type_identity_t<IVec<Dim>>& stride,
                           std::type_identity_t<IVec<Dim>>& lo,
                           std::type_identity_t<IVec<Dim>>& hi) {
  for (int a = 0; a < N; ++a) {
    const IVec<Dim> c = dof_coords<Dim>(s.dof[a], stride);
    for (int d = 0; d < Dim; ++d) {
      lo[d] = std::min(lo[d], c[d]);
      hi[d] = std::max(hi[d], c[d]);
    }
  }
}

template <int Dim, int K>
inline void extend_dof_box(const TensorStencil<Dim, K>& s,
                           const std::type_identity_t<IVec<Dim>>& stride,
                           std::type_identity_t<IVec<Dim>>& lo,
                           std::type_identity_t<IVec<Dim>>& hi) {
  const IVec<Dim> c = dof_coords<Dim>(s.dof0, stride);  // the first DOF in every direction
  for (int d = 0; d < Dim; ++d) {
    lo[d] = std::min(lo[d], c[d]);
    hi[d] = std::max(hi[d], c[d] + K - 1);
  }
}

// The stencil type a basis caches per particle: its compact CachedStencilT when it has one
// (tensor-product bases), else the full StencilT (GIMP, CPDI, DDMPM).
template <class Basis, bool kTensor = Basis::kTensorProduct>
struct CachedStencilOf {
  using type = typename Basis::StencilT;
};
template <class Basis>
struct CachedStencilOf<Basis, true> {
  using type = typename Basis::CachedStencilT;
};

// DOF layout of a tensor-product basis with n[d] functions per direction, x fastest: the
// count and the DOFs whose index in direction d is the first (side 0) or last (side 1).
template <int Dim>
Index dof_count(const IVec<Dim>& n) {
  Index c = 1;
  for (int d = 0; d < Dim; ++d) c *= n[d];
  return c;
}

template <int Dim>
std::vector<Index> side_dofs(const IVec<Dim>& n, int d, int side) {
  std::vector<Index> out;
  for (Index i = 0; i < dof_count<Dim>(n); ++i) {
    Index rem = i;
    for (int e = 0; e < d; ++e) rem /= n[e];
    if (rem % n[d] == (side == 0 ? 0 : n[d] - 1)) out.push_back(i);
  }
  return out;
}

// Position of grid node i (the DOFs of nodal bases), x fastest.
template <int Dim>
Vec<Dim> node_position(const Vec<Dim>& origin, const Vec<Dim>& h, const IVec<Dim>& n, Index i) {
  Vec<Dim> x;
  for (int d = 0; d < Dim; ++d) {
    x[d] = origin[d] + h[d] * static_cast<double>(i % n[d]);
    i /= n[d];
  }
  return x;
}

}  // namespace mpm
