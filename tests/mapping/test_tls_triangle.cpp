// Taylor least-squares reconstruction on triangles (D 6.1.2, 6.3): the Taylor basis on the
// reference triangle (D eq. 6.16-6.18, with the mean of psi_6 corrected), reproduction of
// quadratics, conservation with every strategy for deficient elements, and the rank loss of
// D 6.3.1 (runs with 12 or 16 particles per triangle stop, 24 run): which particle layouts make
// D = sum_p psi(x_p) psi(x_p)^T singular, and why.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "grid/triangle_mesh.hpp"
#include "mapping/tls_triangle.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

constexpr std::array<TlsTriangleStrategy, 4> kStrategies{
    TlsTriangleStrategy::None, TlsTriangleStrategy::Reduce, TlsTriangleStrategy::MinimumNorm,
    TlsTriangleStrategy::Graded};

TlsTriangleSettings settings(TlsTriangleStrategy s, int terms = 6) {
  TlsTriangleSettings out;
  out.strategy = s;
  out.terms = terms;
  return out;
}

// The vertices of triangle e.
std::array<Vec<2>, 3> corners(const TriangleMesh& m, Index e) {
  const auto& v = m.cell_vertices(e);
  return {m.vertex(v[0]), m.vertex(v[1]), m.vertex(v[2])};
}

// The symmetric 6-point rule of degree 4 on a triangle (Dunavant 1985; Strang and Fix), in
// barycentric coordinates (a, a, 1 - 2a) and permutations; weights relative to the area.
struct GaussPoint {
  Vec<2> x;
  double w;
};
std::vector<GaussPoint> gauss6(const TriangleMesh& m, Index e) {
  const auto c = corners(m, e);
  const double area = m.cell_volume(e);
  const double a[2] = {0.44594849091596488632, 0.09157621350977074346};
  const double w[2] = {0.22338158967801146570, 0.10995174365532186764};  // sum: 1/3
  std::vector<GaussPoint> g;
  for (int o = 0; o < 2; ++o)
    for (int k = 0; k < 3; ++k) {
      double l[3] = {a[o], a[o], a[o]};
      l[k] = 1.0 - 2.0 * a[o];
      g.push_back({l[0] * c[0] + l[1] * c[1] + l[2] * c[2], w[o] * area});
    }
  return g;
}

// Integral over element e of the reconstruction, by the rule above (exact: degree 2), and the
// same sum of the terms' absolute values |a_k psi_k| (the scale of its rounding errors).
struct Integral {
  double value = 0.0, scale = 0.0;
};
Integral gauss_integral(const TlsTriangleReconstruction& r, const TlsTriangleCoefficients& a,
                        Index e) {
  Integral s;
  for (const auto& g : gauss6(r.mesh(), e)) {
    const TriangleTaylor terms = a[static_cast<std::size_t>(e)].cwiseProduct(r.basis(e, g.x));
    s.value += g.w * r.evaluate(a, e, g.x);
    s.scale += g.w * terms.cwiseAbs().sum();
  }
  return s;
}

// The structured mesh of [0, 1]^2 with its interior vertices moved by up to `amp` cell widths
// (uniform random in a square), so that no two triangles are similar.
TriangleMesh distorted(const IVec<2>& n, TrianglePattern p, double amp, unsigned seed) {
  const TriangleMesh m = structured_triangles(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), n, p);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amp, amp);
  std::vector<Vec<2>> v;
  for (Index i = 0; i < m.num_vertices(); ++i) {
    Vec<2> x = m.vertex(i);
    const bool boundary = x.minCoeff() < 1e-12 || x.maxCoeff() > 1.0 - 1e-12;
    if (!boundary)
      x += Vec<2>(u(rng) / static_cast<double>(n[0]), u(rng) / static_cast<double>(n[1]));
    v.push_back(x);
  }
  std::vector<TriangleMesh::Triangle> t;
  for (Index c = 0; c < m.num_cells(); ++c) t.push_back(m.cell_vertices(c));
  return TriangleMesh(std::move(v), std::move(t), {}, "the distorted test mesh");
}

// A point of element e given by reference coordinates (xi, eta): x_0 + xi (x_1 - x_0) +
// eta (x_2 - x_0), computed from the vertices (not by the class under test).
Vec<2> from_reference(const TriangleMesh& m, Index e, const Vec<2>& r) {
  const auto c = corners(m, e);
  return c[0] + r[0] * (c[1] - c[0]) + r[1] * (c[2] - c[0]);
}

// The same reference layout in every triangle.
std::vector<Vec<2>> per_triangle(const TriangleMesh& m, const std::vector<Vec<2>>& layout) {
  std::vector<Vec<2>> x;
  for (Index e = 0; e < m.num_cells(); ++e)
    for (const auto& r : layout) x.push_back(from_reference(m, e, r));
  return x;
}

