// B-spline basis (D 3.1.1-3.1.2, 004 sec. 4.3): partition of unity, non-negativity, zero
// derivative sum, linear reproduction with the Greville abscissae, derivatives against finite
// differences, C^(p-1) continuity at interior knots, interpolatory ends, degree 1 = P1, and the
// quadratic example of 004 Fig. 4.1. Degrees 1-5 in 1D, 2D and 3D, including grids with fewer
// cells than the degree (then every function touches a boundary knot).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "basis/bspline.hpp"
#include "basis/linear.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

template <int D, int P>
struct Case {
  static constexpr int kDim = D;
  static constexpr int kDeg = P;
};

template <class C>
class BSplineTest : public ::testing::Test {};

using Cases = ::testing::Types<Case<1, 1>, Case<1, 2>, Case<1, 3>, Case<1, 4>, Case<1, 5>,
                               Case<2, 1>, Case<2, 2>, Case<2, 3>, Case<2, 4>, Case<2, 5>,
                               Case<3, 1>, Case<3, 2>, Case<3, 3>, Case<3, 4>, Case<3, 5>>;

class CaseNames {
 public:
  template <class C>
  static std::string GetName(int) {
    return std::to_string(C::kDim) + "D_p" + std::to_string(C::kDeg);
  }
};
TYPED_TEST_SUITE(BSplineTest, Cases, CaseNames);

// Grids with 1, 2, 3 and 7 cells per direction (cells < degree included), off-origin and
// anisotropic so that no check relies on h = 1.
template <int Dim>
std::vector<Grid<Dim>> test_grids() {
  std::vector<Grid<Dim>> out;
  if constexpr (Dim == 1) {
    for (Index n : {1, 2, 3, 7}) out.emplace_back(Vec<1>(-0.3), Vec<1>(1.7), IVec<1>{n});
  } else if constexpr (Dim == 2) {
    const std::array<IVec<2>, 4> cells{IVec<2>{1, 3}, IVec<2>{2, 7}, IVec<2>{7, 1}, IVec<2>{3, 2}};
    for (const auto& n : cells) out.emplace_back(Vec<2>(0.0, -1.0), Vec<2>(2.0, 0.5), n);
  } else {
    // 3D (issue 20): two grids, one with a single cell along z and fewer cells than the degree.
    const std::array<IVec<3>, 2> cells{IVec<3>{2, 3, 1}, IVec<3>{4, 1, 3}};
    for (const auto& n : cells) out.emplace_back(Vec<3>(0.0, -1.0, 0.5), Vec<3>(2.0, 0.5, 1.5), n);
  }
  return out;
}

// Sample point: random, on a knot, or on the lower or upper end, chosen per direction so that
// corners, edges and interior knots all occur.
template <int Dim>
Vec<Dim> sample_point(const Grid<Dim>& g, int k, std::mt19937& rng) {
  Vec<Dim> x;
  for (int d = 0; d < Dim; ++d) {
    const int mode = (k + d * std::uniform_int_distribution<int>(0, 3)(rng)) % 4;
    if (mode == 0) {
      x[d] = std::uniform_real_distribution<double>(g.origin[d], g.upper()[d])(rng);
    } else if (mode == 1) {
      const Index n = std::uniform_int_distribution<Index>(0, g.cells[d])(rng);
      x[d] = g.origin[d] + g.h[d] * static_cast<double>(n);
    } else {
      x[d] = mode == 2 ? g.origin[d] : g.upper()[d];
    }
  }
  return x;
}

// All basis values (or one gradient component) at x as a dense vector over the DOFs, so that
// evaluations in different spans can be compared.
template <class B, int Dim>
std::vector<double> dense(const B& b, const Vec<Dim>& x, int component = -1) {
  typename B::StencilT s;
  b.evaluate_point(x, s);
  std::vector<double> out(static_cast<std::size_t>(b.num_dofs()), 0.0);
  for (int a = 0; a < s.kSize; ++a)
    out[static_cast<std::size_t>(s.dof[a])] += component < 0 ? s.w[a] : s.grad[a][component];
  return out;
}

