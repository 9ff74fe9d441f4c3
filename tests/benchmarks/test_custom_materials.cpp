// Several materials in one custom problem ([material.NAME], body.material, body.part_materials):
// - a body given a named copy of [material] runs bit for bit as with [material] itself, and so
//   does a body mesh whose parts take copies (the stress stage then loops over each material's
//   particles: each particle's update is its own);
// - a column of two layers of different density and stiffness (tests/data/meshes/
//   layered_column.msh) under slowly ramped gravity reaches the closed-form quasi-static stress
//   and settlement, and its mass is the sum of rho_k V_k to round-off;
// - laws with different internal variables share the particles' rows in blocks;
// - refusals name the key, the material or part, and what exists.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "../support/mohr_coulomb_block.hpp"
#include "../support/stepper.hpp"
#include "../support/threads.hpp"
#include "benchmarks/benchmarks.hpp"
#include "driver/run.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

std::string data_mesh(const std::string& name) {
  return std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

// A Mohr-Coulomb block of little cohesion on a fixed floor (tests/support/mohr_coulomb_block.hpp),
// sheared (it yields in its first steps); `body` and `more` are the [body] table's lines and
// further tables (a body mesh is seeded with 3 particles per triangle, a box with 2 per cell and
// direction).
std::string block(const std::string& body, const std::string& more = "") {
  const bool mesh = body.find("mesh =") != std::string::npos;
  return test::mohr_coulomb_block(body, mesh ? "per_element = 3" : "per_cell = 2",
                                  "[initial]\nvelocity = [\"2*y\", \"0\"]\n" + more);
}

const std::string kCopy = test::kMohrCoulombCopy;

void expect_same_particles(const std::string& a_text, const std::string& b_text,
                           std::size_t materials) {
  const test::Threads one(1);
  test::ConfiguredRun<2> a(Config::parse(a_text, "a.toml"));
  test::ConfiguredRun<2> b(Config::parse(b_text, "b.toml"));
  ASSERT_EQ(a.state().materials.size(), 1u);
  ASSERT_EQ(b.state().materials.size(), materials);
  a.advance(10);
  b.advance(10);
  const auto &P = a.state().particles, &Q = b.state().particles;
  ASSERT_EQ(P.size(), Q.size());
  double plastic = 0.0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    ASSERT_EQ(P.x[i], Q.x[i]) << i;
    ASSERT_EQ(P.v[i], Q.v[i]) << i;
    ASSERT_EQ(P.stress[i], Q.stress[i]) << i;
    ASSERT_EQ(P.mass[i], Q.mass[i]) << i;
    for (std::size_t c = 0; c < P.state.width(); ++c) ASSERT_EQ(P.state[i][c], Q.state[i][c]);
    plastic = std::max(plastic, P.state[i][0]);
  }
  // The block yields: the plastic laws' state is exercised.
  EXPECT_GT(plastic, 0.0);
}

TEST(CustomMaterials, ANamedCopyOfTheMaterialRunsBitForBitAsIt) {
  const std::string box = "min = [0.25, 0.0]\nmax = [0.75, 0.5]";
  expect_same_particles(block(box), block(box + "\nmaterial = \"copy\"", kCopy), 2);
  // Every particle of the copy: material 1 (the copy), none of [material].
  const auto pb = std::get<Problem<2>>(
      make_problem(Config::parse(block(box + "\nmaterial = \"copy\"", kCopy), "b.toml")));
  for (const auto m : pb.particles.material) ASSERT_EQ(m, 1);
}

TEST(CustomMaterials, PartsOfABodyMeshTakeTheirMaterialsBitForBit) {
  const std::string mesh = fmt::format("mesh = \"{}\"", data_mesh("layered_column.msh"));
  expect_same_particles(block(mesh), block(mesh + "\npart_materials = \"upper: copy\"", kCopy), 2);
  const auto pb = std::get<Problem<2>>(make_problem(
      Config::parse(block(mesh + "\npart_materials = \"upper: copy\"", kCopy), "b.toml")));
  const auto& P = pb.particles;
  std::size_t upper = 0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    // The parts meet at y = 0.5; no particle lies on it.
    EXPECT_EQ(P.material[i], P.x0[i][1] > 0.5 ? 1 : 0) << i;
    upper += P.material[i];
  }
  EXPECT_EQ(upper * 2, P.x.size());
}