// Reference layouts (D does not say how its "uniformly distributed" particles were placed).
// The centroids of the k^2 sub-triangles of the uniform k x k subdivision.
std::vector<Vec<2>> centroids(int k) {
  std::vector<Vec<2>> L;
  const double K = k;
  for (int i = 0; i < k; ++i)
    for (int j = 0; i + j < k; ++j) {
      L.emplace_back((i + 1.0 / 3.0) / K, (j + 1.0 / 3.0) / K);
      if (i + j < k - 1) L.emplace_back((i + 2.0 / 3.0) / K, (j + 2.0 / 3.0) / K);
    }
  return L;
}
// `rows` lines parallel to the edge eta = 0 at eta = (r + 1/2) / rows, each with `per_row`
// points spread evenly across the triangle (a collapsed tensor layout).
std::vector<Vec<2>> rows(int nrows, int per_row) {
  std::vector<Vec<2>> L;
  for (int r = 0; r < nrows; ++r) {
    const double eta = (r + 0.5) / nrows;
    for (int i = 0; i < per_row; ++i) L.emplace_back((1.0 - eta) * (i + 0.5) / per_row, eta);
  }
  return L;
}
// The 3-point rule (2/3, 1/6, 1/6) in each of the four midpoint sub-triangles: 12 points.
std::vector<Vec<2>> midpoint_rule3() {
  const double v[4][3][2] = {{{0, 0}, {0.5, 0}, {0, 0.5}},
                             {{0.5, 0}, {1, 0}, {0.5, 0.5}},
                             {{0, 0.5}, {0.5, 0.5}, {0, 1}},
                             {{0.5, 0.5}, {0, 0.5}, {0.5, 0}}};
  std::vector<Vec<2>> L;
  for (const auto& t : v)
    for (int k = 0; k < 3; ++k) {
      double l[3] = {1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0};
      l[k] = 2.0 / 3.0;
      L.emplace_back(l[0] * t[0][0] + l[1] * t[1][0] + l[2] * t[2][0],
                     l[0] * t[0][1] + l[1] * t[1][1] + l[2] * t[2][1]);
    }
  return L;
}
// n points evenly spaced on the Steiner inellipse scaled by rho about the centroid: barycentric
// lambda_i = 1/3 + rho/3 cos(theta - 2 pi i / 3). On it sum_i lambda_i^2 = 1/3 + rho^2 / 6, a
// quadratic in x; rho = 1 gives 1/2, the mean of sum_i lambda_i^2 over the triangle.
std::vector<Vec<2>> ellipse(int n, double rho) {
  std::vector<Vec<2>> L;
  for (int k = 0; k < n; ++k) {
    const double th = 2.0 * M_PI * (k + 0.25) / n;
    L.emplace_back(1.0 / 3.0 + rho / 3.0 * std::cos(th - 2.0 * M_PI / 3.0),
                   1.0 / 3.0 + rho / 3.0 * std::cos(th - 4.0 * M_PI / 3.0));
  }
  return L;
}
// An a x b lattice of cell-centred points in each square of the n x n cells of [0, 1]^2 (the
// rectangle layouts of a structured mesh: on the right-triangle mesh every triangle gets
// a b / 2 of them, none on the diagonal for these a, b), moved by the plate of D 6.3.1: the
// axis-aligned displacement of D eq. 3.11-3.12 with B = 0.05 m, c = sqrt(E / rho_0) = 100 m/s,
// after `step` steps of 1.25e-4 s.
std::vector<Vec<2>> plate_lattice(int n, int a, int b, int step) {
  const double h = 1.0 / n, st = std::sin(100.0 * M_PI * step * 1.25e-4), B = 0.05;
  std::vector<Vec<2>> x;
  for (int J = 0; J < n; ++J)
    for (int I = 0; I < n; ++I)
      for (int j = 0; j < b; ++j)
        for (int i = 0; i < a; ++i) {
          const double X = h * (I + (i + 0.5) / a), Y = h * (J + (j + 0.5) / b);
          x.emplace_back(X + B * std::sin(2.0 * M_PI * X) * st,
                         Y - B * std::sin(2.0 * M_PI * Y) * st);
        }
  return x;
}

// p = c_0 + c_1 x + c_2 y + c_3 x^2 + c_4 x y + c_5 y^2, and its exact integral over a
// triangle by the edge-midpoint rule (exact for degree 2).
struct Quadratic {
  std::array<double, 6> c{};
  double operator()(const Vec<2>& x) const {
    return c[0] + c[1] * x[0] + c[2] * x[1] + c[3] * x[0] * x[0] + c[4] * x[0] * x[1] +
           c[5] * x[1] * x[1];
  }
  double integral(const TriangleMesh& m, Index e) const {
    const auto v = corners(m, e);
    return m.cell_volume(e) / 3.0 *
           ((*this)(0.5 * (v[0] + v[1])) + (*this)(0.5 * (v[1] + v[2])) +
            (*this)(0.5 * (v[2] + v[0])));
  }
  std::vector<double> integrals(const TriangleMesh& m) const {
    std::vector<double> out;
    for (Index e = 0; e < m.num_cells(); ++e) out.push_back(integral(m, e));
    return out;
  }
  std::vector<double> values(const std::vector<Vec<2>>& x) const {
    std::vector<double> f;
    for (const auto& p : x) f.push_back((*this)(p));
    return f;
  }
};

