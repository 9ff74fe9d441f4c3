// The domain-based bases and DDMPM in 2D on rectangular grids (D 2.6.4; Sadeghirad et al. 2011,
// 2013): uGIMP, cpGIMP, CPDI, CPDI2 and DDMPM. For each: partition of unity, non-negative
// weights, zero gradient sum, linear reproduction (sum w_i x_i = x_p, sum x_i grad_i^T = I)
// (D 2.5, P.1-P.3); weights and gradients against references computed independently of the code
// under test (1D midpoint integrals of the hat functions for GIMP, Gauss quadrature of the
// bilinear map for CPDI/CPDI2, particle sums of hat products for DDMPM); finite differences of
// the GIMP weights; the grid boundary (clipped domains, a body that fills the grid); cpGIMP with
// a stretched F, CPDI with a sheared one; fits(); CPDI2 corner tracking; and a 2D MUSL run per
// basis in which a rigid translation stays rigid.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <type_traits>
#include <vector>

#include "../support/stepper.hpp"
#include "basis/bases.hpp"
#include "basis/cpdi.hpp"
#include "basis/ddmpm.hpp"
#include "basis/gimp.hpp"
#include "basis/linear.hpp"
#include "io/checkpoint.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// Offset origin, unequal cell sizes that are not powers of two.
Grid<2> test_grid() {
  return Grid<2>(Vec<2>(-0.3, 0.2), Vec<2>(1.7, 1.4), IVec<2>{9, 7});
}

// P1 hat of node xi (D eq. 2.56) and the 2D tensor product, independent of the code under test.
double hat(double x, double xi, double h) {
  return std::max(0.0, 1.0 - std::abs(x - xi) / h);
}
double hat2(const Vec<2>& x, const Vec<2>& xi, const Vec<2>& h) {
  return hat(x[0], xi[0], h[0]) * hat(x[1], xi[1], h[1]);
}

// One particle whose initial domain is r h_d along d: V_p^0 = r^2 |cell| (initial_length).
Particles<2> particle(const Grid<2>& g, const Vec<2>& x, double r, const Mat<2>& F) {
  Particles<2> P;
  P.resize(1);
  P.x[0] = P.x0[0] = x;
  P.volume0[0] = r * r * g.cell_volume();
  P.F[0] = F;
  P.volume[0] = F.determinant() * P.volume0[0];
  return P;
}

// Stencil scattered into one weight and gradient per DOF (repeated DOFs add up).
struct Dense {
  std::vector<double> w;
  std::vector<Vec<2>> g;
};
template <class Basis>
Dense dense(const Basis& b, const typename Basis::StencilT& s) {
  const auto n = static_cast<std::size_t>(b.num_dofs());
  Dense out{std::vector<double>(n, 0.0), std::vector<Vec<2>>(n, Vec<2>::Zero())};
  for (int a = 0; a < s.kSize; ++a) {
    const auto k = static_cast<std::size_t>(a);
    EXPECT_GE(s.dof[k], 0);
    EXPECT_LT(s.dof[k], b.num_dofs());
    out.w[static_cast<std::size_t>(s.dof[k])] += s.w[k];
    out.g[static_cast<std::size_t>(s.dof[k])] += s.grad[k];
  }
  return out;
}

// P.1-P.3 at one evaluation: sum w = 1, w >= 0, sum grad = 0, sum x_i grad_i^T = I, and
// sum w_i x_i = `centre` (x_p, or the centroid of a clipped domain).
template <class Basis>
void check_properties(const Basis& b, const typename Basis::StencilT& s, const Vec<2>& centre,
                      const char* what) {
  const Vec<2> h = b.grid().h;
  double sum = 0.0;
  Vec<2> xr = Vec<2>::Zero(), gs = Vec<2>::Zero();
  Mat<2> gr = Mat<2>::Zero();
  for (int a = 0; a < s.kSize; ++a) {
    const auto k = static_cast<std::size_t>(a);
    EXPECT_GE(s.w[k], 0.0) << Basis::kName << " " << what;
    const Vec<2> xi = b.dof_position(s.dof[k]);
    sum += s.w[k];
    gs += s.grad[k];
    xr += s.w[k] * xi;
    gr += xi * s.grad[k].transpose();
  }
  // Round-off: O(eps) per term, 16 terms of size <= 1 (weights) or <= 1/h (gradients).
  EXPECT_NEAR(sum, 1.0, 1e-13) << Basis::kName << " " << what;
  EXPECT_LT(gs.cwiseProduct(h).norm(), 1e-12) << Basis::kName << " " << what;
  EXPECT_LT((xr - centre).norm(), 1e-13) << Basis::kName << " " << what;
  EXPECT_LT((gr - Mat<2>::Identity()).norm(), 1e-12) << Basis::kName << " " << what;
}

