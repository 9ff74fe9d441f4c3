// The initial stress of a custom body (benchmarks/initial_stress.hpp): initial.geostatic = "k0"
// gives a soil layer the stress of its own weight, sigma_v = rho g (top - depth) and
// sigma_h = K0 sigma_v, in which it stays still under gravity (the grid forces of the stress
// balance the weight node by node); the out-of-plane stress of a 2D run is in the law's state;
// and what the procedure cannot do is refused naming the key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../support/soil_layer.hpp"
#include "../support/stepper.hpp"
#include "benchmarks/benchmarks.hpp"
#include "driver/stepper.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

constexpr const char* kLayer2D = test::kK0Layer2D;

constexpr const char* kLayer3D = R"toml(benchmark = "custom"
[grid]
dimension = 3
cells = 2
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.5]
[body]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[particles]
per_cell = 2
[time]
dt = 1e-4
end = 2e-2
[material]
model = "drucker_prager"
density = 2000.0
youngs_modulus = 20e6
poisson_ratio = 0.3
cohesion = 10e3
friction_angle = 30.0
dp_match = "compression"
[boundary]
left = "roller"
right = "roller"
bottom = "roller"
top = "roller"
back = "fixed"
front = "free"
[loading]
body_force = ["0", "0", "-9.81"]
[initial]
geostatic = "k0"
k0 = 0.5
)toml";

template <int Dim>
void expect_still(const std::string& toml) {
  const Config c = Config::parse(toml, "layer.toml");
  Problem<Dim> pb = std::get<Problem<Dim>>(make_problem(c));
  const auto& P0 = pb.particles;
  const double rho_g = 2000.0 * 9.81;
  for (std::size_t i = 0; i < P0.x.size(); ++i) {
    const double depth = 1.0 - P0.x0[i][Dim - 1];
    EXPECT_NEAR(P0.stress[i](Dim - 1, Dim - 1), -rho_g * depth, 1e-9 * rho_g);
    EXPECT_NEAR(P0.stress[i](0, 0), -0.5 * rho_g * depth, 1e-9 * rho_g);
    EXPECT_EQ(P0.stress[i](0, 1), 0.0);
    if constexpr (Dim == 2) {
      EXPECT_NEAR(P0.state[i][2], -0.5 * rho_g * depth, 1e-9 * rho_g);
    }
  }
  // Linear basis, direct mapping, USL, lumped mass.
  const Particles<Dim> P = test::step_problem(pb, 1e-4, 200, Usl{});
  double vmax = 0.0, drift = 0.0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    vmax = std::max(vmax, P.v[i].norm());
    drift = std::max(drift, (P.stress[i] - P0.stress[i]).norm());
    EXPECT_EQ(P.state[i][1], 0.0) << "particle " << i << " yielded";
  }
  // Unbalanced, the layer would fall at g t = 0.2 m/s by now.
  EXPECT_LT(vmax, 1e-12) << "the layer moved";
  EXPECT_LT(drift, 1e-9 * rho_g) << "the stress changed";
}

TEST(Geostatic, AK0LayerUnderGravityStaysStill) {
  expect_still<2>(kLayer2D);
  expect_still<3>(kLayer3D);
}

void expect_input_error(const std::string& toml, const std::vector<std::string>& needles) {
  try {
    const Config c = Config::parse(toml, "case.toml");
    (void)make_problem(c);
    ADD_FAILURE() << "no InputError for\n" << toml;
  } catch (const InputError& e) {
    for (const auto& n : needles)
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
  }
}

TEST(Geostatic, WhatTheProcedureCannotDoIsRefusedNamingTheKey) {
  const std::string layer = kLayer2D;
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string t = layer;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  expect_input_error(with("body_force = [\"0\", \"-9.81\"]", "body_force = [\"1\", \"-9.81\"]"),
                     {"case.toml:30:", "along the last axis (y)", "has x = 1"});
  expect_input_error(with("body_force = [\"0\", \"-9.81\"]", "body_force = [\"0\", \"-9.81*t\"]"),
                     {"needs a constant body force", "changes with time"});
  expect_input_error(with("body_force = [\"0\", \"-9.81\"]", "body_force = [\"0\", \"9.81\"]"),
                     {"needs a body force downwards, along -y"});
  expect_input_error(with("k0 = 0.5", "k0 = 0.5\nstress = [\"-1\", \"0\", \"0\"]"),
                     {"computes the initial stress; leave initial.stress"});
  expect_input_error(with("k0 = 0.5\n", ""), {"required key 'initial.k0'"});
  expect_input_error(with("geostatic = \"k0\"\n", ""),
                     {"initial.k0 is read with initial.geostatic = \"k0\""});
  std::string elastic = with("model = \"mohr_coulomb\"", "model = \"linear_elastic\"");
  elastic.erase(elastic.find("cohesion"),
                std::string("cohesion = 10e3\nfriction_angle = 30.0\n").size());
  expect_input_error(elastic, {"case.toml:28:", "initial.geostatic gives an initial stress",
                               "needs an incremental law"});
  // The out-of-plane stress: 2D only, and only for a law that keeps it.
  const std::string plain = with("geostatic = \"k0\"\nk0 = 0.5\n", "stress_zz = \"-1e3\"\n");
  const Config c = Config::parse(plain, "case.toml");
  const auto pb = std::get<Problem<2>>(make_problem(c));
  EXPECT_EQ(pb.particles.state[0][2], -1e3);
  EXPECT_EQ(pb.particles.stress[0], Mat<2>::Zero());
  std::string t3 = kLayer3D;
  t3.replace(t3.find("geostatic = \"k0\"\nk0 = 0.5\n"), 26, "stress_zz = \"-1e3\"\n");
  expect_input_error(t3, {"initial.stress_zz is the out-of-plane stress of a 2D"});
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