Quadratic random_quadratic(unsigned seed, int degree = 2) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  Quadratic q;
  for (std::size_t k = 0; k < 6; ++k)
    q.c[k] = (k == 0 || (k < 3 && degree >= 1) || degree >= 2) ? u(rng) : 0.0;
  return q;
}

// Largest |f^ - p| over the Gauss points of the elements selected by `take` (all by default).
double max_error(
    const TlsTriangleReconstruction& r, const TlsTriangleCoefficients& a,
    const std::function<double(const Vec<2>&)>& p,
    const std::function<bool(Index)>& take = [](Index) { return true; }) {
  double err = 0.0;
  for (Index e = 0; e < r.num_elements(); ++e) {
    if (!take(e)) continue;
    for (const auto& g : gauss6(r.mesh(), e))
      err = std::max(err, std::abs(r.evaluate(a, e, g.x) - p(g.x)));
  }
  return err;
}

bool all_finite(const TlsTriangleCoefficients& a) {
  return std::all_of(a.begin(), a.end(), [](const TriangleTaylor& c) { return c.allFinite(); });
}

// D 6.1.2: psi_1..psi_6 on the reference triangle are D eq. 6.16-6.17 and eq. 6.18 with the
// mean of 4 (xi - 1/3)(eta - 1/3), which is -1/9, subtracted (D prints +1/18, which integrates to
// |Omega_e| / 18, not 0). On every triangle of a distorted mesh, by a Gauss rule in x: int psi_1
// = |Omega_e| and int psi_k = 0 for k = 2..6 (D eq. 5.7); the reference map sends the vertices
// to (0, 0), (1, 0), (0, 1).
TEST(TlsTriangle, BasisIsTheReferenceTaylorBasisWithZeroMeans) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 50; ++k) {
    double xi = u(rng), eta = u(rng);
    if (xi + eta > 1.0) xi = 1.0 - xi, eta = 1.0 - eta;
    const TriangleTaylor psi = triangle_taylor_basis(xi, eta);
    const double X = xi - 1.0 / 3.0, Y = eta - 1.0 / 3.0;
    EXPECT_EQ(psi[0], 1.0);
    EXPECT_NEAR(psi[1], X / 0.5, 1e-15);  // D eq. 6.2 with x_c = 1/3, Delta x = 1/2
    EXPECT_NEAR(psi[2], Y / 0.5, 1e-15);
    EXPECT_NEAR(psi[3], 2.0 * X * X - 1.0 / 9.0, 1e-15);  // D eq. 6.16
    EXPECT_NEAR(psi[4], 2.0 * Y * Y - 1.0 / 9.0, 1e-15);  // D eq. 6.17
    EXPECT_NEAR(psi[5], 4.0 * X * Y + 1.0 / 9.0, 1e-15);  // D eq. 6.18 corrected
  }

  for (const auto pattern : {TrianglePattern::right, TrianglePattern::criss_cross}) {
    const TriangleMesh m = distorted({5, 4}, pattern, 0.25, 2);
    const TlsTriangleReconstruction r(m);
    for (Index e = 0; e < m.num_cells(); ++e) {
      SCOPED_TRACE("element " + std::to_string(e));
      const double area = m.cell_volume(e);
      TriangleTaylor integral = TriangleTaylor::Zero();
      double d618 = 0.0;  // D eq. 6.18 as printed
      for (const auto& g : gauss6(m, e)) {
        integral += g.w * r.basis(e, g.x);
        const Vec<2> ref = r.reference(e, g.x);
        d618 += g.w * (4.0 * (ref[0] - 1.0 / 3.0) * (ref[1] - 1.0 / 3.0) + 1.0 / 18.0);
      }
      EXPECT_NEAR(integral[0], area, 2e-15 * area);
      for (int k = 1; k < 6; ++k) EXPECT_NEAR(integral[k], 0.0, 1e-14 * area) << "psi_" << k + 1;
      EXPECT_NEAR(d618, -area / 18.0, 1e-14 * area);
      const auto c = corners(m, e);
      EXPECT_NEAR((r.reference(e, c[0]) - Vec<2>(0.0, 0.0)).norm(), 0.0, 1e-13);
      EXPECT_NEAR((r.reference(e, c[1]) - Vec<2>(1.0, 0.0)).norm(), 0.0, 1e-13);
      EXPECT_NEAR((r.reference(e, c[2]) - Vec<2>(0.0, 1.0)).norm(), 0.0, 1e-13);
    }
  }
}

