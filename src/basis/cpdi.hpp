#pragma once
// Convected particle domain interpolation (CPDI), D 2.6.4 eq. 2.64-2.65 after Sadeghirad, Brannon
// & Burghardt (2011), and its quadrilateral form CPDI2 (Sadeghirad, Brannon & Guilkey 2013).
//
// CPDI (CpdiBasis). The particle domain is the parallelogram (parallelepiped) spanned by the
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
// Initial size l0_d: NodalDomainBasis::initial_length (V_p^0 in 1D; in Dim > 1 the domain is
// similar to the grid cell, exact for particles seeded k per cell and direction).
//
// Quadrilateral domains (2D; CPDI2, and CPDI domains clipped at the grid boundary). Corners x_c
// with the same numbering (bit 0: xi = +/-1, bit 1: eta = +/-1), bilinear map
//   x(xi, eta) = sum_c M_c x_c,   M_c = (1 + xi_c xi)(1 + eta_c eta) / 4,
// N_i replaced by sum_c N_i(x_c) M_c (Sadeghirad et al. 2013). The averages are again corner
// sums, w_i = sum_c wq_c N_i(x_c) and dw_i = sum_c gq_c N_i(x_c), with
//   wq_c = (1/V) int M_c dOmega,   gq_c = (1/V) int grad M_c dOmega   (D eq. 2.61-2.62).
// Writing x = a0 + a1 xi + a2 eta + a3 xi eta, det(dx/dxi) = J0 + J1 xi + J2 eta with
// J0 = a1 x a2, J1 = a1 x a3, J2 = a3 x a2 (2D cross product u x v = u_x v_y - u_y v_x), so
// V = 4 J0 and, integrating M_c det over [-1, 1]^2,
//   wq_c = 1/4 + (J1 xi_c + J2 eta_c) / (12 J0).
// By the divergence theorem gq_c = (1/V) boundary integral of M_c n; M_c is linear along the two
// edges at corner c and zero on the others, so with the corners taken counter-clockwise
//   gq_c = R(x_next - x_prev) / (2 V),   R(v) = (v_y, -v_x).
// These reduce to 1/4 and 2^-Dim J^-T s_c for a parallelogram. det > 0 at all four corners
// (a strictly convex, counter-clockwise quadrilateral) makes the map invertible and every
// wq_c > 1/4 - 1/12 > 0, so the weights are non-negative.
//
// Properties (D 2.5, P.1-P.3): sum_c wq_c = 1 and sum_c gq_c = 0 give partition of unity and a
// zero gradient sum; the map reproduces x, so sum_i dw_i x_i^T = I, and sum_i w_i x_i is the
// domain's centroid (x_p for the parallelogram).
//
// Stencil: 4 nodes per direction, a window starting at the lowest corner cell; contributions of
// the corners to the same node are added in its slot (DOFs merged, each node at most once).
// That is enough when the domain's extent along every direction is at most 2 h_d (the corners'
// P1 cells then span at most 3 cells); fits() enforces that limit.
//
// Grid boundary. A corner that passes the grid boundary is clamped onto it (each coordinate to
// [origin, upper]), as GIMP clips its domain, so the weights and gradients are those of the part
// of the domain inside the grid and partition of unity and the zero gradient sum hold (there are
// no basis functions outside the grid to carry the rest). This happens at fixed walls, where the
// material boundary sits on the grid boundary and a particle's averaged stretch moves its corners
// past it, and, to round-off, for any body that fills the grid. In 1D the clipped domain is the
// segment between the clamped corners. In 2D it is the quadrilateral of the clamped corners (the
// exact intersection of parallelogram and grid can be a pentagon; the quadrilateral is the
// natural CPDI2 approximation of it); fits() requires that quadrilateral to be strictly convex.
// In 3D it is the trilinear hexahedron of the clamped corners (hex_corner_weights), by
// the same reasoning; fits() requires its Jacobian to be positive at the corners and the Gauss
// points.
#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>
#include <utility>
#include <vector>

#include "basis/basis.hpp"
#include "basis/gimp.hpp"

