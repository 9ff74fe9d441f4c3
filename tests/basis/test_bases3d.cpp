// The domain-averaged bases in 3D on hexahedral grids (issue 20; D 2.6.4): uGIMP, cpGIMP and
// CPDI (parallelepiped domains), and DDMPM. For each, at random points and domains: partition of
// unity, non-negative weights, zero gradient sum and linear completeness (sum w_i x_i = x_p, sum
// x_i grad_i^T = I; D 2.5, P.1-P.3), and uGIMP's weights against 1D midpoint integrals of the hat
// functions (the tensor product of the box averages); CPDI domains clipped by the grid. Then every
// basis available in 3D (P1, the B-splines, GIMP, CPDI, DDMPM) moves a body in uniform translation
// rigidly through the compiled 3D steppers in every scheme. The B-splines' and P1's own properties
// in 3D are in tests/basis/test_bspline.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "../support/stepper.hpp"
#include "basis/cpdi.hpp"
#include "basis/ddmpm.hpp"
#include "basis/gimp.hpp"
#include "basis/linear.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// Offset origin, unequal cell sizes that are not powers of two.
Grid<3> test_grid() {
  return Grid<3>(Vec<3>(-0.3, 0.2, 1.0), Vec<3>(1.7, 1.4, 2.5), IVec<3>{7, 5, 4});
}

// One particle whose initial domain is r h_d along d: V_p^0 = r^3 |cell|.
Particles<3> particle(const Grid<3>& g, const Vec<3>& x, double r, const Mat<3>& F) {
  Particles<3> P;
  P.resize(1);
  P.x[0] = P.x0[0] = x;
  P.volume0[0] = r * r * r * g.cell_volume();
  P.F[0] = F;
  P.volume[0] = F.determinant() * P.volume0[0];
  return P;
}

std::vector<Vec<3>> random_points(const Grid<3>& g, int n, unsigned seed, double margin) {
  std::mt19937 rng(seed);
  std::vector<Vec<3>> out;
  for (int k = 0; k < n; ++k) {
    Vec<3> x;
    for (int d = 0; d < 3; ++d)
      x[d] = std::uniform_real_distribution<double>(g.origin[d] + margin * g.h[d],
                                                    g.upper()[d] - margin * g.h[d])(rng);
    out.push_back(x);
  }
  return out;
}

// P.1-P.3 at one evaluation, with sum w_i x_i = `centre`.
template <class Basis>
void check_properties(const Basis& b, const typename Basis::StencilT& s, const Vec<3>& centre) {
  const Vec<3> h = b.grid().h;
  double sum = 0.0;
  Vec<3> xr = Vec<3>::Zero(), gs = Vec<3>::Zero();
  Mat<3> gr = Mat<3>::Zero();
  for (int a = 0; a < s.kSize; ++a) {
    const auto k = static_cast<std::size_t>(a);
    EXPECT_GE(s.w[k], 0.0) << Basis::kName;
    ASSERT_GE(s.dof[k], 0);
    ASSERT_LT(s.dof[k], b.num_dofs());
    const Vec<3> xi = b.dof_position(s.dof[k]);
    sum += s.w[k];
    gs += s.grad[k];
    xr += s.w[k] * xi;
    gr += xi * s.grad[k].transpose();
  }
  // Round-off: O(eps) per term, 64 terms of size <= 1 (weights) or <= 1/h (gradients).
  EXPECT_NEAR(sum, 1.0, 1e-13) << Basis::kName;
  EXPECT_LT(gs.cwiseProduct(h).norm(), 1e-12) << Basis::kName;
  EXPECT_LT((xr - centre).norm(), 1e-13) << Basis::kName;
  EXPECT_LT((gr - Mat<3>::Identity()).norm(), 1e-12) << Basis::kName;
}

double hat(double x, double xi, double h) {
  return std::max(0.0, 1.0 - std::abs(x - xi) / h);
}
// (1/(e - a)) int_a^e hat, 2000-point midpoint rule (exact on the linear pieces; each kink costs
// at most (2 h / 2000)^2 / (4 h), so each factor is off by < 4e-7).
double box_average(double a, double e, double xi, double h) {
  constexpr int kPoints = 2000;
  double integral = 0.0;
  for (int q = 0; q < kPoints; ++q) integral += hat(a + (q + 0.5) * (e - a) / kPoints, xi, h);
  return integral / kPoints;
}

