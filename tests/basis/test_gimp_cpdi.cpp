// uGIMP, cpGIMP and CPDI bases in 1D (D 2.6.4 eq. 2.58-2.65; Bardenhagen & Kober 2004;
// Sadeghirad et al. 2011): partition of unity, non-negativity, zero gradient sum and linear
// reproduction (D 2.5, P.1-P.3) at many positions and sizes (domain ends on nodes, grid ends);
// GIMP weights against a numerical integral of the P1 basis over the domain, CPDI against the
// corner formula; dependence on F; the l -> 0 limit (P1); fits(); and the gradient continuity
// across a node that removes the grid-crossing error. A 2D check covers the generic code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <type_traits>
#include <vector>

#include "basis/cpdi.hpp"
#include "basis/gimp.hpp"
#include "basis/linear.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// Grid with ends off the origin and a cell size that is not a power of two.
Grid<1> test_grid() {
  return Grid<1>(Vec<1>(-0.3), Vec<1>(1.7), IVec<1>{13});
}

// P1 hat of node x_i and its derivative (D eq. 2.56), independent of the code under test.
double hat(double x, double xi, double h) {
  return std::max(0.0, 1.0 - std::abs(x - xi) / h);
}

Particles<1> one_particle(double x, double l0, double F11) {
  Particles<1> P;
  P.resize(1);
  P.x[0] = Vec<1>(x);
  P.volume0[0] = l0;
  P.volume[0] = F11 * l0;
  P.F[0](0, 0) = F11;
  return P;
}

// Stencil scattered into one weight and one gradient per DOF (repeated DOFs add up).
struct Dense {
  std::vector<double> w, g;
};
template <class Basis>
Dense dense(const Basis& b, const typename Basis::StencilT& s) {
  Dense out{std::vector<double>(static_cast<std::size_t>(b.num_dofs()), 0.0),
            std::vector<double>(static_cast<std::size_t>(b.num_dofs()), 0.0)};
  for (int a = 0; a < s.kSize; ++a) {
    const auto i = static_cast<std::size_t>(s.dof[static_cast<std::size_t>(a)]);
    out.w[i] += s.w[static_cast<std::size_t>(a)];
    out.g[i] += s.grad[static_cast<std::size_t>(a)][0];
  }
  return out;
}

// P.1-P.3 and validity of the stencil; linear reproduction where the domain lies in the grid.
template <class Basis>
void check_properties(const Basis& b, const Particles<1>& P, double lo, double hi) {
  typename Basis::StencilT s;
  b.evaluate(P, 0, s);
  const double x = P.x[0][0], h = b.grid().h[0];
  double sum = 0.0, gsum = 0.0, xr = 0.0, gr = 0.0;
  for (int a = 0; a < s.kSize; ++a) {
    const auto k = static_cast<std::size_t>(a);
    ASSERT_GE(s.dof[k], 0);
    ASSERT_LT(s.dof[k], b.num_dofs());
    EXPECT_GE(s.w[k], 0.0);
    const double xi = b.dof_position(s.dof[k])[0];
    sum += s.w[k];
    gsum += s.grad[k][0];
    xr += s.w[k] * xi;
    gr += s.grad[k][0] * xi;
  }
  EXPECT_NEAR(sum, 1.0, 1e-13) << Basis::kName << " x = " << x;
  EXPECT_LT(std::abs(gsum), 1e-12 / h) << Basis::kName << " x = " << x;
  const double lo_g = b.grid().origin[0], hi_g = b.grid().upper()[0];
  if (lo >= lo_g && hi <= hi_g) {
    EXPECT_NEAR(xr, x, 1e-13) << Basis::kName << " x = " << x;    // sum w_i x_i = x_p
    EXPECT_NEAR(gr, 1.0, 1e-12) << Basis::kName << " x = " << x;  // sum dw_i x_i = 1
  }
}