// D 5.2.1 on triangles: data from a random polynomial of the basis at 6 to 24 random points per
// triangle of a distorted mesh is reproduced to round-off by the plain and the conservative fit
// (integrals exact), with every strategy (the systems are well posed, so they agree); n_b = 3
// and 1 reproduce linear and constant data. Points outside the mesh are ignored and counted.
TEST(TlsTriangle, ReproducesPolynomialsOfTheBasis) {
  const TriangleMesh m = distorted({4, 3}, TrianglePattern::criss_cross, 0.2, 3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<2>> x;
  for (Index e = 0; e < m.num_cells(); ++e) {
    const int count = 6 + static_cast<int>((e * 7) % 19);
    for (int k = 0; k < count; ++k) {
      double xi = u(rng), eta = u(rng);
      if (xi + eta > 1.0) xi = 1.0 - xi, eta = 1.0 - eta;
      x.push_back(from_reference(m, e, Vec<2>(xi, eta)));
    }
  }
  std::shuffle(x.begin(), x.end(), rng);
  x.emplace_back(1.5, 0.5);  // outside
  x.emplace_back(-0.1, -0.2);
  for (const int nb : {6, 3, 1}) {
    const Quadratic p = random_quadratic(17 + nb, nb == 6 ? 2 : (nb == 3 ? 1 : 0));
    std::vector<double> f = p.values(x);
    f[x.size() - 1] = f[x.size() - 2] = 1e300;  // outside: must not be used
    const std::vector<double> c = p.integrals(m);
    for (const auto s : kStrategies) {
      SCOPED_TRACE(std::string(tls_triangle_strategy_name(s)) + ", n_b = " + std::to_string(nb));
      TlsTriangleReconstruction r(m, settings(s, nb));
      const TlsTriangleReport& rep = r.set_points(x);
      EXPECT_EQ(rep.elements, m.num_cells());
      EXPECT_EQ(rep.active, m.num_cells());
      EXPECT_EQ(rep.outside, 2);
      EXPECT_EQ(rep.plain.full, m.num_cells());
      EXPECT_EQ(rep.conservative.full, m.num_cells());
      EXPECT_EQ(rep.plain.min_rank, nb);
      EXPECT_EQ(rep.conservative.min_rank, nb);
      EXPECT_LT(rep.plain.max_condition, 1e6);
      TlsTriangleCoefficients plain, cons;
      r.fit_plain(f, plain);
      r.fit_conservative(f, c, cons);
      EXPECT_LT(max_error(r, plain, p), 1e-11);
      EXPECT_LT(max_error(r, cons, p), 1e-11);
      for (int i = 0; i <= 20; ++i)  // the global evaluate, and zero outside the mesh
        EXPECT_NEAR(r.evaluate(cons, Vec<2>(0.05 * i, 0.37)), p(Vec<2>(0.05 * i, 0.37)), 1e-11);
      EXPECT_EQ(r.evaluate(cons, Vec<2>(1.2, 0.5)), 0.0);
    }
  }
}

// Elements with 0, 1, 2 points, collinear and coincident points, 12 points on two lines, 12 on
// the Steiner inellipse and 4 points: the conservative fit keeps int_e f^ = c_e (by a Gauss rule
// and by a_1 |Omega_e|) to round-off with every strategy, all fields stay finite, and the report
// names what each element lacks. Plain D is singular whenever a quadratic vanishes at all points;
// conservative D (psi_2..psi_6) only when one with zero mean does: the two lines y = a, y = b
// carry (y - a)(y - b), whose mean is not zero, the inellipse sum lambda_i^2 - 1/2, whose mean is.
TEST(TlsTriangle, ConservesWithEveryStrategyAndReportsDeficientElements) {
  const TriangleMesh m = distorted({3, 3}, TrianglePattern::right, 0.2, 7);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<2>> x;
  auto add = [&](Index e, const std::vector<Vec<2>>& ref) {
    for (const auto& r : ref) x.push_back(from_reference(m, e, r));
  };
  // Element: 0 none; 1 one point; 2 two; 3 three collinear; 4 five at one position; 5 rows 2 x 6;
  // 6 the inellipse; 7 four points; the others 10 random points.
  add(1, {{0.2, 0.3}});
  add(2, {{0.2, 0.3}, {0.5, 0.1}});
  add(3, {{0.1, 0.1}, {0.3, 0.3}, {0.45, 0.45}});
  add(4, std::vector<Vec<2>>(5, Vec<2>(0.25, 0.4)));
  add(5, rows(2, 6));
  add(6, ellipse(12, 1.0));
  add(7, {{0.1, 0.2}, {0.6, 0.1}, {0.2, 0.6}, {0.3, 0.3}});
  for (Index e = 8; e < m.num_cells(); ++e)
    for (int k = 0; k < 10; ++k) {
      double xi = u(rng), eta = u(rng);
      if (xi + eta > 1.0) xi = 1.0 - xi, eta = 1.0 - eta;
      x.push_back(from_reference(m, e, Vec<2>(xi, eta)));
    }
  std::uniform_real_distribution<double> v(-1.0, 1.0);
  std::vector<double> f(x.size()), c(static_cast<std::size_t>(m.num_cells()));
  for (double& fp : f) fp = 2.0 + v(rng);
  for (Index e = 0; e < m.num_cells(); ++e)
    c[static_cast<std::size_t>(e)] = m.cell_volume(e) * (2.0 + v(rng));  // element 0 too

  const std::set<Index> plain_deficient{1, 2, 3, 4, 5, 6, 7}, cons_deficient{1, 2, 3, 4, 6, 7};
  for (const auto s : kStrategies) {
    SCOPED_TRACE(std::string(tls_triangle_strategy_name(s)));
    TlsTriangleReconstruction r(m, settings(s));
    const TlsTriangleReport& rep = r.set_points(x);
    EXPECT_EQ(rep.active, m.num_cells() - 1);
    EXPECT_EQ(rep.plain.deficient, 7);
    EXPECT_EQ(rep.conservative.deficient, 6);
    EXPECT_EQ(rep.plain.first_deficient, 1);
    EXPECT_TRUE(std::isinf(rep.plain.max_condition) || rep.plain.max_condition > 1e20);
    for (Index e = 1; e < m.num_cells(); ++e) {
      const auto& info = r.element(e);
      EXPECT_EQ(info.plain.deficient, plain_deficient.count(e) == 1) << e;
      EXPECT_EQ(info.conservative.deficient, cons_deficient.count(e) == 1) << e;
      if (!info.plain.deficient) {
        EXPECT_LT(info.plain.condition, 1e6) << e;
      }
    }
    EXPECT_LT(r.element(5).conservative.condition, 1e3);  // two lines: conservative is fine
    TlsTriangleCoefficients cons, plain;
    r.fit_conservative(f, c, cons);
    r.fit_plain(f, plain);
    EXPECT_TRUE(all_finite(cons));
    EXPECT_TRUE(all_finite(plain));
    EXPECT_EQ(plain[0].norm(), 0.0);  // no points: no plain reconstruction
    for (Index e = 0; e < m.num_cells(); ++e) {
      const double ce = c[static_cast<std::size_t>(e)];
      EXPECT_NEAR(r.integral(cons, e), ce, 1e-15 * std::abs(ce)) << e;
      const Integral gi = gauss_integral(r, cons, e);
      EXPECT_NEAR(gi.value, ce, 1e-14 * gi.scale) << e;
    }
    switch (s) {
      case TlsTriangleStrategy::None:
        EXPECT_EQ(rep.plain.failed, 7);
        EXPECT_EQ(rep.conservative.failed, 6);
        for (Index e : plain_deficient) {  // the constant fits
          EXPECT_EQ(plain[static_cast<std::size_t>(e)].tail(5).norm(), 0.0);
          double mean = 0.0;
          for (Index p : r.points(e)) mean += f[static_cast<std::size_t>(p)];
          EXPECT_NEAR(plain[static_cast<std::size_t>(e)][0],
                      mean / static_cast<double>(r.points(e).size()), 1e-14);
        }
        for (Index e : cons_deficient)
          EXPECT_EQ(cons[static_cast<std::size_t>(e)].tail(5).norm(), 0.0);
        break;
      case TlsTriangleStrategy::Reduce:
        EXPECT_EQ(rep.plain.reduced, 7);
        EXPECT_EQ(rep.conservative.reduced, 6);
        EXPECT_EQ(rep.plain.min_rank, 1);
        EXPECT_LE(rep.plain.max_condition_solved, 1e8);
        EXPECT_EQ(r.element(1).plain.terms, 1);  // one point: the constant
        EXPECT_EQ(r.element(5).plain.terms, 3);  // two lines: linear is well posed
        EXPECT_EQ(r.element(7).plain.terms, 3);
        EXPECT_EQ(r.element(7).conservative.terms, 3);
        EXPECT_EQ(r.element(3).plain.terms, 1);  // collinear: not even linear
        break;
      case TlsTriangleStrategy::MinimumNorm:
      case TlsTriangleStrategy::Graded:
        EXPECT_EQ(rep.plain.truncated, 7);
        EXPECT_EQ(rep.conservative.truncated, 6);
        EXPECT_LE(rep.plain.max_condition_solved, 1e8);
        EXPECT_EQ(r.element(5).plain.rank, 5);  // (y - a)(y - b) undetermined
        EXPECT_EQ(r.element(6).plain.rank, 5);  // the inellipse's quadratic
        EXPECT_EQ(r.element(6).conservative.rank, 5);
        EXPECT_EQ(r.element(7).plain.rank, 4);
        EXPECT_EQ(r.element(4).plain.rank, 1);  // one position
        EXPECT_EQ(r.element(3).plain.rank, 3);  // a line: 1, s, s^2 along it
        for (Index e : {1, 2, 3, 7}) {  // as many distinct points as the rank: interpolation
          for (Index p : r.points(e))
            EXPECT_NEAR(r.evaluate(plain, e, x[static_cast<std::size_t>(p)]),
                        f[static_cast<std::size_t>(p)], 1e-12)
                << e;
        }
        break;
    }
  }
}

// The layouts one may read into D 6.3.1's "12 or 16 uniformly distributed material points per
// element", on right, criss-cross and distorted meshes. The sub-triangle centroids (16), the
// 3-point rule in the midpoint sub-triangles (12), 3 or 4 rows parallel to an edge (12, 16) and
// the 4 x 6, 4 x 8, 6 x 8 rectangle lattices on the right-triangle mesh (12, 16, 24 per
// triangle) and 6 x 8 on the criss-cross mesh (12) are all well conditioned at the start.
// Singular are layouts where a quadratic vanishes at every point: two rows (2 x 6 = 12,
// 2 x 8 = 16), any number of points on one conic (12 on the Steiner inellipse, also for the
// conservative fit, or on a smaller ellipse, plain only), and the 4 x 6 lattice on the
// criss-cross mesh (6 points per triangle on two rows). cond(D) depends only on the reference
// coordinates, so a reference layout has the same cond(D) on every triangle of any mesh.
TEST(TlsTriangle, ConditionOfTheUniformLayoutsOfD631) {
  const TriangleMesh right =
      structured_triangles(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), {4, 4}, TrianglePattern::right);
  const TriangleMesh cc = structured_triangles(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), {4, 4},
                                               TrianglePattern::criss_cross);
  const TriangleMesh dist = distorted({4, 4}, TrianglePattern::right, 0.25, 11);
  auto report = [](const TriangleMesh& m, const std::vector<Vec<2>>& x) {
    TlsTriangleReconstruction r(m, settings(TlsTriangleStrategy::None));
    return r.set_points(x);
  };
  struct Case {
    std::string name;
    std::vector<Vec<2>> layout;
    std::size_t points;
    bool plain_singular, cons_singular;
  };
  const std::vector<Case> cases{
      {"centroids of 16 sub-triangles", centroids(4), 16, false, false},
      {"3-point rule in 4 sub-triangles", midpoint_rule3(), 12, false, false},
      {"3 rows of 4", rows(3, 4), 12, false, false},
      {"4 rows of 4", rows(4, 4), 16, false, false},
      {"2 rows of 6", rows(2, 6), 12, true, false},
      {"2 rows of 8", rows(2, 8), 16, true, false},
      {"12 on the inellipse", ellipse(12, 1.0), 12, true, true},
      {"16 on the inellipse", ellipse(16, 1.0), 16, true, true},
      {"12 on the half inellipse", ellipse(12, 0.5), 12, true, false},
  };
  for (const auto& cs : cases) {
    SCOPED_TRACE(cs.name);
    ASSERT_EQ(cs.layout.size(), cs.points);
    double cond_plain = 0.0, cond_cons = 0.0;
    for (const TriangleMesh* m : {&right, &cc, &dist}) {
      const TlsTriangleReport rep = report(*m, per_triangle(*m, cs.layout));
      EXPECT_EQ(rep.plain.deficient, cs.plain_singular ? m->num_cells() : 0);
      EXPECT_EQ(rep.conservative.deficient, cs.cons_singular ? m->num_cells() : 0);
      if (cs.plain_singular) {
        EXPECT_GT(rep.plain.max_condition, 1e20);
      }
      if (cs.cons_singular) {
        EXPECT_GT(rep.conservative.max_condition, 1e20);
      }
      if (!cs.plain_singular) {
        EXPECT_LT(rep.plain.max_condition, 2e3);
        if (cond_plain > 0.0) {
          EXPECT_NEAR(rep.plain.max_condition, cond_plain, 1e-9 * cond_plain);
        }
        cond_plain = rep.plain.max_condition;
      }
      if (!cs.cons_singular) {
        EXPECT_LT(rep.conservative.max_condition, 600.0);
        if (cond_cons > 0.0) {
          EXPECT_NEAR(rep.conservative.max_condition, cond_cons, 1e-9 * cond_cons);
        }
        cond_cons = rep.conservative.max_condition;
      }
    }
  }
  // Rectangle lattices: per square of the 4 x 4 cells, split by the meshes' diagonals.
  struct Lattice {
    const TriangleMesh* mesh;
    int a, b;
    Index per_triangle;
    bool plain_singular;
  };
  for (const auto& l : {Lattice{&right, 4, 6, 12, false}, Lattice{&right, 4, 8, 16, false},
                        Lattice{&right, 6, 8, 24, false}, Lattice{&cc, 6, 8, 12, false},
                        Lattice{&cc, 4, 6, 6, true}}) {
    SCOPED_TRACE(std::to_string(l.a) + " x " + std::to_string(l.b) + " per square");
    const auto x = plate_lattice(4, l.a, l.b, 0);
    TlsTriangleReconstruction r(*l.mesh, settings(TlsTriangleStrategy::None));
    const TlsTriangleReport& rep = r.set_points(x);
    for (Index e = 0; e < l.mesh->num_cells(); ++e) EXPECT_EQ(r.element(e).points, l.per_triangle);
    EXPECT_EQ(rep.plain.deficient, l.plain_singular ? l.mesh->num_cells() : 0);
    EXPECT_EQ(rep.conservative.deficient, 0);
    if (!l.plain_singular) {
      EXPECT_LT(rep.plain.max_condition, 1e3);
    }
  }
}