namespace mpm {

// 2D cross product u x v [m^2 for lengths in m].
inline double cross2(const Vec<2>& u, const Vec<2>& v) {
  return u[0] * v[1] - u[1] * v[0];
}

// Corner weights wq_c and gradient vectors gq_c [1/m] of a quadrilateral domain (file comment;
// Sadeghirad et al. 2013). Corners numbered as the reference square (bit 0: xi, bit 1: eta).
// Returns false, with wq and gq zero, unless the quadrilateral is strictly convex and
// counter-clockwise in that numbering (det of the bilinear map > 0 at every corner) and finite.
inline bool quad_corner_weights(const std::array<Vec<2>, 4>& x, std::array<double, 4>& wq,
                                std::array<Vec<2>, 4>& gq) {
  // a1 = 1/4 sum xi_c x_c, a2 = 1/4 sum eta_c x_c, a3 = 1/4 sum xi_c eta_c x_c.
  const Vec<2> a1 = 0.25 * ((x[1] - x[0]) + (x[3] - x[2]));
  const Vec<2> a2 = 0.25 * ((x[2] - x[0]) + (x[3] - x[1]));
  const Vec<2> a3 = 0.25 * ((x[0] - x[1]) + (x[3] - x[2]));
  const double J0 = cross2(a1, a2), J1 = cross2(a1, a3), J2 = cross2(a3, a2);
  for (int c = 0; c < 4; ++c) {
    const double xi = (c & 1) ? 1.0 : -1.0, eta = (c & 2) ? 1.0 : -1.0;
    const double det = J0 + J1 * xi + J2 * eta;
    if (!(det > 0.0) || !std::isfinite(det)) {
      wq.fill(0.0);
      gq.fill(Vec<2>::Zero());
      return false;
    }
  }
  // Counter-clockwise ring 0 -> 1 -> 3 -> 2: next and previous corner of each corner.
  constexpr std::array<int, 4> kNext = {1, 3, 0, 2}, kPrev = {2, 0, 3, 1};
  const double inv_2V = 1.0 / (8.0 * J0);  // 1 / (2 V), V = 4 J0 [1/m^2]
  for (std::size_t c = 0; c < 4; ++c) {
    const double xi = (c & 1) ? 1.0 : -1.0, eta = (c & 2) ? 1.0 : -1.0;
    wq[c] = 0.25 + (J1 * xi + J2 * eta) / (12.0 * J0);
    const Vec<2> e = x[static_cast<std::size_t>(kNext[c])] - x[static_cast<std::size_t>(kPrev[c])];
    gq[c] = Vec<2>(e[1], -e[0]) * inv_2V;
  }
  return true;
}

// Corner weights wq_c and gradient vectors gq_c [1/m] of a hexahedral domain, the 3D analogue
// of quad_corner_weights for the trilinear map x(xi) = sum_c M_c(xi) x_c (corner c at
// xi_d = +1 where bit d of c is set, -1 otherwise; M_c = prod_d (1 + xi_cd xi_d) / 8):
//   wq_c = (1/V) int M_c det J dxi,   gq_c = (1/V) int cof(J) grad_xi M_c dxi,
//   V = int det J dxi over [-1, 1]^3,  J = dx/dxi,  cof(J) = det(J) J^-T = [b x c, c x a, a x b]
// for the columns a, b, c of J (gq_c = (1/V) int grad_x M_c dOmega, D eq. 2.62). Each column of J
// is bilinear in the other two coordinates, so det J has degree <= 2 in every xi_d, M_c det J
// and cof(J) grad_xi M_c degree <= 3: the 2 x 2 x 2 Gauss rule integrates all of them exactly.
// Hence sum_c wq_c = 1, sum_c gq_c = 0 (sum_c M_c = 1) and sum_c gq_c x_c^T = (1/V) int cof(J)
// J^T = I to round-off. For a parallelepiped wq_c = 1/8 and gq_c = J^-T xi_c / 8. Returns false,
// with wq and gq zero, unless det J is positive and finite at the eight corners and the eight
// Gauss points (a positive corner Jacobian alone does not exclude a folded trilinear map; no
// finite test does, but these sixteen points cover the clipped shapes of a convex domain).
inline bool hex_corner_weights(const std::array<Vec<3>, 8>& x, std::array<double, 8>& wq,
                               std::array<Vec<3>, 8>& gq) {
  auto sign = [](std::size_t c, int d) { return ((c >> d) & 1) ? 1.0 : -1.0; };
  // J at xi, and the derivatives dM_c/dxi at xi (into dM).
  auto jacobian = [&](const Vec<3>& xi, std::array<Vec<3>, 8>& dM) {
    Mat<3> J = Mat<3>::Zero();
    for (std::size_t c = 0; c < 8; ++c) {
      Vec<3> f;  // the 1D factors (1 + xi_cd xi_d) / 2
      for (int d = 0; d < 3; ++d) f[d] = 0.5 * (1.0 + sign(c, d) * xi[d]);
      dM[c] = 0.5 *
              Vec<3>(sign(c, 0) * f[1] * f[2], sign(c, 1) * f[0] * f[2], sign(c, 2) * f[0] * f[1]);
      J += x[c] * dM[c].transpose();
    }
    return J;
  };
  auto fail = [&] {
    wq.fill(0.0);
    gq.fill(Vec<3>::Zero());
    return false;
  };
  std::array<Vec<3>, 8> dM;
  for (std::size_t c = 0; c < 8; ++c) {
    const double det = jacobian(Vec<3>(sign(c, 0), sign(c, 1), sign(c, 2)), dM).determinant();
    if (!(det > 0.0) || !std::isfinite(det)) return fail();
  }
  const double g = 1.0 / std::sqrt(3.0);  // 2-point Gauss-Legendre nodes, weights 1
  double V = 0.0;
  std::array<double, 8> w{};
  std::array<Vec<3>, 8> gr;
  gr.fill(Vec<3>::Zero());
  for (std::size_t q = 0; q < 8; ++q) {
    const Vec<3> xi(g * sign(q, 0), g * sign(q, 1), g * sign(q, 2));
    const Mat<3> J = jacobian(xi, dM);
    const double det = J.determinant();
    if (!(det > 0.0) || !std::isfinite(det)) return fail();
    Mat<3> cof;
    cof.col(0) = J.col(1).cross(J.col(2));
    cof.col(1) = J.col(2).cross(J.col(0));
    cof.col(2) = J.col(0).cross(J.col(1));
    V += det;
    for (std::size_t c = 0; c < 8; ++c) {
      double M = 0.125;
      for (int d = 0; d < 3; ++d) M *= 1.0 + sign(c, d) * xi[d];
      w[c] += M * det;
      gr[c] += cof * dM[c];
    }
  }
  for (std::size_t c = 0; c < 8; ++c) {
    wq[c] = w[c] / V;
    gq[c] = gr[c] / V;
  }
  return true;
}

namespace detail {

// The corner-sum bases (CPDI, CPDI2) on the nodal 4-per-direction window: weights and gradients
// w_i = sum_c wc_c N_i(x_c), dw_i = sum_c N_i(x_c) gc_c, with N_i the P1 basis at the corners
// (D eq. 2.56). The corners must lie in the grid (clamped by the caller) and span at most 2 h_d
// per direction (fits()); if that is broken, contributions that fall outside the window are
// dropped so memory stays safe, but the result is meaningless.
template <int Dim, int kCorners>
void corner_sum_stencil(const Grid<Dim>& g, const Vec<Dim>& inv_h, const IVec<Dim>& n,
                        const std::array<Vec<Dim>, kCorners>& x,
                        const std::array<double, kCorners>& wc,
                        const std::array<Vec<Dim>, kCorners>& gc,
                        Stencil<Dim, ipow(kDomainPerDim, Dim)>& s) {
  constexpr int kPerDim = kDomainPerDim;
  constexpr int kCellNodes = ipow(2, Dim);
  // Grid coordinates and P1 cells of the corners; the stencil window starts at the lowest.
  std::array<Vec<Dim>, kCorners> xi;
  std::array<IVec<Dim>, kCorners> cell;
  IVec<Dim> first;
  for (int d = 0; d < Dim; ++d) {
    Index c_min = g.cells[d];
    for (std::size_t c = 0; c < x.size(); ++c) {
      const double sd = (x[c][d] - g.origin[d]) * inv_h[d];
      cell[c][d] = clamped_cell(sd, g.cells[d]);
      xi[c][d] = std::clamp(sd - static_cast<double>(cell[c][d]), 0.0, 1.0);
      c_min = std::min(c_min, cell[c][d]);
    }
    first[d] = window_first(c_min, n[d]);
  }
  // Slot DOFs as NodalDomainBasis::slot_dof (slots past the last node repeat it, weight zero).
  for (int k = 0; k < Stencil<Dim, ipow(kPerDim, Dim)>::kSize; ++k) {
    Index dof = 0, stride = 1;
    int rem = k;
    for (int d = 0; d < Dim; ++d) {
      dof += std::min<Index>(first[d] + rem % kPerDim, n[d] - 1) * stride;
      rem /= kPerDim;
      stride *= n[d];
    }
    s.dof[static_cast<std::size_t>(k)] = dof;
    s.w[static_cast<std::size_t>(k)] = 0.0;
    s.grad[static_cast<std::size_t>(k)] = Vec<Dim>::Zero();
  }
  for (std::size_t c = 0; c < x.size(); ++c) {
    // The 2^Dim P1 nodes of the corner's cell (D eq. 2.56), tensor product.
    for (int b = 0; b < kCellNodes; ++b) {
      int slot = 0, stride = 1;
      double N = 1.0;
      bool inside = true;
      for (int d = 0; d < Dim; ++d) {
        const int bd = (b >> d) & 1;
        const Index k = cell[c][d] + bd - first[d];
        if (k < 0 || k >= kPerDim) inside = false;
        slot += static_cast<int>(k) * stride;
        stride *= kPerDim;
        N *= bd ? xi[c][d] : 1.0 - xi[c][d];
      }
      if (!inside) continue;
      s.w[static_cast<std::size_t>(slot)] += wc[c] * N;
      s.grad[static_cast<std::size_t>(slot)] += N * gc[c];
    }
  }
}

// Clamps x into the grid box; returns whether it moved.
template <int Dim>
bool clamp_to_grid(const Grid<Dim>& g, Vec<Dim>& x) {
  const Vec<Dim> hi = g.upper();
  bool moved = false;
  for (int d = 0; d < Dim; ++d) {
    const double c = std::clamp(x[d], g.origin[d], hi[d]);
    moved |= c != x[d];
    x[d] = c;
  }
  return moved;
}

// Whether corner positions span at most 2 h_d along every direction (the 4-node window); false
// for NaN.
template <int Dim, std::size_t K>
bool corners_within_window(const Grid<Dim>& g, const std::array<Vec<Dim>, K>& x) {
  for (int d = 0; d < Dim; ++d) {
    double lo = x[0][d], hi = x[0][d];
    for (const auto& xc : x) {
      lo = std::min(lo, xc[d]);
      hi = std::max(hi, xc[d]);
    }
    if (!(hi - lo <= 2.0 * g.h[d])) return false;
  }
  return true;
}

}  // namespace detail

template <int Dim>
class CpdiBasis : public NodalDomainBasis<Dim> {
  using Base = NodalDomainBasis<Dim>;
  static constexpr int kCorners = ipow(2, Dim);