// GIMP reference along one direction: (1/(e - a)) int_a^e hat over the clipped interval, 2000-
// point midpoint rule, and the gradient (hat(e) - hat(a)) / (e - a) (D eq. 2.61-2.62).
struct Factor1D {
  double w, g;
};
Factor1D gimp_1d(double a, double e, double xi, double h) {
  constexpr int kPoints = 2000;
  double integral = 0.0;
  for (int q = 0; q < kPoints; ++q) integral += hat(a + (q + 0.5) * (e - a) / kPoints, xi, h);
  return {integral / kPoints, (hat(e, xi, h) - hat(a, xi, h)) / (e - a)};
}

// The box [x_p - l/2, x_p + l/2] clipped to the grid; GIMP averages are tensor products of the
// 1D averages over its sides.
template <class Basis>
void check_gimp_reference(const Basis& b, const Particles<2>& P, const Vec<2>& l) {
  typename Basis::StencilT s;
  b.evaluate(P, 0, s);
  const Dense d = dense(b, s);
  const Grid<2>& g = b.grid();
  Vec<2> lo, hi;
  for (int k = 0; k < 2; ++k) {
    lo[k] = std::max(P.x[0][k] - 0.5 * l[k], g.origin[k]);
    hi[k] = std::min(P.x[0][k] + 0.5 * l[k], g.upper()[k]);
  }
  check_properties(b, s, 0.5 * (lo + hi), "box");
  for (Index i = 0; i < b.num_dofs(); ++i) {
    const Vec<2> xi = b.dof_position(i);
    const Factor1D fx = gimp_1d(lo[0], hi[0], xi[0], g.h[0]);
    const Factor1D fy = gimp_1d(lo[1], hi[1], xi[1], g.h[1]);
    const auto k = static_cast<std::size_t>(i);
    // The midpoint rule is exact on the linear pieces; each of the <= 3 kinks costs at most
    // d^2 / (4 h) with d = (e - a) / 2000 <= 2 h / 2000, so each averaged factor is off by
    // < 4e-7 and the product by < 8e-7. The hats are 1/h-Lipschitz, so |g| <= 1/h.
    EXPECT_NEAR(d.w[k], fx.w * fy.w, 1e-6) << Basis::kName << " node " << i;
    EXPECT_NEAR(d.g[k][0], fx.g * fy.w, 1e-6 / g.h[0]) << Basis::kName << " node " << i;
    EXPECT_NEAR(d.g[k][1], fx.w * fy.g, 1e-6 / g.h[1]) << Basis::kName << " node " << i;
  }
}

std::vector<Vec<2>> random_points(const Grid<2>& g, int n, unsigned seed, double margin) {
  std::mt19937 rng(seed);
  std::vector<Vec<2>> out;
  for (int k = 0; k < n; ++k) {
    Vec<2> x;
    for (int d = 0; d < 2; ++d) {
      std::uniform_real_distribution<double> u(g.origin[d] + margin * g.h[d],
                                               g.upper()[d] - margin * g.h[d]);
      x[d] = u(rng);
    }
    out.push_back(x);
  }
  return out;
}

TEST(Bases2D, InitialLengthTilesSeededLattice) {
  // Particles seeded k per cell and direction have the lattice cell h_d / k as their initial
  // domain, whatever the cell's aspect ratio (the choice documented in gimp.hpp).
  const Grid<2> g = test_grid();
  const UGimpBasis<2> ug(g);
  for (int k : {1, 2, 3}) {
    const Vec<2> hi(g.origin[0] + 4 * g.h[0], g.origin[1] + 3 * g.h[1]);
    const Particles<2> P = seed_particles<2>(g, g.origin, hi, k, 1000.0);
    for (Index p = 0; p < P.size(); ++p)
      for (int d = 0; d < 2; ++d)
        EXPECT_NEAR(ug.length(P, p, d), g.h[d] / k, 1e-15) << "k = " << k << " d = " << d;
  }
}

TEST(Bases2D, UGimpPropertiesAndReference) {
  const UGimpBasis<2> b(test_grid());
  Mat<2> F;
  F << 1.3, 0.4, -0.2, 0.8;  // uGIMP ignores F
  for (double r : {0.1, 0.5, 1.0, 1.7, 2.0}) {
    for (const Vec<2>& x : random_points(b.grid(), 25, 3, 0.0)) {
      const Particles<2> P = particle(b.grid(), x, r, F);
      ASSERT_TRUE(b.fits(P, 0));
      check_gimp_reference(b, P, r * b.grid().h);
    }
  }
}