TYPED_TEST(BSplineTest, PartitionOfUnityPositivityAndLinearReproduction) {
  constexpr int Dim = TypeParam::kDim, P = TypeParam::kDeg;
  std::mt19937 rng(7);
  for (const Grid<Dim>& g : test_grids<Dim>()) {
    const BSplineBasis<Dim, P> b(g);
    for (int d = 0; d < Dim; ++d) ASSERT_EQ(b.dofs_per_dim()[d], g.cells[d] + P);
    Particles<Dim> particles;
    particles.resize(1);
    typename BSplineBasis<Dim, P>::StencilT s;
    for (int k = 0; k < 400; ++k) {
      const Vec<Dim> x = sample_point(g, k, rng);
      ASSERT_TRUE(g.inside(x));
      particles.x[0] = x;
      b.evaluate(particles, 0, s);
      double sum = 0.0;
      Vec<Dim> gsum = Vec<Dim>::Zero(), xr = Vec<Dim>::Zero();
      Mat<Dim> gr = Mat<Dim>::Zero();
      for (int a = 0; a < s.kSize; ++a) {
        EXPECT_GE(s.w[a], 0.0) << "x = " << x.transpose();  // exactly, also at knots
        ASSERT_GE(s.dof[a], 0);
        ASSERT_LT(s.dof[a], b.num_dofs());
        sum += s.w[a];
        gsum += s.grad[a];
        const Vec<Dim> xi = b.dof_position(s.dof[a]);  // Greville abscissa
        xr += s.w[a] * xi;
        gr += xi * s.grad[a].transpose();
      }
      EXPECT_NEAR(sum, 1.0, 1e-13);
      EXPECT_LT(gsum.norm(), 1e-12 * g.h.cwiseInverse().norm());
      EXPECT_LT((xr - x).norm(), 1e-13);                     // sum phi_j xi*_j = x
      EXPECT_LT((gr - Mat<Dim>::Identity()).norm(), 1e-12);  // sum xi*_j grad phi_j^T = I
    }
  }
}

// Central differences of the values against the analytic derivative, per direction. Degree 1
// has kinks at the knots, so its points stay inside cells; from degree 2 on the derivative is
// continuous, so knots are included too (the FD error there is O(eps) from the jump in the
// second derivative, hence the looser bound).
TYPED_TEST(BSplineTest, DerivativesMatchFiniteDifferences) {
  constexpr int Dim = TypeParam::kDim, P = TypeParam::kDeg;
  std::mt19937 rng(11);
  for (const Grid<Dim>& g : test_grids<Dim>()) {
    const BSplineBasis<Dim, P> b(g);
    for (int k = 0; k < 40; ++k) {
      const bool on_knot = P >= 2 && k % 2 == 1;
      Vec<Dim> x;
      for (int d = 0; d < Dim; ++d) {
        const Index c = std::uniform_int_distribution<Index>(0, g.cells[d] - 1)(rng);
        // Knot points: an interior knot (the lower one of cell c > 0, else the upper one of
        // cell 0); a single cell has none, so its midpoint is used instead.
        const double t = !on_knot         ? std::uniform_real_distribution<double>(0.05, 0.95)(rng)
                         : c > 0          ? 0.0
                         : g.cells[d] > 1 ? 1.0
                                          : 0.5;
        x[d] = g.origin[d] + g.h[d] * (static_cast<double>(c) + t);
      }
      for (int d = 0; d < Dim; ++d) {
        const double eps = (on_knot ? 1e-7 : 1e-5) * g.h[d];
        Vec<Dim> xp = x, xm = x;
        xp[d] += eps;
        xm[d] -= eps;
        const auto fp = dense(b, xp), fm = dense(b, xm), df = dense(b, x, d);
        const double tol = (on_knot ? 1e-5 : 1e-7) / g.h[d];
        for (std::size_t j = 0; j < df.size(); ++j)
          EXPECT_NEAR(df[j], (fp[j] - fm[j]) / (2.0 * eps), tol)
              << "dof " << j << " d " << d << " x = " << x.transpose();
      }
    }
  }
}

// 1D span evaluation per degree (the tensor product inherits its continuity).
template <class C>
class BSplineSpanTest : public ::testing::Test {};
using Degrees = ::testing::Types<std::integral_constant<int, 1>, std::integral_constant<int, 2>,
                                 std::integral_constant<int, 3>, std::integral_constant<int, 4>,
                                 std::integral_constant<int, 5>>;
class DegreeNames {
 public:
  template <class C>
  static std::string GetName(int) {
    return "p" + std::to_string(C::value);
  }
};
TYPED_TEST_SUITE(BSplineSpanTest, Degrees, DegreeNames);

// C^(p-1) at every interior knot: the left span at t = 1 and the right span at t = 0 give the
// same values (p >= 1) and first derivatives (p >= 2) (D 3.1.2, P.6 with multiplicity 1).
TYPED_TEST(BSplineSpanTest, ContinuityAtInteriorKnots) {
  constexpr int P = TypeParam::value;
  for (Index n : {2, 3, 7}) {
    for (Index c = 1; c < n; ++c) {
      std::array<double, P + 1> wl, dl, wr, dr;
      bspline_span<P>(c - 1, 1.0, n, wl, dl);
      bspline_span<P>(c, 0.0, n, wr, dr);
      std::vector<double> vl(static_cast<std::size_t>(n + P), 0.0), vr = vl, gl = vl, gr = vl;
      for (int r = 0; r <= P; ++r) {
        vl[static_cast<std::size_t>(c - 1 + r)] = wl[r];
        gl[static_cast<std::size_t>(c - 1 + r)] = dl[r];
        vr[static_cast<std::size_t>(c + r)] = wr[r];
        gr[static_cast<std::size_t>(c + r)] = dr[r];
      }
      for (std::size_t j = 0; j < vl.size(); ++j) {
        EXPECT_NEAR(vl[j], vr[j], 1e-12) << "n " << n << " knot " << c << " dof " << j;
        if (P >= 2) {
          EXPECT_NEAR(gl[j], gr[j], 1e-12) << "n " << n << " knot " << c << " dof " << j;
        }
      }
    }
  }
}

