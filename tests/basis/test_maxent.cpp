// The local max-ent basis (D 4.3, eq. 4.36-4.52) in 1D and 2D: non-negativity, partition of
// unity, affine reproduction of values and gradients (D 4.3.2); that the weights are the
// maximum-entropy ones (the optimality condition: ln(phi_i / w_i) is affine in x_i, which with
// the two constraints determines them uniquely); the weak Kronecker-delta property at boundary
// nodes (eq. 4.52) and not at interior ones; gradients against central differences (which
// checks the sign of D eq. 4.43, see basis/maxent.cpp); the prior and its slope (eq. 4.48, 4.49);
// Newton failures reported with the point, the nodes and the residual (exit code 10); runs that
// conserve mass and momentum to round-off; the mappings refused with it.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "../support/stepper.hpp"
#include "basis/maxent.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"
#include "setup/run_settings.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

template <int Dim>
Grid<Dim> test_grid();
template <>
Grid<1> test_grid<1>() {
  return Grid<1>(Vec<1>(-0.3), Vec<1>(1.7), IVec<1>{9});
}
// Unequal cell sizes: zeta is the smaller (0.2 in y, 0.25 in x).
template <>
Grid<2> test_grid<2>() {
  return Grid<2>(Vec<2>(-0.3, 0.2), Vec<2>(1.7, 1.6), IVec<2>{8, 7});
}

template <int Dim>
std::vector<Vec<Dim>> sample_points(const Grid<Dim>& g, int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<Dim>> pts;
  const Vec<Dim> hi = g.upper();
  for (int k = 0; k < n; ++k) {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) {
      double s = u(rng);
      if (k % 5 == 0) s = 1e-3 * s;                   // close to the lower boundary
      if (k % 5 == 1) s = 1.0 - 1e-3 * s;             // close to the upper boundary
      if (k % 7 == 2) s = std::round(s * 4.0) / 4.0;  // on a node line (or the boundary)
      x[d] = g.origin[d] + s * (hi[d] - g.origin[d]);
    }
    pts.push_back(x);
  }
  return pts;
}