TEST(Bases2D, CpGimpStretchedF) {
  // cpGIMP: l_d = F_dd l0_d; the off-diagonal part of F does not change the box.
  const CpGimpBasis<2> b(test_grid());
  Mat<2> F;
  F << 1.6, 0.5, -0.3, 0.7;
  for (double r : {0.25, 0.5, 1.0}) {
    for (const Vec<2>& x : random_points(b.grid(), 25, 5, 0.0)) {
      const Particles<2> P = particle(b.grid(), x, r, F);
      ASSERT_TRUE(b.fits(P, 0));
      const Vec<2> l(F(0, 0) * r * b.grid().h[0], F(1, 1) * r * b.grid().h[1]);
      check_gimp_reference(b, P, l);
    }
  }
  // A stretch beyond the 2 h_d stencil limit in one direction does not fit.
  Mat<2> S = Mat<2>::Identity();
  S(1, 1) = 2.1;
  EXPECT_FALSE(b.fits(particle(b.grid(), Vec<2>(0.5, 0.7), 1.0, S), 0));
  S(1, 1) = 1.9;
  EXPECT_TRUE(b.fits(particle(b.grid(), Vec<2>(0.5, 0.7), 1.0, S), 0));
  S(1, 1) = -0.5;  // inverted
  EXPECT_FALSE(b.fits(particle(b.grid(), Vec<2>(0.5, 0.7), 1.0, S), 0));
}

// GIMP weights are differentiable in x_p (the domain translates with it), and the GIMP
// gradient is that derivative: grad w_i = (1/|Omega|) int grad N_i = d w_i / d x_p. The 1D
// factor is C^1 and piecewise quadratic in x_p with |w''| <= 2 / (l h), so a central difference
// with step e is exact away from the kinks and off by at most e / (l h) next to one; rounding
// adds about 1e-16 / e.
TEST(Bases2D, GimpGradientIsDerivativeOfWeight) {
  const Grid<2> g = test_grid();
  const UGimpBasis<2> ug(g);
  const CpGimpBasis<2> cg(g);
  Mat<2> F;
  F << 1.2, 0.0, 0.0, 0.9;
  const double r = 0.6, e_rel = 1e-6;
  auto check = [&](const auto& b, const Vec<2>& x) {
    using B = std::decay_t<decltype(b)>;
    typename B::StencilT s;
    b.evaluate(particle(g, x, r, F), 0, s);
    const Dense d0 = dense(b, s);
    for (int k = 0; k < 2; ++k) {
      const double e = e_rel * g.h[k];
      Vec<2> xp = x, xm = x;
      xp[k] += e;
      xm[k] -= e;
      b.evaluate(particle(g, xp, r, F), 0, s);
      const Dense dp = dense(b, s);
      b.evaluate(particle(g, xm, r, F), 0, s);
      const Dense dm = dense(b, s);
      // Shorter of uGIMP's r h_k and cpGIMP's F_kk r h_k. Weights carry an absolute round-off
      // of a few eps times the grid coordinate (<= 10 cells): <= 2e-14, so the difference
      // quotient is off by up to 2e-14 / e more.
      const double l_min = 0.9 * r * g.h[k];
      const double tol = e / (l_min * g.h[k]) + 2e-14 / e;
      for (std::size_t i = 0; i < d0.w.size(); ++i)
        EXPECT_NEAR((dp.w[i] - dm.w[i]) / (2 * e), d0.g[i][k], tol)
            << B::kName << " dof " << i << " direction " << k;
    }
  };
  // Domains inside the grid (clipping changes the domain's size, not only its position).
  for (const Vec<2>& x : random_points(g, 30, 17, 1.0)) {
    check(ug, x);
    check(cg, x);
  }
}

// Corner weights wq_c and gradient vectors gq_c of a quadrilateral from their defining
// integrals (1/V) int M_c dOmega and (1/V) int grad M_c dOmega, by 3x3 Gauss quadrature on the
// reference square (exact: the integrands M_c det J and adj(J)^T grad_xi M_c are polynomials of
// degree <= 2 per variable). Corners numbered bit 0: xi, bit 1: eta.
void quad_reference(const std::array<Vec<2>, 4>& x, std::array<double, 4>& wq,
                    std::array<Vec<2>, 4>& gq) {
  const double a = std::sqrt(0.6);
  const std::array<double, 3> q = {-a, 0.0, a}, qw = {5.0 / 9, 8.0 / 9, 5.0 / 9};
  double V = 0.0;
  wq.fill(0.0);
  gq.fill(Vec<2>::Zero());
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double xi = q[static_cast<std::size_t>(i)], eta = q[static_cast<std::size_t>(j)];
      const double wgt = qw[static_cast<std::size_t>(i)] * qw[static_cast<std::size_t>(j)];
      Mat<2> J = Mat<2>::Zero();  // dx/d(xi, eta)
      std::array<double, 4> M;
      std::array<Vec<2>, 4> dM;
      for (std::size_t c = 0; c < 4; ++c) {
        const double xc = (c & 1) ? 1.0 : -1.0, ec = (c & 2) ? 1.0 : -1.0;
        M[c] = 0.25 * (1 + xc * xi) * (1 + ec * eta);
        dM[c] = Vec<2>(0.25 * xc * (1 + ec * eta), 0.25 * ec * (1 + xc * xi));
        J += x[c] * dM[c].transpose();
      }
      const double det = J.determinant();
      V += wgt * det;
      for (std::size_t c = 0; c < 4; ++c) {
        wq[c] += wgt * det * M[c];
        gq[c] += wgt * det * (J.inverse().transpose() * dM[c]);
      }
    }
  }
  for (std::size_t c = 0; c < 4; ++c) {
    wq[c] /= V;
    gq[c] /= V;
  }
}

