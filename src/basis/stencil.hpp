#pragma once
// A particle's view of the grid basis: the degrees of freedom whose functions do not vanish at
// the particle, with values and gradients. Fixed size per basis, so stages never allocate.
#include <array>
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