TEST(Bases3D, UGimpPropertiesAndReference) {
  const UGimpBasis<3> b(test_grid());
  const Grid<3>& g = b.grid();
  Mat<3> F;
  F << 1.3, 0.4, 0.1, -0.2, 0.8, 0.0, 0.1, 0.2, 1.1;  // uGIMP ignores F
  for (double r : {0.3, 1.0, 1.7}) {
    for (const Vec<3>& x : random_points(g, 12, 3, 0.0)) {
      const Particles<3> P = particle(g, x, r, F);
      ASSERT_TRUE(b.fits(P, 0));
      UGimpBasis<3>::StencilT s;
      b.evaluate(P, 0, s);
      Vec<3> lo, hi;  // the box clipped to the grid
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::max(x[d] - 0.5 * r * g.h[d], g.origin[d]);
        hi[d] = std::min(x[d] + 0.5 * r * g.h[d], g.upper()[d]);
      }
      check_properties(b, s, 0.5 * (lo + hi));
      for (int a = 0; a < s.kSize; ++a) {
        const Vec<3> xi = b.dof_position(s.dof[static_cast<std::size_t>(a)]);
        double w = 1.0;
        for (int d = 0; d < 3; ++d) w *= box_average(lo[d], hi[d], xi[d], g.h[d]);
        // Stencil entries may repeat a DOF only where the box is clipped; the reference is per
        // entry's DOF, so compare where the DOF occurs once.
        int count = 0;
        for (int c = 0; c < s.kSize; ++c)
          count += s.dof[static_cast<std::size_t>(c)] == s.dof[static_cast<std::size_t>(a)];
        if (count == 1) {
          EXPECT_NEAR(s.w[static_cast<std::size_t>(a)], w, 1.2e-6);
        }
      }
    }
  }
}

TEST(Bases3D, CpGimpAndCpdiProperties) {
  const Grid<3> g = test_grid();
  const CpGimpBasis<3> gimp(g);
  const CpdiBasis<3> cpdi(g);
  std::vector<Mat<3>> Fs(3);
  Fs[0] = Mat<3>::Identity();
  Fs[1] << 1.0, 0.6, 0.0, 0.0, 1.0, 0.3, 0.0, 0.0, 1.0;  // shear
  Fs[2] << 1.2, 0.3, -0.1, -0.4, 0.9, 0.2, 0.1, -0.2, 1.1;
  int tested = 0;
  for (const Mat<3>& F : Fs)
    for (double r : {0.3, 0.6}) {
      // Points at least a cell from the sides: no domain is clipped.
      for (const Vec<3>& x : random_points(g, 12, 23, 1.0)) {
        const Particles<3> P = particle(g, x, r, F);
        ASSERT_TRUE(gimp.fits(P, 0));
        CpGimpBasis<3>::StencilT sg;
        gimp.evaluate(P, 0, sg);
        check_properties(gimp, sg, x);
        if (!cpdi.fits(P, 0)) continue;
        ++tested;
        CpdiBasis<3>::StencilT sc;
        cpdi.evaluate(P, 0, sc);
        check_properties(cpdi, sc, x);  // the parallelepiped's centroid is x_p
      }
    }
  EXPECT_GT(tested, 60);
}

// CPDI domains that pass the grid's sides are clipped: their corners are clamped onto the sides
// and the domain is the trilinear hexahedron of the clamped corners (basis/cpdi.hpp,
// hex_corner_weights, 2 x 2 x 2 Gauss, exact for its polynomials). Unclipped, that
// construction gives the parallelepiped's closed form (wq_c = 1/8, gq_c = J^-T xi_c / 8);
// clipped, the basis keeps partition of unity, the zero gradient sum and sum x_i grad^T = I,
// with sum w_i x_i the clipped domain's centroid sum_c wq_c x_c.
TEST(Bases3D, CpdiClippedAtTheGridSides) {
  Mat<3> F;
  F << 1.2, 0.3, -0.1, -0.4, 0.9, 0.2, 0.1, -0.2, 1.1;
  const Mat<3> J = 0.5 * 0.6 * F;  // half edges of a domain of 0.6 h per direction (h = 1)
  std::array<Vec<3>, 8> x;
  for (std::size_t c = 0; c < 8; ++c) {
    x[c] = Vec<3>(0.3, -0.2, 0.7);
    for (int d = 0; d < 3; ++d) x[c] += (((c >> d) & 1) ? 1.0 : -1.0) * J.col(d);
  }
  std::array<double, 8> wq;
  std::array<Vec<3>, 8> gq;
  ASSERT_TRUE(hex_corner_weights(x, wq, gq));
  const Mat<3> JinvT = J.inverse().transpose();
  for (std::size_t c = 0; c < 8; ++c) {
    const Vec<3> sc(((c >> 0) & 1) ? 1.0 : -1.0, ((c >> 1) & 1) ? 1.0 : -1.0,
                    ((c >> 2) & 1) ? 1.0 : -1.0);
    EXPECT_NEAR(wq[c], 0.125, 1e-15);
    EXPECT_LT((gq[c] - 0.125 * JinvT * sc).norm(), 1e-14 * JinvT.norm());
  }

  const Grid<3> g = test_grid();
  const CpdiBasis<3> cpdi(g);
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int clipped = 0;
  for (int k = 0; k < 200; ++k) {
    // Centres within a third of a cell of a side, edge or corner of the grid.
    Vec<3> xp;
    for (int d = 0; d < 3; ++d) {
      const double off = (0.02 + 0.3 * u(rng)) * g.h[d];
      xp[d] = u(rng) < 0.5 ? g.origin[d] + off : g.upper()[d] - off;
      if (u(rng) < 0.3) xp[d] = g.origin[d] + (1.0 + 3.0 * u(rng)) * g.h[d];  // an inner one
    }
    const Particles<3> P =
        particle(g, xp, 0.6 + 0.3 * u(rng), u(rng) < 0.5 ? Mat<3>(F) : Mat<3>::Identity());
    bool was_clipped = false;
    const auto corners = cpdi.corners(P, 0, &was_clipped);
    if (!was_clipped) continue;
    ASSERT_TRUE(cpdi.fits(P, 0)) << xp.transpose();
    ++clipped;
    ASSERT_TRUE(hex_corner_weights(corners, wq, gq));
    Vec<3> centroid = Vec<3>::Zero();
    for (std::size_t c = 0; c < 8; ++c) centroid += wq[c] * corners[c];
    CpdiBasis<3>::StencilT s;
    cpdi.evaluate(P, 0, s);
    check_properties(cpdi, s, centroid);
  }
  EXPECT_GT(clipped, 100);
}

