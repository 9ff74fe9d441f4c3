// Taylor least squares on hexahedra (issue 20): the ten-term quadratic basis, the 3D analogue of
// D 6.1.1 (1, s, t, u, the centred squares, s t, s u, t u); polynomial reproduction of the
// complete spaces of 1, 4 and 10 terms from scattered points, plain and conservative; element
// integrals kept to round-off with every completion; the completions restoring the full basis
// in an element with one or two points (virtual points on the 3 x 3 face nodes, points borrowed
// across faces, edges and corners); and the TLS mapping conserving mass and momentum to
// round-off through MUSL steps of a free 3D body with every completion (D Table 6.1 in 3D).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "../support/examples.hpp"
#include "../support/stepper.hpp"
#include "mapping/tls.hpp"
#include "model/problem.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TlsSettings settings(int terms, TlsCompletion c) {
  TlsSettings s;
  s.terms = terms;
  s.completion = c;
  return s;
}

// psi_2..psi_10 integrate to zero over the element with the mapping's 2 x 2 x 2 rule (and 3 x 3
// x 3), psi_1 to the volume 8 of [-1, 1]^3; the ten functions are mutually orthogonal there and
// their mean squares are 1, 1/3, 1/45 and 1/9, the scales of the orthonormal basis in which the
// condition number is measured (TlsSettings::max_condition).
TEST(TlsBasis3D, IntegratesToZeroAndIsOrthogonal) {
  for (int n : {2, 3}) {
    const GaussRule rule = gauss_legendre(n);
    TaylorVector<3> integral = TaylorVector<3>::Zero();
    Eigen::Matrix<double, 10, 10> gram = Eigen::Matrix<double, 10, 10>::Zero();
    for (std::size_t i = 0; i < rule.xi.size(); ++i)
      for (std::size_t j = 0; j < rule.xi.size(); ++j)
        for (std::size_t k = 0; k < rule.xi.size(); ++k) {
          const double w = rule.w[i] * rule.w[j] * rule.w[k];
          const TaylorVector<3> psi = taylor_basis(rule.xi[i], rule.xi[j], rule.xi[k]);
          integral += w * psi;
          gram += w * psi * psi.transpose();
        }
    EXPECT_NEAR(integral[0], 8.0, 1e-14);
    for (int t = 1; t < 10; ++t) EXPECT_NEAR(integral[t], 0.0, 1e-14) << "psi_" << t + 1;
    if (n < 3) continue;  // the squares of the quadratic terms need degree 4: 3 points
    const double mean_sq[10] = {1.0,        1.0 / 3,    1.0 / 3,   1.0 / 3,   1.0 / 45,
                                1.0 / 45.0, 1.0 / 45.0, 1.0 / 9.0, 1.0 / 9.0, 1.0 / 9.0};
    for (int a = 0; a < 10; ++a)
      for (int b = 0; b < 10; ++b)
        EXPECT_NEAR(gram(a, b) / 8.0, a == b ? mean_sq[a] : 0.0, 1e-14) << a << ", " << b;
  }
  // The 2D basis is the 3D one at u = 0 without the u terms (the same order of the shared ones).
  const TaylorVector<3> p3 = taylor_basis(0.3, -0.7, 0.0);
  const TaylorVector<2> p2 = taylor_basis(0.3, -0.7);
  for (int k : {0, 1, 2}) EXPECT_EQ(p3[k], p2[k]);
  EXPECT_EQ(p3[4], p2[3]);
  EXPECT_EQ(p3[5], p2[4]);
  EXPECT_EQ(p3[7], p2[5]);
}

// counts[e] uniform random points in element e of g (x fastest), shuffled.
std::vector<Vec<3>> scatter(const Grid<3>& g, const std::vector<int>& counts, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<3>> x;
  for (std::size_t e = 0; e < counts.size(); ++e) {
    Index r = static_cast<Index>(e);
    Vec<3> lo;
    for (int d = 0; d < 3; ++d) {
      lo[d] = g.origin[d] + g.h[d] * static_cast<double>(r % g.cells[d]);
      r /= g.cells[d];
    }
    for (int k = 0; k < counts[e]; ++k) {
      const double a = u(rng), b = u(rng), c = u(rng);
      x.emplace_back(lo[0] + g.h[0] * a, lo[1] + g.h[1] * b, lo[2] + g.h[2] * c);
    }
  }
  std::shuffle(x.begin(), x.end(), rng);
  return x;
}

