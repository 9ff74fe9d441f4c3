#pragma once
// B-spline basis of degree p on a uniform grid, tensor product in Dim > 1 (D 3.1.1, 004 sec. 4.3,
// 001 eq. 2-5). One open uniform knot vector per direction: p+1 copies of the lower end, the
// interior cell boundaries, p+1 copies of the upper end, so the knot spans are the grid cells and
// there are cells+p functions per direction. The parametric and physical domains coincide
// (D 3.1.1), so derivatives are taken directly with respect to x. DOFs are the control points,
// x fastest; degree 1 reproduces LinearBasis (D 3.1: linear B-splines are the P1 functions).
#include <algorithm>
#include <array>
#include <stdexcept>
#include <string_view>
#include <type_traits>
#include <vector>

#include "basis/basis.hpp"
#include "basis/stencil.hpp"
#include "grid/grid.hpp"
#include "particles/particles.hpp"

namespace mpm {

// Non-zero B-splines of degree P on one span of an open uniform knot vector with n spans, and
// their derivatives with respect to the span coordinate (units: 1/cell). c is the span (cell)
// index, t in [0, 1] the position inside it; value r belongs to function c + r.
//
// Knots are measured in cell units relative to the span's lower knot, so the knots needed are
// small integers computed on the fly (repeated end knots are clamped indices): no knot array and
// no dependence on the number of knots. With knot U_k = clamp(k - P, 0, n) and span index
// i = c + P, The NURBS Book's left[j] = u - U_{i+1-j} and right[j] = U_{i+j} - u become
//   left[j] = t + min(j - 1, c),   right[j] = min(j, n - c) - t,
// both >= 0 for t in [0, 1]. The triangular recursion (Piegl & Tiller A2.2/A2.3) then only adds
// and multiplies non-negative numbers and divides by knot differences >= 1, so no weight can
// come out negative from round-off.
template <int P>
inline void bspline_span_recursion(Index c, double t, Index n, std::array<double, P + 1>& N,
                                   std::array<double, P + 1>& dN) {
  static_assert(P >= 1, "degree 0 has no derivative");
  std::array<double, P + 1> left{}, right{};
  // ndu[r][j] (r <= j): value of function r of degree j on this span (upper triangle);
  // ndu[j][r] (r < j): knot difference U_{i+r+1} - U_{i+r+1-j} used at degree j (lower one).
  std::array<std::array<double, P + 1>, P + 1> ndu{};
  ndu[0][0] = 1.0;
  for (int j = 1; j <= P; ++j) {
    left[j] = t + static_cast<double>(std::min<Index>(j - 1, c));
    right[j] = static_cast<double>(std::min<Index>(j, n - c)) - t;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];
      const double temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  // First derivative from the degree P-1 functions (A2.3 with one derivative; D 3.1.1):
  //   dN_r = P (N_{r-1,P-1} / (U_{i+r} - U_{i+r-P}) - N_{r,P-1} / (U_{i+r+1} - U_{i+r+1-P})),
  // where the out-of-span degree P-1 functions (r-1 = -1, r = P) vanish. 001 eq. 3 prints a '+'
  // between the terms; the minus (D 3.1.1, 004 eq. 4.23) is the correct sign.
  for (int r = 0; r <= P; ++r) {
    N[r] = ndu[r][P];
    double d = 0.0;
    if (r >= 1) d += ndu[r - 1][P - 1] / ndu[P][r - 1];
    if (r <= P - 1) d -= ndu[r][P - 1] / ndu[P][r];
    dN[r] = static_cast<double>(P) * d;
  }
}

// Spans whose P knots on either side are all distinct, c in [P - 1, n - P]: there the knots are
// uniform (spacing 1 in cell units) and the B-splines are the translates of the cardinal
// B-spline, polynomials in t with constant coefficients (de Boor, A Practical Guide to Splines,
// IX; the uniform quadratic and cubic weights of 001 eq. 4-5 and Steffen et al. 2008). Degrees 2
// and 3 have them here; other degrees and the end spans of the open knot vector use the
// recursion. They equal the recursion up to round-off (tests/basis/test_bspline.cpp) and are
// non-negative in floating point: every term below is a square, a cube or a sum of
// non-negative numbers for t in [0, 1].
template <int P>
inline constexpr bool kBsplineClosedForm = P == 2 || P == 3;

template <int P>
inline void bspline_span_uniform(double t, std::array<double, P + 1>& N,
                                 std::array<double, P + 1>& dN) {
  static_assert(kBsplineClosedForm<P>);
  const double s = 1.0 - t;  // distance to the span's upper knot
  if constexpr (P == 2) {
    // N = (s^2, 1 + 2 t s, t^2) / 2, dN/dt = (-s, s - t, t).
    N = {0.5 * s * s, 0.5 + t * s, 0.5 * t * t};
    dN = {-s, s - t, t};
  } else {
    // N_0 = s^3 / 6, N_1 = (4 - 6 t^2 + 3 t^3) / 6 = 2/3 - t^2 (1 - t/2), N_2 = N_1(s),
    // N_3 = t^3 / 6; dN/dt = (-s^2 / 2, t (3 t / 2 - 2), -s (3 s / 2 - 2), t^2 / 2).
    constexpr double kSixth = 1.0 / 6.0, kTwoThirds = 2.0 / 3.0;
    N = {kSixth * s * s * s, kTwoThirds - t * t * (1.0 - 0.5 * t),
         kTwoThirds - s * s * (1.0 - 0.5 * s), kSixth * t * t * t};
    dN = {-0.5 * s * s, t * (1.5 * t - 2.0), -s * (1.5 * s - 2.0), 0.5 * t * t};
  }
}

// The non-zero B-splines of degree P on span c (see bspline_span_recursion): the closed form on
// uniform spans of degrees 2 and 3, the recursion elsewhere.
template <int P>
inline void bspline_span(Index c, double t, Index n, std::array<double, P + 1>& N,
                         std::array<double, P + 1>& dN) {
  if constexpr (kBsplineClosedForm<P>) {
    if (c >= P - 1 && c <= n - P) {
      bspline_span_uniform<P>(t, N, dN);
      return;
    }
  }
  bspline_span_recursion<P>(c, t, n, N, dN);
}

template <int Dim, int Degree>
class BSplineBasis {
  static_assert(Degree >= 1, "B-spline MPM needs gradients: degree >= 1");