// Dense CPDI/CPDI2 reference from (clamped) corners: w_i = sum_c wq_c N_i(x_c),
// grad w_i = sum_c gq_c N_i(x_c).
template <class Basis>
void check_corner_reference(const Basis& b, const typename Basis::StencilT& s,
                            const std::array<Vec<2>, 4>& x, const char* what) {
  std::array<double, 4> wq;
  std::array<Vec<2>, 4> gq;
  quad_reference(x, wq, gq);
  const Dense d = dense(b, s);
  const Vec<2> h = b.grid().h;
  Vec<2> centroid = Vec<2>::Zero();
  for (std::size_t c = 0; c < 4; ++c) centroid += wq[c] * x[c];
  check_properties(b, s, centroid, what);
  for (Index i = 0; i < b.num_dofs(); ++i) {
    const Vec<2> xi = b.dof_position(i);
    double w = 0.0;
    Vec<2> gr = Vec<2>::Zero();
    for (std::size_t c = 0; c < 4; ++c) {
      w += wq[c] * hat2(x[c], xi, h);
      gr += gq[c] * hat2(x[c], xi, h);
    }
    const auto k = static_cast<std::size_t>(i);
    EXPECT_NEAR(d.w[k], w, 1e-13) << Basis::kName << " " << what << " node " << i;
    EXPECT_LT((d.g[k] - gr).cwiseProduct(h).norm(), 1e-11)
        << Basis::kName << " " << what << " node " << i;
  }
}

// CPDI corners from the test's own reading of D eq. 2.64-2.65: x_p +/- F r_1^0 +/- F r_2^0,
// r_d^0 = (r h_d / 2) e_d, clamped to the grid.
std::array<Vec<2>, 4> cpdi_corners(const Grid<2>& g, const Vec<2>& x, double r, const Mat<2>& F) {
  std::array<Vec<2>, 4> c;
  for (std::size_t k = 0; k < 4; ++k) {
    const double s1 = (k & 1) ? 1.0 : -1.0, s2 = (k & 2) ? 1.0 : -1.0;
    c[k] = x + s1 * F.col(0) * (0.5 * r * g.h[0]) + s2 * F.col(1) * (0.5 * r * g.h[1]);
    for (int d = 0; d < 2; ++d) c[k][d] = std::clamp(c[k][d], g.origin[d], g.upper()[d]);
  }
  return c;
}

TEST(Bases2D, CpdiShearedF) {
  const CpdiBasis<2> b(test_grid());
  const Grid<2>& g = b.grid();
  std::vector<Mat<2>> Fs(4);
  Fs[0] = Mat<2>::Identity();
  Fs[1] << 1.0, 0.8, 0.0, 1.0;  // simple shear
  Fs[2] << 1.2, 0.3, -0.4, 0.9;
  Fs[3] << 0.7, -0.5, 0.6, 1.1;
  int tested = 0;
  for (const Mat<2>& F : Fs) {
    for (double r : {0.2, 0.5, 0.8}) {
      for (const Vec<2>& x : random_points(g, 25, 23, 0.0)) {
        const Particles<2> P = particle(g, x, r, F);
        const auto c = cpdi_corners(g, x, r, F);
        bool inside = true;
        for (std::size_t k = 0; k < 4; ++k) {
          const Vec<2> raw = x + ((k & 1) ? 1.0 : -1.0) * F.col(0) * (0.5 * r * g.h[0]) +
                             ((k & 2) ? 1.0 : -1.0) * F.col(1) * (0.5 * r * g.h[1]);
          inside = inside && (raw - c[k]).norm() == 0.0;
        }
        if (!b.fits(P, 0)) {
          // Only an extent beyond 2 h_d may fail here (the clamped quads stay convex).
          const Mat<2> J = F * Vec<2>(0.5 * r * g.h[0], 0.5 * r * g.h[1]).asDiagonal();
          EXPECT_TRUE(J.row(0).cwiseAbs().sum() > g.h[0] || J.row(1).cwiseAbs().sum() > g.h[1]);
          continue;
        }
        ++tested;
        CpdiBasis<2>::StencilT s;
        b.evaluate(P, 0, s);
        check_corner_reference(b, s, c, inside ? "parallelogram" : "clipped");
        if (inside) {  // the parallelogram's centroid is x_p
          std::array<double, 4> wq;
          std::array<Vec<2>, 4> gq;
          quad_reference(c, wq, gq);
          for (double wc : wq) EXPECT_NEAR(wc, 0.25, 1e-14);
        }
      }
    }
  }
  EXPECT_GT(tested, 250);
}