 public:
  static constexpr std::string_view kName = "cpdi";
  using Base::kPerDim;
  using typename Base::StencilT;

  explicit CpdiBasis(const Grid<Dim>& g) : Base(g) {}

  // Corners x_c of the convected domain (D eq. 2.64-2.65), clamped to the grid (file comment);
  // corner c has s_{c,d} = +1 where bit d of c is set. `clipped` tells whether any moved.
  std::array<Vec<Dim>, kCorners> corners(const Particles<Dim>& P, Index p,
                                         bool* clipped = nullptr) const {
    const auto i = static_cast<std::size_t>(p);
    const Mat<Dim> J = this->half_edges(P, p);
    std::array<Vec<Dim>, kCorners> x;
    bool moved = false;
    for (int c = 0; c < kCorners; ++c) {
      auto& xc = x[static_cast<std::size_t>(c)];
      xc = P.x[i];
      for (int d = 0; d < Dim; ++d) xc += (((c >> d) & 1) ? 1.0 : -1.0) * J.col(d);
      if constexpr (Dim == 1) {
        xc[0] = std::clamp(xc[0], this->grid_.origin[0], this->grid_.upper()[0]);
      } else {
        moved |= detail::clamp_to_grid(this->grid_, xc);
      }
    }
    if (clipped) *clipped = moved;
    return x;
  }

