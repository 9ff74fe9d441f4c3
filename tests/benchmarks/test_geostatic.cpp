// The initial stress of a custom body (benchmarks/initial_stress.hpp): initial.geostatic = "k0"
// gives a soil layer the stress of its own weight, sigma_v = rho g (top - depth) and
// sigma_h = K0 sigma_v, in which it stays still under gravity (the grid forces of the stress
// balance the weight node by node); the out-of-plane stress of a 2D run is in the law's state;
// and what the procedure cannot do is refused naming the key.
#include <fmt/format.h>
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

// A body mesh of layers of different density and K0 (tests/data/meshes/layered_column.msh in 2D,
// cube_tets.msh in 3D: parts "lower" and "upper", each 0.5 m thick): sigma_v is g times the mass
// above, -g (rho2 0.5 + rho1 (0.5 - depth)) in the lower layer and -g rho2 (1 - y) in the upper,
// sigma_h = K0 sigma_v with each layer's K0 (the upper layer's own material.k0, the lower one's
// initial.k0), exactly: the vertical line through a particle crosses the layers' elements.
template <int Dim>
std::string layered_k0(const std::string& mesh) {
  return fmt::format(R"toml(benchmark = "custom"
[grid]
dimension = {0}
cells = 4
min = {1}
max = {2}
[body]
mesh = "{3}/tests/data/meshes/{4}"
part_materials = "upper: soft"
[particles]
per_element = 1
[time]
dt = 1e-4
end = 2e-2
[material]
model = "mohr_coulomb"
density = 2000.0
youngs_modulus = 20e6
poisson_ratio = 0.3
cohesion = 10e3
friction_angle = 30.0
[material.soft]
model = "drucker_prager"
density = 1000.0
youngs_modulus = 5e6
poisson_ratio = 0.3
cohesion = 5e3
friction_angle = 25.0
k0 = 0.4
[boundary]
left = "roller"
right = "roller"
bottom = "fixed"
top = "free"
{5}[loading]
body_force = {6}
[initial]
geostatic = "k0"
k0 = 0.5
)toml",
                     Dim, Dim == 2 ? "[0.0, 0.0]" : "[0.0, 0.0, 0.0]",
                     Dim == 2 ? "[0.2, 1.25]" : "[1.0, 1.0, 1.25]", MPM_SOURCE_DIR, mesh,
                     Dim == 2 ? "" : "back = \"roller\"\nfront = \"roller\"\n",
                     Dim == 2 ? "[\"0\", \"-9.81\"]" : "[\"0\", \"0\", \"-9.81\"]");
}

template <int Dim>
void expect_layered_k0(const std::string& mesh) {
  const auto pb =
      std::get<Problem<Dim>>(make_problem(Config::parse(layered_k0<Dim>(mesh), "layers.toml")));
  const auto& P = pb.particles;
  const double g = 9.81;
  std::size_t upper = 0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const double y = P.x0[i][Dim - 1];
    const bool soft = y > 0.5;
    ASSERT_EQ(P.material[i], soft ? 1 : 0) << i;
    upper += soft;
    const double v = soft ? -g * 1000.0 * (1.0 - y) : -g * (1000.0 * 0.5 + 2000.0 * (0.5 - y));
    const double k0 = soft ? 0.4 : 0.5;
    EXPECT_NEAR(P.stress[i](Dim - 1, Dim - 1), v, 1e-10 * g * 1500.0) << i;
    EXPECT_NEAR(P.stress[i](0, 0), k0 * v, 1e-10 * g * 1500.0) << i;
    EXPECT_EQ(P.stress[i](0, 1), 0.0);
    if constexpr (Dim == 2) {
      EXPECT_NEAR(P.state[i][2], k0 * v, 1e-10 * g * 1500.0) << i;
    }
  }
  EXPECT_EQ(2 * upper, P.x.size());
}

TEST(Geostatic, ALayeredBodyMeshCarriesTheWeightOfEachLayerWithItsK0) {
  expect_layered_k0<2>("layered_column.msh");
  expect_layered_k0<3>("cube_tets.msh");
}

// Under a sloping surface the overburden is that of the column above each point: the slope of
// examples/meshes/slope_layered.msh (one material here) has its surface at y = 10 m for x < 8,
// 10 - (x - 8) for 8 < x < 14 and 4 m beyond.
TEST(Geostatic, UnderASlopeTheOverburdenIsTheColumnAbove) {
  std::string text = fmt::format(R"toml(benchmark = "custom"
[grid]
dimension = 2
cells = 40
min = [0.0, 0.0]
max = [20.0, 11.0]
[body]
mesh = "{}/examples/meshes/slope_layered.msh"
[particles]
per_element = 1
[time]
dt = 1e-3
end = 1e-2
[material]
model = "mohr_coulomb"
density = 1800.0
youngs_modulus = 20e6
poisson_ratio = 0.3
cohesion = 10e3
friction_angle = 30.0
[loading]
body_force = ["0", "-10"]
[initial]
geostatic = "k0"
k0 = 0.6
)toml",
                                 MPM_SOURCE_DIR);
  const auto pb = std::get<Problem<2>>(make_problem(Config::parse(text, "slope.toml")));
  const auto& P = pb.particles;
  ASSERT_EQ(P.x.size(), 1531u);
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const double x = P.x0[i][0], y = P.x0[i][1];
    const double surface = x < 8.0 ? 10.0 : x < 14.0 ? 10.0 - (x - 8.0) : 4.0;
    EXPECT_NEAR(P.stress[i](1, 1), -18000.0 * (surface - y), 1e-9 * 18000.0 * 10.0) << i;
    EXPECT_NEAR(P.stress[i](0, 0), -0.6 * 18000.0 * (surface - y), 1e-9 * 18000.0 * 10.0) << i;
  }
  // A particle file has no elements to weigh; a material.k0 without initial.geostatic is refused.
  expect_input_error(
      [&] {
        std::string t = text;
        t.replace(t.find("geostatic = \"k0\""), 16, "geostatic = \"none\"");
        t.replace(t.find("k0 = 0.6"), 8, "");
        t.replace(t.find("friction_angle = 30.0\n"), 22, "friction_angle = 30.0\nk0 = 0.5\n");
        return t;
      }(),
      {"material.k0 is read with initial.geostatic = \"k0\""});
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
