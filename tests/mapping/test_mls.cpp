// MLS (001 eq. 6-17) and IMLS (003 eq. 1-17) reconstruction and mappings in 1D.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "../support/stepper.hpp"
#include "app/reconstruct.hpp"
#include "basis/bases.hpp"
#include "basis/bspline.hpp"
#include "basis/linear.hpp"
#include "mapping/mls.hpp"
#include "material/materials.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

const Grid<1> kGrid(Vec<1>(0.0), Vec<1>(2.0), IVec<1>{8});  // l = 0.25

std::vector<double> scattered(unsigned seed, int per_cell) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> x;
  for (Index c = 0; c < kGrid.cells[0]; ++c)
    for (int k = 0; k < per_cell; ++k) x.push_back((static_cast<double>(c) + u(rng)) * 0.25);
  return x;
}

double poly(int degree, double x) {
  return degree == 0 ? 1.7 : degree == 1 ? 1.7 - 2.3 * x : 1.7 - 2.3 * x + 0.9 * x * x;
}

TEST(Mls, WeightFunctions) {
  EXPECT_DOUBLE_EQ(mls_weight(MlsWeight::QuadraticSpline, 0.0, 0.5), 0.75);
  EXPECT_DOUBLE_EQ(mls_weight(MlsWeight::QuadraticSpline, 0.5, 0.5), 0.5);  // r = 1/2
  EXPECT_EQ(mls_weight(MlsWeight::QuadraticSpline, 1.5, 0.5), 0.0);         // r = 3/2
  EXPECT_GT(mls_weight(MlsWeight::QuadraticSpline, -1.49, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(mls_weight(MlsWeight::Linear, 0.25, 1.0), 0.75);
  EXPECT_EQ(mls_weight(MlsWeight::Linear, 1.0, 1.0), 0.0);
  // Dilation a: r = |dx| / (a l); the published a = 2 is the default (001 eq. 16).
  EXPECT_DOUBLE_EQ(mls_weight(MlsWeight::QuadraticSpline, 0.25, 0.5, 1.0), 0.5);  // r = 1/2
  EXPECT_EQ(mls_weight(MlsWeight::QuadraticSpline, 0.75, 0.5, 1.0), 0.0);         // r = 3/2
  EXPECT_DOUBLE_EQ(mls_support(MlsWeight::QuadraticSpline, 0.5, 1.0), 0.75);
  EXPECT_DOUBLE_EQ(mls_support(MlsWeight::QuadraticSpline, 0.5), 1.5);
  EXPECT_THROW(MovingLeastSquares<1>(false, 1, 1e8, 0.0), InputError);
}

TEST(Mls, ReproducesPolynomialsWithAnyDilation) {
  // 9 particles per cell so that the narrowest support (a = 1, 1.5 cells each side) still
  // holds more distinct points than the quadratic basis has terms.
  const auto x = scattered(3, 9);
  for (bool improved : {false, true})
    for (int degree : {1, 2})
      for (double a : {1.0, 1.5, 3.0}) {
        std::vector<double> f;
        for (double xp : x) f.push_back(poly(degree, xp));
        MovingLeastSquares m(improved, degree, 1e8, a);
        m.set_points(kGrid, x);
        for (double xe = 0.0; xe <= 2.0; xe += 0.0371)
          EXPECT_NEAR(m.evaluate(xe, MlsWeight::QuadraticSpline, f), poly(degree, xe), 1e-11)
              << improved << " " << degree << " a = " << a << " x = " << xe;
        EXPECT_EQ(m.report().singular, 0);
      }
}

TEST(Mls, ReproducesPolynomialsUpToDegree) {
  const auto x = scattered(3, 3);
  for (bool improved : {false, true})
    for (int degree : {1, 2})
      for (int pd = 0; pd <= degree; ++pd)
        for (MlsWeight wk : {MlsWeight::QuadraticSpline, MlsWeight::Linear}) {
          std::vector<double> f;
          for (double xp : x) f.push_back(poly(pd, xp));
          MovingLeastSquares m(improved, degree);
          m.set_points(kGrid, x);
          for (double xe = 0.0; xe <= 2.0; xe += 0.0371)
            EXPECT_NEAR(m.evaluate(xe, wk, f), poly(pd, xe), 1e-12)
                << improved << " " << degree << " " << pd << " x = " << xe;
          EXPECT_EQ(m.report().empty, 0);
          EXPECT_EQ(m.report().singular, 0);
        }
}

TEST(Mls, ImlsEqualsMlsWhenWellConditioned) {
  const auto x = scattered(7, 4);
  std::vector<double> f;
  for (double xp : x) f.push_back(std::sin(3.0 * xp) + xp * xp * xp);
  for (int degree : {1, 2}) {
    MovingLeastSquares a(false, degree), b(true, degree);
    a.set_points(kGrid, x);
    b.set_points(kGrid, x);
    for (double xe = 0.01; xe < 2.0; xe += 0.0523)
      EXPECT_NEAR(a.evaluate(xe, MlsWeight::QuadraticSpline, f),
                  b.evaluate(xe, MlsWeight::QuadraticSpline, f), 1e-12);
    EXPECT_EQ(b.report().reduced, 0);
    EXPECT_LT(a.report().max_condition, 1e6);
  }
}

TEST(Mls, ImlsOneAndTwoParticles) {
  // One particle: the value itself, whatever the degree.
  for (int degree : {1, 2}) {
    MovingLeastSquares m(true, degree);
    const std::vector<double> x{0.9}, f{4.5};
    m.set_points(kGrid, x);
    const double v = m.evaluate(1.1, MlsWeight::QuadraticSpline, f);
    EXPECT_TRUE(std::isfinite(v));
    EXPECT_NEAR(v, 4.5, 1e-14);
    EXPECT_EQ(m.report().reduced, 1);
    // MLS cannot: singular moment matrix, value 0 and counted.
    MovingLeastSquares mls(false, degree);
    mls.set_points(kGrid, x);
    EXPECT_EQ(mls.evaluate(1.1, MlsWeight::QuadraticSpline, f), 0.0);
    EXPECT_EQ(mls.report().singular, 1);
  }
  // Two particles, degree 2: the quadratic term is dropped, the line through them remains.
  MovingLeastSquares m(true, 2);
  const std::vector<double> x{0.8, 1.05}, f{poly(1, 0.8), poly(1, 1.05)};
  m.set_points(kGrid, x);
  for (double xe : {0.7, 0.9, 1.0, 1.3}) {
    EXPECT_NEAR(m.evaluate(xe, MlsWeight::QuadraticSpline, f), poly(1, xe), 1e-12);
  }
  EXPECT_EQ(m.report().reduced, 4);
  // No particle in the support: 0, counted.
  EXPECT_EQ(m.evaluate(0.0, MlsWeight::Linear, f), 0.0);
  EXPECT_EQ(m.report().empty, 1);
}

TEST(Mls, ConditionNumberReportedForNearCoincidentParticles) {
  const std::vector<double> x{1.0, 1.0 + 1e-6, 1.0 + 2e-6}, f{1.0, 1.0, 1.0};
  MovingLeastSquares m(false, 1);
  m.set_points(kGrid, x);
  m.evaluate(1.1, MlsWeight::QuadraticSpline, f);
  EXPECT_GT(m.report().max_condition, 1e8);
  EXPECT_EQ(m.report().ill_conditioned, 1);
  // Well spread: small.
  MovingLeastSquares w(false, 1);
  const std::vector<double> y{0.9, 1.0, 1.1};
  w.set_points(kGrid, y);
  w.evaluate(1.0, MlsWeight::QuadraticSpline, f);
  EXPECT_LT(w.report().max_condition, 1e3);
}

TEST(Mls, RejectsBadDegree) {
  EXPECT_THROW(MovingLeastSquares(false, 3), InputError);
  MlsSettings s;
  s.degree = 0;
  EXPECT_THROW(ImlsMapping{s}, InputError);
}

// A bar filling [0.25, 1.75] of a grid on [0, 2] (8 cells): uniform density, linear velocity.
template <class Mapping, class Basis>
void check_mapping(int degree) {
  const Grid<1> g = kGrid;
  auto P = seed_particles<1>(g, Vec<1>(0.25), Vec<1>(1.75), 3, 1000.0);
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    P.v[i][0] = 0.3 + 0.7 * P.x[i][0];
    P.body[i][0] = -9.81;
    P.stress[i](0, 0) = 100.0 + 50.0 * P.x[i][0];
  }
  ElasticParameters ep{1000.0, 1e6, 0.0};
  MlsSettings s;
  s.degree = degree;
  Simulation<1, Basis, Mapping> sim(g, Basis(g), Mapping(s), P, Elastic1DSmall{ep});
  sim.mapping.map_mass(sim);
  const double particle_mass = std::accumulate(P.mass.begin(), P.mass.end(), 0.0);
  const double grid_mass = std::accumulate(sim.nodes.mass.begin(), sim.nodes.mass.end(), 0.0);
  EXPECT_NEAR(grid_mass, particle_mass, 1e-12 * particle_mass);
  EXPECT_EQ(sim.mapping.last_report().empty, 0);
  if constexpr (std::is_same_v<Basis, LinearBasis<1>>) {
    EXPECT_EQ(sim.mapping.last_report().widened, 0);
  }

  sim.mapping.map_forces(sim);
  // Uniform b: f_i = m_i b plus the stress term; total body force = M b (sum grad phi_i = 0).
  double ftot = 0.0;
  for (const auto& f : sim.nodes.force) ftot += f[0];
  // sum_i f_i = -int sigma^ sum_i grad phi_i + M b = M b (partition of unity).
  EXPECT_NEAR(ftot, -9.81 * particle_mass, 1e-9 * 9.81 * particle_mass);

  sim.mapping.map_momentum(sim);
  if constexpr (Mapping::kName == "mls") {
    // q = int rho v: the linear field integrated exactly.
    double q = 0.0, qp = 0.0;
    for (const auto& qi : sim.nodes.momentum) q += qi[0];
    for (std::size_t i = 0; i < P.x.size(); ++i) qp += P.mass[i] * P.v[i][0];
    EXPECT_NEAR(q, qp, 1e-12 * std::abs(qp));
  } else {
    // v_i = q_i / m_i equals the linear field at interior nodes.
    for (Index i = 0; i < sim.basis.num_dofs(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      const double xi = sim.basis.dof_position(i)[0];
      if (xi < 0.5 || xi > 1.5 || sim.nodes.mass[k] <= 0.0) continue;
      EXPECT_NEAR(sim.nodes.momentum[k][0] / sim.nodes.mass[k], 0.3 + 0.7 * xi, 1e-12)
          << "node " << i;
    }
  }
}

TEST(MlsMapping, LinearBasis) {
  check_mapping<MlsMapping, LinearBasis<1>>(1);
  check_mapping<MlsMapping, LinearBasis<1>>(2);
  check_mapping<ImlsMapping, LinearBasis<1>>(1);
  check_mapping<ImlsMapping, LinearBasis<1>>(2);
}

TEST(MlsMapping, BSplineBasis) {
  check_mapping<MlsMapping, BSplineBasis<1, 2>>(1);
  check_mapping<MlsMapping, BSplineBasis<1, 2>>(2);
  check_mapping<ImlsMapping, BSplineBasis<1, 2>>(1);
  check_mapping<ImlsMapping, BSplineBasis<1, 2>>(2);
}

TEST(MlsMapping, ConsistentMass) {
  const Grid<1> g = kGrid;
  auto P = seed_particles<1>(g, Vec<1>(0.25), Vec<1>(1.75), 3, 1000.0);
  ElasticParameters ep{1000.0, 1e6, 0.0};
  Simulation<1, LinearBasis<1>, ImlsMapping> sim(g, LinearBasis<1>(g), ImlsMapping{}, P,
                                                 Elastic1DSmall{ep});
  sim.mass_type = MassType::Consistent;
  EXPECT_THROW(sim.mapping.map_mass(sim), InputError);
  Simulation<1, LinearBasis<1>, MlsMapping> ok(g, LinearBasis<1>(g), MlsMapping{}, P,
                                               Elastic1DSmall{ep});
  ok.mass_type = MassType::Consistent;
  EXPECT_NO_THROW(ok.mapping.map_mass(ok));
}

// Uniform translation over many steps (crossing cells): velocity and stress unchanged.
template <class Mapping>
void rigid_translation() {
  const Grid<1> g = kGrid;
  auto P = seed_particles<1>(g, Vec<1>(0.5), Vec<1>(1.25), 3, 1000.0);
  for (auto& v : P.v) v[0] = 0.5;
  ElasticParameters ep{1000.0, 1e6, 0.0};
  MlsSettings s;
  s.degree = 2;
  auto stepper = test::compiled_stepper<1>({.grid = g,
                                            .particles = P,
                                            .material = Elastic1DSmall{ep},
                                            .basis = BSplineKind<2>{},
                                            .mapping = Mapping(s)});
  const RunState<1>& sim = stepper->state();
  for (int k = 0; k < 100; ++k) stepper->step(1e-3);  // travels 0.05 = 0.2 cells
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    EXPECT_NEAR(sim.particles.v[i][0], 0.5, 1e-12);
    EXPECT_NEAR(sim.particles.x[i][0], P.x[i][0] + 0.05, 1e-12);
    EXPECT_LT(std::abs(sim.particles.stress[i](0, 0)), 1e-6);
  }
}

TEST(MlsMapping, RigidTranslationMusl) {
  rigid_translation<MlsMapping>();
  rigid_translation<ImlsMapping>();
}

TEST(MlsPlayground, ReproducesLine) {
  for (const char* mapping : {"mls", "imls"})
    for (int degree : {1, 2}) {
      ReconstructOptions opt;
      opt.function = "3 - 0.5*x";
      opt.mapping = mapping;
      opt.mls_degree = degree;
      opt.points = "random:3";
      opt.error_points = 10;
      const auto r = reconstruct(opt);
      EXPECT_LT(r.rms_error, 1e-12) << mapping << degree;
      EXPECT_LT(r.relative_integral_error, 1e-12) << mapping << degree;
    }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