// A quadratic in x, y, z truncated to `terms` terms (the complete space of degree 0, 1 or 2:
// 1, 4 or 10 terms), and its exact element integrals (3 x 3 x 3 Gauss is exact).
struct Quadratic {
  double c[10] = {1.7, -0.8, 0.6, 0.45, 2.3, -1.1, 0.7, 0.9, -0.55, 1.25};
  int terms = 10;
  double operator()(const Vec<3>& x) const {
    const double m[10] = {1.0,         x[0],        x[1],        x[2],        x[0] * x[0],
                          x[1] * x[1], x[2] * x[2], x[0] * x[1], x[0] * x[2], x[1] * x[2]};
    double v = 0.0;
    for (int k = 0; k < terms; ++k) v += c[k] * m[k];
    return v;
  }
  std::vector<double> integrals(const Grid<3>& g) const {
    const GaussRule rule = gauss_legendre(3);
    std::vector<double> out;
    for (Index e = 0; e < g.num_cells(); ++e) {
      Index r = e;
      Vec<3> c;
      for (int d = 0; d < 3; ++d) {
        c[d] = g.origin[d] + (static_cast<double>(r % g.cells[d]) + 0.5) * g.h[d];
        r /= g.cells[d];
      }
      double s = 0.0;
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j)
          for (std::size_t k = 0; k < 3; ++k)
            s += 0.125 * g.cell_volume() * rule.w[i] * rule.w[j] * rule.w[k] *
                 (*this)(Vec<3>(c[0] + 0.5 * g.h[0] * rule.xi[i], c[1] + 0.5 * g.h[1] * rule.xi[j],
                                c[2] + 0.5 * g.h[2] * rule.xi[k]));
      out.push_back(s);
    }
    return out;
  }
};

// n x n x n Gauss integral of the reconstruction of element e.
double element_integral(const TlsReconstruction3D& r, const TlsCoefficients3D& a, Index e, int n) {
  const GaussRule rule = gauss_legendre(n);
  const Vec<3> c = r.centre(e), hw = r.half_width();
  double sum = 0.0;
  for (std::size_t i = 0; i < rule.xi.size(); ++i)
    for (std::size_t j = 0; j < rule.xi.size(); ++j)
      for (std::size_t k = 0; k < rule.xi.size(); ++k)
        sum += hw.prod() * rule.w[i] * rule.w[j] * rule.w[k] *
               r.evaluate(a, e,
                          Vec<3>(c[0] + hw[0] * rule.xi[i], c[1] + hw[1] * rule.xi[j],
                                 c[2] + hw[2] * rule.xi[k]));
  return sum;
}

// n_b = 1, 4, 10 reproduce the complete polynomials of degree 0, 1, 2 from scattered points on
// elements that are not cubes, plain and conservative.
TEST(TlsReconstruction3D, ReproducesPolynomialsOfTheBasis) {
  const Grid<3> g(Vec<3>(0.3, -1.0, 0.2), Vec<3>(2.3, 0.5, 1.0), IVec<3>{3, 2, 2});
  const auto x = scatter(g, {20, 24, 30, 18, 22, 27, 25, 19, 21, 26, 23, 28}, 7);
  for (int nb : {1, 4, 10}) {
    SCOPED_TRACE("n_b = " + std::to_string(nb));
    Quadratic p;
    p.terms = nb;
    TlsReconstruction3D r(settings(nb, TlsCompletion::None));
    const TlsReport& rep = r.set_points(g, x);
    ASSERT_EQ(rep.failed, 0);
    EXPECT_EQ(rep.full, 12);
    std::vector<double> f;
    for (const auto& xp : x) f.push_back(p(xp));
    TlsCoefficients3D plain, cons;
    r.fit_plain(f, plain);
    r.fit_conservative(f, p.integrals(g), cons);
    for (int i = 0; i <= 12; ++i)
      for (int j = 0; j <= 9; ++j)
        for (int k = 0; k <= 8; ++k) {
          const Vec<3> xs(0.3 + 2.0 * i / 12.0, -1.0 + 1.5 * j / 9.0, 0.2 + 0.8 * k / 8.0);
          EXPECT_NEAR(r.evaluate(plain, xs), p(xs), 1e-11);
          EXPECT_NEAR(r.evaluate(cons, xs), p(xs), 1e-11);
        }
  }
}

