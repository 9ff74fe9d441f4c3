// Runs on triangles read from a Gmsh file (grid.mesh; setup/gmsh_mesh.hpp, benchmarks/problem.cpp
// mesh_from_config): a file holding a structured triangulation runs bitwise as the generated one
// (P1 and Powell-Sabin, rollers and body force included), P1 with consistent mass carries a
// linear velocity field exactly through a step on an unstructured mesh, a particle that leaves a
// non-convex mesh inside its bounding box stops the run, and input that does not fit is refused
// with the key.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "../support/msh.hpp"
#include "../support/stepper.hpp"
#include "benchmarks/benchmarks.hpp"
#include "driver/stepper.hpp"
#include "grid/triangle_mesh.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"
#include "setup/run_settings.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// The triangles of `square` outside its upper right quarter (an L-shaped mesh).
std::vector<bool> l_shape(const TriangleMesh& square) {
  std::vector<bool> keep(static_cast<std::size_t>(square.num_cells()));
  for (Index c = 0; c < square.num_cells(); ++c) {
    Vec<2> centre = Vec<2>::Zero();
    for (Index v : square.cell_vertices(c)) centre += square.vertex(v) / 3.0;
    keep[static_cast<std::size_t>(c)] = !(centre[0] > 0.5 && centre[1] > 0.5);
  }
  return keep;
}

// The same triangles from a file and from method.triangles: the same vertices, triangles and
// box sides, hence bitwise the same steps, with the plate's rollers and body force, for both
// masses with the direct mapping and with TLS on the triangles.
TEST(MeshFileRun, StructuredMeshFromAFileRunsBitwiseAsTheGeneratedOne) {
  for (const std::string pattern : {"right", "criss_cross"}) {
    const auto p = pattern == "right" ? TrianglePattern::right : TrianglePattern::criss_cross;
    const std::string file =
        test::write_msh(structured_triangles(Vec<2>(0, 0), Vec<2>(1, 1), {3, 3}, p), pattern);
    for (const std::string basis : {"p1_triangles", "powell_sabin"})
      for (const auto& [mass, mapping] :
           {std::pair{"lumped", "direct"}, std::pair{"consistent", "direct"},
            std::pair{"lumped", "tls"}}) {
        SCOPED_TRACE(pattern + " " + basis + " " + mass + " " + mapping);
        const std::vector<std::string> common{
            "grid.cells=3", "particles.per_triangle=12", "method.basis=" + basis,
            std::string("method.mass=") + mass, std::string("method.mapping=") + mapping};
        auto with = [&](std::string extra) {
          auto sets = common;
          sets.push_back(std::move(extra));
          return test::plate_run(sets, false);
        };
        const auto generated = with("method.triangles=" + pattern);
        const auto read = with("grid.mesh=" + file);
        ASSERT_TRUE(read->pb.mesh);
        EXPECT_FALSE(generated->pb.mesh);
        for (int s = 0; s < 3; ++s) {
          generated->stepper->step(1e-5);
          read->stepper->step(1e-5);
        }
        const auto& a = generated->stepper->state().particles;
        const auto& b = read->stepper->state().particles;
        ASSERT_EQ(a.x.size(), b.x.size());
        for (std::size_t i = 0; i < a.x.size(); ++i) {
          ASSERT_EQ(a.x[i], b.x[i]) << i;
          ASSERT_EQ(a.v[i], b.v[i]) << i;
          ASSERT_EQ(a.stress[i], b.stress[i]) << i;
        }
      }
    std::filesystem::remove(file);
  }
}

// On Gmsh's unstructured triangulation of the square (tests/data/meshes/square_v41.msh) P1
// reproduces a linear field and the consistent mass matrix projects v = A x exactly, so one USL
// step gives F = I + dt A and x += dt A x to round-off; lumped mass does not (the control).
TEST(MeshFileRun, P1OnAnUnstructuredMeshCarriesALinearFieldWithConsistentMass) {
  Mat<2> A;
  A << 0.3, -1.1, 0.7, 0.2;
  const std::string mesh = std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/square_v41.msh";
  for (const std::string mass : {"consistent", "lumped"}) {
    auto r =
        test::plate_run({"method.basis=p1_triangles", "grid.mesh=" + mesh, "grid.cells=4",
                         "particles.per_triangle=3", "method.scheme=usl", "method.mass=" + mass},
                        true);
    ASSERT_EQ(r->stepper->state().particles.x.size(), 42u * 3u);
    const auto e = test::linear_field_step(*r->stepper, A, 1e-4);
    if (mass == "consistent") {
      EXPECT_LT(e.f, 1e-12);
      EXPECT_LT(e.x, 1e-15);
    } else {
      EXPECT_GT(e.f, 1e-6);
    }
  }
}