// GIMP reference: (1/l) int N_i over the domain clipped to the grid, 2000-point midpoint rule;
// gradient (N_i(b) - N_i(a)) / (b - a) (D eq. 2.61-2.62).
template <class Basis>
void check_gimp_integral(const Basis& b, const Particles<1>& P, double l) {
  typename Basis::StencilT s;
  b.evaluate(P, 0, s);
  const Dense d = dense(b, s);
  const double h = b.grid().h[0];
  const double a = std::max(P.x[0][0] - 0.5 * l, b.grid().origin[0]);
  const double e = std::min(P.x[0][0] + 0.5 * l, b.grid().upper()[0]);
  constexpr int kPoints = 2000;
  for (Index i = 0; i < b.num_dofs(); ++i) {
    const double xi = b.dof_position(i)[0];
    const auto k = static_cast<std::size_t>(i);
    if (xi + h <= a || xi - h >= e) {  // support misses the domain (to round-off at its ends)
      EXPECT_NEAR(d.w[k], 0.0, 1e-13);
      EXPECT_NEAR(d.g[k], 0.0, 1e-9 / h);
      continue;
    }
    double integral = 0.0;
    for (int q = 0; q < kPoints; ++q) integral += hat(a + (q + 0.5) * (e - a) / kPoints, xi, h);
    integral /= kPoints;
    EXPECT_NEAR(d.w[k], integral, 1e-6) << Basis::kName << " node " << i << " x = " << P.x[0][0];
    EXPECT_NEAR(d.g[k], (hat(e, xi, h) - hat(a, xi, h)) / (e - a), 1e-9 / h)
        << Basis::kName << " node " << i << " x = " << P.x[0][0];
  }
}

// CPDI reference: corners x_{1,2} = x_p -/+ F l0/2, w_i = (N_i(x_1) + N_i(x_2))/2,
// dw_i = (N_i(x_2) - N_i(x_1)) / (x_2 - x_1) (Sadeghirad et al. 2011, 1D).
void check_cpdi_corners(const CpdiBasis<1>& b, const Particles<1>& P) {
  CpdiBasis<1>::StencilT s;
  b.evaluate(P, 0, s);
  const Dense d = dense(b, s);
  const double h = b.grid().h[0];
  const double half = 0.5 * P.F[0](0, 0) * P.volume0[0];
  const double x1 = P.x[0][0] - half, x2 = P.x[0][0] + half;
  for (Index i = 0; i < b.num_dofs(); ++i) {
    const double xi = b.dof_position(i)[0];
    const auto k = static_cast<std::size_t>(i);
    EXPECT_NEAR(d.w[k], 0.5 * (hat(x1, xi, h) + hat(x2, xi, h)), 1e-13);
    EXPECT_NEAR(d.g[k], (hat(x2, xi, h) - hat(x1, xi, h)) / (x2 - x1), 1e-10 / h);
  }
}

// Sizes l / h and the positions tested for each: random, domain ends on nodes, particle on a
// node, and the grid ends (domain poking out for GIMP, touching the end for CPDI).
std::vector<double> sizes() {
  std::vector<double> out = {0.1, 0.25, 0.5, 1.0, 1.3, 1.7, 2.0};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.1, 2.0);
  for (int k = 0; k < 6; ++k) out.push_back(u(rng));
  return out;
}
std::vector<double> positions(const Grid<1>& g, double l, bool domain_inside) {
  const double h = g.h[0], lo = g.origin[0], hi = g.upper()[0];
  std::vector<double> out;
  for (Index k = 0; k <= g.cells[0]; ++k) {
    const double node = lo + h * static_cast<double>(k);
    for (double x : {node - 0.5 * l, node + 0.5 * l, node}) out.push_back(x);
  }
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(lo, hi);
  for (int k = 0; k < 40; ++k) out.push_back(u(rng));
  out.push_back(lo);
  out.push_back(hi);
  out.push_back(lo + 0.5 * l);
  out.push_back(hi - 0.5 * l);
  std::vector<double> kept;
  for (double x : out) {
    if (x < lo || x > hi) continue;
    if (domain_inside && (x - 0.5 * l < lo || x + 0.5 * l > hi)) continue;
    kept.push_back(x);
  }
  return kept;
}

