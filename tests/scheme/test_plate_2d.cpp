// The 2D plate benchmark in the time step (001, D 3.4.1): per-component Dirichlet conditions,
// second-order convergence of the displacement at small amplitude (no grid crossing) for the
// nodal and B-spline bases, conservation with lumped and consistent mass, and the failure mode
// of fixing both components on the boundary.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "app/perf.hpp"
#include "basis/bases.hpp"
#include "driver/run.hpp"
#include "methods/kinds.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

Config plate(std::vector<std::string> sets) {
  sets.insert(sets.begin(), {"output.frames=0", "output.csv=false", "output.vtk=false"});
  return Config::load(std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml", sets);
}

RunResult run_plate(const std::vector<std::string>& sets) {
  auto r = run(plate(sets), RunOptions{});
  EXPECT_EQ(r.exit_code, 0) << r.failure;
  return r;
}

TEST(Plate2D, RollersFixOnlyTheNormalComponent) {
  Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{4, 4});
  Particles<2> P;
  Simulation<2, LinearBasis<2>, DirectMapping> sim(g, LinearBasis<2>(g), DirectMapping{}, P,
                                                   NeoHookean{ElasticParameters{}});
  sim.fix_side(0, 0, 1u);
  sim.fix_side(0, 1, 1u);
  sim.fix_side(1, 0, 2u);
  sim.fix_side(1, 1, 2u);
  for (Index i = 0; i < sim.basis.num_dofs(); ++i) {
    const Vec<2> x = sim.basis.dof_position(i);
    const bool on_x = x[0] == 0.0 || x[0] == 1.0, on_y = x[1] == 0.0 || x[1] == 1.0;
    const unsigned expected = (on_x ? 1u : 0u) | (on_y ? 2u : 0u);
    EXPECT_EQ(sim.nodes.fixed[static_cast<std::size_t>(i)], expected) << x.transpose();
  }
}

TEST(Plate2D, ConvergenceOrdersAtSmallAmplitude) {
  // A = 1e-4 m: displacements far below a cell, so no grid crossing; the displacement error is
  // the spatial discretisation error: O(h^2) for P1 (lumped mass), O(h^3) for quadratic
  // B-splines with consistent mass (D 5.4.1; with lumped mass BSMPM loses accuracy at the
  // boundary, D Fig. 5.10, and is not tested for an order here).
  struct Case {
    const char* basis;
    const char* mass;
    double min_order;
  };
  for (const Case& c : {Case{"linear", "lumped", 1.8}, Case{"bspline", "consistent", 2.5}}) {
    SCOPED_TRACE(fmt::format("{} {}", c.basis, c.mass));
    std::vector<double> err;
    for (int n : {8, 16, 32}) {
      const auto r = run_plate({fmt::format("grid.cells={}", n), "mms.amplitude=1e-4",
                                "time.end=1e-3", fmt::format("method.basis={}", c.basis),
                                fmt::format("method.mass={}", c.mass)});
      err.push_back(*r.errors.displacement_rms);
      // Round-off of sums over up to 9216 particles: ~N eps.
      EXPECT_LT(r.diag.max_rel_mass_error, 1e-12);
      EXPECT_LT(r.diag.max_rel_momentum_error, 1e-12);
    }
    for (std::size_t k = 1; k < err.size(); ++k) {
      const double order = std::log2(err[k - 1] / err[k]);
      EXPECT_GT(order, c.min_order) << "cells " << (8 << k);
    }
  }
}

TEST(Plate2D, ConsistentMassWithRollers) {
  // Rollers fix different components on different sides: each component gets its own
  // elimination. The consistent-mass run must be as accurate as the lumped one at small
  // amplitude (both converge; consistent mass is not less accurate) and conserve mass.
  const auto lumped = run_plate({"grid.cells=8", "mms.amplitude=1e-4", "time.end=1e-3",
                                 "method.basis=bspline", "method.mass=lumped"});
  const auto consistent = run_plate({"grid.cells=8", "mms.amplitude=1e-4", "time.end=1e-3",
                                     "method.basis=bspline", "method.mass=consistent"});
  EXPECT_LT(*consistent.errors.displacement_rms, 1.5 * *lumped.errors.displacement_rms);
  EXPECT_LT(consistent.diag.max_rel_mass_error, 1e-13);
}

TEST(Plate2D, LargeAmplitudeRunsAndCrossesCells) {
  // A = 0.1 m (the published amplitude) over a short time: particles cross cells, the run stays
  // finite, conserves mass and momentum of the mapping, and B-splines are more accurate than
  // P1 (001 Figs. 2-4).
  const auto p1 = run_plate({"grid.cells=16", "time.end=0.005", "method.basis=linear"});
  const auto bs = run_plate({"grid.cells=16", "time.end=0.005", "method.basis=bspline"});
  EXPECT_GT(p1.diag.grid_crossings, 0);
  EXPECT_LT(*bs.errors.velocity_rms, *p1.errors.velocity_rms);
  EXPECT_LT(bs.diag.max_rel_mass_error, 1e-12);
}

