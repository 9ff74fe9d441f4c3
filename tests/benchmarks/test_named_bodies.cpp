// Several bodies in one custom problem ([body.NAME] tables beside [body]):
// - two boxes stacked on each other seed the particles of the one box they fill, in the same
//   order, and run as it (the upper one with a named copy of the material), bit for bit; their
//   geostatic stress is the one box's;
// - two blocks of different density thrown at each other keep the total momentum at zero to
//   round-off through their collision (one velocity field: they meet and move on together);
// - a body mesh on a box foundation takes its parts' materials, each body its range of ids, and
//   its K0 stress the weight of both bodies above;
// - a particle file's velocities go to its own particles, by row;
// - overlapping bodies, a table that gives no body, a body off the grid and named bodies where
//   they do not apply are refused, naming the tables.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "../support/mohr_coulomb_block.hpp"
#include "../support/stepper.hpp"
#include "../support/threads.hpp"
#include "benchmarks/benchmarks.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

std::string data_mesh(const std::string& name) {
  return std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

// The block of tests/support/mohr_coulomb_block.hpp with the given [body] lines, further tables
// and [particles] lines.
std::string problem(const std::string& body, const std::string& more = "",
                    const std::string& particles = "per_cell = 2") {
  return test::mohr_coulomb_block(body, particles, more);
}

const std::string kCopy = test::kMohrCoulombCopy;

Problem<2> problem_of(const std::string& text) {
  return std::get<Problem<2>>(make_problem(Config::parse(text, "bodies.toml")));
}

TEST(NamedBodies, TwoStackedBoxesAreTheOneBoxTheyFill) {
  const std::string one =
      problem("min = [0.25, 0.0]\nmax = [0.75, 0.5]", "[initial]\nvelocity = [\"2*y\", \"0\"]\n");
  const std::string two =
      problem("min = [0.25, 0.0]\nmax = [0.75, 0.25]",
              std::string(kCopy) +
                  "[body.upper]\nmin = [0.25, 0.25]\nmax = [0.75, 0.5]\nmaterial = \"copy\"\n"
                  "[initial]\nvelocity = [\"2*y\", \"0\"]\n");
  const Problem<2> a = problem_of(one), b = problem_of(two);
  ASSERT_EQ(a.particles.size(), b.particles.size());
  ASSERT_EQ(b.bodies.size(), 2u);
  EXPECT_EQ(b.bodies[0].table, "body");
  EXPECT_EQ(b.bodies[1].table, "body.upper");
  EXPECT_EQ(b.bodies[1].first_id, b.bodies[0].count);
  EXPECT_EQ(b.bodies[0].count + b.bodies[1].count, static_cast<Index>(b.particles.size()));
  for (std::size_t i = 0; i < a.particles.x.size(); ++i) {
    ASSERT_EQ(a.particles.id[i], b.particles.id[i]);
    ASSERT_EQ(a.particles.x[i], b.particles.x[i]) << i;
    ASSERT_EQ(a.particles.volume[i], b.particles.volume[i]) << i;
    ASSERT_EQ(b.particles.material[i], b.particles.id[i] < b.bodies[1].first_id ? 0 : 1) << i;
  }
  // Ten steps of the yielding block: the same bits.
  const test::Threads one_thread(1);
  test::ConfiguredRun<2> ra(Config::parse(one, "a.toml")), rb(Config::parse(two, "b.toml"));
  ra.advance(10);
  rb.advance(10);
  const auto &P = ra.state().particles, &Q = rb.state().particles;
  double plastic = 0.0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    ASSERT_EQ(P.x[i], Q.x[i]) << i;
    ASSERT_EQ(P.v[i], Q.v[i]) << i;
    ASSERT_EQ(P.stress[i], Q.stress[i]) << i;
    for (std::size_t c = 0; c < P.state.width(); ++c) ASSERT_EQ(P.state[i][c], Q.state[i][c]);
    plastic = std::max(plastic, P.state[i][0]);
  }
  EXPECT_GT(plastic, 0.0);

  // K0: the weight of the upper box bears on the lower, as in the one box (rho g (top - y)).
  const std::string k0 = "[initial]\ngeostatic = \"k0\"\nk0 = 0.5\n";
  const Problem<2> c = problem_of(problem("min = [0.25, 0.0]\nmax = [0.75, 0.5]", k0));
  const Problem<2> d =
      problem_of(problem("min = [0.25, 0.0]\nmax = [0.75, 0.25]",
                         k0 + "[body.upper]\nmin = [0.25, 0.25]\nmax = [0.75, 0.5]\n"));
  for (std::size_t i = 0; i < c.particles.x.size(); ++i) {
    const double y = c.particles.x[i][1];
    EXPECT_NEAR(c.particles.stress[i](1, 1), -2e4 * (0.5 - y), 1e-9);
    EXPECT_NEAR(d.particles.stress[i](1, 1), c.particles.stress[i](1, 1), 1e-9) << i;
    EXPECT_NEAR(d.particles.stress[i](0, 0), 0.5 * c.particles.stress[i](1, 1), 1e-9) << i;
  }
}

