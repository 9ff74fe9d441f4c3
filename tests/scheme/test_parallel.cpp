// The OpenMP explicit core (core/parallel.hpp) gives the same bits for any thread count: the
// particle sums run over a fixed partition into chunks that does not depend on the threads.
// Every problem here has more than one chunk (> ParticleChunks::kMinSize particles) and more
// than kParallelMin particles, so two threads really split the work.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <memory>
#include <numbers>
#include <random>

#include "../support/stepper.hpp"
#include "../support/threads.hpp"
#include "core/parallel.hpp"
#include "driver/run.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

using test::same_bits;
using test::Threads;

RunResult run_with_threads(int threads, const std::string& example,
                           const std::vector<std::string>& sets) {
  const Threads t(threads);
  const Config cfg = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/" + example, sets);
  RunOptions ro;
  ro.quiet = true;
  return run(cfg, ro);
}

void expect_same_run(const std::string& example, const std::vector<std::string>& sets) {
  const RunResult r1 = run_with_threads(1, example, sets);
  const RunResult r2 = run_with_threads(2, example, sets);
  ASSERT_EQ(r1.exit_code, 0) << r1.failure;
  ASSERT_EQ(r2.exit_code, 0) << r2.failure;
  ASSERT_GT(r1.particles, 2 * ParticleChunks::kMinSize);
  // nlohmann::json compares numbers with ==: the error norms must agree to the last bit.
  EXPECT_EQ(r1.summary["errors"], r2.summary["errors"]);
  EXPECT_FALSE(r1.summary["errors"].empty());
  EXPECT_EQ(r1.diag.max_rel_mass_error, r2.diag.max_rel_mass_error);
  EXPECT_EQ(r1.diag.max_rel_momentum_error, r2.diag.max_rel_momentum_error);
  EXPECT_EQ(r1.diag.grid_crossings, r2.diag.grid_crossings);
}

const std::vector<std::string> kBar = {"grid.cells=200", "particles.per_cell=12"};
const std::vector<std::string> kPlate = {"grid.cells=24", "particles.per_cell=3", "time.end=1e-4"};

std::vector<std::string> with(std::vector<std::string> base, std::vector<std::string> more) {
  base.insert(base.end(), more.begin(), more.end());
  return base;
}

TEST(Parallel, Bar1DLinearSameForOneAndTwoThreads) {
  expect_same_run("vibrating_bar_small.toml", with(kBar, {"method.basis=\"linear\""}));
}
TEST(Parallel, Bar1DQuadraticBSplineSameForOneAndTwoThreads) {
  expect_same_run("vibrating_bar_small.toml",
                  with(kBar, {"method.basis=\"bspline\"", "method.degree=2"}));
}
TEST(Parallel, Bar1DConsistentMassSameForOneAndTwoThreads) {
  expect_same_run("vibrating_bar_small.toml", with(kBar, {"method.mass=\"consistent\""}));
}
TEST(Parallel, Plate2DLinearSameForOneAndTwoThreads) {
  expect_same_run("plate_mms_2d.toml",
                  with(kPlate, {"method.basis=\"linear\"", "mms.amplitude=0.01"}));
}
TEST(Parallel, Plate2DQuadraticBSplineEverySchemeSameForOneAndTwoThreads) {
  for (const char* scheme : {"usl", "usf", "musl", "usavg"}) {
    SCOPED_TRACE(scheme);
    expect_same_run("plate_mms_2d.toml",
                    with(kPlate, {fmt::format("method.scheme=\"{}\"", scheme)}));
  }
}

// The full particle state and grid after a few steps, compared byte for byte (quadratic
// B-splines, direct mapping: the library's compiled stepper).
std::unique_ptr<driver::Stepper<2>> run_plate(const Scheme& scheme, int threads) {
  const Threads t(threads);
  Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{20, 20});
  auto P = seed_particles<2>(g, Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), 3, 1000.0);
  for (std::size_t i = 0; i < P.v.size(); ++i) {
    using std::numbers::pi;
    P.v[i] = Vec<2>(0.5 * std::sin(2 * pi * P.x[i][0]), -0.3 * std::sin(2 * pi * P.x[i][1]));
  }
  ElasticParameters ep{1000.0, 1e7, 0.3};
  auto stepper = test::compiled_stepper<2>({.grid = g,
                                            .particles = std::move(P),
                                            .material = NeoHookean{ep},
                                            .basis = BSplineKind<2>{},
                                            .scheme = scheme,
                                            .fixed_sides = {FixedSide{0, 0}, FixedSide{0, 1}}});
  for (int s = 0; s < 20; ++s) stepper->step(1e-4);
  return stepper;
}

