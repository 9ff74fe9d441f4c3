// DDMPM (D 2.6.4): P1 values, smoothed gradients. Checks: partition of unity of the values,
// zero gradient sum, linear reproduction of the smoothed gradient where every node carries
// volume, continuity of the gradient across a node (the grid-crossing fix, alpha = 0 there),
// and the interior closed form for uniformly spaced particles.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "basis/ddmpm.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"
#include "setup/run_settings.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

struct DdmpmSetup {
  Grid<1> g{Vec<1>(0.0), Vec<1>(1.0), IVec<1>{10}};
  Particles<1> P = seed_particles<1>(g, Vec<1>(0.0), Vec<1>(1.0), 8, 1.0);
  DdmpmBasis<1> basis{g};
  DdmpmSetup() { basis.prepare(P); }
};

TEST(Ddmpm, PartitionOfUnityZeroGradientSumLinearReproduction) {
  DdmpmSetup s;
  DdmpmBasis<1>::StencilT st;
  for (Index p = 0; p < s.P.size(); ++p) {
    s.basis.evaluate(s.P, p, st);
    double w = 0.0, gsum = 0.0, xg = 0.0, xw = 0.0;
    for (int a = 0; a < st.kSize; ++a) {
      EXPECT_GE(st.w[a], 0.0);
      w += st.w[a];
      gsum += st.grad[a][0];
      xg += s.basis.dof_position(st.dof[a])[0] * st.grad[a][0];
      xw += s.basis.dof_position(st.dof[a])[0] * st.w[a];
    }
    EXPECT_NEAR(w, 1.0, 1e-14);
    EXPECT_NEAR(gsum, 0.0, 1e-10);
    EXPECT_NEAR(xg, 1.0, 1e-12) << "particle " << p;
    EXPECT_NEAR(xw, s.P.x[static_cast<std::size_t>(p)][0], 1e-14);
  }
}

TEST(Ddmpm, GradientIsContinuousAcrossANode) {
  DdmpmSetup s;
  DdmpmBasis<1>::StencilT left, right;
  Particles<1> probe;
  probe.resize(1);
  const double node = 0.5, eps = 1e-10;
  probe.x[0][0] = node - eps;
  s.basis.evaluate(probe, 0, left);
  probe.x[0][0] = node + eps;
  s.basis.evaluate(probe, 0, right);
  // Gradient of the node-5 function (DOF 5) on both sides: P1 jumps by 2/h = 20, DDMPM not.
  auto grad_of = [](const DdmpmBasis<1>::StencilT& st, Index dof) {
    double g = 0.0;
    for (int a = 0; a < st.kSize; ++a)
      if (st.dof[a] == dof) g += st.grad[a][0];
    return g;
  };
  for (Index dof = 3; dof <= 7; ++dof)
    EXPECT_NEAR(grad_of(left, dof), grad_of(right, dof), 1e-6) << "dof " << dof;
}

TEST(Ddmpm, InteriorNodesGiveCentralDifferenceGradients) {
  // With uniformly spaced particles the particle sums are the exact integrals in the interior:
  // (1/V_j) int phi_j dphi_{j+-1}/dx = +-1/(2h), and 0 for i = j. At a node (alpha = 0) the
  // gradient of phi_{j+1} is then 1/(2h) and that of phi_{j-1} is -1/(2h).
  DdmpmSetup s;
  DdmpmBasis<1>::StencilT st;
  Particles<1> probe;
  probe.resize(1);
  probe.x[0][0] = 0.5;  // node 5
  s.basis.evaluate(probe, 0, st);
  const double h = 0.1;
  for (int a = 0; a < st.kSize; ++a) {
    if (st.dof[a] == 6) {
      EXPECT_NEAR(st.grad[a][0], 1.0 / (2 * h), 1e-9);
    }
    if (st.dof[a] == 4) {
      EXPECT_NEAR(st.grad[a][0], -1.0 / (2 * h), 1e-9);
    }
  }
}

