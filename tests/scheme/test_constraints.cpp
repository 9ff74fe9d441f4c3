// Constraints of the grid beyond fixed sides (scheme/grid_stages.cpp): a box of prescribed
// velocities (prescribed.*) carries its nodes and the body with them; the reactions of the
// constrained boundaries (output.reactions) balance the weight and the earth pressure of a
// layer at rest to round-off; Cundall's local damping (method.local_damping) takes a column to
// the equilibrium of the undamped equations; and what they cannot do is refused naming the key.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "../support/soil_layer.hpp"
#include "../support/stepper.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// An elastic block 1 m x 0.5 m on a 2 m x 1 m grid, nothing fixed, under `body_force`.
std::string block(const std::string& extra) {
  return fmt::format(R"toml(benchmark = "custom"
[grid]
dimension = 2
cells = 8
min = [0.0, 0.0]
max = [2.0, 1.0]
[body]
min = [0.5, 0.25]
max = [1.5, 0.75]
[time]
dt = 1e-4
end = 1e-2
[material]
model = "linear_elastic"
density = 1000.0
youngs_modulus = 1e6
poisson_ratio = 0.3
[boundary]
left = "free"
right = "free"
bottom = "free"
top = "free"
{})toml",
                     extra);
}

double total_mass(const Particles<2>& P) {
  double m = 0.0;
  for (double mi : P.mass) m += mi;
  return m;
}

// Every DOF in the box moves at the prescribed velocity, so a body inside it translates
// rigidly (no stress) and the box's reaction holds it against gravity: R = -sum m_p g.
TEST(Constraints, APrescribedBoxCarriesTheBodyAndHoldsItsWeight) {
  for (const char* scheme : {"usl", "musl", "usf", "usavg"}) {
    const Config cfg = Config::parse(block(fmt::format(R"toml(
[method]
scheme = "{}"
[loading]
body_force = ["0", "-9.81"]
[prescribed]
nodes = "box"
min = [0.0, 0.0]
max = [2.0, 1.0]
velocity = [0.2, -0.1]
[output]
reactions = true
)toml",
                                                       scheme)),
                                     "box.toml");
    test::ConfiguredRun<2> run(cfg);
    run.advance(50);
    const auto& sim = run.state();
    const auto& P = sim.particles;
    const double t = 50 * 1e-4;
    for (std::size_t i = 0; i < P.x.size(); ++i) {
      EXPECT_NEAR(P.x[i][0] - P.x0[i][0], 0.2 * t, 1e-13) << scheme << " particle " << i;
      EXPECT_NEAR(P.x[i][1] - P.x0[i][1], -0.1 * t, 1e-13) << scheme << " particle " << i;
      EXPECT_LT(P.stress[i].norm(), 1e-9) << scheme;
    }
    // reaction_names: no side is fixed, so the box is the only constrained boundary.
    ASSERT_EQ(sim.diag.reactions.size(), 2u);
    const double weight = total_mass(P) * 9.81;
    EXPECT_NEAR(sim.diag.reactions[0], 0.0, 1e-12 * weight) << scheme;
    EXPECT_NEAR(sim.diag.reactions[1], weight, 1e-12 * weight) << scheme;
  }
}

// prescribed.components = "y" (a smooth footing): x stays free, so a body sliding along x keeps
// its speed while its y velocity is prescribed.
TEST(Constraints, APrescribedComponentLeavesTheOthersFree) {
  const Config cfg = Config::parse(block(R"toml(
[initial]
velocity = ["0.3", "0"]
[prescribed]
nodes = "box"
min = [0.0, 0.0]
max = [2.0, 1.0]
velocity = [0.0, -0.1]
components = "y"
)toml"),
                                   "smooth.toml");
  test::ConfiguredRun<2> run(cfg);
  run.advance(50);
  const auto& P = run.state().particles;
  const double t = 50 * 1e-4;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    EXPECT_NEAR(P.v[i][0], 0.3, 1e-12) << "particle " << i;
    EXPECT_NEAR(P.x[i][0] - P.x0[i][0], 0.3 * t, 1e-13) << "particle " << i;
    EXPECT_NEAR(P.x[i][1] - P.x0[i][1], -0.1 * t, 1e-13) << "particle " << i;
  }
}

// A Mohr-Coulomb layer at rest under gravity at K0 (as tests/benchmarks/test_geostatic.cpp): the
// base carries its weight rho g H W and each roller the earth pressure K0 rho g H^2 / 2, in
// every step, to round-off (the particles integrate the linear stress exactly).
const std::string kLayer = std::string(test::kK0Layer2D) + "[output]\nreactions = true\n";

TEST(Constraints, TheReactionsOfALayerAtRestAreItsWeightAndEarthPressure) {
  const Config cfg = Config::parse(kLayer, "layer.toml");
  test::ConfiguredRun<2> run(cfg);
  // reaction_names order: left, right, bottom (sides_from_config: x sides, then y).
  EXPECT_EQ(reaction_names(run.problem), (std::vector<std::string>{"left", "right", "bottom"}));
  const double rho_g = 2000.0 * 9.81, weight = rho_g * 1.0 * 1.0, thrust = 0.5 * rho_g * 0.5;
  for (int k = 0; k < 4; ++k) {
    run.advance(25);
    const auto& r = run.state().diag.reactions;
    ASSERT_EQ(r.size(), 6u);
    EXPECT_NEAR(r[0], thrust, 1e-9 * weight);   // the left wall pushes along +x
    EXPECT_NEAR(r[2], -thrust, 1e-9 * weight);  // the right one along -x
    EXPECT_NEAR(r[5], weight, 1e-9 * weight);   // the base carries the weight
  }
}