void expect_same_state(const Scheme& scheme) {
  const auto pa = run_plate(scheme, 1);
  const auto pb = run_plate(scheme, 2);
  const RunState<2>& a = pa->state();
  const RunState<2>& b = pb->state();
  ASSERT_GT(a.particles.size(), 4 * ParticleChunks::kMinSize);
  EXPECT_TRUE(same_bits(a.particles.x, b.particles.x));
  EXPECT_TRUE(same_bits(a.particles.v, b.particles.v));
  EXPECT_TRUE(same_bits(a.particles.F, b.particles.F));
  EXPECT_TRUE(same_bits(a.particles.stress, b.particles.stress));
  EXPECT_TRUE(same_bits(a.particles.volume, b.particles.volume));
  EXPECT_TRUE(same_bits(a.nodes.mass, b.nodes.mass));
  EXPECT_TRUE(same_bits(a.nodes.momentum, b.nodes.momentum));
  EXPECT_TRUE(same_bits(a.nodes.force, b.nodes.force));
  EXPECT_EQ(a.diag.max_rel_momentum_error, b.diag.max_rel_momentum_error);
}

TEST(Parallel, BitwiseStateMusl) {
  expect_same_state(Musl{});
}
TEST(Parallel, BitwiseStateUsl) {
  expect_same_state(Usl{});
}
TEST(Parallel, BitwiseStateUsf) {
  expect_same_state(Usf{});
}
TEST(Parallel, BitwiseStateUsavg) {
  expect_same_state(Usavg{});
}

// The particle sums of the conservation checks, taken inside the direct mapping's scatters
// (ScatterBuffers::particle_mass, particle_momentum), give the bits of the separate
// deterministic_sum passes they replace. After a MUSL or USAVG step the latest mapping is the
// momentum remap from the final particle velocities, so both errors can be recomputed from the
// final state. Two threads, so the chunk sums come from both.
void expect_fused_sums_as_separate_passes(const Scheme& scheme) {
  const auto ps = run_plate(scheme, 2);
  const RunState<2>& sim = ps->state();
  const auto& P = sim.particles;
  const auto mp = [&](Index p) { return P.mass[static_cast<std::size_t>(p)]; };
  const double particle_mass = deterministic_sum(P.size(), 0.0, mp);
  const auto& m = sim.nodes.mass;
  const double grid_mass = deterministic_sum(
      static_cast<Index>(m.size()), 0.0, [&](Index i) { return m[static_cast<std::size_t>(i)]; });
  EXPECT_EQ(sim.diag.rel_mass_error, std::abs(grid_mass - particle_mass) / particle_mass);
  using Sums = Eigen::Matrix<double, 3, 1>;
  const Sums sums = deterministic_sum(P.size(), Sums::Zero().eval(), [&](Index p) {
    const auto i = static_cast<std::size_t>(p);
    Sums r;
    r.head<2>() = P.mass[i] * P.v[i];
    r[2] = P.mass[i] * P.v[i].norm();
    return r;
  });
  const auto& q = sim.nodes.momentum;
  const Vec<2> grid_p = deterministic_sum(static_cast<Index>(q.size()), Vec<2>::Zero().eval(),
                                          [&](Index i) { return q[static_cast<std::size_t>(i)]; });
  const Vec<2> part_p = sums.head<2>();
  EXPECT_EQ(sim.diag.rel_momentum_error, (grid_p - part_p).norm() / sums[2]);
  EXPECT_FALSE(sim.scatter.has_particle_mass);  // consumed by the checks
  EXPECT_FALSE(sim.scatter.has_particle_momentum);
}

TEST(Parallel, FusedConservationSumsMusl) {
  expect_fused_sums_as_separate_passes(Musl{});
}
TEST(Parallel, FusedConservationSumsUsavg) {
  expect_fused_sums_as_separate_passes(Usavg{});
}

// A stencil of three DOFs, with the DOF bounds ChunkDofRanges::scan reads (found by ADL; the
// stride argument is for the compact tensor-product stencils and unused here).
struct ThreeDofs {
  static constexpr int kSize = 3;
  std::array<Index, 3> dof;
};
std::array<Index, 2> dof_bounds(const ThreeDofs& s, std::nullptr_t /*stride*/) {
  return {*std::min_element(s.dof.begin(), s.dof.end()),
          *std::max_element(s.dof.begin(), s.dof.end())};
}