 public:
  static constexpr std::string_view kName = "bspline";
  static constexpr int kDegree = Degree;
  static constexpr int kPerDim = Degree + 1;
  // Capabilities (basis/basis.hpp): compact tensor-product stencils evaluated from cell
  // coordinates; no particle domain, no preparation pass, no tracked per-particle state.
  static constexpr bool kTensorProduct = true, kParticleDomain = false, kPrepare = false,
                        kNodalSums = false, kTrackedCorners = false, kIterative = false,
                        kTriangleMesh = false;
  using StencilT = Stencil<Dim, ipow(Degree + 1, Dim)>;
  using CachedStencilT = TensorStencil<Dim, Degree + 1>;

  explicit BSplineBasis(const Grid<Dim>& g) : grid_(g) {
    for (int d = 0; d < Dim; ++d) {
      n_[d] = g.cells[d] + Degree;  // functions = knots - degree - 1 = cells + degree
      inv_h_[d] = 1.0 / g.h[d];
    }
    stride_ = dof_strides<Dim>(n_);
  }

  const Grid<Dim>& grid() const { return grid_; }
  IVec<Dim> dofs_per_dim() const { return n_; }
  Index num_dofs() const { return dof_count<Dim>(n_); }
  // Greville abscissa of a DOF, xi*_j = (U_{j+1} + ... + U_{j+p}) / p per direction: the point
  // with sum_j phi_j xi*_j = x, so it is where a control value "sits" (output, boundary
  // conditions, linear initial fields). For p = 1 these are the grid nodes.
  Vec<Dim> dof_position(Index i) const {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) {
      const Index j = i % n_[d];
      i /= n_[d];
      Index sum = 0;  // knots in cell units from the origin, end knots clamped
      for (int k = 1; k <= Degree; ++k) sum += std::clamp<Index>(j + k - Degree, 0, grid_.cells[d]);
      x[d] = grid_.origin[d] + grid_.h[d] * static_cast<double>(sum) / static_cast<double>(Degree);
    }
    return x;
  }
  // DOFs prescribed by a Dirichlet condition on the grid side `side` (0 lower, 1 upper) normal to
  // direction d: the first / last function in that direction. With an open knot vector these are
  // the only functions non-zero on that side and equal 1 there (D 3.1.1, interpolatory ends), so
  // fixing them prescribes the boundary value.
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