// Elements with 0 to 3 points, coplanar and coincident points, next to well-filled ones: every
// completion keeps int_e f^ = c_e to round-off (D eq. 5.8-5.9 on hexahedra), inactive elements
// stay zero; None reports the deficient elements with their cell indices.
TEST(TlsReconstruction3D, ConservesElementIntegralsWithEveryCompletion) {
  const Grid<3> g(Vec<3>(-1.0, 0.0, 0.5), Vec<3>(1.4, 2.0, 1.7), IVec<3>{3, 3, 3});
  std::vector<int> counts(27);
  for (int e = 0; e < 27; ++e) counts[static_cast<std::size_t>(e)] = 18 + (7 * e) % 13;
  counts[1] = 0;
  counts[5] = 1;
  counts[9] = 2;
  counts[13] = 3;
  counts[20] = 0;
  auto x = scatter(g, counts, 11);
  // Element 22: all points on the plane z = 1.45 (u = const: psi_4, psi_7 constant); element 17:
  // six points at one position.
  const Vec<3> at17 = g.origin + Vec<3>(2.6, 2.3, 1.4).cwiseProduct(g.h);
  for (auto& xp : x) {
    const Index e = g.cell_index(xp);
    if (e == 22) xp[2] = 1.45;
    if (e == 17) xp = at17;
  }
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> f(x.size()), c(27);
  for (double& v : f) v = 2.0 + u(rng);
  for (double& v : c) v = 0.3 * (2.0 + u(rng));

  for (TlsCompletion mode :
       {TlsCompletion::Reduce, TlsCompletion::Virtual, TlsCompletion::Neighbour}) {
    SCOPED_TRACE(std::string(tls_completion_name(mode)));
    TlsReconstruction3D r(settings(10, mode));
    const TlsReport& rep = r.set_points(g, x);
    EXPECT_EQ(rep.elements, 27);
    EXPECT_EQ(rep.active, 25);
    EXPECT_EQ(rep.failed, 0);
    EXPECT_GE(rep.full, 15);
    EXPECT_GT(mode == TlsCompletion::Reduce    ? rep.reduced
              : mode == TlsCompletion::Virtual ? rep.with_virtual
                                               : rep.with_neighbours,
              0);
    TlsCoefficients3D a;
    r.fit_conservative(f, c, a);
    for (Index e = 0; e < 27; ++e) {
      const auto ei = static_cast<std::size_t>(e);
      if (!r.active(e)) {
        EXPECT_EQ(a[ei].norm(), 0.0);
        EXPECT_EQ(r.element(e).terms, 0);
        continue;
      }
      EXPECT_TRUE(a[ei].allFinite()) << "element " << e;
      EXPECT_NEAR(element_integral(r, a, e, 2), c[ei], 1e-14 * std::abs(c[ei])) << "element " << e;
      EXPECT_NEAR(element_integral(r, a, e, 4), c[ei], 1e-14 * std::abs(c[ei])) << "element " << e;
    }
  }

  TlsReconstruction3D none(settings(10, TlsCompletion::None));
  const TlsReport& rep = none.set_points(g, x);
  EXPECT_GE(rep.failed, 5);  // elements 5, 9, 13, 17, 22
  EXPECT_EQ(rep.failed_element, 5);
  EXPECT_EQ(rep.failed_points, 1);
  EXPECT_EQ(none.describe(22), "22 at cell (1, 1, 2)");
  EXPECT_TRUE(none.element(17).failed);
  EXPECT_TRUE(none.element(22).failed);
  TlsCoefficients3D a;
  none.fit_conservative(f, c, a);
  EXPECT_TRUE(std::isnan(a[5][0]));
}