// Why D's MPM-TLS runs with 12 and 16 particles per triangle stop while 24 run (D 6.3.1): the
// 4 x 6, 4 x 8 and 6 x 8 rectangle lattices per square of D's 1058-triangle mesh (23 x 23
// squares, right triangles), moved by the plate's displacement (separable: x depends on X only,
// y on Y only, so lattice columns and rows stay straight lines parallel to the triangles' legs).
// At some steps a triangle holds points on only two of them; then (x - a)(x - b) or (y - a)(y - b)
// vanishes at all its points and plain D is singular (the stress fit of D 5.3.1), while the
// conservative fit (density, momentum) stays regular; at these steps it is singular only where
// the element also has fewer than 5 points (5 unknowns a_2..a_6). Scanning all 120 steps of D's run
// (dt = 1.25e-4 s, T = 0.015 s): 4 x 6 first at step 12 (up to 86 plain-deficient triangles in a
// step), 4 x 8 first at step 20 (up to 70), 6 x 8 never.
TEST(TlsTriangle, PlateMotionLosesRankWith12And16ParticlesPerTriangleNot24) {
  const int n = 23;
  const TriangleMesh m =
      structured_triangles(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), {n, n}, TrianglePattern::right);
  ASSERT_EQ(m.num_cells(), 1058);
  TlsTriangleReconstruction r(m, settings(TlsTriangleStrategy::None));
  struct Step {
    int a, b, step;
    Index plain, cons;
  };
  for (const auto& s : {Step{4, 6, 0, 0, 0}, Step{4, 6, 11, 0, 0}, Step{4, 6, 12, 4, 0},
                        Step{4, 6, 22, 30, 2}, Step{4, 8, 0, 0, 0}, Step{4, 8, 20, 2, 0},
                        Step{6, 8, 12, 0, 0}, Step{6, 8, 20, 0, 0}, Step{6, 8, 22, 0, 0}}) {
    SCOPED_TRACE(std::to_string(s.a) + " x " + std::to_string(s.b) + " at step " +
                 std::to_string(s.step));
    const auto x = plate_lattice(n, s.a, s.b, s.step);
    const TlsTriangleReport& rep = r.set_points(x);
    EXPECT_EQ(rep.outside, 0);
    EXPECT_EQ(rep.plain.deficient, s.plain);
    EXPECT_EQ(rep.conservative.deficient, s.cons);
    EXPECT_EQ(rep.plain.failed, s.plain);
    if (s.plain == 0) {
      EXPECT_LT(rep.plain.max_condition, 2e3);
    }
    if (s.cons == 0) {
      EXPECT_LT(rep.conservative.max_condition, 1e3);
    }
    for (Index e = 0; e < m.num_cells(); ++e) {
      const auto& info = r.element(e);
      if (!info.plain.deficient) continue;
      std::set<double> xs, ys;  // lattice lines hold bitwise equal coordinates
      for (Index p : r.points(e)) {
        xs.insert(x[static_cast<std::size_t>(p)][0]);
        ys.insert(x[static_cast<std::size_t>(p)][1]);
      }
      EXPECT_EQ(std::min(xs.size(), ys.size()), 2u) << e;
      EXPECT_GE(info.points, 4) << e;
      EXPECT_EQ(info.conservative.deficient, info.points < 5) << e;
    }
  }
}