// DDMPM in 3D (basis/ddmpm.hpp: alpha = prod_d 2 xi_d (1 - xi_d), the smoothed gradient from
// the 27 neighbours of each node) on particles seeded 3 per cell and direction over the whole
// grid, so that every node carries volume: at the particles and at random points, partition of
// unity, non-negative weights, zero gradient sum and sum x_i grad_bar phi_i^T = I; the values
// are P1's (D 2.6.4: only the gradients are smoothed); at a cell face, where alpha vanishes,
// the gradient is the smoothed one alone and so continuous, where P1's jumps.
TEST(Bases3D, DdmpmProperties) {
  const Grid<3> g = test_grid();
  const auto P = seed_particles<3>(g, g.origin, g.upper(), 3, 1.0);
  DdmpmBasis<3> basis(g);
  basis.prepare(P);
  const LinearBasis<3> p1(g);
  DdmpmBasis<3>::StencilT st;
  LinearBasis<3>::StencilT sp;
  for (Index p = 0; p < P.size(); p += 7) {
    basis.evaluate(P, p, st);
    check_properties(basis, st, P.x[static_cast<std::size_t>(p)]);
  }
  for (const Vec<3>& x : random_points(g, 60, 31, 0.0)) {
    basis.evaluate_point(x, st);
    check_properties(basis, st, x);
    p1.evaluate_point(x, sp);
    // Per node (a node may fill several slots near the grid's sides, the outer ones with zero
    // weight): the summed weights against P1's.
    std::map<Index, double> dd, lin;
    for (int a = 0; a < st.kSize; ++a)
      dd[st.dof[static_cast<std::size_t>(a)]] += st.w[static_cast<std::size_t>(a)];
    for (int a = 0; a < sp.kSize; ++a)
      lin[sp.dof[static_cast<std::size_t>(a)]] += sp.w[static_cast<std::size_t>(a)];
    for (const auto& [dof, w] : dd) EXPECT_NEAR(w, lin.count(dof) ? lin[dof] : 0.0, 1e-15);
    for (const auto& [dof, w] : lin) EXPECT_TRUE(dd.count(dof) > 0 || w == 0.0);
  }
  // Across the face x = node 3 inside cell (.., 2, 1): the largest gradient jump over the nodes.
  const Vec<3> x = g.origin + Vec<3>(3.0, 2.4, 1.7).cwiseProduct(g.h);
  auto jump = [&](const auto& b, auto& lo, auto& hi) {
    const Vec<3> e(1e-10, 0.0, 0.0);
    b.evaluate_point(x - e, lo);
    b.evaluate_point(x + e, hi);
    double m = 0.0;
    std::map<Index, Vec<3>> gl, gh;  // summed per node, as the weights above
    for (int a = 0; a < lo.kSize; ++a) {
      const auto k = static_cast<std::size_t>(a);
      gl.try_emplace(lo.dof[k], Vec<3>::Zero()).first->second += lo.grad[k];
      gh.try_emplace(lo.dof[k], Vec<3>::Zero());
    }
    for (int a = 0; a < hi.kSize; ++a) {
      const auto k = static_cast<std::size_t>(a);
      gh.try_emplace(hi.dof[k], Vec<3>::Zero()).first->second += hi.grad[k];
      gl.try_emplace(hi.dof[k], Vec<3>::Zero());
    }
    for (const auto& [dof, gr] : gl) m = std::max(m, (gr - gh[dof]).cwiseProduct(g.h).norm());
    return m;
  };
  DdmpmBasis<3>::StencilT lo, hi;
  LinearBasis<3>::StencilT plo, phi;
  EXPECT_LT(jump(basis, lo, hi), 1e-8);
  EXPECT_GT(jump(p1, plo, phi), 0.5);
}