TEST(Bases2D, FitsChecksStencilLimitGridAndInversion) {
  const Grid<2> g = test_grid();
  const UGimpBasis<2> ug(g);
  const CpdiBasis<2> cp(g);
  const Vec<2> x(0.5, 0.7);
  const Mat<2> I = Mat<2>::Identity();
  EXPECT_TRUE(ug.fits(particle(g, x, 2.0, I), 0));
  EXPECT_FALSE(ug.fits(particle(g, x, 2.01, I), 0));
  EXPECT_FALSE(ug.fits(particle(g, Vec<2>(0.5, 1.41), 0.5, I), 0));  // x_p outside
  EXPECT_FALSE(ug.fits(particle(g, Vec<2>(std::nan(""), 0.7), 0.5, I), 0));
  Mat<2> shear;
  shear << 1.0, 1.5 * g.h[0] / g.h[1], 0.0, 1.0;  // extent along x: (1 + 1.5) r h_x <= 2 h_x
  EXPECT_TRUE(cp.fits(particle(g, x, 0.79, shear), 0));
  EXPECT_FALSE(cp.fits(particle(g, x, 0.81, shear), 0));
  Mat<2> inverted;
  inverted << 0.0, 1.0, 1.0, 0.0;  // det -1
  EXPECT_FALSE(cp.fits(particle(g, x, 0.5, inverted), 0));
  EXPECT_FALSE(cp.fits(particle(g, x, 0.5, Mat<2>::Zero()), 0));
  EXPECT_FALSE(cp.fits(particle(g, Vec<2>(1.71, 0.7), 0.5, I), 0));
  Mat<2> bad = I;
  bad(0, 1) = std::nan("");
  EXPECT_FALSE(cp.fits(particle(g, x, 0.5, bad), 0));
}

TEST(Bases2D, GridBoundaryClipsDomains) {
  // Particles at the grid's corners and sides with domains poking out: GIMP clips the box, CPDI
  // clamps the corners; partition of unity, zero gradient sum and sum x_i grad_i^T = I hold, and
  // sum w_i x_i is the centroid of the clipped domain (checked inside the reference helpers).
  const Grid<2> g = test_grid();
  const UGimpBasis<2> ug(g);
  const CpGimpBasis<2> cg(g);
  const CpdiBasis<2> cp(g);
  const Vec<2> lo = g.origin, hi = g.upper(), h = g.h;
  Mat<2> F;
  F << 1.1, 0.2, -0.1, 0.95;
  const std::vector<Vec<2>> xs = {lo,
                                  hi,
                                  Vec<2>(lo[0], hi[1]),
                                  lo + 0.2 * h,
                                  hi - 0.3 * h,
                                  Vec<2>(lo[0] + 0.1 * h[0], 0.8),
                                  Vec<2>(0.4, hi[1] - 0.25 * h[1])};
  for (const Vec<2>& x : xs) {
    const Particles<2> P = particle(g, x, 0.8, F);
    ASSERT_TRUE(ug.fits(P, 0));
    check_gimp_reference(ug, P, 0.8 * h);
    ASSERT_TRUE(cg.fits(P, 0));
    check_gimp_reference(cg, P, Vec<2>(0.8 * F(0, 0) * h[0], 0.8 * F(1, 1) * h[1]));
    ASSERT_TRUE(cp.fits(P, 0)) << x.transpose();
    CpdiBasis<2>::StencilT s;
    cp.evaluate(P, 0, s);
    check_corner_reference(cp, s, cpdi_corners(g, x, 0.8, F), "grid boundary");
  }
}

TEST(Bases2D, BodyFillingTheGridFits) {
  // Seeded domains tile the grid; their outer corners lie on the grid boundary up to round-off.
  const Grid<2> g = test_grid();
  const Particles<2> P = seed_particles<2>(g, g.origin, g.upper(), 2, 1000.0);
  const UGimpBasis<2> ug(g);
  const CpdiBasis<2> cp(g);
  Cpdi2Basis<2> c2(g);
  c2.prepare(P);
  for (Index p = 0; p < P.size(); ++p) {
    ASSERT_TRUE(ug.fits(P, p));
    ASSERT_TRUE(cp.fits(P, p));
    ASSERT_TRUE(c2.fits(P, p));
    CpdiBasis<2>::StencilT s;
    cp.evaluate(P, p, s);
    check_properties(cp, s, P.x[static_cast<std::size_t>(p)], "filling");
    c2.evaluate(P, p, s);
    check_properties(c2, s, P.x[static_cast<std::size_t>(p)], "filling");
  }
}