TEST(GimpBasis, UGimpPropertiesAndExactIntegral) {
  const UGimpBasis<1> b(test_grid());
  const double h = b.grid().h[0];
  for (double r : sizes()) {
    const double l = r * h;
    for (double x : positions(b.grid(), l, false)) {
      // uGIMP ignores F: the domain keeps its initial length l0 = V_p^0.
      const Particles<1> P = one_particle(x, l, 1.4);
      ASSERT_TRUE(b.fits(P, 0)) << "x = " << x << " l/h = " << r;
      check_properties(b, P, x - 0.5 * l, x + 0.5 * l);
      check_gimp_integral(b, P, l);
    }
  }
}

TEST(GimpBasis, CpGimpPropertiesAndExactIntegral) {
  const CpGimpBasis<1> b(test_grid());
  const double h = b.grid().h[0];
  for (double r : sizes()) {
    const double l = r * h;
    for (double F : {1.0, 0.8, 1.25}) {
      for (double x : positions(b.grid(), l, false)) {
        // cpGIMP: l = F_11 l0.
        const Particles<1> P = one_particle(x, l / F, F);
        const double lc = F * (l / F);
        if (lc > 2.0 * h) continue;  // l / F * F may round above the 2h limit
        ASSERT_TRUE(b.fits(P, 0)) << "x = " << x << " l/h = " << r;
        check_properties(b, P, x - 0.5 * lc, x + 0.5 * lc);
        check_gimp_integral(b, P, lc);
      }
    }
  }
}

TEST(CpdiBasis, PropertiesAndCornerFormula) {
  const CpdiBasis<1> b(test_grid());
  const double h = b.grid().h[0];
  int tested = 0, skipped = 0;
  for (double r : sizes()) {
    const double l = r * h;
    for (double F : {1.0, 0.8, 1.25}) {
      for (double x : positions(b.grid(), l, true)) {
        const Particles<1> P = one_particle(x, l / F, F);
        if (!b.fits(P, 0)) {
          // Only a corner pushed past a grid end or the 2h limit by round-off may fail.
          const double half = F * (0.5 * (l / F));
          EXPECT_TRUE(x - half < b.grid().origin[0] || x + half > b.grid().upper()[0] ||
                      2.0 * half > 2.0 * h)
              << "x = " << x << " l/h = " << r;
          ++skipped;
          continue;
        }
        ++tested;
        check_properties(b, P, x - 0.5 * l, x + 0.5 * l);
        check_cpdi_corners(b, P);
      }
    }
  }
  EXPECT_LT(skipped, tested / 20) << skipped << " of " << tested + skipped << " did not fit";
}

TEST(GimpCpdiBasis, FDependence) {
  const UGimpBasis<1> ug(test_grid());
  const CpGimpBasis<1> cg(test_grid());
  const CpdiBasis<1> cp(test_grid());
  const double h = ug.grid().h[0];
  const double x = 0.4321;
  const Particles<1> P1 = one_particle(x, 0.8 * h, 1.0);
  const Particles<1> P2 = one_particle(x, 0.8 * h, 1.6);
  auto differs = [](const Dense& a, const Dense& b) {
    double m = 0.0;
    for (std::size_t i = 0; i < a.w.size(); ++i)
      m = std::max({m, std::abs(a.w[i] - b.w[i]), std::abs(a.g[i] - b.g[i])});
    return m;
  };
  UGimpBasis<1>::StencilT s1, s2;
  ug.evaluate(P1, 0, s1);
  ug.evaluate(P2, 0, s2);
  EXPECT_EQ(differs(dense(ug, s1), dense(ug, s2)), 0.0);  // uGIMP: initial size always
  cg.evaluate(P1, 0, s1);
  cg.evaluate(P2, 0, s2);
  EXPECT_GT(differs(dense(cg, s1), dense(cg, s2)), 1e-3);
  cp.evaluate(P1, 0, s1);
  cp.evaluate(P2, 0, s2);
  EXPECT_GT(differs(dense(cp, s1), dense(cp, s2)), 1e-3);
  // cpGIMP and CPDI with a stretch F are the uGIMP of the stretched length.
  const Particles<1> P3 = one_particle(x, 1.6 * 0.8 * h, 1.0);
  UGimpBasis<1>::StencilT s3;
  ug.evaluate(P3, 0, s3);
  cg.evaluate(P2, 0, s2);
  EXPECT_LT(differs(dense(ug, s3), dense(cg, s2)), 1e-12);
}