  // Whether the stencil can hold the domain: extent <= 2 h_d along every direction, x_p in the
  // grid, a non-degenerate, non-inverted domain (det J > 0), and, where corners were clamped to
  // the grid, a strictly convex clipped quadrilateral (2D) or a clipped hexahedron with positive
  // Jacobian (3D). False for NaN. No allocation, no
  // exceptions.
  bool fits(const Particles<Dim>& P, Index p) const {
    const auto i = static_cast<std::size_t>(p);
    // Extent along d is 2 sum_e |J_de|, taken from J rather than from corner differences so
    // that the limit does not depend on the position by round-off.
    const Mat<Dim> J = this->half_edges(P, p);
    for (int d = 0; d < Dim; ++d)
      if (!(J.row(d).cwiseAbs().sum() <= this->grid_.h[d])) return false;
    if (!this->grid_.inside(P.x[i])) return false;
    bool clipped = false;
    const auto x = corners(P, p, &clipped);
    for (const auto& xc : x)
      if (!this->grid_.inside(xc)) return false;  // never after clamping unless NaN
    // In 1D the gradient divides by x_2 - x_1, so the corners must differ after round-off too.
    if constexpr (Dim == 1) {
      return x[1][0] > x[0][0];
    } else {
      const double det = J.determinant();
      if (!(det > 0.0 && std::isfinite(det))) return false;
      if (!clipped) return true;
      std::array<double, kCorners> wq;
      std::array<Vec<Dim>, kCorners> gq;
      if constexpr (Dim == 2)
        return quad_corner_weights(x, wq, gq);
      else
        return hex_corner_weights(x, wq, gq);
    }
  }