// The closed-form weights of the uniform spans (degrees 2 and 3, bspline_span_uniform) against
// the general recursion: values and derivatives to round-off, partition of unity, zero
// derivative sum and non-negativity, on a dense set of t in [0, 1] including the knots. The
// uniform spans are c in [p - 1, n - p]; bspline_span uses the closed form exactly there.
TYPED_TEST(BSplineSpanTest, ClosedFormEqualsRecursionOnUniformSpans) {
  constexpr int P = TypeParam::value;
  if constexpr (kBsplineClosedForm<P>) {
    constexpr double kEps = std::numeric_limits<double>::epsilon();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    std::vector<double> ts = {0.0, 1.0, 0.5, 0.25, 0.75, kEps, 1.0 - kEps};
    for (int k = 0; k < 1000; ++k) ts.push_back(uni(rng));
    for (Index n : {2 * P - 1, 2 * P, 9, 100}) {
      for (Index c = P - 1; c <= n - P; ++c) {
        for (double t : ts) {
          std::array<double, P + 1> w, dw, wr, dr;
          bspline_span_uniform<P>(t, w, dw);
          bspline_span_recursion<P>(c, t, n, wr, dr);
          double sum = 0.0, dsum = 0.0;
          for (int r = 0; r <= P; ++r) {
            // Values are at most 1 and derivatives at most p (1/cell): a few ulp of that.
            EXPECT_NEAR(w[r], wr[r], 4 * kEps) << "n " << n << " c " << c << " t " << t;
            EXPECT_NEAR(dw[r], dr[r], 4 * P * kEps) << "n " << n << " c " << c << " t " << t;
            EXPECT_GE(w[r], 0.0);
            sum += w[r];
            dsum += dw[r];
          }
          EXPECT_NEAR(sum, 1.0, 4 * kEps);
          EXPECT_NEAR(dsum, 0.0, 4 * P * kEps);
          // The dispatcher picks the closed form on these spans.
          std::array<double, P + 1> wd, dd;
          bspline_span<P>(c, t, n, wd, dd);
          EXPECT_EQ(wd, w);
          EXPECT_EQ(dd, dw);
        }
      }
      // The end spans keep the recursion (their knots repeat).
      for (Index c : {Index{0}, n - 1}) {
        if (c >= P - 1 && c <= n - P) continue;
        std::array<double, P + 1> wd, dd, wr, dr;
        bspline_span<P>(c, 0.3, n, wd, dd);
        bspline_span_recursion<P>(c, 0.3, n, wr, dr);
        EXPECT_EQ(wd, wr);
        EXPECT_EQ(dd, dr);
      }
    }
  }
}

// Open knot vector: interpolatory at the ends (D 3.1.1). On a side only the functions with
// first / last index in that direction are non-zero, their values summing to 1; in 1D the end
// function is exactly 1 and all others exactly 0. These are the boundary DOFs.
TYPED_TEST(BSplineTest, InterpolatoryEndsAndBoundaryDofs) {
  constexpr int Dim = TypeParam::kDim, P = TypeParam::kDeg;
  std::mt19937 rng(3);
  for (const Grid<Dim>& g : test_grids<Dim>()) {
    const BSplineBasis<Dim, P> b(g);
    for (int d = 0; d < Dim; ++d) {
      for (int side = 0; side < 2; ++side) {
        const std::vector<Index> bd = b.boundary_dofs(d, side);
        Index expected = 1;
        for (int e = 0; e < Dim; ++e)
          if (e != d) expected *= b.dofs_per_dim()[e];
        ASSERT_EQ(static_cast<Index>(bd.size()), expected);
        std::vector<bool> on_side(static_cast<std::size_t>(b.num_dofs()), false);
        for (Index i : bd) {
          on_side[static_cast<std::size_t>(i)] = true;
          const double xi = b.dof_position(i)[d];  // Greville abscissa of an end function
          EXPECT_EQ(xi, side == 0 ? g.origin[d] : g.upper()[d]);
        }
        for (int k = 0; k < 20; ++k) {
          Vec<Dim> x = sample_point(g, k, rng);
          x[d] = side == 0 ? g.origin[d] : g.upper()[d];
          const auto w = dense(b, x);
          double on = 0.0;
          for (std::size_t j = 0; j < w.size(); ++j) {
            if (on_side[j])
              on += w[j];
            else
              EXPECT_EQ(w[j], 0.0) << "dof " << j << " d " << d << " side " << side;
          }
          EXPECT_NEAR(on, 1.0, 1e-14);
        }
      }
    }
    if constexpr (Dim == 1) {
      const auto lo = dense(b, Vec<1>(g.origin[0]));
      const auto hi = dense(b, Vec<1>(g.upper()[0]));
      EXPECT_EQ(lo.front(), 1.0);
      EXPECT_EQ(hi.back(), 1.0);
      EXPECT_EQ(b.boundary_dofs(0, 0), std::vector<Index>{0});
      EXPECT_EQ(b.boundary_dofs(0, 1), std::vector<Index>{g.cells[0] + P - 1});
    }
  }
}