// A column released stress-free under gravity swings about its equilibrium; local damping
// takes it there: the base carries the weight, the particles are still, and the stress is the
// discrete equilibrium of the undamped equations (linear basis, lumped mass: each cell's stress
// carries the nodal weights above it, -rho g times the depth of the cell's middle, to the
// shift of the particles against the grid under the column's strain, 7e-4). Undamped,
// the column is still swinging at the same time.
TEST(Constraints, LocalDampingTakesAColumnToTheUndampedEquilibrium) {
  std::string toml = kLayer;
  toml.replace(toml.find("geostatic = \"k0\"\nk0 = 0.5\n"), 25, "");
  toml.replace(toml.find("model = \"mohr_coulomb\""), 22, "model = \"linear_elastic\"");
  for (const char* cut : {"cohesion = 10e3\n", "friction_angle = 30.0\n"})
    toml.erase(toml.find(cut), std::string(cut).size());
  const double rho_g = 2000.0 * 9.81, weight = rho_g, h = 0.25;
  for (const char* scheme : {"usl", "musl"}) {
    double vmax[2] = {0.0, 0.0};
    for (int damped = 0; damped < 2; ++damped) {
      const Config cfg =
          Config::parse(toml, "column.toml",
                        {fmt::format("method.scheme={}", scheme),
                         fmt::format("method.local_damping={}", damped ? 0.8 : 0.0)});
      test::ConfiguredRun<2> run(cfg);
      run.advance(3000);  // 0.3 s, about ten periods of the column's first mode
      const auto& sim = run.state();
      const auto& P = sim.particles;
      for (std::size_t i = 0; i < P.x.size(); ++i)
        vmax[damped] = std::max(vmax[damped], P.v[i].norm());
      if (!damped) continue;
      EXPECT_NEAR(sim.diag.reactions[5], weight, 1e-4 * weight) << scheme;
      for (std::size_t i = 0; i < P.x.size(); ++i) {
        const double middle = (std::floor(P.x0[i][1] / h) + 0.5) * h;
        EXPECT_NEAR(P.stress[i](1, 1), -rho_g * (1.0 - middle), 2e-3 * rho_g)
            << scheme << " particle " << i;
      }
    }
    std::printf("column, %s: largest particle speed after 0.3 s %.3g m/s undamped, %.3g damped\n",
                scheme, vmax[0], vmax[1]);
    EXPECT_LT(vmax[1], 1e-5) << scheme;
    EXPECT_GT(vmax[0], 1e3 * vmax[1]) << scheme;
  }
}

std::string refusal(const std::string& toml) {
  return test::message_of([&] {
    const Config cfg = Config::parse(toml, "case.toml");
    (void)make_problem(cfg);
    (void)run_settings(cfg, 2);
  });
}

TEST(Constraints, WhatTheyCannotDoIsRefusedNamingTheKey) {
  const std::string box = R"toml(
[prescribed]
nodes = "box"
min = [0.0, 0.9]
max = [0.5, 1.0]
velocity = [0.0, -0.1]
)toml";
  auto has = [](const std::string& msg, const std::string& needle) {
    EXPECT_NE(msg.find(needle), std::string::npos) << msg;
  };
  has(refusal(block(box + "[method]\nmass = \"consistent\"\n")),
      "case.toml:25:9: prescribed.nodes needs method.mass = \"lumped\"");
  has(refusal(block(box + "components = \"z\"\n")), "prescribed.components = \"z\" in 2D");
  has(refusal(block(R"toml(
[prescribed]
nodes = "box"
min = [0.0, 0.9]
velocity = [0.0, -0.1]
)toml")),
      "required key 'prescribed.max'");
  has(refusal(block(R"toml(
[prescribed]
nodes = "box"
min = [0.5, 0.9]
max = [0.0, 1.0]
velocity = [0.0, -0.1]
)toml")),
      "prescribed.max = 0 is below prescribed.min = 0.5 in x");
  has(refusal(block("[prescribed]\nvelocity = [0.0, -0.1]\n")),
      "case.toml:24:12: prescribed.velocity is read with prescribed.nodes = \"box\"");
  has(refusal(block("[output]\nreactions = true\n")),
      "output.reactions: benchmark = \"custom\" has no constrained boundary");
  has(refusal(std::string(kLayer) + "[method]\nmass = \"consistent\"\n"),
      "output.reactions needs method.mass = \"lumped\"");
  has(refusal(block("[method]\nlocal_damping = 1.0\n")), "method.local_damping");
  // A box between the DOFs holds none: refused when the stepper is built.
  const Config cfg = Config::parse(block(R"toml(
[prescribed]
nodes = "box"
min = [0.3, 0.3]
max = [0.4, 0.4]
velocity = [0.0, -0.1]
)toml"),
                                   "empty.toml");
  has(test::message_of([&] { test::ConfiguredRun<2> run(cfg); }),
      "the box holds no degree of freedom of the basis");
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