TEST(Bases2D, Cpdi2StartsAsCpdiAndHandlesQuadrilaterals) {
  const Grid<2> g = test_grid();
  const CpdiBasis<2> cp(g);
  Cpdi2Basis<2> c2(g);
  Mat<2> F;
  F << 1.1, 0.4, -0.2, 0.9;
  const auto xs = random_points(g, 40, 31, 1.0);
  Particles<2> P;
  P.resize(static_cast<Index>(xs.size()));
  for (std::size_t i = 0; i < xs.size(); ++i) {
    P.x[i] = xs[i];
    P.F[i] = F;
    P.volume0[i] = 0.36 * g.cell_volume();
  }
  EXPECT_FALSE(c2.fits(P, 0));  // not prepared
  c2.prepare(P);
  for (Index p = 0; p < P.size(); ++p) {
    ASSERT_TRUE(c2.fits(P, p));
    CpdiBasis<2>::StencilT a, b;
    cp.evaluate(P, p, a);
    c2.evaluate(P, p, b);
    const Dense da = dense(cp, a), db = dense(c2, b);
    for (std::size_t i = 0; i < da.w.size(); ++i) {
      EXPECT_NEAR(da.w[i], db.w[i], 1e-14);
      EXPECT_LT((da.g[i] - db.g[i]).cwiseProduct(g.h).norm(), 1e-12);
    }
  }
  // General convex quadrilaterals (trapezoids, kites), then invalid ones.
  auto corners = c2.corners();
  const Vec<2> h = g.h;
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-0.25, 0.25);
  int tested = 0;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const Vec<2> x = P.x[i];
    // Square of side 0.8 h, corners jittered by up to 0.25 h: stays convex, extent < 2 h.
    for (std::size_t c = 0; c < 4; ++c) {
      const Vec<2> s(((c & 1) ? 0.4 : -0.4) + u(rng), ((c & 2) ? 0.4 : -0.4) + u(rng));
      corners[i][c] = x + s.cwiseProduct(h);
    }
  }
  c2.set_corners(corners);
  for (Index p = 0; p < P.size(); ++p) {
    if (!c2.fits(P, p)) continue;
    ++tested;
    CpdiBasis<2>::StencilT s;
    c2.evaluate(P, p, s);
    check_corner_reference(c2, s, c2.clamped_corners(p), "quadrilateral");
  }
  EXPECT_GT(tested, 30);
  // Re-entrant, clockwise (inverted) and too large quadrilaterals do not fit.
  auto bad = corners;
  const Vec<2> x = P.x[0];
  bad[0] = {x + Vec<2>(-0.4, -0.4).cwiseProduct(h), x + Vec<2>(0.4, -0.4).cwiseProduct(h),
            x + Vec<2>(-0.4, 0.4).cwiseProduct(h), x + Vec<2>(-0.3, -0.3).cwiseProduct(h)};
  c2.set_corners(bad);
  EXPECT_FALSE(c2.fits(P, 0));
  bad[0] = corners[0];
  std::swap(bad[0][1], bad[0][2]);
  c2.set_corners(bad);
  EXPECT_FALSE(c2.fits(P, 0));
  bad[0] = {x + Vec<2>(-1.1, -0.4).cwiseProduct(h), x + Vec<2>(1.1, -0.4).cwiseProduct(h),
            x + Vec<2>(-1.1, 0.4).cwiseProduct(h), x + Vec<2>(1.1, 0.4).cwiseProduct(h)};
  c2.set_corners(bad);
  EXPECT_FALSE(c2.fits(P, 0));  // extent 2.2 h along x
  bad[0][3][0] = std::nan("");
  c2.set_corners(bad);
  EXPECT_FALSE(c2.fits(P, 0));
}

// Minimal stand-in for the simulation state that advect() reads.
struct GridVelocity {
  GridState<2> nodes;
};

TEST(Bases2D, Cpdi2CornersMoveWithAffineGridVelocity) {
  // P1 reproduces an affine velocity field exactly, so each corner moves by dt (v0 + A x_c).
  const Grid<2> g = test_grid();
  Cpdi2Basis<2> c2(g);
  const Particles<2> P = seed_particles<2>(g, Vec<2>(0.1, 0.5), Vec<2>(0.9, 1.0), 2, 1.0);
  c2.prepare(P);
  GridVelocity sim;
  sim.nodes.resize(c2.num_dofs());
  Mat<2> A;
  A << 0.3, -0.2, 0.5, 0.1;
  const Vec<2> v0(0.7, -0.4);
  for (Index i = 0; i < c2.num_dofs(); ++i)
    sim.nodes.velocity[static_cast<std::size_t>(i)] = v0 + A * c2.dof_position(i);
  const auto before = c2.corners();
  const double dt = 1e-2;
  c2.advect(sim, dt);
  for (std::size_t p = 0; p < before.size(); ++p)
    for (std::size_t c = 0; c < 4; ++c) {
      const Vec<2> expect = before[p][c] + dt * (v0 + A * before[p][c]);
      EXPECT_LT((c2.corners()[p][c] - expect).norm(), 1e-15);
    }
}

// DDMPM in 2D on particles seeded k per cell and direction over the whole grid.
struct DdmpmSetup2D {
  Grid<2> g = test_grid();
  Particles<2> P = seed_particles<2>(g, g.origin, g.upper(), 4, 1.0);
  DdmpmBasis<2> basis{g};
  DdmpmSetup2D() { basis.prepare(P); }
};