  // Requires fits(P, p); the caller checks.
  void evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
    bool clipped = false;
    const auto x = corners(P, p, &clipped);
    constexpr double kAvg = 1.0 / kCorners;
    std::array<double, kCorners> wc;
    std::array<Vec<Dim>, kCorners> gc;
    wc.fill(kAvg);
    if constexpr (Dim >= 2) {
      // A clipped domain is the quadrilateral (2D) or hexahedron (3D) of its clamped corners
      // (file comment).
      bool ok = false;
      if (clipped) {
        if constexpr (Dim == 2)
          ok = quad_corner_weights(x, wc, gc);
        else
          ok = hex_corner_weights(x, wc, gc);
      }
      if (ok) {
        detail::corner_sum_stencil<Dim, kCorners>(this->grid_, this->inv_h_, this->n_, x, wc, gc,
                                                  s);
        return;
      }
      wc.fill(kAvg);
    }
    // 2^-Dim J^-T s_c: in 1D from the computed corners, 1 / (x_2 - x_1) each way, so that
    // sum_i dw_i x_i = 1 to round-off (also for a clipped segment).
    Mat<Dim> JinvT;
    if constexpr (Dim == 1) {
      JinvT(0, 0) = 2.0 / (x[1][0] - x[0][0]);
    } else {
      JinvT = this->half_edges(P, p).inverse().transpose();
    }
    for (int c = 0; c < kCorners; ++c) {
      Vec<Dim> sc;
      for (int d = 0; d < Dim; ++d) sc[d] = ((c >> d) & 1) ? 1.0 : -1.0;
      gc[static_cast<std::size_t>(c)] = kAvg * (JinvT * sc);
    }
    detail::corner_sum_stencil<Dim, kCorners>(this->grid_, this->inv_h_, this->n_, x, wc, gc, s);
  }
};

// CPDI2 in 2D (Sadeghirad et al. 2013; D 2.6.4): quadrilateral domains whose four corners are
// tracked individually and moved with the grid velocity like particles,
//   x_c^{s+1} = x_c^s + dt sum_i N_i(x_c^s) v_i^{s+1}   (P1 at the corner, D eq. 2.38 / 2.51),
// and the weights and gradients of the quadrilateral (file comment). The corners are per-run
// state held here: set at the first prepare() from the CPDI parallelogram of each particle
// (x_p, F and the initial size, clamped into the grid, which removes round-off at a body that
// fills the grid), then moved by advect(), which update_particle_position calls after the
// particles. A restart must restore them (corners() / set_corners()); otherwise the next
// prepare() would rebuild parallelograms from F.
// Grid boundary: corners are clamped into the grid for the evaluation as in CPDI (the stored
// corner is not changed). A corner outside the grid is advected with the velocity of the
// nearest grid point. Corners on a grid side whose nodes are fixed do not move off it.
template <int Dim>
class Cpdi2Basis : public NodalDomainBasis<Dim> {
  static_assert(Dim == 2, "CPDI2 is implemented for quadrilateral domains (2D)");
  using Base = NodalDomainBasis<Dim>;

 public:
  static constexpr std::string_view kName = "cpdi2";
  static constexpr int kCorners = 4;
  // Capabilities (basis/basis.hpp): the corners are set up by prepare() and tracked between
  // steps (corners(), set_corners(), advect(), permute()).
  static constexpr bool kPrepare = true, kTrackedCorners = true;
  using Base::kPerDim;
  using typename Base::StencilT;
  using Corners = std::array<Vec<Dim>, kCorners>;  // numbered as CpdiBasis::corners()

  explicit Cpdi2Basis(const Grid<Dim>& g) : Base(g) {}