// l -> 0: all three tend to P1 at x_p (away from nodes, where P1's gradient is defined).
TEST(GimpCpdiBasis, VanishingDomainGivesP1) {
  const UGimpBasis<1> ug(test_grid());
  const CpGimpBasis<1> cg(test_grid());
  const CpdiBasis<1> cp(test_grid());
  const double h = ug.grid().h[0], lo = ug.grid().origin[0];
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(1e-3, 1.0 - 1e-3);
  for (int k = 0; k < 200; ++k) {
    const double x = lo + h * (static_cast<double>(k % 13) + u(rng));
    const Particles<1> P = one_particle(x, 1e-9 * h, 1.0);
    auto check = [&](const auto& b) {
      using B = std::decay_t<decltype(b)>;
      ASSERT_TRUE(b.fits(P, 0));
      typename B::StencilT s;
      b.evaluate(P, 0, s);
      const Dense d = dense(b, s);
      for (Index i = 0; i < b.num_dofs(); ++i) {
        const double xi = b.dof_position(i)[0];
        const auto j = static_cast<std::size_t>(i);
        const double dp1 = std::abs(x - xi) < h ? (xi > x ? 1.0 : -1.0) / h : 0.0;
        EXPECT_NEAR(d.w[j], hat(x, xi, h), 1e-12) << B::kName << " x = " << x;
        EXPECT_NEAR(d.g[j], dp1, 1e-5 / h) << B::kName << " x = " << x;
      }
    };
    check(ug);
    check(cg);
    check(cp);
  }
}