TEST(Plate2D, TlsImprovesMpmAndConservesOnTheD631Plate) {
  // D 6.3.1 (Table 6.1, Fig. 6.8): 32 x 32 elements, A = 0.05 m, 120 steps. The TLS
  // reconstruction conserves mass and momentum to round-off like the direct mapping, and
  // "significantly improves the MPM results" (D Fig. 6.8, the stress along x1 = 0.5).
  auto run_d631 = [](const char* mapping) {
    auto cfg = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/plate_tls_2d.toml",
                            {"output.frames=0", "output.csv=false", "output.vtk=false",
                             fmt::format("method.mapping={}", mapping)});
    auto r = run(cfg, RunOptions{});
    EXPECT_EQ(r.exit_code, 0) << r.failure;
    return r;
  };
  const auto direct = run_d631("direct");
  const auto tls = run_d631("tls");
  EXPECT_LT(tls.diag.max_rel_mass_error, 1e-13);
  EXPECT_LT(tls.diag.max_rel_momentum_error, 1e-13);
  EXPECT_LT(*tls.errors.stress_rms, 0.5 * *direct.errors.stress_rms);
  EXPECT_LT(*tls.errors.displacement_rms, 0.5 * *direct.errors.displacement_rms);
  // 25 particles per element: nearly every fit has all six terms within the condition limit
  // of the orthonormal basis (measured: 98.6 %; the rest are reduced).
  EXPECT_GT(tls.summary["tls"]["full"].get<double>(),
            0.95 * tls.summary["tls"]["element_fits"].get<double>());
}

TEST(Plate2D, EveryBasisRunsWithEveryMappingIn2D) {
  // Small amplitude, 20 steps on 6 x 6 cells: every 2D basis with every 2D mapping runs from the
  // configuration, stays close to the exact solution, and the conservative mappings (direct,
  // TLS) conserve mass and momentum to round-off.
  const std::vector<std::pair<std::string, int>> bases = {
      {"linear", 1},  {"ugimp", 1},   {"cpgimp", 1},  {"cpdi", 1},    {"cpdi2", 1},  {"ddmpm", 1},
      {"bspline", 1}, {"bspline", 2}, {"bspline", 3}, {"bspline", 4}, {"bspline", 5}};
  const double A = 1e-4, v_amplitude = A * 100.0 * std::numbers::pi;  // A c pi / L
  for (const auto& [basis, degree] : bases)
    for (const char* mapping : {"direct", "tls", "mls", "imls"}) {
      SCOPED_TRACE(fmt::format("{} p={} {}", basis, degree, mapping));
      const auto r =
          run_plate({"grid.cells=6", "mms.amplitude=1e-4", "time.end=2e-4",
                     fmt::format("method.basis={}", basis), fmt::format("method.degree={}", degree),
                     fmt::format("method.mapping={}", mapping)});
      if (r.exit_code != 0) continue;  // reported by run_plate
      EXPECT_LT(*r.errors.velocity_rms, 0.2 * v_amplitude);
      if (std::string(mapping) == "direct" || std::string(mapping) == "tls") {
        EXPECT_LT(r.diag.max_rel_mass_error, 1e-13);
        EXPECT_LT(r.diag.max_rel_momentum_error, 1e-12);
      }
    }
}

TEST(Plate2D, UnavailableCombinationsAreInputErrors) {
  try {
    run(plate({"method.mapping=cubic_spline"}), RunOptions{});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("method.mapping = \"cubic_spline\" is not available in 2D"),
        std::string::npos)
        << e.what();
  }
  try {
    run(plate({"material.model=elastic_1d_small"}), RunOptions{});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("material.model"), std::string::npos) << e.what();
  }
}

// `mpm bench --dim 2 --problem refkernel`: the yardstick's problem (n x n cells of the unit
// square, 3 x 3 particles per cell) runs through the normal step with every quadratic B-spline
// span interior (two padding cells per side), for one and two threads; the plate stays the
// default problem.
TEST(Plate2D, BenchRunsTheRefkernelProblem) {
  BenchOptions opt;
  opt.dim = 2;
  opt.particles = 2000;
  opt.steps = 2;
  opt.repeats = 1;
  opt.basis = "bspline";
  opt.degree = 2;
  EXPECT_EQ(opt.problem, "plate");
  opt.problem = "refkernel";
  for (int threads : {1, 2}) {
    opt.threads = threads;
    const BenchResult r = bench_2d(opt);
    EXPECT_EQ(r.cells, 15);
    EXPECT_EQ(r.particles, 15 * 15 * 9);
    EXPECT_EQ(r.steps, 2);
    EXPECT_GT(r.best_ns_per_particle_step, 0.0);
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