// n particles in random order, each with three consecutive DOFs from [lo, hi] and a weight in
// [-1, 1] (seeded).
void random_three_dof_particles(Index n, Index lo, Index hi, unsigned seed,
                                std::vector<ThreeDofs>& st, std::vector<double>& w) {
  std::mt19937 gen(seed);
  std::uniform_int_distribution<Index> node(lo, hi - 2);
  std::uniform_real_distribution<double> val(-1.0, 1.0);
  st.resize(static_cast<std::size_t>(n));
  w.resize(static_cast<std::size_t>(n));
  for (std::size_t p = 0; p < st.size(); ++p) {
    const Index j = node(gen);
    st[p].dof = {j, j + 1, j + 2};
    w[p] = val(gen);
  }
}

// The chunked scatter against a plain serial sum, with particles in random order so that the
// chunks' DOF ranges overlap everywhere; equal to round-off, and the same bits for 1..3 threads.
TEST(Parallel, GridAccumulatorMatchesSerialSum) {
  constexpr Index n = 5000, nodes = 700;
  std::vector<ThreeDofs> st;
  std::vector<double> w;
  random_three_dof_particles(n, 0, nodes - 1, 7, st, w);
  std::vector<double> serial(nodes, 0.0);
  for (std::size_t p = 0; p < st.size(); ++p)
    for (Index d : st[p].dof) serial[static_cast<std::size_t>(d)] += w[p];
  ChunkDofRanges r;
  r.scan(st, nullptr);
  std::vector<double> first;
  for (int threads = 1; threads <= 3; ++threads) {
    const Threads t(threads);
    GridAccumulator<double> acc;
    DofArray<double> out;
    out.assign(0, static_cast<Index>(nodes), 99.0);  // stale values must be overwritten
    acc.scatter(out, 0.0, r, [&](Index p, const auto& slice) {
      for (Index d : st[static_cast<std::size_t>(p)].dof)
        slice[d] += w[static_cast<std::size_t>(p)];
    });
    for (std::size_t i = 0; i < out.size(); ++i) EXPECT_NEAR(out[i], serial[i], 1e-12);
    const std::vector<double> values(out.begin(), out.end());
    if (threads == 1)
      first = values;
    else
      EXPECT_TRUE(same_bits(first, values));
  }
}

// Grid arrays over a window of the DOFs (core/dof_array.hpp; a distributed run's slab, issue 21):
// the scatter sums into the window by global DOF number with the bits of the whole-grid sum; a
// bounded scatter writes only the DOFs its chunks touch, an unbounded one zeroes the rest of the
// window; a sum reaching past the window is refused, not cut; moving the window keeps the values
// of the DOFs in both windows.
TEST(Parallel, GridAccumulatorIntoAWindowOfTheDofs) {
  constexpr Index n = 3000, nodes = 700, lo = 300, hi = 497;
  std::vector<ThreeDofs> st;
  std::vector<double> w;
  random_three_dof_particles(n, lo, hi, 11, st, w);
  const auto add = [&](Index p, const auto& slice) {
    for (Index d : st[static_cast<std::size_t>(p)].dof) slice[d] += w[static_cast<std::size_t>(p)];
  };
  ChunkDofRanges r;
  r.scan(st, nullptr);
  const auto [first, last] = r.span();  // [lo, hi] unless a DOF at the ends was never drawn
  const Threads t(2);
  GridAccumulator<double> acc;
  DofArray<double> whole;
  whole.assign(0, nodes, 99.0);
  acc.scatter(whole, 0.0, r, add);
  for (const bool bounded : {false, true}) {
    r.bounded = bounded;
    DofArray<double> part;
    part.assign(250, 310, 99.0);  // DOFs [250, 560)
    acc.scatter(part, 0.0, r, add);
    ASSERT_EQ(part.first(), 250);
    ASSERT_EQ(part.stop(), 560);
    for (Index i = part.first(); i < part.stop(); ++i) {
      const bool touched = i >= first && i <= last;
      const double expect = touched ? whole[i] : bounded ? 99.0 : 0.0;
      EXPECT_EQ(std::memcmp(&part[i], &expect, sizeof(double)), 0) << i << " bounded " << bounded;
    }
    DofArray<double> narrow;
    narrow.assign(first + 1, last - first, 0.0);  // misses the lowest DOF touched
    EXPECT_THROW(acc.scatter(narrow, 0.0, r, add), std::logic_error);
  }
  DofArray<double> a;
  a.assign(10, 5, 0.0);
  for (Index i = 10; i < 15; ++i) a[i] = static_cast<double>(i);
  a.rewindow(12, 6, -1.0);
  EXPECT_EQ(std::vector<double>(a.begin(), a.end()),
            (std::vector<double>{12.0, 13.0, 14.0, -1.0, -1.0, -1.0}));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