// The robust strategies on the worst of those steps (4 x 6 lattice, step 22: 30 triangles with
// singular plain D, 2 with 4 points and singular conservative D). D eq. 5.1 solved as written
// (a = D^{-1} B U) gives garbage there. Every strategy gives finite fields that conserve to
// round-off and reproduce quadratics wherever the system is well posed; on the deficient
// elements Reduce and Graded reproduce linear data exactly, MinimumNorm and Graded interpolate
// the data (the undetermined quadratic is the only freedom), MinimumNorm does not reproduce
// linear data off the lines, and None gives the constant. The conservative fit of quadratic data
// is exact even where plain D is singular, as long as the conservative system is regular: a_1
// from the integral fixes the coefficient of (x - a)(x - b), whose mean is not zero.
TEST(TlsTriangle, RobustStrategiesOnThePlateStepWithSingularElements) {
  const int n = 23;
  const TriangleMesh m =
      structured_triangles(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), {n, n}, TrianglePattern::right);
  const auto x = plate_lattice(n, 4, 6, 22);
  const Quadratic quad = random_quadratic(23), lin = random_quadratic(29, 1);
  const std::vector<double> fq = quad.values(x), fl = lin.values(x);
  const std::vector<double> cq = quad.integrals(m), cl = lin.integrals(m);

  double naive = 0.0;  // D^{-1} B U on the plain-deficient elements
  for (const auto s : kStrategies) {
    SCOPED_TRACE(std::string(tls_triangle_strategy_name(s)));
    TlsTriangleReconstruction r(m, settings(s));
    const TlsTriangleReport& rep = r.set_points(x);
    ASSERT_EQ(rep.plain.deficient, 30);
    ASSERT_EQ(rep.conservative.deficient, 2);
    auto plain_ok = [&](Index e) { return !r.element(e).plain.deficient; };
    auto plain_bad = [&](Index e) { return r.element(e).plain.deficient; };
    auto cons_ok = [&](Index e) { return !r.element(e).conservative.deficient; };
    TlsTriangleCoefficients pq, cqf, pl, cl_fit;
    r.fit_plain(fq, pq);
    r.fit_conservative(fq, cq, cqf);
    r.fit_plain(fl, pl);
    r.fit_conservative(fl, cl, cl_fit);
    for (const auto* a : {&pq, &cqf, &pl, &cl_fit}) EXPECT_TRUE(all_finite(*a));
    for (Index e = 0; e < m.num_cells(); ++e) {
      const double c = cq[static_cast<std::size_t>(e)];
      EXPECT_NEAR(r.integral(cqf, e), c, 1e-15 * std::abs(c)) << e;
      const Integral gi = gauss_integral(r, cqf, e);
      EXPECT_NEAR(gi.value, c, 1e-14 * gi.scale) << e;
    }
    EXPECT_LT(max_error(r, pq, quad, plain_ok), 1e-11);
    EXPECT_LT(max_error(r, cqf, quad, cons_ok), 1e-11);  // including the 28 plain-singular
    const double lin_err = max_error(r, pl, lin, plain_bad);
    double data_err = 0.0;  // residual at the points of the plain-deficient elements
    for (Index e = 0; e < m.num_cells(); ++e) {
      if (!plain_bad(e)) continue;
      for (Index p : r.points(e))
        data_err = std::max(data_err, std::abs(r.evaluate(pq, e, x[static_cast<std::size_t>(p)]) -
                                               fq[static_cast<std::size_t>(p)]));
    }
    switch (s) {
      case TlsTriangleStrategy::None:
        EXPECT_EQ(rep.plain.failed, 30);
        EXPECT_GT(lin_err, 1e-3);
        break;
      case TlsTriangleStrategy::Reduce:
        EXPECT_LT(lin_err, 1e-12);
        EXPECT_EQ(rep.plain.reduced, 30);
        break;
      case TlsTriangleStrategy::MinimumNorm:
        EXPECT_GT(lin_err, 1e-3);
        EXPECT_LT(data_err, 1e-12);
        break;
      case TlsTriangleStrategy::Graded:
        EXPECT_LT(lin_err, 1e-12);
        EXPECT_LT(data_err, 1e-12);
        break;
    }
    if (s == TlsTriangleStrategy::None) {
      for (Index e = 0; e < m.num_cells(); ++e) {
        if (!plain_bad(e)) continue;
        Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Zero();
        TriangleTaylor BU = TriangleTaylor::Zero();
        for (Index p : r.points(e)) {
          const TriangleTaylor psi = r.basis(e, x[static_cast<std::size_t>(p)]);
          D += psi * psi.transpose();  // D eq. 5.2
          BU += psi * fq[static_cast<std::size_t>(p)];
        }
        TlsTriangleCoefficients a(static_cast<std::size_t>(m.num_cells()), TriangleTaylor::Zero());
        a[static_cast<std::size_t>(e)] = D.inverse() * BU;  // D eq. 5.1
        for (const auto& g : gauss6(m, e)) {
          const double err = std::abs(r.evaluate(a, e, g.x) - quad(g.x));
          naive =
              std::isfinite(err) ? std::max(naive, err) : std::numeric_limits<double>::infinity();
        }
      }
    }
  }
  EXPECT_GT(naive, 1.0);  // O(1) data, O(1e2) errors (or non-finite)
}