// Two linear elastic layers (nu = 0: uniaxial strain without lateral stress) of height 0.5 m,
// the lower of rho1 = 2000 kg/m^3 and E1 = 1e7 Pa, the upper of rho2 = 1000 and E2 = 2.5e6, on a
// fixed base between rollers, under gravity ramped over T = 0.5 s (about seven periods of the
// column: nearly quasi-static). At equilibrium the stress is the weight above,
//   sigma_yy = -g (rho2 H2 + rho1 (H1 - Y)) below the interface, -g rho2 (H - Y) above,
// and u_y is its integral over E: -g / E1 ((rho2 H2 + rho1 H1) Y - rho1 Y^2 / 2) below and
// u_y(H1) - g rho2 / E2 (H (Y - H1) - (Y^2 - H1^2) / 2) above; the top settles 1.0e-3 m.
TEST(CustomMaterials, ALayeredColumnSettlesToTheClosedForm) {
  const std::string text = fmt::format(R"toml(benchmark = "custom"
[constants]
g = 10.0
T = 0.5
r1 = 2000.0
r2 = 1000.0
E1 = 1.0e7
E2 = 2.5e6
[grid]
dimension = 2
cells = 4
min = [0.0, 0.0]
max = [0.2, 1.1]
[body]
mesh = "{}"
part_materials = "upper: soft"
[particles]
per_element = 3
[time]
dt = 2.5e-4
end = 0.5
[method]
scheme = "musl"
basis = "linear"
[material]
model = "linear_elastic"
density = 2000.0
youngs_modulus = 1.0e7
[material.soft]
model = "linear_elastic"
density = 1000.0
youngs_modulus = 2.5e6
[loading]
body_force = ["0", "-g*min(t/T, 1)"]
[boundary]
left = "roller"
right = "roller"
bottom = "fixed"
top = "free"
[exact]
displacement = ["0", "-g*min(t/T, 1)*(y < 0.5 ? ((r2*0.5 + r1*0.5)*y - r1*y^2/2)/E1 : (r2*0.5 + r1*0.5)*0.5/E1 - r1*0.125/E1 + r2*(y - 0.5 - (y^2 - 0.25)/2)/E2)"]
velocity = "0"
stress = ["0", "-g*min(t/T, 1)*(y < 0.5 ? r2*0.5 + r1*(0.5 - y) : r2*(1 - y))", "0"]
)toml",
                                       data_mesh("layered_column.msh"));
  const auto r = run(Config::parse(text, "layered.toml"), RunOptions{});
  ASSERT_EQ(r.exit_code, 0) << r.failure;
  ASSERT_TRUE(r.errors.stress_rel_l2 && r.errors.displacement_rms);
  std::printf("layered column: stress rel L2 %.4g, displacement RMS %.4g m\n",
              *r.errors.stress_rel_l2, *r.errors.displacement_rms);
  EXPECT_LT(*r.errors.stress_rel_l2, 0.05);
  EXPECT_LT(*r.errors.displacement_rms, 2e-5);  // of a settlement of 1.0e-3 m at the top
  ASSERT_TRUE(r.summary.contains("materials"));
  EXPECT_EQ(r.summary["materials"][1]["name"], "soft");
  EXPECT_EQ(r.summary["materials"][1]["density"], 1000.0);

  // The mass: rho_k times the parts' areas (0.1 m^2 each), to round-off.
  const auto pb = std::get<Problem<2>>(make_problem(Config::parse(text, "layered.toml")));
  double mass = 0.0;
  for (const double m : pb.particles.mass) mass += m;
  EXPECT_NEAR(mass, 2000.0 * 0.1 + 1000.0 * 0.1, 1e-11 * 300.0);
}

// A tracked-elastic lower part under a Mohr-Coulomb upper one: two laws whose internal
// variables stand in two blocks of each particle's row (the plastic laws' three, then the
// tracked law's two), each law writing its own block and leaving the other at 0.
TEST(CustomMaterials, LawsWithDifferentInternalVariablesShareTheRowsInBlocks) {
  const std::string mesh = fmt::format("mesh = \"{}\"", data_mesh("layered_column.msh"));
  const std::string text =
      block(mesh + "\npart_materials = \"lower: tracked\"",
            "[material.tracked]\nmodel = \"tracked_elastic\"\ndensity = 1500.0\n"
            "youngs_modulus = 1e6\n");
  const test::Threads one(1);
  test::ConfiguredRun<2> run(Config::parse(text, "mixed.toml"));
  const auto& materials = run.state().materials;
  ASSERT_EQ(materials.size(), 2u);
  const auto names = materials.state_names();
  ASSERT_EQ(names.size(), 5u);
  EXPECT_EQ(names[0], "plastic_strain");
  EXPECT_EQ(names[3], "updates");
  EXPECT_EQ(materials.state_offset(0), 0u);
  EXPECT_EQ(materials.state_offset(1), 3u);
  run.advance(10);
  const auto& P = run.state().particles;
  bool yielded = false;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const double density = P.mass[i] / P.volume0[i];
    const auto row = P.state[i];
    if (P.material[i] == 1) {
      EXPECT_NEAR(density, 1500.0, 1e-9);
      EXPECT_EQ(row[3], 10.0) << i;  // one update a step
      EXPECT_GT(row[4], 0.0) << i;
      EXPECT_EQ(row[0], 0.0) << i;
      EXPECT_EQ(row[1], 0.0) << i;
      EXPECT_EQ(row[2], 0.0) << i;
    } else {
      EXPECT_NEAR(density, 2000.0, 1e-9);
      EXPECT_EQ(row[3], 0.0) << i;
      EXPECT_EQ(row[4], 0.0) << i;
      yielded = yielded || row[0] > 0.0;
    }
  }
  EXPECT_TRUE(yielded);
}