// An L-shaped mesh (the square less its upper right quarter) in its bounding box: a body moving
// towards the missing corner leaves the mesh while still inside the grid, and the run stops
// naming the mesh and the particles (it would otherwise lose their mass silently).
TEST(MeshFileRun, AParticleLeavingANonConvexMeshStopsTheRun) {
  const auto square =
      structured_triangles(Vec<2>(0, 0), Vec<2>(1, 1), {4, 4}, TrianglePattern::right);
  const std::string file = test::write_msh(square, "l_shape", l_shape(square));
  const std::string text = fmt::format(R"(benchmark = "custom"
[grid]
dimension = 2
cells = 4
mesh = "{}"
[body]
min = [0.25, 0.25]
max = [0.5, 0.5]
[particles]
per_cell = 2
[initial]
velocity = ["20", "20"]
[time]
dt = 1e-4
end = 0.1
[method]
basis = "p1_triangles"
[material]
model = "linear_elastic"
density = 1000.0
youngs_modulus = 1.0e6
poisson_ratio = 0.3
[boundary]
left = "free"
right = "free"
bottom = "free"
top = "free"
)",
                                       file);
  const Config cfg = Config::parse(text, "l_shape.toml");
  auto pb = std::get<Problem<2>>(make_problem(cfg));
  ASSERT_TRUE(pb.mesh);
  EXPECT_EQ(pb.grid.upper(), Vec<2>(1, 1));
  const RunSettings s = run_settings(cfg, 2);
  auto stepper =
      driver::make_stepper<2>(s.method.basis, driver::StepperInput<2>{pb, s.method, true});
  std::string what;
  int steps = 0;
  try {
    for (; steps < 200; ++steps) stepper->step(1e-4);
  } catch (const RunError& e) {
    what = e.what();
  }
  // The particle nearest the missing quarter sits at (0.4375, 0.4375) (2 per cell of 0.25 m)
  // and moves 2 mm a step in x and y: it enters the quarter in the 32nd step, and the next one
  // stops when it locates the particles (32 steps done), long before any particle could reach
  // the grid's sides (about 280 steps).
  EXPECT_EQ(steps, 32);
  EXPECT_NE(what.find("left the mesh (mesh file"), std::string::npos) << what;
  EXPECT_EQ(what.find("left the grid"), std::string::npos) << what;
  std::filesystem::remove(file);
}

// Input that does not fit a mesh file is refused before the run, naming the key.
TEST(MeshFileRun, InputThatDoesNotFitIsRefusedWithTheKey) {
  const std::string mesh = std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/square_v41.msh";
  const std::string plate = std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml";
  auto refusal = [&](std::vector<std::string> sets, const std::string& config = "") {
    return test::message_of(
        [&] { (void)make_problem(Config::load(config.empty() ? plate : config, sets)); });
  };
  const std::string tri = "method.basis=p1_triangles";
  EXPECT_NE(refusal({"grid.mesh=" + mesh}).find("grid.mesh = \"" + mesh + "\" holds triangles"),
            std::string::npos);
  EXPECT_NE(refusal({tri, "grid.mesh=" + mesh, "method.triangles=criss_cross"})
                .find("leave method.triangles out"),
            std::string::npos);
  EXPECT_NE(refusal({tri, "grid.mesh=no/such/file.msh"}).find("No such file or directory"),
            std::string::npos);
  EXPECT_NE(refusal({tri, "grid.mesh=" + mesh, "plate.length=2"}).find("is not the grid's"),
            std::string::npos);
  EXPECT_NE(refusal({tri, "grid.mesh=" + mesh},
                    std::string(MPM_SOURCE_DIR) + "/examples/vibrating_bar_small.toml")
                .find("grid.mesh applies to the 2D problems"),
            std::string::npos);
  // A body that reaches outside an L-shaped mesh, and a side the mesh only touches.
  const auto square =
      structured_triangles(Vec<2>(0, 0), Vec<2>(1, 1), {2, 2}, TrianglePattern::right);
  const std::string l_file = test::write_msh(square, "l_refusal", l_shape(square));
  const std::string custom = std::string(MPM_SOURCE_DIR) + "/examples/custom_plate_2d.toml";
  const std::vector<std::string> base{tri,
                                      "grid.mesh=" + l_file,
                                      "grid.min=[0, 0]",
                                      "grid.max=[1, 1]",
                                      "body.min=[0, 0]",
                                      "body.max=[1, 1]"};
  EXPECT_NE(refusal(base, custom).find("lie in no triangle of mesh file"), std::string::npos);
  std::filesystem::remove(l_file);
}

// A custom problem on Gmsh's triangulation of the square (tests/data/meshes/square_v41.msh,
// whose physical groups are "bottom", "right", "top_left" and "7"): `sets` added.
std::unique_ptr<test::PlateRun> custom_on_square(std::vector<std::string> sets) {
  const std::string mesh = std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/square_v41.msh";
  std::vector<std::string> all{"grid.mesh=" + mesh,
                               "grid.min=[0, 0]",
                               "grid.max=[1, 1]",
                               "body.min=[0, 0]",
                               "body.max=[1, 1]",
                               "grid.cells=4",
                               "particles.per_triangle=12",
                               "boundary.left=free",
                               "boundary.right=free",
                               "boundary.bottom=free",
                               "boundary.top=free",
                               "time.dt=1e-4",
                               "loading.body_force=[\"0\", \"-10\"]",
                               "exact.displacement=0",
                               "exact.stress=0"};
  all.insert(all.end(), sets.begin(), sets.end());
  return test::run_2d(
      Config::load(std::string(MPM_SOURCE_DIR) + "/examples/custom_plate_2d.toml", all));
}