TEST(TlsTriangle, RejectsBadSettingsAndNames) {
  const TriangleMesh m =
      structured_triangles(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), {1, 1}, TrianglePattern::right);
  for (int t : {-1, 2, 4, 5, 7}) {
    TlsTriangleSettings s;
    s.terms = t;
    EXPECT_THROW((void)TlsTriangleReconstruction(m, s), InputError) << t;
  }
  for (double c : {1.0, 0.5, std::numeric_limits<double>::quiet_NaN(),
                   std::numeric_limits<double>::infinity()}) {
    TlsTriangleSettings s;
    s.max_condition = c;
    EXPECT_THROW((void)TlsTriangleReconstruction(m, s), InputError) << c;
  }
  for (const auto s : kStrategies)
    EXPECT_EQ(parse_tls_triangle_strategy(tls_triangle_strategy_name(s)), s);
  EXPECT_THROW(parse_tls_triangle_strategy("virtual"), InputError);
  TlsTriangleReconstruction r(m);
  EXPECT_EQ(r.terms(), 6);
  const std::vector<Vec<2>> x{Vec<2>(0.7, 0.2), Vec<2>(0.2, 0.7)};
  r.set_points(x);
  TlsTriangleCoefficients a;
  const std::vector<double> one{1.0};
  EXPECT_THROW(r.fit_plain(one, a), std::invalid_argument);
  const std::vector<double> two{1.0, 2.0};
  EXPECT_THROW(r.fit_conservative(two, one, a), std::invalid_argument);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