  // First call (or a different particle count): corners from the CPDI parallelograms.
  void prepare(const Particles<Dim>& P) {
    if (corners_.size() == static_cast<std::size_t>(P.size())) return;
    corners_.resize(static_cast<std::size_t>(P.size()));
    for (Index p = 0; p < P.size(); ++p) {
      const auto i = static_cast<std::size_t>(p);
      const Mat<Dim> J = this->half_edges(P, p);
      for (int c = 0; c < kCorners; ++c) {
        Vec<Dim> xc = P.x[i];
        for (int d = 0; d < Dim; ++d) xc += (((c >> d) & 1) ? 1.0 : -1.0) * J.col(d);
        detail::clamp_to_grid(this->grid_, xc);
        corners_[i][static_cast<std::size_t>(c)] = xc;
      }
    }
  }

  // The tracked corners (checkpoint state) and their replacement (restart).
  const std::vector<Corners>& corners() const { return corners_; }
  void set_corners(std::vector<Corners> c) { corners_ = std::move(c); }
  // Re-sorted particles (state/sort.hpp): the corners move with their particles.
  template <class Permutation>
  void permute(Permutation& perm) {
    if (static_cast<Index>(corners_.size()) == perm.size()) perm.apply(corners_);
  }

  // Corners of particle p as evaluated: clamped into the grid.
  Corners clamped_corners(Index p) const {
    Corners x = corners_[static_cast<std::size_t>(p)];
    for (auto& xc : x) detail::clamp_to_grid(this->grid_, xc);
    return x;
  }

  // Whether the stencil can hold the domain: prepared, x_p in the grid, the clamped corners
  // within 2 h_d along every direction and a strictly convex, counter-clockwise quadrilateral
  // (an inverted, degenerate or re-entrant domain stops the run). False for NaN.
  bool fits(const Particles<Dim>& P, Index p) const {
    if (p < 0 || static_cast<std::size_t>(p) >= corners_.size()) return false;
    if (!this->grid_.inside(P.x[static_cast<std::size_t>(p)])) return false;
    const Corners x = clamped_corners(p);
    if (!detail::corners_within_window(this->grid_, x)) return false;
    std::array<double, kCorners> wq;
    Corners gq;
    return quad_corner_weights(x, wq, gq);
  }

  // Requires fits(P, p); the caller checks.
  void evaluate(const Particles<Dim>& /*P*/, Index p, StencilT& s) const {
    const Corners x = clamped_corners(p);
    std::array<double, kCorners> wq;
    Corners gq;
    quad_corner_weights(x, wq, gq);
    detail::corner_sum_stencil<Dim, kCorners>(this->grid_, this->inv_h_, this->n_, x, wq, gq, s);
  }

  // x_c += dt sum_i N_i(x_c) v_i with the grid velocity the particles were just moved with
  // (stages::update_particle_position). No allocation.
  template <class Sim>
  void advect(const Sim& sim, double dt) {
    const auto& v = sim.nodes.velocity;
    const Grid<Dim>& g = this->grid_;
    const Vec<Dim> hi = g.upper();
    for (auto& corners : corners_) {
      for (auto& xc : corners) {
        // P1 at the corner clamped into the grid (D eq. 2.56): the 4 nodes of its cell.
        std::array<Index, Dim> first;
        std::array<double, Dim> xi;
        for (std::size_t d = 0; d < Dim; ++d) {
          const auto e = static_cast<int>(d);
          const double sd = (std::clamp(xc[e], g.origin[e], hi[e]) - g.origin[e]) * this->inv_h_[e];
          first[d] = clamped_cell(sd, g.cells[d]);
          xi[d] = std::clamp(sd - static_cast<double>(first[d]), 0.0, 1.0);
        }
        Vec<Dim> vc = Vec<Dim>::Zero();
        for (int b = 0; b < 4; ++b) {
          const int bx = b & 1, by = (b >> 1) & 1;
          const double N = (bx ? xi[0] : 1.0 - xi[0]) * (by ? xi[1] : 1.0 - xi[1]);
          const Index dof = (first[0] + bx) + (first[1] + by) * this->n_[0];
          vc += N * v[static_cast<std::size_t>(dof)];
        }
        xc += dt * vc;
      }
    }
  }

 private:
  std::vector<Corners> corners_;
};

// The basis concept (basis/basis.hpp).
static_assert(Basis<CpdiBasis<1>, 1> && Basis<CpdiBasis<2>, 2>);
static_assert(Basis<Cpdi2Basis<2>, 2>);

}  // namespace mpm