// boundary.fixed and boundary.roller act on the mesh file's physical groups: the groups
// "bottom" and "right" of square_v41.msh are the box sides y- and x+, so naming them gives
// bitwise the run of boundary.bottom = "fixed" and boundary.right = "roller", for P1 and PS.
TEST(MeshFileRun, NamedBoundariesOfTheFileActAsTheSidesTheyLieOn) {
  for (const std::string basis : {"p1_triangles", "powell_sabin"}) {
    SCOPED_TRACE(basis);
    const auto named = custom_on_square(
        {"method.basis=" + basis, "boundary.fixed=bottom", "boundary.roller= right"});
    const auto sides = custom_on_square(
        {"method.basis=" + basis, "boundary.bottom=fixed", "boundary.right=roller"});
    const auto& fixed = named->stepper->state().nodes.fixed;
    ASSERT_EQ(fixed, sides->stepper->state().nodes.fixed);
    EXPECT_GT(std::count(fixed.begin(), fixed.end(), std::uint8_t{3}), 0);
    EXPECT_GT(std::count(fixed.begin(), fixed.end(), std::uint8_t{1}), 0);
    for (int s = 0; s < 5; ++s) {
      named->stepper->step(1e-4);
      sides->stepper->step(1e-4);
    }
    const auto& a = named->stepper->state().particles;
    const auto& b = sides->stepper->state().particles;
    for (std::size_t i = 0; i < a.x.size(); ++i) {
      ASSERT_EQ(a.x[i], b.x[i]) << i;
      ASSERT_EQ(a.stress[i], b.stress[i]) << i;
    }
  }
}

// Named boundaries that cannot carry the condition are refused with the key: an unknown name
// (the mesh's names listed), a roller on a boundary that bends ("top_left") with PS splines, a
// name in both lists, and the keys without a mesh file or in another problem.
TEST(MeshFileRun, NamedBoundariesThatDoNotFitAreRefused) {
  auto refusal = [](const std::function<void()>& f) { return test::message_of(f); };
  const std::string tri = "method.basis=p1_triangles";
  EXPECT_NE(refusal([&] {
              custom_on_square({tri, "boundary.fixed=inlet"});
            })
                .find("has no boundary \"inlet\"; its boundaries: \"7\", \"bottom\", "
                      "\"right\", \"top_left\", \"x+\", \"x-\", \"y+\", \"y-\""),
            std::string::npos);
  EXPECT_NE(refusal([&] {
              custom_on_square({"method.basis=powell_sabin", "boundary.roller=top_left"});
            })
                .find("does not lie on one straight line, so it has no single normal; "
                      "method.basis = \"p1_triangles\" follows a bent boundary"),
            std::string::npos);
  EXPECT_NE(refusal([&] {
              custom_on_square({tri, "boundary.fixed=bottom, right", "boundary.roller=right"});
            }).find("is in boundary.fixed and in boundary.roller"),
            std::string::npos);
  EXPECT_NE(refusal([&] {
              custom_on_square({"method.basis=powell_sabin", "boundary.fixed=top_left"});
            }).find("does not lie on one straight line; Powell-Sabin splines"),
            std::string::npos);
  // A right triangle whose hypotenuse "slope" is a physical group.
  const std::vector<Vec<2>> corners{{0, 0}, {1, 0}, {0, 1}};
  const TriangleMesh half(corners, {{0, 1, 2}}, {}, "half");
  const std::string file = test::write_msh(half, "slope", {}, {{"slope", {{1, 2}}}});
  const std::string custom = std::string(MPM_SOURCE_DIR) + "/examples/custom_plate_2d.toml";
  auto on_half = [&](std::vector<std::string> sets) {
    sets.insert(sets.end(),
                {tri, "grid.mesh=" + file, "grid.cells=2", "grid.min=[0, 0]", "grid.max=[1, 1]",
                 "body.min=[0, 0]", "body.max=[0.3, 0.3]", "boundary.left=free",
                 "boundary.right=free", "boundary.bottom=free", "boundary.top=free"});
    (void)make_problem(Config::load(custom, sets));
  };
  // (An inclined roller is accepted: tests/scheme/test_mesh_boundaries.cpp.)
  EXPECT_EQ(refusal([&] { on_half({"boundary.roller=slope"}); }), "");
  EXPECT_EQ(refusal([&] { on_half({"boundary.fixed=slope"}); }), "");
  std::filesystem::remove(file);
  EXPECT_NE(refusal([&] {
              (void)make_problem(Config::load(custom, {"boundary.fixed=bottom"}));
            }).find("names boundaries of a mesh file (grid.mesh); without one"),
            std::string::npos);
  EXPECT_NE(
      refusal([&] {
        (void)make_problem(Config::load(std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml",
                                        {"boundary.roller=x-"}));
      }).find("key 'boundary.roller' is read by benchmark = \"custom\" only"),
      std::string::npos);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
