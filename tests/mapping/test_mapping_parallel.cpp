// The reconstruction mappings (TLS, MLS, IMLS, cubic spline) run their element, Gauss-point and
// node loops in parallel over fixed chunks (mapping/quadrature.hpp, mapping/mls.hpp): one thread
// and two threads must give the same bits. Every problem here has more Gauss points than one
// chunk (ParticleChunks::kMinSize) and more elements or particles than kParallelMin, so the
// chunked scatters really regroup their sums and two threads really split the loops: a chunking
// that followed the thread count would change the last bits of the grid sums within a step.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "../support/stepper.hpp"
#include "../support/threads.hpp"
#include "basis/bases.hpp"
#include "core/parallel.hpp"
#include "mapping/mls.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

using test::same_bits;
using test::Threads;

template <int Dim>
Grid<Dim> make_grid() {
  if constexpr (Dim == 1)
    return Grid<1>(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{2500});
  else
    return Grid<2>(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{48, 48});
}

template <int Dim>
Material material() {
  if constexpr (Dim == 1)
    return Elastic1DSmall{ElasticParameters{1000.0, 1e7, 0.0}};
  else
    return NeoHookean{ElasticParameters{1000.0, 1e7, 0.3}};
}

// A body with a free boundary inside the grid (partly filled cells, so the TLS completions and
// the IMLS widened nodal rows are exercised), a smooth velocity field and a body force, fixed at
// x = 0; steps of the scheme with dt = 0.1 h / c (the library's compiled stepper).
template <int Dim, class Basis>
std::unique_ptr<driver::Stepper<Dim>> run(int threads, const MappingKind& mapping) {
  const Threads t(threads);
  const Grid<Dim> g = make_grid<Dim>();
  Vec<Dim> lo, hi;
  for (int d = 0; d < Dim; ++d) {
    lo[d] = 0.0;
    hi[d] = 0.83;  // not on a cell face
  }
  auto P = seed_particles<Dim>(g, lo, hi, 2, 1000.0);
  for (std::size_t i = 0; i < P.v.size(); ++i) {
    using std::numbers::pi;
    for (int d = 0; d < Dim; ++d) {
      P.v[i][d] = 0.5 * std::sin(2 * pi * P.x[i][d]) + 0.1 * d;
      P.body[i][d] = d == 0 ? -9.81 : 3.0 * P.x[i][0];
    }
  }
  auto stepper = test::compiled_stepper<Dim>({.grid = g,
                                              .particles = std::move(P),
                                              .material = material<Dim>(),
                                              .basis = test::kind_of<Dim, Basis>(),
                                              .mapping = mapping,
                                              .fixed_sides = {FixedSide{0, 0}}});  // x = 0
  const double dt = 0.1 * g.h[0] / std::sqrt(1e7 / 1000.0);
  for (int s = 0; s < 4; ++s) stepper->step(dt);
  return stepper;
}

template <int Dim, class Basis>
void expect_same_state(const MappingKind& mapping) {
  const auto pa = run<Dim, Basis>(1, mapping);
  const auto pb = run<Dim, Basis>(2, mapping);
  const RunState<Dim>& a = pa->state();
  const RunState<Dim>& b = pb->state();
  ASSERT_GT(a.particles.size(), kParallelMin);
  EXPECT_TRUE(same_bits(a.particles.x, b.particles.x));
  EXPECT_TRUE(same_bits(a.particles.v, b.particles.v));
  EXPECT_TRUE(same_bits(a.particles.F, b.particles.F));
  EXPECT_TRUE(same_bits(a.particles.stress, b.particles.stress));
  EXPECT_TRUE(same_bits(a.nodes.mass, b.nodes.mass));
  EXPECT_TRUE(same_bits(a.nodes.momentum, b.nodes.momentum));
  EXPECT_TRUE(same_bits(a.nodes.force, b.nodes.force));
  EXPECT_EQ(a.diag.max_rel_mass_error, b.diag.max_rel_mass_error);
  EXPECT_EQ(a.diag.max_rel_momentum_error, b.diag.max_rel_momentum_error);
  // The run totals of the mapping's report, combined chunk by chunk: every count, the largest
  // condition number and where it was (the dump prints doubles exactly, a NaN as null).
  const auto ra = test::mapping_report(*pa), rb = test::mapping_report(*pb);
  EXPECT_EQ(ra.dump(), rb.dump());
  if (ra.contains("mls")) {
    EXPECT_GT(static_cast<Index>(ra["mls"]["evaluations"]), 4 * ParticleChunks::kMinSize);
  }
  if (ra.contains("tls")) {
    EXPECT_GT(static_cast<Index>(ra["tls"]["element_fits"]), 0);
  }
  const bool reports = std::holds_alternative<DirectMapping>(mapping) ||
                       std::holds_alternative<CubicSplineMapping>(mapping) || !ra.empty();
  EXPECT_TRUE(reports) << "the reconstruction mappings report their totals";
}