// The middle element of 3 x 3 x 3 with one or two points among well-filled neighbours: virtual
// points (3 x 3 per face for the quadratic basis, 2 x 2 for the linear one, 6 faces) and
// borrowed points restore the full basis, so the polynomial is reproduced there exactly; Reduce
// keeps the conserved mean.
TEST(TlsReconstruction3D, CompletionsRestoreTheFullBasis) {
  const Grid<3> g(Vec<3>(0.0, 0.0, 0.0), Vec<3>(3.0, 1.5, 2.1), IVec<3>{3, 3, 3});
  for (int own : {1, 2}) {
    for (int nb : {4, 10}) {
      std::vector<int> counts(27, 27);
      counts[13] = own;
      const auto x = scatter(g, counts, 2 + static_cast<unsigned>(own));
      Quadratic p;
      p.terms = nb;
      std::vector<double> fx;
      for (const auto& xp : x) fx.push_back(p(xp));
      const auto c = p.integrals(g);
      for (TlsCompletion mode :
           {TlsCompletion::Reduce, TlsCompletion::Virtual, TlsCompletion::Neighbour}) {
        SCOPED_TRACE(
            fmt::format("{}, n_b = {}, own points {}", tls_completion_name(mode), nb, own));
        TlsReconstruction3D r(settings(nb, mode));
        r.set_points(g, x);
        TlsCoefficients3D cons, plain;
        r.fit_conservative(fx, c, cons);
        r.fit_plain(fx, plain);
        const TlsElementInfo& mid = r.element(13);
        EXPECT_EQ(mid.points, own);
        EXPECT_NEAR(element_integral(r, cons, 13, 2), c[13], 1e-14 * std::abs(c[13]));
        if (mode == TlsCompletion::Reduce) {
          EXPECT_EQ(mid.terms, 1);
          EXPECT_NEAR(r.evaluate(cons, 13, r.centre(13)), c[13] / g.cell_volume(), 1e-13);
          continue;
        }
        EXPECT_EQ(mid.terms, nb);
        if (mode == TlsCompletion::Virtual)
          EXPECT_EQ(mid.virtual_points, 6 * (nb == 10 ? 9 : 4));
        else
          EXPECT_GE(mid.borrowed, nb - own);  // at least the missing terms
        for (double sx : {-1.0, -0.3, 0.4, 1.0})
          for (double sy : {-1.0, 0.2, 0.9})
            for (double sz : {-0.8, 0.1, 1.0}) {
              const Vec<3> xs(1.5 + 0.5 * sx, 0.75 + 0.25 * sy, 1.05 + 0.35 * sz);
              EXPECT_NEAR(r.evaluate(cons, 13, xs), p(xs), 1e-10);
              EXPECT_NEAR(r.evaluate(plain, 13, xs), p(xs), 1e-10);
            }
      }
    }
  }
}

// With the six face neighbours empty, the neighbour completion borrows from the twelve edge
// neighbours; with those empty too, from the eight corners. The linear field is then reproduced
// in the middle element.
TEST(TlsReconstruction3D, NeighbourCompletionFallsBackToEdgesAndCorners) {
  const Grid<3> g(Vec<3>::Zero(), Vec<3>(3.0, 3.0, 3.0), IVec<3>{3, 3, 3});
  auto steps = [](int e) {  // offsets from the middle that are not zero
    int n = 0;
    for (int d = 0, r = e; d < 3; ++d, r /= 3) n += r % 3 != 1;
    return n;
  };
  for (int from : {2, 3}) {
    SCOPED_TRACE(from == 2 ? "edges" : "corners");
    std::vector<int> counts(27, 0);
    for (int e = 0; e < 27; ++e)
      if (steps(e) == from) counts[static_cast<std::size_t>(e)] = 12;
    counts[13] = 1;
    const auto x = scatter(g, counts, 9);
    Quadratic p;
    p.terms = 4;
    std::vector<double> fx;
    for (const auto& xp : x) fx.push_back(p(xp));
    TlsSettings s = settings(4, TlsCompletion::Neighbour);
    s.max_borrowed = 12;
    TlsReconstruction3D r(s);
    r.set_points(g, x);
    EXPECT_EQ(r.element(13).terms, 4);
    EXPECT_GE(r.element(13).borrowed, 3);
    TlsCoefficients3D a;
    r.fit_plain(fx, a);
    for (double sx : {-1.0, 0.5})
      for (double sz : {-0.2, 1.0}) {
        const Vec<3> xs(1.5 + 0.5 * sx, 1.5 - 0.3 * sx, 1.5 + 0.5 * sz);
        EXPECT_NEAR(r.evaluate(a, 13, xs), p(xs), 1e-11);
      }
  }
}