TEST(Ddmpm, ABodyInPartOfTheGridSmoothsOnlyNearItsParticles) {
  // The smoothed gradients are held for the nodes of the particles' cells only (DofArray): at
  // any point of the grid the gradient is alpha grad phi + (1 - alpha) sum_j phi_j G_j, with G_j
  // the particle sums of D 2.6.4 computed here over every node (zero where no particle is).
  const Grid<1> g{Vec<1>(0.0), Vec<1>(1.0), IVec<1>{10}};
  const Particles<1> P = seed_particles<1>(g, Vec<1>(0.3), Vec<1>(0.55), 3, 1.0);
  DdmpmBasis<1> basis{g};
  basis.prepare(P);
  const double h = 0.1;
  const auto phi = [&](Index j, double x) { return std::max(0.0, 1.0 - std::abs(x / h - j)); };
  const auto dphi = [&](Index j, double x) {
    const double s = x / h - static_cast<double>(j);
    return s > -1.0 && s < 0.0 ? 1.0 / h : s >= 0.0 && s < 1.0 ? -1.0 / h : 0.0;
  };
  // G[j][o + 1] = (1/V_j) sum_p V_p phi_j(x_p) dphi_{j+o}(x_p), nodes 0..10.
  std::vector<std::array<double, 3>> G(11, {0.0, 0.0, 0.0});
  std::vector<double> V(11, 0.0);
  for (Index p = 0; p < P.size(); ++p) {
    const double x = P.x[static_cast<std::size_t>(p)][0],
                 Vp = P.volume[static_cast<std::size_t>(p)];
    for (Index j = 0; j <= 10; ++j) {
      V[static_cast<std::size_t>(j)] += Vp * phi(j, x);
      for (int o = -1; o <= 1; ++o)
        if (j + o >= 0 && j + o <= 10)
          G[static_cast<std::size_t>(j)][static_cast<std::size_t>(o + 1)] +=
              Vp * phi(j, x) * dphi(j + o, x);
    }
  }
  int away = 0;
  for (int k = 1; k < 200; ++k) {
    const double x = 0.005 * k;
    DdmpmBasis<1>::StencilT st;
    basis.evaluate_point(Vec<1>(x), st);
    const Index c = std::min<Index>(static_cast<Index>(std::floor(x / h)), 9);
    const double xi = x / h - static_cast<double>(c), alpha = 2.0 * (1.0 - xi) * xi;
    double smoothing = 0.0;
    for (int a = 0; a < st.kSize; ++a) {
      const Index i = st.dof[a];
      if (st.w[a] == 0.0 && (i == c || i == c + 1)) continue;  // a node clamped at the side
      double smooth = 0.0;
      for (const Index j : {c, c + 1})
        if (std::abs(i - j) <= 1 && V[static_cast<std::size_t>(j)] > 0.0)
          smooth += phi(j, x) *
                    G[static_cast<std::size_t>(j)][static_cast<std::size_t>(i - j + 1)] /
                    V[static_cast<std::size_t>(j)];
      smoothing += std::abs(smooth);
      const double plain = (i == c || i == c + 1) ? dphi(i, x) : 0.0;
      EXPECT_NEAR(st.grad[a][0], alpha * plain + (1.0 - alpha) * smooth, 1e-9)
          << "x = " << x << ", node " << i;
    }
    if (smoothing == 0.0) ++away;
  }
  // Cells 0-1 and 7-9 (x < 0.2, x >= 0.7): no particle reaches their nodes; half the points.
  EXPECT_GE(away, 95);
}