TEST(MappingParallel, Mls1DSameForOneAndTwoThreads) {
  expect_same_state<1, LinearBasis<1>>(MlsMapping{});
}
TEST(MappingParallel, Imls1DSameForOneAndTwoThreads) {
  expect_same_state<1, BSplineBasis<1, 2>>(ImlsMapping{});
}
TEST(MappingParallel, Tls1DSameForOneAndTwoThreads) {
  expect_same_state<1, BSplineBasis<1, 2>>(TlsMapping{});
}
TEST(MappingParallel, CubicSpline1DSameForOneAndTwoThreads) {
  expect_same_state<1, LinearBasis<1>>(CubicSplineMapping{});
}
TEST(MappingParallel, Mls2DSameForOneAndTwoThreads) {
  expect_same_state<2, LinearBasis<2>>(MlsMapping{});
}
TEST(MappingParallel, Mls2DQuadraticBSplineSameForOneAndTwoThreads) {
  expect_same_state<2, BSplineBasis<2, 2>>(MlsMapping{});
}
TEST(MappingParallel, Imls2DSameForOneAndTwoThreads) {
  expect_same_state<2, LinearBasis<2>>(ImlsMapping{});
}
TEST(MappingParallel, Imls2DQuadraticBSplineSameForOneAndTwoThreads) {
  expect_same_state<2, BSplineBasis<2, 2>>(ImlsMapping{});
}
TEST(MappingParallel, Tls2DSameForOneAndTwoThreads) {
  expect_same_state<2, LinearBasis<2>>(TlsMapping(TlsSettings{}, 2));
}
TEST(MappingParallel, Tls2DNeighbourCompletionSameForOneAndTwoThreads) {
  TlsSettings s;
  s.completion = TlsCompletion::Neighbour;
  expect_same_state<2, BSplineBasis<2, 2>>(TlsMapping(s, 2));
}

// The chunked rows of add_rows are bitwise the rows of serial add_row calls, with the same
// report, for one to three threads (scattered points: rows of very different lengths).
TEST(MappingParallel, AddRowsMatchesSerialRows) {
  const Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(2.0, 1.0), IVec<2>{40, 20});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0.0, 2.0), uy(0.0, 1.0);
  std::vector<Vec<2>> x, at;
  for (int k = 0; k < 3000; ++k) x.emplace_back(ux(rng), 0.6 * uy(rng) * uy(rng));
  for (int k = 0; k < 2000; ++k) at.emplace_back(ux(rng), uy(rng));
  for (bool improved : {false, true})
    for (MlsWeight wk : {MlsWeight::QuadraticSpline, MlsWeight::Linear}) {
      MovingLeastSquares<2> serial(improved, 1);
      serial.set_points(g, x);
      ShapeTable rows;
      for (const auto& p : at) serial.add_row(p, wk, rows, true);
      for (int threads = 1; threads <= 3; ++threads) {
        const Threads t(threads);
        MovingLeastSquares<2> mls(improved, 1);
        mls.set_points(g, x);
        ShapeTables tables;
        mls.add_rows(
            static_cast<Index>(at.size()),
            [&](Index i) -> const Vec<2>& { return at[static_cast<std::size_t>(i)]; }, wk, tables,
            true);
        ASSERT_GT(tables.chunks(), 2);
        std::vector<Index> point;
        std::vector<double> phi;
        std::vector<std::size_t> start{0};
        // for_each_row hands every global row its chunk and local row.
        std::vector<std::size_t> length(at.size(), 0);
        tables.for_each_row([&](std::size_t r, const ShapeTable& tc, std::size_t k) {
          length[r] = tc.start[k + 1] - tc.start[k];
        });
        for (std::size_t r = 0; r < at.size(); ++r)
          EXPECT_EQ(length[r], rows.start[r + 1] - rows.start[r]);
        for (int c = 0; c < tables.chunks(); ++c) {
          const ShapeTable& tc = tables.chunk[static_cast<std::size_t>(c)];
          for (std::size_t r = 0; r < tc.rows(); ++r)
            start.push_back(point.size() + tc.start[r + 1]);
          point.insert(point.end(), tc.point.begin(), tc.point.end());
          phi.insert(phi.end(), tc.phi.begin(), tc.phi.end());
        }
        EXPECT_EQ(start, rows.start);
        EXPECT_EQ(point, rows.point);
        EXPECT_TRUE(same_bits(phi, rows.phi));
        const MlsReport &a = serial.report(), &b = mls.report();
        EXPECT_EQ(a.points, b.points);
        EXPECT_EQ(a.empty, b.empty);
        EXPECT_EQ(a.widened, b.widened);
        EXPECT_EQ(a.reduced, b.reduced);
        EXPECT_EQ(a.ill_conditioned, b.ill_conditioned);
        EXPECT_EQ(a.max_condition, b.max_condition);
        EXPECT_EQ(a.worst_x, b.worst_x);
        EXPECT_EQ(a.worst_y, b.worst_y);
      }
    }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