// Terms other than 1, 4 and 10 are refused in 3D, naming the key and the choices.
TEST(TlsReconstruction3D, SettingsAreValidatedIn3D) {
  TlsSettings s;
  s.terms = 6;
  const std::string m = [&] {
    try {
      validate(s, 3);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  }();
  EXPECT_NE(m.find("method.tls_terms = 6 must be 1 (constant), 4 (linear) or 10 (quadratic) in 3D"),
            std::string::npos)
      << m;
  s.terms = 10;
  EXPECT_NO_THROW(validate(s, 3));
  EXPECT_THROW(validate(s, 2), InputError);
}

// A free elastic block whose faces cut cells, a swirling initial velocity, random masses: 20
// MUSL steps with the TLS mapping conserve mass and momentum to round-off at every step, with
// each completion and with P1 and quadratic B-splines, lumped mass. The block
// starts a third of a cell into cell 1 of 6 and spans 3 cells in x and y, 2 in z, 3 particles
// per cell width: the inner cells hold the 3 x 3 x 3 lattice (the full quadratic basis, cond
// 2.4 in the orthonormal basis), the edge cells 2 or 1 particles per direction (deficient:
// completed or reduced).
TEST(TlsMapping3D, MuslStepsConserveMassAndMomentum) {
  const Grid<3> g(Vec<3>::Zero(), Vec<3>(1.0, 1.0, 1.0), IVec<3>{6, 6, 6});
  const double h = 1.0 / 6.0, lo = (1.0 + 1.0 / 3.0) * h;
  auto P = seed_particles<3>(g, Vec<3>(lo, lo, lo), Vec<3>(lo + 3 * h, lo + 3 * h, lo + 2 * h), 3,
                             1000.0);
  ASSERT_EQ(P.size(), 9 * 9 * 6);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.8, 1.2);
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const Vec<3> r = P.x[i] - Vec<3>(0.51, 0.5, 0.475);
    P.v[i] = Vec<3>(0.2 - 0.5 * r[1], 0.1 + 0.5 * r[0] - 0.3 * r[2], 0.3 * r[1]) +
             0.3 * Vec<3>(r[0], -r[1], 0.5 * r[2]);
    P.mass[i] *= u(rng);
  }
  struct Case {
    BasisKind basis;
    MassType mass;
    TlsCompletion completion;
  };
  for (const Case& c : {Case{LinearKind{}, MassType::Lumped, TlsCompletion::Reduce},
                        Case{LinearKind{}, MassType::Lumped, TlsCompletion::Virtual},
                        Case{LinearKind{}, MassType::Lumped, TlsCompletion::Neighbour},
                        Case{BSplineKind<2>{}, MassType::Lumped, TlsCompletion::Reduce},
                        Case{BSplineKind<2>{}, MassType::Lumped, TlsCompletion::Virtual}}) {
    SCOPED_TRACE(fmt::format(
        "{} degree {}, {} mass, {}", basis_name(c.basis), basis_degree(c.basis),
        c.mass == MassType::Lumped ? "lumped" : "consistent", tls_completion_name(c.completion)));
    TlsSettings s;
    s.completion = c.completion;
    s.max_condition = 10.0;  // the run set-up's default in 2D and 3D
    auto stepper =
        test::compiled_stepper<3>({.grid = g,
                                   .particles = P,
                                   .material = NeoHookean{ElasticParameters{1000.0, 1e6, 0.3}},
                                   .basis = c.basis,
                                   .mapping = TlsMapping(s, 3),
                                   .mass = c.mass});
    RunState<3>& sim = stepper->state();
    for (int k = 0; k < 20; ++k) {
      stepper->step(1e-4);
      ++sim.step;
    }
    EXPECT_LT(sim.diag.max_rel_mass_error, 1e-14);
    EXPECT_LT(sim.diag.max_rel_momentum_error, 1e-13);
    const auto report = test::mapping_report(*stepper)["tls"];
    EXPECT_GT(static_cast<Index>(report["element_fits"]), 0);
    EXPECT_GT(static_cast<Index>(report["full"]), 0);
    for (const auto& v : sim.particles.v) ASSERT_TRUE(std::isfinite(v.norm()));
  }
}

// Consistent mass with TLS (D eq. 5.17) on the cube, whose particles fill the grid: mass and
// momentum of the mapping to round-off through the run. (A body that cuts cells makes the
// consistent matrix singular at step 0, in 3D as in 2D: issue 22, item 1. B-spline TLS with
// consistent mass is refused unless method.allow_unstable: in 2D it flutters under load.)
TEST(TlsMapping3D, ConsistentMassOnTheCubeConserves) {
  const RunResult r =
      test::run_example_ok("cube_mms_3d", {"grid.cells=3", "particles.per_cell=3",
                                           "method.mapping=tls", "method.basis=bspline",
                                           "method.mass=consistent", "method.allow_unstable=true",
                                           "mms.amplitude=0.01", "time.dt=1e-4", "time.end=1e-3"});
  EXPECT_LT(r.diag.max_rel_mass_error, 1e-14);
  EXPECT_LT(r.diag.max_rel_momentum_error, 1e-13);
  ASSERT_TRUE(r.errors.displacement_rms.has_value());
  EXPECT_LT(*r.errors.displacement_rms, 1e-3);  // m, with A = 0.01 m
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