template <int Dim>
void check_reproduction(double dmax) {
  SCOPED_TRACE(::testing::Message() << Dim << "D, d_max = " << dmax);
  const Grid<Dim> g = test_grid<Dim>();
  const MaxEntBasis<Dim> basis(g, MaxEntSettings{dmax, 1e-12, 50});
  typename MaxEntBasis<Dim>::StencilT s;
  for (const Vec<Dim>& x : sample_points(g, 300)) {
    SCOPED_TRACE(::testing::Message() << "x = " << x.transpose());
    basis.evaluate_point(x, s);
    double sum = 0.0;
    Vec<Dim> first = Vec<Dim>::Zero(), grad_sum = Vec<Dim>::Zero();
    Mat<Dim> grad_first = Mat<Dim>::Zero();
    for (int a = 0; a < s.kSize; ++a) {
      ASSERT_GE(s.w[a], 0.0);
      const Vec<Dim> xa = basis.dof_position(s.dof[a]);
      sum += s.w[a];
      first += s.w[a] * xa;
      grad_sum += s.grad[a];
      grad_first += xa * s.grad[a].transpose();
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    EXPECT_LT((first - x).norm(), 1e-11 * basis.zeta());
    // The gradients sum to zero exactly (basis/maxent.cpp). Their affine reproduction holds to
    // the Newton residual amplified by H^-1, which grows as delta^-2 at a distance delta from
    // the boundary; on it, the gradients are those of a point 1e-6 zeta inside.
    double delta = 1.0;
    for (int d = 0; d < Dim; ++d)
      delta = std::min(
          {delta, (x[d] - g.origin[d]) / basis.zeta(), (g.upper()[d] - x[d]) / basis.zeta()});
    const double tol = delta <= 0.0 ? 1e-5 : std::max(1e-10, 1e-17 / (delta * delta));
    EXPECT_LT(grad_sum.norm() * basis.zeta(), 1e-12);
    EXPECT_LT((grad_first - Mat<Dim>::Identity()).norm(), tol) << "delta = " << delta;
  }
  basis.throw_if_failed(0, 0.0, "test points");
}

TEST(MaxEnt, PartitionOfUnityAndAffineReproduction) {
  for (double dmax : {1.5, 2.0, 3.0}) {
    check_reproduction<1>(dmax);
    check_reproduction<2>(dmax);
  }
}

// The maximum-entropy solution: phi_i = w_i exp(-lambda . (x_i - x)) / Z, so ln(phi_i / w_i) is
// an affine function of x_i. Fitted by least squares over the nodes of nonzero weight, the
// residual is round-off; with partition of unity and affine reproduction this fixes the weights.
TEST(MaxEnt, WeightsAreTheMaximumEntropyOnes) {
  const Grid<2> g = test_grid<2>();
  const MaxEntSettings settings{3.0, 1e-12, 50};
  const MaxEntBasis<2> basis(g, settings);
  MaxEntBasis<2>::StencilT s;
  for (const Vec<2>& x : {Vec<2>(0.31, 0.77), Vec<2>(-0.25, 0.23), Vec<2>(1.0, 1.0)}) {
    basis.evaluate_point(x, s);
    std::vector<Vec<2>> xs;
    std::vector<double> lhs;
    for (int a = 0; a < s.kSize; ++a) {
      const Vec<2> xa = basis.dof_position(s.dof[a]);
      const double w = maxent_prior((xa - x).norm() / (settings.dmax * basis.zeta()));
      if (w <= 0.0) {
        EXPECT_EQ(s.w[a], 0.0);
        continue;
      }
      ASSERT_GT(s.w[a], 0.0);
      xs.push_back(xa);
      lhs.push_back(std::log(s.w[a] / w));
    }
    ASSERT_GE(xs.size(), 3u);
    Eigen::MatrixXd A(static_cast<Index>(xs.size()), 3);
    Eigen::VectorXd b(static_cast<Index>(xs.size()));
    for (std::size_t k = 0; k < xs.size(); ++k) {
      A.row(static_cast<Index>(k)) << 1.0, xs[k][0], xs[k][1];
      b[static_cast<Index>(k)] = lhs[k];
    }
    const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
    EXPECT_LT((A * c - b).cwiseAbs().maxCoeff(), 1e-9) << "x = " << x.transpose();
  }
}

// The weak Kronecker-delta property (D eq. 4.52; Arroyo and Ortiz 2006): on a face of the nodes'
// convex hull only the nodes of that face carry weight, so the functions interpolate at the
// hull's vertices (the grid's corners). D states it for every "boundary node"; along an edge,
// though, the functions are the 1D max-ent functions of the edge's nodes, which do not
// interpolate at the edge's inner nodes (checked below). Interior nodes are not interpolatory.
TEST(MaxEnt, WeakKroneckerDeltaProperty) {
  const Grid<2> g = test_grid<2>();
  const MaxEntBasis<2> basis(g, MaxEntSettings{2.0, 1e-12, 50});
  MaxEntBasis<2>::StencilT s;
  const IVec<2> n = basis.dofs_per_dim();
  for (Index j = 0; j < basis.num_dofs(); ++j) {
    const Vec<2> xj = basis.dof_position(j);
    basis.evaluate_point(xj, s);
    const Index ix = j % n[0], iy = j / n[0];
    const bool x_side = ix == 0 || ix == n[0] - 1, y_side = iy == 0 || iy == n[1] - 1;
    double own = 0.0;
    for (int a = 0; a < s.kSize; ++a) {
      if (s.dof[a] == j) own += s.w[a];
      const Index ax = s.dof[a] % n[0], ay = s.dof[a] / n[0];
      // Off the node's face(s): no weight.
      if ((x_side && ax != ix) || (y_side && ay != iy)) {
        EXPECT_EQ(s.w[a], 0.0) << j;
      }
    }
    if (x_side && y_side) {
      EXPECT_DOUBLE_EQ(own, 1.0) << "corner node " << j;
    } else {
      EXPECT_LT(own, 0.9) << "node " << j;
    }
  }
  // Along a boundary edge, only the nodes on that edge carry weight.
  basis.evaluate_point(Vec<2>(0.41, 0.2), s);
  for (int a = 0; a < s.kSize; ++a) {
    if (basis.dof_position(s.dof[a])[1] > 0.2) {
      EXPECT_EQ(s.w[a], 0.0);
    }
  }
}

template <int Dim>
void check_gradients(double dmax) {
  SCOPED_TRACE(::testing::Message() << Dim << "D, d_max = " << dmax);
  const Grid<Dim> g = test_grid<Dim>();
  const MaxEntBasis<Dim> basis(g, MaxEntSettings{dmax, 1e-14, 100});
  typename MaxEntBasis<Dim>::StencilT s, sp, sm;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  for (int k = 0; k < 40; ++k) {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) x[d] = g.origin[d] + u(rng) * (g.upper()[d] - g.origin[d]);
    basis.evaluate_point(x, s);
    const double e = 1e-6 * basis.zeta();
    for (int d = 0; d < Dim; ++d) {
      Vec<Dim> xp = x, xm = x;
      xp[d] += e;
      xm[d] -= e;
      basis.evaluate_point(xp, sp);
      basis.evaluate_point(xm, sm);
      for (int a = 0; a < s.kSize; ++a) {
        // The same window at x +- e (away from cell boundaries the stencils coincide).
        if (sp.dof[a] != s.dof[a] || sm.dof[a] != s.dof[a]) continue;
        const double fd = (sp.w[a] - sm.w[a]) / (2.0 * e);
        EXPECT_NEAR(s.grad[a][d] * basis.zeta(), fd * basis.zeta(), 2e-6)
            << "x = " << x.transpose() << ", node " << s.dof[a];
      }
    }
  }
  basis.throw_if_failed(0, 0.0, "test points");
}