void expect_refused(const std::string& text, const std::vector<std::string>& needles) {
  try {
    const Config c = Config::parse(text, "case.toml");
    (void)make_problem(c);
    (void)run(c, RunOptions{});
    ADD_FAILURE() << "no InputError for\n" << text;
  } catch (const InputError& e) {
    for (const auto& n : needles)
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << n << "\n" << e.what();
  }
}

TEST(CustomMaterials, RefusalsNameTheKeyAndWhatExists) {
  const std::string box = "min = [0.25, 0.0]\nmax = [0.75, 0.5]";
  const std::string mesh = fmt::format("mesh = \"{}\"", data_mesh("layered_column.msh"));
  expect_refused(
      block(box + "\nmaterial = \"nope\"", kCopy),
      {"case.toml:10:", "body.material names the material \"nope\"", "\"material\", \"copy\""});
  expect_refused(block(mesh + "\npart_materials = \"middle: copy\"", kCopy),
                 {"body.part_materials", "has no part \"middle\"", "\"lower\", \"upper\""});
  expect_refused(block(mesh + "\npart_materials = \"upper: copy, upper: material\"", kCopy),
                 {"the part \"upper\" is named twice"});
  expect_refused(block(mesh + "\npart_materials = \"upper copy\"", kCopy),
                 {"\"upper copy\" is not PART: NAME"});
  expect_refused(block(mesh + "\npart_materials = \"upper: clay\"", kCopy),
                 {"body.part_materials names the material \"clay\""});
  expect_refused(block(box + "\npart_materials = \"upper: copy\"", kCopy),
                 {"body.part_materials gives materials to the parts", "box body.min"});
  expect_refused(block(box, kCopy), {"[material.copy] is the material of no body"});
  expect_refused(block(box, "[material.soft]\nmodel = \"linear_elastic\"\nyoungs_modulus = 1e6\n"),
                 {"required key 'material.soft.density'", "(in [material.soft])"});
  expect_refused(block(box, std::string(kCopy) + "densty = 1.0\n"),
                 {"unknown key 'material.copy.densty'", "did you mean 'material.copy.density'"});
  expect_refused(block(box + "\nmaterial = \"copy\"",
                       "[material.copy]\nmodel = \"neo_hookean\"\ndensity = 1.0\n"
                       "youngs_modulus = 1e6\nfriction_angle = 20.0\n"),
                 {"material.copy.friction_angle is a parameter of", "material.copy.model"});
  // Named materials are for the custom problem's bodies.
  expect_refused(std::string("benchmark = \"vibrating_bar\"\n[time]\ndt = 1e-4\nend = 1e-3\n"
                             "[material]\ndensity = 1.0\n"
                             "youngs_modulus = 100.0\n[material.other]\ndensity = 2.0\n"
                             "youngs_modulus = 1.0\n"),
                 {"[material.other] is a named material", "benchmark = \"custom\""});
}

TEST(CustomMaterials, NamedMaterialsSurviveTheStoredConfiguration) {
  const std::string box = "min = [0.25, 0.0]\nmax = [0.75, 0.5]";
  const Config c = Config::parse(block(box + "\nmaterial = \"copy\"", kCopy), "b.toml",
                                 {"material.copy.cohesion=2500", "material.extra.density=3",
                                  "material.extra.youngs_modulus=5"});
  EXPECT_EQ(c.instances("material"), (std::vector<std::string>{"copy", "extra"}));
  EXPECT_EQ(c.get_real("material.copy.cohesion"), 2500.0);
  EXPECT_EQ(c.where("material.copy.cohesion"), "--set material.copy.cohesion=2500");
  EXPECT_EQ(c.get_real("material.copy.poisson_ratio"), 0.3);
  EXPECT_TRUE(c.at_default("material.extra.poisson_ratio"));
  // The effective configuration names every key of each named table and reads back the same.
  const std::string stored = c.to_toml();
  EXPECT_NE(stored.find("\n[material.copy]\n"), std::string::npos) << stored;
  const Config back = Config::parse(stored, "config.toml");
  EXPECT_EQ(back.instances("material"), c.instances("material"));
  EXPECT_EQ(back.get_real("material.copy.cohesion"), 2500.0);
  EXPECT_EQ(back.get_string("material.copy.model"), "mohr_coulomb");
  EXPECT_EQ(back.get_real("material.extra.density"), 3.0);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