TEST(Ddmpm2D, PartitionOfUnityZeroGradientSumLinearReproduction) {
  DdmpmSetup2D s;
  DdmpmBasis<2>::StencilT st;
  for (Index p = 0; p < s.P.size(); ++p) {
    s.basis.evaluate(s.P, p, st);
    check_properties(s.basis, st, s.P.x[static_cast<std::size_t>(p)], "particle");
  }
  for (const Vec<2>& x : random_points(s.g, 100, 43, 0.0)) {
    s.basis.evaluate_point(x, st);
    check_properties(s.basis, st, x, "point");
  }
}

TEST(Ddmpm2D, ValuesAreP1) {
  DdmpmSetup2D s;
  const LinearBasis<2> p1(s.g);
  for (const Vec<2>& x : random_points(s.g, 50, 47, 0.0)) {
    DdmpmBasis<2>::StencilT st;
    s.basis.evaluate_point(x, st);
    const Dense d = dense(s.basis, st);
    for (Index i = 0; i < p1.num_dofs(); ++i)
      EXPECT_NEAR(d.w[static_cast<std::size_t>(i)], hat2(x, p1.dof_position(i), s.g.h), 1e-14);
  }
}

TEST(Ddmpm2D, GradientIsContinuousAcrossCellFaces) {
  // alpha = prod_d 2 xi_d (1 - xi_d) vanishes on every face, where only the smoothed gradient
  // (a combination of the continuous P1 values) remains; P1's gradient jumps by ~1/h there.
  DdmpmSetup2D s;
  const LinearBasis<2> p1(s.g);
  const double eps = 1e-10;
  const Vec<2> h = s.g.h;
  auto jump = [&](const auto& b, const Vec<2>& x, int d) {
    using B = std::decay_t<decltype(b)>;
    typename B::StencilT a, c;
    Vec<2> xm = x, xp = x;
    xm[d] -= eps;
    xp[d] += eps;
    b.evaluate_point(xm, a);
    b.evaluate_point(xp, c);
    Dense da = dense(b, a), dc = dense(b, c);
    double m = 0.0;
    for (std::size_t i = 0; i < da.g.size(); ++i)
      m = std::max(m, (da.g[i] - dc.g[i]).cwiseProduct(h).norm());
    return m;
  };
  const Vec<2> lo = s.g.origin;
  // A vertical face (x = node 4), a horizontal one (y = node 3), and a cell corner.
  const std::vector<std::pair<Vec<2>, int>> cases = {
      {Vec<2>(lo[0] + 4 * h[0], lo[1] + 2.3 * h[1]), 0},
      {Vec<2>(lo[0] + 5.6 * h[0], lo[1] + 3 * h[1]), 1},
      {Vec<2>(lo[0] + 3 * h[0], lo[1] + 4 * h[1]), 0},
      {Vec<2>(lo[0] + 3 * h[0], lo[1] + 4 * h[1]), 1}};
  for (const auto& [x, d] : cases) {
    EXPECT_LT(jump(s.basis, x, d), 1e-8) << x.transpose() << " d = " << d;
    EXPECT_GT(jump(p1, x, d), 0.5) << x.transpose() << " d = " << d;
  }
}

TEST(Ddmpm2D, InteriorNodeGradientsAreParticleSums) {
  // At an interior node j (alpha = 0, phi_j = 1) grad_bar phi_i = (1/V_j) sum_p V_p phi_j(x_p)
  // grad phi_i(x_p). With a lattice of particles and tensor-product hats the sum factorises into
  // 1D sums, computed here from the hat functions alone.
  DdmpmSetup2D s;
  const Vec<2> h = s.g.h, lo = s.g.origin;
  const int k = 4;  // particles per cell and direction
  const IVec<2> jn = {4, 3};
  const Vec<2> xj(lo[0] + jn[0] * h[0], lo[1] + jn[1] * h[1]);
  // 1D sums over the particle coordinates along d: S0 = sum a_j a_i, S1 = sum a_j a_i'.
  auto sums = [&](int d, Index off, double& S0, double& S1) {
    S0 = S1 = 0.0;
    const Index n = s.g.cells[d] * k;
    const double xi_node = xj[d] + static_cast<double>(off) * h[d];
    for (Index q = 0; q < n; ++q) {
      const double x = lo[d] + (static_cast<double>(q) + 0.5) * h[d] / k;
      const double aj = hat(x, xj[d], h[d]);
      const double ai = hat(x, xi_node, h[d]);
      const double dai = std::abs(x - xi_node) < h[d] ? (x < xi_node ? 1.0 : -1.0) / h[d] : 0.0;
      S0 += aj * ai;
      S1 += aj * dai;
    }
  };
  DdmpmBasis<2>::StencilT st;
  s.basis.evaluate_point(xj, st);
  const Dense d = dense(s.basis, st);
  const Index nx = s.g.cells[0] + 1;
  for (Index ox = -1; ox <= 1; ++ox)
    for (Index oy = -1; oy <= 1; ++oy) {
      double Sx0, Sx1, Sy0, Sy1, Vx = 0.0, Vy = 0.0;  // V_j / V_p = (sum a_j)(sum b_j)
      sums(0, ox, Sx0, Sx1);
      sums(1, oy, Sy0, Sy1);
      for (Index q = 0; q < s.g.cells[0] * k; ++q)
        Vx += hat(lo[0] + (static_cast<double>(q) + 0.5) * h[0] / k, xj[0], h[0]);
      for (Index q = 0; q < s.g.cells[1] * k; ++q)
        Vy += hat(lo[1] + (static_cast<double>(q) + 0.5) * h[1] / k, xj[1], h[1]);
      const Vec<2> expect(Sx1 * Sy0 / (Vx * Vy), Sx0 * Sy1 / (Vx * Vy));
      const auto i = static_cast<std::size_t>((jn[0] + ox) + (jn[1] + oy) * nx);
      EXPECT_LT((d.g[i] - expect).cwiseProduct(h).norm(), 1e-13) << ox << " " << oy;
    }
  // The smoothed gradient is not P1's: at the node P1's gradient is one-sided.
  EXPECT_GT(std::abs(d.g[static_cast<std::size_t>(jn[0] + 1 + jn[1] * nx)][0]), 0.1 / h[0]);
}