TEST(MaxEnt, GradientsMatchFiniteDifferences) {
  for (double dmax : {1.5, 2.0, 3.0}) {
    check_gradients<1>(dmax);
    check_gradients<2>(dmax);
  }
}

// D eq. 4.48 and its derivative (D eq. 4.49 prints -12 r^2 in the second branch; the slope here
// is the derivative of the prior, checked by differences).
TEST(MaxEnt, PriorAndSlope) {
  EXPECT_DOUBLE_EQ(maxent_prior(0.0), 2.0 / 3.0);
  EXPECT_NEAR(maxent_prior(0.5), 1.0 / 6.0, 1e-15);
  EXPECT_EQ(maxent_prior(1.0), 0.0);
  EXPECT_EQ(maxent_prior(1.2), 0.0);
  for (double r = 0.01; r < 1.0; r += 0.0173) {
    const double e = 1e-6;
    EXPECT_NEAR(maxent_prior_slope(r), (maxent_prior(r + e) - maxent_prior(r - e)) / (2 * e), 1e-8)
        << r;
  }
}

// A point where Newton does not converge stops with exit code 10, naming the point, the
// iterations, the residual and the nodes; the weights are NaN, never a silent result.
TEST(MaxEnt, NewtonFailureIsReported) {
  const Grid<1> g = test_grid<1>();
  const MaxEntBasis<1> basis(g, MaxEntSettings{2.0, 1e-12, 1});
  MaxEntBasis<1>::StencilT s;
  basis.evaluate_point(Vec<1>(-0.29), s);  // near the boundary: many iterations needed
  EXPECT_TRUE(std::isnan(s.w[0]));
  try {
    basis.throw_if_failed(7, 0.5, "test points");
    FAIL() << "no error";
  } catch (const RunError& e) {
    EXPECT_EQ(e.exit_code(), exit_code::kBasis);
    const std::string m = e.what();
    EXPECT_NE(m.find("step 7, t = 0.5 s"), std::string::npos) << m;
    EXPECT_NE(m.find("at 1 of the test points"), std::string::npos) << m;
    EXPECT_NE(m.find("point (-0.28999999999999998)"), std::string::npos) << m;
    EXPECT_NE(m.find("did not converge in 1 iteration(s)"), std::string::npos) << m;
    EXPECT_NE(m.find("method.maxent_max_iterations = 1"), std::string::npos) << m;
    EXPECT_NE(m.find("3 node(s) of nonzero prior"), std::string::npos) << m;
    EXPECT_NE(m.find("0 (-0.3), 1 (-0.0777778), 2 (0.144444)"), std::string::npos) << m;
  }
  EXPECT_NO_THROW(basis.throw_if_failed(8, 0.6, "test points"));  // the record was reset
}