// method.ddmpm_integrals = "quadrature": the integrals are exact over the cells holding particles,
// whatever the particles' positions inside them. Particles in cells 2-4 of a 10-cell grid, moved
// unevenly within their cells: at node 2 (the body's edge, alpha = 0, phi_2 = 1) the smoothed
// gradients are G_2[o] = (1/V_2) int_{cell 2} phi_2 phi_{2+o}', V_2 = h/2: -1/h for node 2,
// +1/h for node 3, 0 for node 1; at node 3, V_3 = h: -1/(2h), 0, +1/(2h) (central differences).
// The particles' sums give other values for these positions (at node 3: not 0).
TEST(Ddmpm, QuadratureIntegralsAreExactOverTheParticlesCells) {
  const Grid<1> g{Vec<1>(0.0), Vec<1>(1.0), IVec<1>{10}};
  Particles<1> P = seed_particles<1>(g, Vec<1>(0.2), Vec<1>(0.5), 2, 1.0);
  ASSERT_EQ(P.size(), 6);
  const std::array<double, 6> shift = {0.013, -0.02, 0.007, 0.018, -0.011, 0.004};
  for (std::size_t p = 0; p < 6; ++p) P.x[p][0] += shift[p];  // each stays in its cell
  const double h = 0.1;
  DdmpmBasis<1> exact(g, {DdmpmIntegrals::quadrature, DdmpmWeight::per_direction});
  DdmpmBasis<1> sums(g, {DdmpmIntegrals::particles, DdmpmWeight::per_direction});
  exact.prepare(P);
  sums.prepare(P);
  auto grad_at = [](const DdmpmBasis<1>& b, double x, Index dof) {
    DdmpmBasis<1>::StencilT st;
    b.evaluate_point(Vec<1>(x), st);
    double gsum = 0.0;
    for (int a = 0; a < st.kSize; ++a)
      if (st.dof[a] == dof) gsum += st.grad[a][0];
    return gsum;
  };
  EXPECT_NEAR(grad_at(exact, 0.2, 1), 0.0, 1e-12);
  EXPECT_NEAR(grad_at(exact, 0.2, 2), -1.0 / h, 1e-12);
  EXPECT_NEAR(grad_at(exact, 0.2, 3), 1.0 / h, 1e-12);
  EXPECT_NEAR(grad_at(exact, 0.3, 2), -0.5 / h, 1e-12);
  EXPECT_NEAR(grad_at(exact, 0.3, 3), 0.0, 1e-12);
  EXPECT_NEAR(grad_at(exact, 0.3, 4), 0.5 / h, 1e-12);
  EXPECT_GT(std::abs(grad_at(sums, 0.3, 3)), 1e-3 / h);
  // Linear reproduction at the particles holds in both readings.
  for (const DdmpmBasis<1>* b : {&exact, &sums}) {
    DdmpmBasis<1>::StencilT st;
    for (Index p = 0; p < P.size(); ++p) {
      b->evaluate(P, p, st);
      double xg = 0.0;
      for (int a = 0; a < st.kSize; ++a) xg += b->dof_position(st.dof[a])[0] * st.grad[a][0];
      EXPECT_NEAR(xg, 1.0, 1e-12) << "particle " << p;
    }
  }
}

// The keys reach the kind (and so make_basis); with another basis they are refused, naming the
// key and the basis, rather than ignored.
TEST(Ddmpm, SettingsFromTheKeysAndRefusedWithAnotherBasis) {
  const std::string base = std::string(MPM_SOURCE_DIR) + "/examples/vibrating_bar_small.toml";
  const MethodSettings m =
      run_settings(Config::load(base, {"method.basis=ddmpm", "method.ddmpm_integrals=quadrature",
                                       "method.ddmpm_weight=product"}),
                   1)
          .method;
  const auto& kind = std::get<DdmpmKind>(m.basis);
  EXPECT_EQ(kind.settings.integrals, DdmpmIntegrals::quadrature);
  EXPECT_EQ(kind.settings.weight, DdmpmWeight::product);
  EXPECT_EQ(
      std::get<DdmpmKind>(run_settings(Config::load(base, {"method.basis=ddmpm"}), 1).method.basis)
          .settings.weight,
      DdmpmWeight::per_direction);
  try {
    (void)run_settings(Config::load(base, {"method.ddmpm_integrals=quadrature"}), 1);
    FAIL() << "no input error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("method.ddmpm_integrals"), std::string::npos) << what;
    EXPECT_NE(what.find("method.basis = \"linear\""), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