TEST(NamedBodies, ThreeDimensionalBoxesStackAsTheOneBox) {
  // Two boxes one above the other (z) seed the particles of the box they fill, in its order, and
  // carry its geostatic stress (the upper box's weight on the lower).
  auto cube = [](const std::string& body, const std::string& more) {
    return fmt::format(R"toml(benchmark = "custom"
[grid]
dimension = 3
cells = 4
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[body]
{}
[time]
dt = 1e-4
end = 1e-3
[material]
model = "von_mises"
density = 1000.0
youngs_modulus = 1e6
poisson_ratio = 0.25
yield_stress = 1e5
[loading]
body_force = ["0", "0", "-10"]
[initial]
geostatic = "k0"
k0 = 0.4
{})toml",
                       body, more);
  };
  const auto a = std::get<Problem<3>>(make_problem(
      Config::parse(cube("min = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 0.75]", ""), "a.toml")));
  const auto b = std::get<Problem<3>>(make_problem(
      Config::parse(cube("min = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 0.5]",
                         "[body.top]\nmin = [0.0, 0.0, 0.5]\nmax = [1.0, 1.0, 0.75]\n"),
                    "b.toml")));
  ASSERT_EQ(a.particles.size(), b.particles.size());
  ASSERT_EQ(b.bodies.size(), 2u);
  for (std::size_t i = 0; i < a.particles.x.size(); ++i) {
    ASSERT_EQ(a.particles.id[i], b.particles.id[i]);
    ASSERT_EQ(a.particles.x[i], b.particles.x[i]) << i;
    ASSERT_EQ(a.particles.volume[i], b.particles.volume[i]) << i;
    EXPECT_NEAR(b.particles.stress[i](2, 2), a.particles.stress[i](2, 2), 1e-9) << i;
    EXPECT_NEAR(b.particles.stress[i](0, 0), a.particles.stress[i](0, 0), 1e-9) << i;
  }
}

TEST(NamedBodies, BlocksThrownAtEachOtherKeepZeroMomentum) {
  // A light block at +1 m/s and one of twice the density at -0.5 m/s: zero momentum. No gravity,
  // free sides; they meet in the first steps and go on as one velocity field.
  std::string text = problem("min = [0.1, 0.3]\nmax = [0.45, 0.7]",
                             R"toml([material.heavy]
model = "neo_hookean"
density = 4000.0
youngs_modulus = 1e6
poisson_ratio = 0.3
[body.right]
min = [0.5, 0.3]
max = [0.85, 0.7]
material = "heavy"
[initial]
velocity = ["x < 0.475 ? 1 : -0.5", "0"]
)toml");
  text.replace(text.find("model = \"mohr_coulomb\""), 22, "model = \"neo_hookean\"");
  for (const char* line : {"cohesion = 50.0\n", "friction_angle = 30.0\n"})
    text.erase(text.find(line), std::string(line).size());
  text.replace(text.find("body_force = [\"0\", \"-10\"]"), 25, "body_force = [\"0\", \"0\"]");
  text.replace(text.find("bottom = \"fixed\""), 16, "bottom = \"free\"");
  const test::Threads one_thread(1);
  test::ConfiguredRun<2> run(Config::parse(text, "blocks.toml"));
  const auto& P = run.state().particles;
  auto momentum = [&] {
    Vec<2> p = Vec<2>::Zero();
    double scale = 0.0, kinetic = 0.0;
    for (std::size_t i = 0; i < P.x.size(); ++i) {
      p += P.mass[i] * P.v[i];
      scale += P.mass[i] * P.v[i].norm();
      kinetic += 0.5 * P.mass[i] * P.v[i].squaredNorm();
    }
    return std::tuple{p, scale, kinetic};
  };
  const auto [p0, s0, k0] = momentum();
  EXPECT_LT(p0.norm(), 1e-14 * s0);
  run.advance(400);  // 0.04 s: the gap of 0.05 m closes at 1.5 m/s in 0.033 s
  const auto [p1, s1, k1] = momentum();
  EXPECT_LT(p1.norm(), 1e-12 * s0) << p1.transpose();
  // They met: kinetic energy went into the blocks' strain (and is not all back).
  EXPECT_LT(k1, 0.9 * k0);
}