TEST(GimpCpdiBasis, FitsChecksStencilLimitAndGrid) {
  const UGimpBasis<1> ug(test_grid());
  const CpGimpBasis<1> cg(test_grid());
  const CpdiBasis<1> cp(test_grid());
  const Grid<1>& g = ug.grid();
  const double h = g.h[0], lo = g.origin[0], hi = g.upper()[0], x = 0.5;
  // Stencil limit l <= 2h.
  EXPECT_TRUE(ug.fits(one_particle(x, 2.0 * h, 1.0), 0));
  EXPECT_FALSE(ug.fits(one_particle(x, 2.01 * h, 1.0), 0));
  EXPECT_TRUE(ug.fits(one_particle(x, h, 2.5), 0));  // uGIMP ignores F
  EXPECT_TRUE(cg.fits(one_particle(x, h, 2.0), 0));
  EXPECT_FALSE(cg.fits(one_particle(x, h, 2.1), 0));
  EXPECT_TRUE(cp.fits(one_particle(x, h, 2.0), 0));
  EXPECT_FALSE(cp.fits(one_particle(x, h, 2.1), 0));
  // Degenerate or inverted domains, NaN.
  EXPECT_FALSE(cg.fits(one_particle(x, h, -0.5), 0));
  EXPECT_FALSE(cp.fits(one_particle(x, h, -0.5), 0));
  EXPECT_FALSE(cp.fits(one_particle(x, h, 0.0), 0));
  EXPECT_FALSE(ug.fits(one_particle(x, std::nan(""), 1.0), 0));
  EXPECT_FALSE(cp.fits(one_particle(x, h, std::nan("")), 0));
  // Grid ends: GIMP and (1D) CPDI clip a domain that pokes out of the grid.
  EXPECT_TRUE(ug.fits(one_particle(lo, h, 1.0), 0));
  EXPECT_TRUE(cg.fits(one_particle(hi, h, 1.0), 0));
  EXPECT_TRUE(cp.fits(one_particle(lo + 0.5 * h, h, 1.0), 0));
  EXPECT_TRUE(cp.fits(one_particle(lo + 0.4 * h, h, 1.0), 0));
  EXPECT_TRUE(cp.fits(one_particle(hi - 0.5 * h, h, 1.2), 0));   // stretched past the end
  EXPECT_FALSE(ug.fits(one_particle(hi + 0.1 * h, h, 1.0), 0));  // x_p outside
  EXPECT_FALSE(cp.fits(one_particle(hi + 0.1 * h, h, 1.0), 0));
  {
    // A clipped CPDI particle keeps partition of unity and a zero gradient sum, and its
    // gradient is that of the clipped domain [lo, x_p + l/2].
    CpdiBasis<1>::StencilT st;
    const double xp = lo + 0.3 * h, l = h;
    cp.evaluate(one_particle(xp, l, 1.0), 0, st);
    double w = 0.0, gs = 0.0, xg = 0.0;
    for (int a = 0; a < st.kSize; ++a) {
      w += st.w[a];
      gs += st.grad[a][0];
      xg += cp.dof_position(st.dof[a])[0] * st.grad[a][0];
    }
    EXPECT_NEAR(w, 1.0, 1e-13);
    EXPECT_NEAR(gs * h, 0.0, 1e-12);
    EXPECT_NEAR(xg, 1.0, 1e-12);
  }
}

// Grid-crossing fix: as x_p passes a node the GIMP and CPDI gradients change continuously,
// while P1's jump by 1/h and more.
TEST(GimpCpdiBasis, GradientContinuousAcrossNode) {
  const Grid<1> g = test_grid();
  const UGimpBasis<1> ug(g);
  const CpGimpBasis<1> cg(g);
  const CpdiBasis<1> cp(g);
  const LinearBasis<1> p1(g);
  const double h = g.h[0];
  auto jump = [&](const auto& b, double node, double l) {
    using B = std::decay_t<decltype(b)>;
    typename B::StencilT s;
    b.evaluate(one_particle(node - 1e-9, l, 1.0), 0, s);
    const Dense a = dense(b, s);
    b.evaluate(one_particle(node + 1e-9, l, 1.0), 0, s);
    const Dense c = dense(b, s);
    double m = 0.0;
    for (std::size_t i = 0; i < a.g.size(); ++i) m = std::max(m, std::abs(a.g[i] - c.g[i]));
    return m;
  };
  for (Index k = 1; k < g.cells[0]; ++k) {
    const double node = g.origin[0] + h * static_cast<double>(k);
    for (double r : {0.25, 0.5, 1.0, 1.5}) {
      EXPECT_LT(jump(ug, node, r * h), 1e-6 / h) << "node " << k;
      EXPECT_LT(jump(cg, node, r * h), 1e-6 / h) << "node " << k;
      EXPECT_LT(jump(cp, node, r * h), 1e-6 / h) << "node " << k;
    }
    EXPECT_GT(jump(p1, node, 0.5 * h), 0.99 / h) << "node " << k;
  }
}