// Degree 1 is the P1 basis (D 3.1), with the same DOF numbering.
template <int Dim>
void check_degree_one_is_linear() {
  std::mt19937 rng(5);
  for (const Grid<Dim>& g : test_grids<Dim>()) {
    const BSplineBasis<Dim, 1> b(g);
    const LinearBasis<Dim> lin(g);
    ASSERT_EQ(b.num_dofs(), lin.num_dofs());
    for (Index i = 0; i < b.num_dofs(); ++i)
      EXPECT_LT((b.dof_position(i) - lin.dof_position(i)).norm(), 1e-14);
    Particles<Dim> particles;
    particles.resize(1);
    typename BSplineBasis<Dim, 1>::StencilT s;
    typename LinearBasis<Dim>::StencilT sl;
    static_assert(decltype(s)::kSize == decltype(sl)::kSize);
    for (int k = 0; k < 200; ++k) {
      particles.x[0] = sample_point(g, k, rng);
      b.evaluate(particles, 0, s);
      lin.evaluate(particles, 0, sl);
      for (int a = 0; a < s.kSize; ++a) {
        EXPECT_EQ(s.dof[a], sl.dof[a]);
        EXPECT_NEAR(s.w[a], sl.w[a], 1e-15);
        EXPECT_LT((s.grad[a] - sl.grad[a]).norm(), 1e-14 * g.h.cwiseInverse().norm());
      }
    }
  }
}

TEST(BSplineBasis, DegreeOneEqualsLinearBasis1D) {
  check_degree_one_is_linear<1>();
}
TEST(BSplineBasis, DegreeOneEqualsLinearBasis2D) {
  check_degree_one_is_linear<2>();
}
TEST(BSplineBasis, DegreeOneEqualsLinearBasis3D) {
  check_degree_one_is_linear<3>();
}

// 004 Fig. 4.1: quadratic, knots {0,0,0,1/3,2/3,1,1,1}, h = 1/3. By hand, with t = 3x in the
// first span: phi_1 = (1-t)^2, phi_2 = t(1-t) + t(2-t)/2, phi_3 = t^2/2, so at x = 1/6 (t = 1/2)
// phi = (1/4, 5/8, 1/8) and dphi/dx = 3 (-2(1-t), 2 - 2t, t) = (-3, 3/2, 3/2). In the middle
// span (t = 3x - 1) the three functions are (1-t)^2/2, (1 + 2t - 2t^2)/2, t^2/2: (1/8, 3/4, 1/8)
// at x = 1/2. Greville abscissae: (0, 1/6, 1/2, 5/6, 1).
TEST(BSplineBasis, QuadraticExampleOf004Fig41) {
  const BSplineBasis<1, 2> b(Grid<1>(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{3}));
  ASSERT_EQ(b.num_dofs(), 5);
  BSplineBasis<1, 2>::StencilT s;
  b.evaluate_point(Vec<1>(1.0 / 6.0), s);
  const std::array<double, 3> w1{0.25, 0.625, 0.125}, g1{-3.0, 1.5, 1.5};
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(s.dof[a], a);
    EXPECT_NEAR(s.w[a], w1[a], 1e-15);
    EXPECT_NEAR(s.grad[a][0], g1[a], 1e-14);
  }
  b.evaluate_point(Vec<1>(0.5), s);
  const std::array<double, 3> w2{0.125, 0.75, 0.125};
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(s.dof[a], a + 1);
    EXPECT_NEAR(s.w[a], w2[a], 1e-15);
  }
  const std::array<double, 5> greville{0.0, 1.0 / 6.0, 0.5, 5.0 / 6.0, 1.0};
  for (Index i = 0; i < 5; ++i) EXPECT_NEAR(b.dof_position(i)[0], greville[i], 1e-15);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