TEST(NamedBodies, ABodyMeshOnABoxFoundationTakesItsMaterialsAndWeight) {
  // The layered column (0.2 m by 1 m, parts "lower" and "upper") standing on a box foundation
  // 0.25 m deep; the column's parts of densities 2000 ([material]) and 1000 ([material.light]).
  const std::string light = R"toml(
[material.light]
model = "mohr_coulomb"
density = 1000.0
youngs_modulus = 1e6
poisson_ratio = 0.3
cohesion = 50.0
friction_angle = 30.0
)toml";
  const std::string text = fmt::format(
      R"toml({}
[body.column]
mesh = "{}"
part_materials = "upper: light"
[initial]
geostatic = "k0"
k0 = 0.5
)toml",
      light, data_mesh("layered_column.msh"));
  // The grid [0, 1] x [-0.25, 1.25] (h = 0.125), the foundation [0, 1] x [-0.25, 0].
  std::string cfg =
      problem("min = [0.0, -0.25]\nmax = [1.0, 0.0]", text, "per_cell = 2\nper_element = 3");
  cfg.replace(cfg.find("min = [0.0, 0.0]\nmax = [1.0, 1.0]"), 33,
              "min = [0.0, -0.25]\nmax = [1.0, 1.25]");
  const Problem<2> pb = problem_of(cfg);
  ASSERT_EQ(pb.bodies.size(), 2u);
  const Index first = pb.bodies[1].first_id;
  double foundation = 0.0, lower = 0.0, upper = 0.0;
  for (std::size_t i = 0; i < pb.particles.x.size(); ++i) {
    const auto& x = pb.particles.x[i];
    const bool column = pb.particles.id[i] >= first;
    ASSERT_EQ(column, x[1] > 0.0) << i;
    const double m = pb.particles.mass[i];
    if (!column) {
      foundation += m;
      ASSERT_EQ(pb.particles.material[i], 0);
    } else if (x[1] < 0.5) {
      lower += m;
      ASSERT_EQ(pb.particles.material[i], 0);
    } else {
      upper += m;
      ASSERT_EQ(pb.particles.material[i], 1);
    }
    // sigma_v = -g (mass above per unit area): the column's parts, and the foundation below it.
    double above = 0.0;
    if (column)
      above = x[1] < 0.5 ? 2000.0 * (0.5 - x[1]) + 1000.0 * 0.5 : 1000.0 * (1.0 - x[1]);
    else
      above = 2000.0 * (0.0 - x[1]) + (x[0] < 0.2 ? 2000.0 * 0.5 + 1000.0 * 0.5 : 0.0);
    EXPECT_NEAR(pb.particles.stress[i](1, 1), -10.0 * above, 1e-5) << i;
  }
  EXPECT_NEAR(foundation, 2000.0 * 0.25, 1e-12 * 500.0);
  EXPECT_NEAR(lower, 2000.0 * 0.1, 1e-12 * 200.0);
  EXPECT_NEAR(upper, 1000.0 * 0.1, 1e-12 * 100.0);
}

