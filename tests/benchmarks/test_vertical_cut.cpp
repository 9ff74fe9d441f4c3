// examples/vertical_cut_2d.toml on a coarser grid: a vertical cut in Tresca clay falls when
// gamma H / c_u is above the critical 3.77 of limit analysis (Pastor et al. 2000) and stands
// below it, the plastic laws running through the whole step (2D, B-splines, MUSL) from
// configuration.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "../support/stepper.hpp"
#include "benchmarks/benchmarks.hpp"
#include "driver/stepper.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"
#include "setup/run_settings.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// The largest horizontal displacement of the cut's particles after t = 2 s, with c_u = c.
double largest_slide(double c, double* plastic) {
  const Config cfg =
      Config::load(std::string(MPM_SOURCE_DIR) + "/examples/vertical_cut_2d.toml",
                   {"grid.cells=20", "time.dt=4e-4", fmt::format("material.cohesion={}", c)});
  test::ConfiguredRun<2> run(cfg);
  run.advance(static_cast<int>(std::llround(cfg.get_real("time.end") / run.dt)));
  const RunState<2>& sim = run.state();
  const auto& P = sim.particles;
  double slide = 0.0;
  *plastic = 0.0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    slide = std::max(slide, std::abs(P.x[i][0] - P.x0[i][0]));
    *plastic = std::max(*plastic, P.state[i][0]);
  }
  return slide;
}

TEST(VerticalCut, FallsAboveTheCriticalHeightAndStandsBelow) {
  double plastic_fall = 0.0, plastic_stand = 0.0;
  const double fall = largest_slide(20e3, &plastic_fall);    // gamma H / c_u = 5
  const double stand = largest_slide(30e3, &plastic_stand);  // 3.33
  std::printf(
      "vertical cut: c_u 20 kPa slides %.3g m (plastic strain up to %.3g), 30 kPa %.3g m "
      "(%.3g)\n",
      fall, plastic_fall, stand, plastic_stand);
  EXPECT_GT(fall, 0.2);  // still sliding at the end; the standing cut moves 30 times less
  EXPECT_GT(plastic_fall, 0.1);
  EXPECT_LT(plastic_stand, 0.05);
  EXPECT_LT(stand, 0.05);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