TEST(GimpCpdiBasis, EvaluatePointIsP1AndLayoutIsNodal) {
  const CpdiBasis<1> cp(test_grid());
  const UGimpBasis<1> ug(test_grid());
  const double h = cp.grid().h[0];
  EXPECT_EQ(cp.num_dofs(), 14);
  EXPECT_EQ(ug.dofs_per_dim()[0], 14);
  EXPECT_EQ(ug.boundary_dofs(0, 0), std::vector<Index>{0});
  EXPECT_EQ(cp.boundary_dofs(0, 1), std::vector<Index>{13});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 1.7);
  for (int k = 0; k < 100; ++k) {
    const double x = k == 0 ? -0.3 : (k == 1 ? 1.7 : u(rng));
    CpdiBasis<1>::StencilT s;
    cp.evaluate_point(Vec<1>(x), s);
    const Dense d = dense(cp, s);
    for (Index i = 0; i < cp.num_dofs(); ++i)
      EXPECT_NEAR(d.w[static_cast<std::size_t>(i)], hat(x, cp.dof_position(i)[0], h), 1e-13);
  }
}

// Grids of one and two cells have fewer nodes than the stencil: the extra slots repeat a valid
// node with zero weight.
TEST(GimpCpdiBasis, SmallGrids) {
  for (Index cells : {1, 2}) {
    const Grid<1> g(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{cells});
    const double h = g.h[0];
    const UGimpBasis<1> ug(g);
    const CpdiBasis<1> cp(g);
    for (double x : {0.0, 0.3, 0.5, 1.0}) {
      const Particles<1> P = one_particle(x, std::min(0.9, 1.5 * h), 1.0);
      ASSERT_TRUE(ug.fits(P, 0));
      check_properties(ug, P, x - 0.5 * P.volume0[0], x + 0.5 * P.volume0[0]);
      check_gimp_integral(ug, P, P.volume0[0]);
    }
    const Particles<1> Q = one_particle(0.5, 0.5 * h, 1.0);
    ASSERT_TRUE(cp.fits(Q, 0));
    check_properties(cp, Q, 0.5 - 0.25 * h, 0.5 + 0.25 * h);
  }
}

// The generic (Dim > 1) code: tensor-product GIMP and sheared CPDI parallelograms keep partition
// of unity and linear reproduction.
TEST(GimpCpdiBasis, TwoDimensionalReproduction) {
  const Grid<2> g(Vec<2>(0.0, -1.0), Vec<2>(2.0, 0.5), IVec<2>{7, 5});
  const UGimpBasis<2> ug(g);
  const CpGimpBasis<2> cg(g);
  const CpdiBasis<2> cp(g);
  Particles<2> P;
  P.resize(1);
  P.volume0[0] = 0.04;  // 0.04 m^2, a domain similar to the cell (about 0.195 x 0.205 m)
  Mat<2> F;
  F << 1.2, 0.3, -0.1, 0.9;
  P.F[0] = F;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> ux(0.4, 1.6), uy(-0.6, 0.1);
  auto check = [&](const auto& b) {
    using B = std::decay_t<decltype(b)>;
    ASSERT_TRUE(b.fits(P, 0));
    typename B::StencilT s;
    b.evaluate(P, 0, s);
    double sum = 0.0;
    Vec<2> xr = Vec<2>::Zero(), gs = Vec<2>::Zero();
    Mat<2> gr = Mat<2>::Zero();
    for (int a = 0; a < s.kSize; ++a) {
      const auto k = static_cast<std::size_t>(a);
      EXPECT_GE(s.w[k], 0.0);
      const Vec<2> xi = b.dof_position(s.dof[k]);
      sum += s.w[k];
      gs += s.grad[k];
      xr += s.w[k] * xi;
      gr += xi * s.grad[k].transpose();
    }
    EXPECT_NEAR(sum, 1.0, 1e-13) << B::kName;
    EXPECT_LT(gs.norm(), 1e-11) << B::kName;
    EXPECT_LT((xr - P.x[0]).norm(), 1e-13) << B::kName;
    EXPECT_LT((gr - Mat<2>::Identity()).norm(), 1e-12) << B::kName;
  };
  for (int k = 0; k < 50; ++k) {
    P.x[0] = Vec<2>(ux(rng), uy(rng));
    check(ug);
    check(cg);
    check(cp);
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