struct TempFile {
  std::string path;
  TempFile(const std::string& name, const std::string& text) : path(::testing::TempDir() + name) {
    std::ofstream(path) << text;
  }
  ~TempFile() { std::remove(path.c_str()); }
};

TEST(NamedBodies, AParticleFilesVelocitiesGoToItsOwnParticles) {
  const TempFile csv("named_bodies_ball.csv",
                     "x,y,volume,vx,vy\n0.5,0.8,0.01,1,-2\n0.6,0.8,0.01,3,-4\n");
  const Problem<2> pb = problem_of(problem(
      "min = [0.0, 0.0]\nmax = [1.0, 0.5]",
      fmt::format("[body.ball]\nparticles = \"{}\"\nmaterial = \"copy\"\n{}", csv.path, kCopy)));
  ASSERT_EQ(pb.bodies.size(), 2u);
  const Index first = pb.bodies[1].first_id;
  ASSERT_EQ(pb.bodies[1].count, 2);
  int seen = 0;
  for (std::size_t i = 0; i < pb.particles.x.size(); ++i) {
    if (pb.particles.id[i] < first) {
      ASSERT_EQ(pb.particles.v[i], Vec<2>::Zero());
      continue;
    }
    const Index row = pb.particles.id[i] - first;
    EXPECT_EQ(pb.particles.v[i], row == 0 ? Vec<2>(1, -2) : Vec<2>(3, -4));
    EXPECT_EQ(pb.particles.mass[i], 2000.0 * 0.01);
    EXPECT_EQ(pb.particles.material[i], 1);
    ++seen;
  }
  EXPECT_EQ(seen, 2);
}

TEST(NamedBodies, RefusalsNameTheTables) {
  auto refusal = [](const std::string& text) {
    return test::message_of([&] { make_problem(Config::parse(text, "bad.toml")); });
  };
  const std::string base = "min = [0.0, 0.0]\nmax = [1.0, 0.5]";
  struct Case {
    std::string message, text;
  };
  const TempFile csv("named_bodies_inside.csv", "x,y,volume\n0.5,0.25,0.01\n");
  const std::vector<Case> cases = {
      {"the bodies of [body] (the box body.min, body.max) and [body.top] (the box body.top.min, "
       "body.top.max) overlap",
       problem(base, "[body.top]\nmin = [0.2, 0.4]\nmax = [0.4, 0.8]\n")},
      {"and [body.ball] (particle file",
       problem(base, fmt::format("[body.ball]\nparticles = \"{}\"\n", csv.path))},
      {"overlap",
       problem(base, fmt::format("[body.column]\nmesh = \"{}\"\n", data_mesh("layered_column.msh")),
               "per_cell = 2\nper_element = 3")},
      {"[body.top] gives no body: give its box",
       problem(base, "[body.top]\nmaterial = \"material\"\n")},
      {"must lie inside the grid",
       problem(base, "[body.top]\nmin = [0.2, 0.6]\nmax = [0.4, 1.2]\n")},
      {"body.top.part_materials gives materials to the parts",
       problem(base,
               "[body.top]\nmin = [0.2, 0.6]\nmax = [0.4, 0.8]\npart_materials = \"a: b\"\n")},
      {"body.top.material names the material \"clay\", which is not given",
       problem(base, "[body.top]\nmin = [0.2, 0.6]\nmax = [0.4, 0.8]\nmaterial = \"clay\"\n")},
  };
  for (const auto& c : cases)
    EXPECT_NE(refusal(c.text).find(c.message), std::string::npos) << refusal(c.text);
  // 1D has the one body of [body].
  const std::string bar = R"toml(benchmark = "custom"
[grid]
dimension = 1
cells = 10
[time]
dt = 1e-4
end = 1e-3
[material]
density = 1000.0
youngs_modulus = 1e6
[body.second]
min = 0.2
max = 0.4
)toml";
  EXPECT_NE(refusal(bar).find("[body.second]: named bodies are for 2D and 3D"), std::string::npos)
      << refusal(bar);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