  // Basis at any point with grid().inside(x).
  void evaluate_point(const Vec<Dim>& x, StencilT& s) const {
    IVec<Dim> first;
    std::array<std::array<double, Degree + 1>, Dim> w, dw;
    factors(x, first, w, dw);
    tensor_product<Dim, Degree + 1>(first, w, dw, n_, s);
  }

 private:
  // The 1D factors at x: the first function per direction, values and derivatives [1/m].
  void factors(const Vec<Dim>& x, IVec<Dim>& first,
               std::array<std::array<double, Degree + 1>, Dim>& w,
               std::array<std::array<double, Degree + 1>, Dim>& dw) const {
    Vec<Dim> s;
    for (int d = 0; d < Dim; ++d) {
      s[d] = (x[d] - grid_.origin[d]) / grid_.h[d];
      first[d] = cell_of_scaled(s[d], grid_.cells[d]);  // span c supports functions c .. c + p
    }
    factors_scaled(s, first, w, dw);
  }
  // The same from s = (x - origin) / h and the span c = cell_of_scaled(s): t = s - c lies in
  // [0, 1] exactly (Grid::cell_of's rounding, upper end in the last span), which keeps every
  // left/right term in bspline_span_recursion non-negative.
  void factors_scaled(const Vec<Dim>& s, const IVec<Dim>& c,
                      std::array<std::array<double, Degree + 1>, Dim>& w,
                      std::array<std::array<double, Degree + 1>, Dim>& dw) const {
    for (int d = 0; d < Dim; ++d) {
      const double t = s[d] - static_cast<double>(c[d]);
      bspline_span<Degree>(c[d], t, grid_.cells[d], w[d], dw[d]);
      for (double& v : dw[d]) v *= inv_h_[d];  // d/dx = (1/h) d/dt [1/m]
    }
  }

  Grid<Dim> grid_;
  IVec<Dim> n_{}, stride_{};
  Vec<Dim> inv_h_;
};

// The basis concept (basis/basis.hpp).
static_assert(Basis<BSplineBasis<1, 2>, 1> && Basis<BSplineBasis<2, 3>, 2>);

// fn(std::integral_constant<int, P>{}) for a B-spline degree p = 1..5 chosen at run time
// (solver/spline_matrices.cpp, methods/otm.cpp); std::invalid_argument for another degree (the
// callers validate the degree of their input first).
template <class Fn>
decltype(auto) with_bspline_degree(int p, Fn&& fn) {
  switch (p) {
    case 1:
      return fn(std::integral_constant<int, 1>{});
    case 2:
      return fn(std::integral_constant<int, 2>{});
    case 3:
      return fn(std::integral_constant<int, 3>{});
    case 4:
      return fn(std::integral_constant<int, 4>{});
    case 5:
      return fn(std::integral_constant<int, 5>{});
    default:
      throw std::invalid_argument("with_bspline_degree: the degrees are 1 to 5");
  }
}

}  // namespace mpm