// A body in uniform translation must move rigidly with every basis (MUSL, as
// tests/scheme/test_generic_dim.cpp for P1): velocity unchanged, x = x0 + v t, F = I, no stress.
// Each basis reproduces constants, so L = sum v grad phi_i = 0 while every node the body touches
// carries mass; CPDI2's corners move with the body.
void rigid_translation_2d(const BasisKind& basis) {
  const std::string_view name = basis_name(basis);
  SCOPED_TRACE(name);
  Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.2), IVec<2>{8, 6});
  auto P = seed_particles<2>(g, Vec<2>(0.3, 0.35), Vec<2>(0.6, 0.8), 2, 1000.0);
  const Vec<2> vel(0.3, -0.2);
  for (auto& v : P.v) v = vel;
  ElasticParameters ep{1000.0, 1e6, 0.3};
  auto stepper = test::compiled_stepper<2>(
      {.grid = g, .particles = P, .material = NeoHookean{ep}, .basis = basis});
  const RunState<2>& sim = stepper->state();
  const double dt = 1e-3;
  const int steps = 200;  // travels 0.06 and 0.04: crosses cells
  // CPDI2's tracked corners, 4 x 2 coordinates per particle, as a checkpoint saves them.
  const bool cpdi2 = std::holds_alternative<Cpdi2Kind>(basis);
  io::Checkpoint after_first, at_end;
  for (int s = 0; s < steps; ++s) {
    stepper->step(dt);
    if (cpdi2 && s == 0) stepper->save(after_first);
  }
  if (cpdi2) {
    stepper->save(at_end);
    ASSERT_EQ(at_end.basis_state.size(), 8 * P.x.size());
    ASSERT_EQ(after_first.basis_state.size(), at_end.basis_state.size());
  }
  for (Index p = 0; p < sim.particles.size(); ++p) {
    const auto i = static_cast<std::size_t>(p);
    EXPECT_LT((sim.particles.v[i] - vel).norm(), 1e-13);
    EXPECT_LT((sim.particles.x[i] - (P.x[i] + vel * dt * steps)).norm(), 1e-12);
    EXPECT_LT(sim.particles.stress[i].norm(), 1e-6);  // Pa, with E = 1e6 Pa
    EXPECT_LT((sim.particles.F[i] - Mat<2>::Identity()).norm(), 1e-12);
    if (cpdi2) {
      for (std::size_t c = 0; c < 4; ++c)
        for (std::size_t d = 0; d < 2; ++d) {
          const std::size_t k = 8 * i + 2 * c + d;
          EXPECT_NEAR(at_end.basis_state[k],
                      after_first.basis_state[k] + vel[static_cast<Index>(d)] * dt * (steps - 1),
                      1e-12);
        }
    }
  }
  EXPECT_GT(sim.diag.grid_crossings, 0);
}

TEST(Bases2D, RigidTranslationUGimp) {
  rigid_translation_2d(UGimpKind{});
}
TEST(Bases2D, RigidTranslationCpGimp) {
  rigid_translation_2d(CpGimpKind{});
}
TEST(Bases2D, RigidTranslationCpdi) {
  rigid_translation_2d(CpdiKind{});
}
TEST(Bases2D, RigidTranslationCpdi2) {
  rigid_translation_2d(Cpdi2Kind{});
}
TEST(Bases2D, RigidTranslationDdmpm) {
  rigid_translation_2d(DdmpmKind{});
}

TEST(Bases2D, KindsDeclareTheirDimensions) {
  EXPECT_TRUE(supports_dimension<DdmpmKind>(1));
  EXPECT_TRUE(supports_dimension<DdmpmKind>(2));
  EXPECT_FALSE(supports_dimension<Cpdi2Kind>(1));
  EXPECT_TRUE(supports_dimension<Cpdi2Kind>(2));
  EXPECT_TRUE(supports_dimension<CpdiKind>(2));
  EXPECT_EQ(Cpdi2Kind::kName, Cpdi2Basis<2>::kName);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