// A body in uniform translation moves rigidly with every basis available in 3D: velocity
// unchanged, x = x0 + v t, F = I, no stress (each basis reproduces constants, so
// L = sum v grad phi_i = 0 while every node the body touches takes part). Every scheme with P1
// and quadratic B-splines, MUSL with the others.
// The nodal mass cut-off (method.mass_tolerance) per basis: a node touched only by the corner of
// a GIMP box, or by the far tail of a quartic or quintic B-spline, has a mass of order 1e-12 of
// the largest in 3D (a product of three small 1D factors); the default cut-off (1e-10) drops it,
// and the constants are then reproduced only to about 1e-8 (this test saw velocities off by
// 7e-9 m/s). Those bases are C1 (GIMP's weights in x_p, B-splines of degree >= 2): a node's
// gradient vanishes with its weight, so nodes of any positive mass can be kept (cut-off 0).
// P1, degree-1 B-splines and CPDI are C0: the gradient of a node whose weight tends to zero does
// not, so the round-off force on a nearly massless node becomes an acceleration that reaches the
// particles through that gradient; they keep the default cut-off. (P1 is fragile either way when
// a particle lands on a cell face to round-off: with velocities (0.6, -0.4, 0.5) m/s a particle
// reached x = 0.375 at step 75, and P1 lost the rigid motion, by 0.06-0.1 m/s, in MUSL with
// cut-off 0 and in USF with the default, whose dropped node leaves sum grad phi_i = O(1/h).
// The velocities below avoid that coincidence; the weakness is P1's, in any dimension.)
TEST(Bases3D, RigidTranslationWithEveryBasis) {
  const Grid<3> g(Vec<3>(0.0, 0.0, 0.0), Vec<3>(1.0, 1.2, 0.9), IVec<3>{8, 6, 6});
  const auto P0 = seed_particles<3>(g, Vec<3>(0.3, 0.35, 0.3), Vec<3>(0.6, 0.8, 0.6), 2, 1000.0);
  const Vec<3> vel(0.57, -0.43, 0.51);
  const ElasticParameters ep{1000.0, 1e6, 0.3};
  const std::vector<BasisKind> kinds = test::basis_kinds<3>();
  ASSERT_EQ(kinds.size(), 10u);  // linear, uGIMP, cpGIMP, CPDI, B-splines of degree 1-5, DDMPM
  for (const BasisKind& basis : kinds)
    for (const Scheme& scheme : {Scheme(Musl{}), Scheme(Usl{}), Scheme(Usf{}), Scheme(Usavg{})}) {
      const int degree = basis_degree(basis);
      const bool every_scheme = std::holds_alternative<LinearKind>(basis) || degree == 2;
      const bool c1 = degree >= 2 || std::holds_alternative<UGimpKind>(basis) ||
                      std::holds_alternative<CpGimpKind>(basis);
      if (!every_scheme && !std::holds_alternative<Musl>(scheme)) continue;
      SCOPED_TRACE(std::string(basis_name(basis)) + " degree " + std::to_string(degree) +
                   " scheme " + std::to_string(scheme.index()));
      auto P = P0;
      for (auto& v : P.v) v = vel;
      auto stepper = test::compiled_stepper<3>({.grid = g,
                                                .particles = P,
                                                .material = NeoHookean{ep},
                                                .basis = basis,
                                                .scheme = scheme,
                                                .mass_tolerance = c1 ? 0.0 : 1e-10});
      const RunState<3>& sim = stepper->state();
      const double dt = 1e-3;
      const int steps = 150;  // travels 0.0855, 0.0645, 0.0765: crosses cells
      for (int s = 0; s < steps; ++s) stepper->step(dt);
      double dv = 0.0, dx = 0.0, stress = 0.0, dF = 0.0;
      for (std::size_t i = 0; i < P.x.size(); ++i) {
        dv = std::max(dv, (sim.particles.v[i] - vel).norm());
        dx = std::max(dx, (sim.particles.x[i] - (P0.x[i] + vel * dt * steps)).norm());
        stress = std::max(stress, sim.particles.stress[i].norm());
        dF = std::max(dF, (sim.particles.F[i] - Mat<3>::Identity()).norm());
      }
      EXPECT_LT(dv, 1e-13);
      EXPECT_LT(dx, 1e-12);
      EXPECT_LT(stress, 1e-6);  // Pa, with E = 1e6 Pa
      EXPECT_LT(dF, 1e-12);
      EXPECT_GT(sim.diag.grid_crossings, 0);
    }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
