// How the particle stage stops a run whose particles failed (stages::throw_particle_failure):
// a plastic law's return without an admissible stress is its own failure (exit code 12), named
// with the particle, the trial stress it was left with and the yield function there; a
// non-finite stress stays exit code 3.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <string>

#include "../support/stepper.hpp"
#include "scheme/stages.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(ParticleFailure, AFailedReturnIsNamedWithItsStressAndResidual) {
  // The vertical cut (Tresca clay, c_u = 20 kPa) after a few steps; particle 7 is given a
  // trial stress far outside the surface and marked as its law marks a failed return.
  const Config cfg = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/vertical_cut_2d.toml",
                                  {"grid.cells=20", "time.dt=4e-4"});
  test::ConfiguredRun<2> run(cfg);
  run.advance(3);
  RunState<2>& sim = run.state();
  auto& P = sim.particles;
  const std::size_t k = 7;
  P.stress[k](0, 1) = P.stress[k](1, 0) = 250e3;
  P.state[k][1] = kNoReturn;
  const auto residual = failed_update<2>(sim.materials, P, k);
  ASSERT_TRUE(residual.has_value());
  EXPECT_GT(*residual, 400e3);  // Tresca: 2 * 250 kPa of shear against 2 c_u = 40 kPa
  try {
    stages::throw_particle_failure(sim);
    FAIL() << "no failure reported";
  } catch (const RunError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.exit_code(), exit_code::kReturnMapping) << what;
    EXPECT_NE(what.find("step 3,"), std::string::npos) << what;
    EXPECT_NE(what.find("\"mohr_coulomb\" found no admissible stress at 1 particle(s)"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find(fmt::format("particle {} at x = ", P.id[k])), std::string::npos) << what;
    EXPECT_NE(what.find("sxy = 250000"), std::string::npos) << what;
    EXPECT_NE(what.find(fmt::format("yield function there {:.6g} Pa", *residual)),
              std::string::npos)
        << what;
  }
  // A non-finite stress is not a failed return.
  P.state[k][1] = 0.0;
  EXPECT_FALSE(failed_update<2>(sim.materials, P, k).has_value());
  P.stress[k + 1](0, 0) = std::numeric_limits<double>::quiet_NaN();
  try {
    stages::throw_particle_failure(sim);
    FAIL() << "no failure reported";
  } catch (const RunError& e) {
    EXPECT_EQ(e.exit_code(), exit_code::kNonFinite) << e.what();
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
