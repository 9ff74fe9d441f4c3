// examples/footing_2d.toml on a coarser grid: a rigid rough strip footing pushed into weightless
// Tresca clay (von Mises in plane strain) approaches Prandtl's limit pressure
// q_u = (2 + pi) c_u. The footing is a box of prescribed velocities, its load the box's reaction
// (output.reactions), the push kept quasi-static by local damping: the whole chain a user runs,
// from configuration. docs/verification.md, "Strip footing", refines it per basis.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "../support/stepper.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(StripFooting, ApproachesPrandtlsLimitPressure) {
  // h = 0.25 m: the B-splines' control rows nearest the surface y = 2.5 m sit at 2.375 and
  // 2.625 m, so the footing's box takes those.
  const Config cfg = Config::load(
      std::string(MPM_SOURCE_DIR) + "/examples/footing_2d.toml",
      {"grid.cells=20", "time.dt=5e-4", "prescribed.min=[0, 2.3]", "prescribed.max=[0.5, 2.7]"});
  const double c_u = cfg.get_real("material.yield_stress") / std::sqrt(3.0);
  const double half_width = 0.5, speed = 0.01;
  const double prandtl = 2.0 + std::numbers::pi;
  test::ConfiguredRun<2> run(cfg);
  const std::vector<std::string> names = reaction_names(run.problem);
  ASSERT_EQ(names.back(), "prescribed");
  const std::size_t footing = 2 * (names.size() - 1) + 1, base = 2 * 2 + 1;  // left, right, bottom
  ASSERT_EQ(names[2], "bottom");
  // q / c_u at settlements of 0.5, 1.0 and 1.5 % of B.
  std::vector<double> q, base_q;
  for (int k = 0; k < 3; ++k) {
    run.advance(1000);
    const auto& r = run.state().diag.reactions;
    q.push_back(-r[footing] / half_width / c_u);
    base_q.push_back(r[base] / half_width / c_u);
  }
  std::printf(
      "strip footing, B-splines degree 2, h = B / 4: q / c_u = %.3f, %.3f, %.3f at "
      "settlements of %.1f, %.1f, %.1f %% of B (Prandtl %.3f); the base carries %.3f\n",
      q[0], q[1], q[2], 100 * speed * 0.5, 100 * speed * 1.0, 100 * speed * 1.5, prandtl,
      base_q[2]);
  // Rising towards the limit, and flattening: the last 0.5 % of B adds less than 0.6 times the
  // previous 0.5 %.
  EXPECT_GT(q[1], q[0]);
  EXPECT_GT(q[2], q[1]);
  EXPECT_LT(q[2] - q[1], 0.6 * (q[1] - q[0]));
  // Within 10 % of Prandtl on this coarse grid (h = B / 4; the refinement study in
  // docs/verification.md).
  EXPECT_NEAR(q[2], prandtl, 0.10 * prandtl);
  // Quasi-static: the base carries the footing's load, to the damped inertia of the soil.
  EXPECT_NEAR(base_q[2], q[2], 0.05 * q[2]);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