// In a run: the particle evaluation stops the step with exit code 10 naming the particle id.
TEST(MaxEnt, NewtonFailureInAStepNamesTheParticle) {
  const Grid<1> g(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{10});
  auto P = seed_particles<1>(g, Vec<1>(0.0), Vec<1>(1.0), 2, 1000.0);
  MaxEntKind kind;
  kind.settings.max_iterations = 1;
  auto stepper =
      test::compiled_stepper<1>({.grid = g,
                                 .particles = P,
                                 .material = Elastic1DSmall{ElasticParameters{1000.0, 1e6, 0.0}},
                                 .basis = kind});
  try {
    stepper->step(1e-5);
    FAIL() << "no error";
  } catch (const RunError& e) {
    EXPECT_EQ(e.exit_code(), exit_code::kBasis);
    const std::string m = e.what();
    EXPECT_NE(m.find("step 0, t = 0 s: the max-ent basis could not be evaluated at"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("of the particles: at the first, particle 0 (0.025000000000000001)"),
              std::string::npos)
        << m;
  }
}

TEST(MaxEnt, InputErrors) {
  EXPECT_THROW(MaxEntBasis<1>(test_grid<1>(), MaxEntSettings{3.5, 1e-12, 50}), InputError);
  EXPECT_THROW(MaxEntBasis<1>(Grid<1>(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{4}), MaxEntSettings{}),
               InputError);
  EXPECT_NO_THROW(MaxEntBasis<1>(Grid<1>(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{5}), MaxEntSettings{}));
}

// The explicit limit of the max-ent basis is below P1's h / c (its stiffness is wider) and falls
// with the support.
TEST(MaxEnt, StabilityFactor) {
  const double f2 = maxent_stability_factor(MaxEntSettings{2.0, 1e-12, 50});
  const double f3 = maxent_stability_factor(MaxEntSettings{3.0, 1e-12, 50});
  EXPECT_GT(f2, 0.3);
  EXPECT_LT(f2, 2.0);
  EXPECT_GT(f3, 0.3);
  EXPECT_LT(f3, f2 * 1.5);
}

// MUSL steps of a 2D body with the max-ent basis: mass and momentum conserved to round-off
// through the partition of unity; a rigid translation stays rigid (affine reproduction).
TEST(MaxEnt, RigidTranslationConservesMassAndMomentum) {
  const Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{10, 10});
  auto P = seed_particles<2>(g, Vec<2>(0.3, 0.3), Vec<2>(0.7, 0.6), 3, 1000.0);
  const Vec<2> vel(0.2, -0.1);
  for (auto& v : P.v) v = vel;
  const auto x0 = P.x;
  MaxEntKind kind;
  kind.settings.dmax = 3.0;
  auto stepper =
      test::compiled_stepper<2>({.grid = g,
                                 .particles = P,
                                 .material = LinearElastic{ElasticParameters{1000.0, 1e6, 0.3}},
                                 .basis = kind});
  RunState<2>& sim = stepper->state();
  const double dt = 1e-4;
  for (int s = 0; s < 20; ++s) {
    stepper->step(dt);
    ++sim.step;
  }
  EXPECT_LT(sim.diag.max_rel_mass_error, 1e-14);
  EXPECT_LT(sim.diag.max_rel_momentum_error, 1e-13);
  for (std::size_t i = 0; i < x0.size(); ++i) {
    EXPECT_LT((sim.particles.v[i] - vel).norm(), 1e-11);
    EXPECT_LT((sim.particles.x[i] - (x0[i] + 20 * dt * vel)).norm(), 1e-12);
    EXPECT_LT(sim.particles.stress[i].norm(), 1e-5);
  }
}

// Max-ent with a reconstruction mapping is refused naming the key (methods/kinds.hpp).
TEST(MaxEnt, ReconstructionMappingsAreRefused) {
  const std::string base = R"(benchmark = "mms_1d"
[time]
dt = 1e-5
end = 1e-4
[method]
basis = "maxent"
mapping = "tls"
[material]
model = "neo_hookean"
density = 1000.0
youngs_modulus = 1e7
)";
  try {
    (void)run_settings(Config::parse(base, "t.toml"), 1);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.toml:7:11: method.mapping = \"tls\" is not available "
                                         "with method.basis = \"maxent\""),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
