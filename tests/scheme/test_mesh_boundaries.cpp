// Conditions and loads on the named boundaries of a mesh file (benchmarks/custom.cpp,
// state/simulation.hpp, model/loads.hpp): a roller on an inclined boundary (v . n = 0, which
// couples the velocity components) gives the rotated run of the same roller parallel to an
// axis, for lumped and consistent mass, P1 and Powell-Sabin; rollers that meet at an angle fix
// their corner; a loaded boundary adds exactly its force to the body's momentum; a loaded point
// that leaves the mesh stops the run; input that does not fit is refused with the key.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "../support/msh.hpp"
#include "../support/stepper.hpp"
#include "benchmarks/benchmarks.hpp"
#include "driver/run.hpp"
#include "driver/stepper.hpp"
#include "grid/triangle_mesh.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"
#include "setup/run_settings.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

Mat<2> rotation(double angle) {
  Mat<2> R;
  R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  return R;
}

// The rectangle [0, 1] x [0, 0.5] in 4 x 2 squares of two right triangles each, turned by `angle`
// about the origin, as a Gmsh file whose physical groups "base", "top", "left" and "right" are
// its sides (y = 0, y = 0.5, x = 0, x = 1 before the turn).
std::string turned_rectangle(double angle, const std::string& name) {
  const TriangleMesh m =
      structured_triangles(Vec<2>(0, 0), Vec<2>(1, 0.5), {4, 2}, TrianglePattern::right);
  const Mat<2> R = rotation(angle);
  std::vector<Vec<2>> vertices;
  for (Index v = 0; v < m.num_vertices(); ++v) vertices.push_back(R * m.vertex(v));
  std::vector<TriangleMesh::Triangle> triangles;
  for (Index c = 0; c < m.num_cells(); ++c) triangles.push_back(m.cell_vertices(c));
  std::map<std::string, std::vector<TriangleMesh::Edge>> sides{{"base", m.boundary("y-").edges},
                                                               {"top", m.boundary("y+").edges},
                                                               {"left", m.boundary("x-").edges},
                                                               {"right", m.boundary("x+").edges}};
  return test::write_msh(TriangleMesh(vertices, triangles, {}, name), name, {}, sides);
}

std::string vec(const Vec<2>& v) {
  return fmt::format("[\"{:.17g}\", \"{:.17g}\"]", v[0], v[1]);
}

// A neo-Hookean body filling the mesh file (12 particles per triangle), free grid sides, the
// settings `sets` added.
std::unique_ptr<test::PlateRun> on_mesh(const std::string& file, std::vector<std::string> sets) {
  const std::string text = fmt::format(R"(benchmark = "custom"
[grid]
dimension = 2
cells = 4
mesh = "{}"
[particles]
per_triangle = 12
[time]
dt = 1e-4
end = 0.1
[material]
model = "neo_hookean"
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
  return test::run_2d(Config::parse(text, "mesh_boundaries.toml", sets));
}

// The same body on the rectangle and on the rectangle turned by 30 degrees, with its base on a
// roller, gravity and initial velocity turned alike, and a pressure on its top: the turned run's
// base roller is v . n = 0 along an inclined line (the coupled consistent system, direct or cg, or
// the projection of the lumped solve), the other's the y component alone; x, v and the stress of
// the turned run are those of the first turned, to round-off, after 10 steps.
TEST(MeshBoundaries, AnInclinedRollerGivesTheTurnedRunOfAnAxisParallelOne) {
  const double angle = M_PI / 6.0;
  const Mat<2> R = rotation(angle);
  const std::string flat = turned_rectangle(0.0, "flat"), turned = turned_rectangle(angle, "turn");
  for (const std::string basis : {"p1_triangles", "powell_sabin"})
    for (const std::string mass : {"lumped", "consistent", "consistent cg"}) {
      SCOPED_TRACE(basis + " " + mass);
      const bool cg = mass == "consistent cg";
      auto run = [&](const std::string& file, const Mat<2>& Q) {
        return on_mesh(file,
                       {"method.basis=" + basis, "method.mass=" + mass.substr(0, 10),
                        std::string("method.mass_solver=") + (cg ? "cg" : "direct"),
                        // (cg: a residual near round-off, so that the bounds below hold)
                        std::string("method.mass_solver_tolerance=") + (cg ? "1e-14" : "1e-12"),
                        "boundary.roller=base", "boundary.loaded=top", "pressure.loaded=1e4",
                        "loading.body_force=" + vec(Q * Vec<2>(0.0, -10.0)),
                        "initial.velocity=" + vec(Q * Vec<2>(0.4, 0.0))});
      };
      auto a = run(flat, Mat<2>::Identity());
      auto b = run(turned, R);
      EXPECT_TRUE(a->stepper->state().nodes.projected.empty());
      const auto& proj = b->stepper->state().nodes.projected;
      ASSERT_FALSE(proj.empty());
      for (int s = 0; s < 10; ++s) {
        a->stepper->step(1e-4);
        b->stepper->step(1e-4);
      }
      const auto& pa = a->stepper->state().particles;
      const auto& pb = b->stepper->state().particles;
      ASSERT_EQ(pa.x.size(), pb.x.size());
      double vmax = 0.0, smax = 0.0;
      for (std::size_t i = 0; i < pa.x.size(); ++i) {
        vmax = std::max(vmax, pa.v[i].norm());
        smax = std::max(smax, pa.stress[i].norm());
      }
      ASSERT_GT(smax, 1e2);  // the load and gravity did act
      for (std::size_t i = 0; i < pa.x.size(); ++i) {
        ASSERT_LT((R * pa.x[i] - pb.x[i]).norm(), 1e-13) << i;
        ASSERT_LT((R * pa.v[i] - pb.v[i]).norm(), 1e-11 * vmax) << i;
        ASSERT_LT((R * pa.stress[i] * R.transpose() - pb.stress[i]).norm(), 1e-10 * smax) << i;
      }
      // The grid velocity of the base's DOFs has no normal component.
      const Vec<2> n = R * Vec<2>(0.0, -1.0);
      const auto& v = b->stepper->state().nodes.velocity;
      for (const auto& e : proj) {
        EXPECT_LT((e.free * n).norm(), 1e-15);
        EXPECT_LT(std::abs(v[static_cast<std::size_t>(e.dof)].dot(n)), 1e-15 * vmax);
      }
    }
  std::filesystem::remove(flat);
  std::filesystem::remove(turned);
}

// The ring 0.5 <= r <= 1 in 3 x 32 cells of the polar grid, each cut into two triangles, as a
// Gmsh file whose physical groups "outer" and "inner" are its circles. Vertex (i, j) (radius
// index i, angle index j) is number 32 i + j.
std::string ring_mesh(const std::string& name) {
  const int nr = 3, nt = 32;
  std::vector<Vec<2>> vertices;
  for (int i = 0; i <= nr; ++i)
    for (int j = 0; j < nt; ++j) {
      const double r = 0.5 + 0.5 * i / nr, a = 2.0 * M_PI * j / nt;
      vertices.emplace_back(r * std::cos(a), r * std::sin(a));
    }
  auto at = [&](int i, int j) { return static_cast<Index>(i * nt + (j % nt)); };
  std::vector<TriangleMesh::Triangle> triangles;
  std::map<std::string, std::vector<TriangleMesh::Edge>> circles;
  for (int j = 0; j < nt; ++j) {
    for (int i = 0; i < nr; ++i) {
      triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
    circles["inner"].push_back({at(0, j), at(0, j + 1)});
    circles["outer"].push_back({at(nr, j), at(nr, j + 1)});
  }
  return test::write_msh(TriangleMesh(vertices, triangles, {}, name), name, {}, circles);
}

// A roller along a bent boundary (P1): each vertex of the ring's outer circle gets the normal of
// the chord between its neighbours, here the radius, so its admissible velocity is the tangent.
// A rigid rotation v = w (-y, x) then passes the wall untouched: with consistent mass P1 carries
// the linear field exactly, and after a step the grid velocity is w x at every vertex to
// round-off (the coupled consistent system with per-vertex normals), where a fixed wall stops the
// outer vertices.
TEST(MeshBoundaries, ARollerFollowsABentBoundaryWithANormalPerVertex) {
  const std::string file = ring_mesh("ring");
  const double w = 2.0;
  auto run = [&](const std::string& wall) {
    return on_mesh(
        file, {"method.basis=p1_triangles", "method.mass=consistent", "particles.per_triangle=6",
               wall, fmt::format("initial.velocity=[\"-{0}*y\", \"{0}*x\"]", w)});
  };
  auto slip = run("boundary.roller=outer");
  const auto& proj = slip->stepper->state().nodes.projected;
  // The four vertices on the axes have axis-parallel normals, kept as fixed bits.
  ASSERT_EQ(proj.size(), 28u);
  const auto& mesh = *slip->pb.mesh;
  const auto& bits = slip->stepper->state().nodes.fixed;
  for (int j = 0; j < 32; j += 8) EXPECT_EQ(bits[static_cast<std::size_t>(96 + j)], j % 16 ? 2 : 1);
  for (const auto& e : proj) {
    const Vec<2> x = mesh.vertex(e.dof);
    EXPECT_NEAR(x.norm(), 1.0, 1e-14);
    const Vec<2> t = Vec<2>(-x[1], x[0]).normalized();
    EXPECT_LT((e.free - t * t.transpose()).norm(), 1e-14) << e.dof;
  }
  auto fixed = run("boundary.fixed=outer");
  slip->stepper->step(1e-4);
  fixed->stepper->step(1e-4);
  const auto& v = slip->stepper->state().nodes.velocity;
  const auto& vf = fixed->stepper->state().nodes.velocity;
  for (Index i = 0; i < mesh.num_vertices(); ++i) {
    const Vec<2> x = mesh.vertex(i), rigid(-w * x[1], w * x[0]);
    EXPECT_LT((v[static_cast<std::size_t>(i)] - rigid).norm(), 1e-12 * w) << i;
    if (i >= 3 * 32) {
      EXPECT_EQ(vf[static_cast<std::size_t>(i)], Vec<2>::Zero()) << i;
    }
  }
  // PS splines need a straight boundary for a roller.
  EXPECT_NE(test::message_of([&] {
              (void)on_mesh(file, {"method.basis=powell_sabin", "boundary.roller=outer"});
            }).find("does not lie on one straight line, so it has no single normal"),
            std::string::npos);
  std::filesystem::remove(file);
}

// Each DOF's constraint is the span of its conditions: two inclined rollers that meet at an
// angle fix their common corner in both components, an inclined roller and one parallel to an
// axis likewise, and the other DOFs of an inclined roller keep the tangential component.
TEST(MeshBoundaries, RollersMeetingAtAnAngleFixTheirCorner) {
  const std::string file = turned_rectangle(0.3, "corner");
  auto r = on_mesh(file, {"method.basis=p1_triangles", "boundary.roller=base, left"});
  const auto& nd = r->stepper->state().nodes;
  // Vertex 0 is the corner of base and left; base has 5 vertices, left 3.
  EXPECT_EQ(nd.fixed[0], 3);
  EXPECT_EQ(nd.projected.size(), 4u + 2u);
  for (const auto& e : nd.projected) {
    EXPECT_NE(e.dof, 0);
    EXPECT_NEAR(e.free.trace(), 1.0, 1e-14);  // a line of admissible velocities
  }
  std::filesystem::remove(file);
  // The right triangle (0, 0), (1, 0), (0, 1): the hypotenuse "slope" meets "bottom" (y = 0)
  // at vertex 1.
  const TriangleMesh half({{0, 0}, {1, 0}, {0, 1}}, {{0, 1, 2}}, {}, "half");
  const std::string hfile =
      test::write_msh(half, "half", {}, {{"slope", {{1, 2}}}, {"bottom", {{0, 1}}}});
  auto h = on_mesh(hfile, {"method.basis=p1_triangles", "boundary.roller=slope, bottom",
                           "particles.per_triangle=3"});
  const auto& hn = h->stepper->state().nodes;
  EXPECT_EQ(hn.fixed[0], 2);  // bottom only: the y component
  EXPECT_EQ(hn.fixed[1], 3);  // bottom and slope
  ASSERT_EQ(hn.projected.size(), 1u);
  EXPECT_EQ(hn.projected[0].dof, 2);
  const Vec<2> t = Vec<2>(-1.0, 1.0).normalized();  // along the slope
  EXPECT_LT((hn.projected[0].free - t * t.transpose()).norm(), 1e-15);
  std::filesystem::remove(hfile);
  // A bent roller turning by 90 degrees at a corner: the unit square's "top_left" (its top and
  // left sides, tests/data/meshes/square_v41.msh) fixes the corner (0, 1) and keeps the
  // tangential component elsewhere.
  const std::string square = std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/square_v41.msh";
  auto sq = on_mesh(square, {"method.basis=p1_triangles", "boundary.roller=top_left"});
  const auto& sn = sq->stepper->state().nodes;
  const auto& sm = *sq->pb.mesh;
  int corners = 0;
  for (Index v : sm.boundary_vertices("top_left")) {
    const Vec<2> x = sm.vertex(v);
    if ((x - Vec<2>(0, 1)).norm() < 1e-12) {
      EXPECT_EQ(sn.fixed[static_cast<std::size_t>(v)], 3);
      ++corners;
    } else {  // a side parallel to an axis: one component, as bits
      EXPECT_EQ(sn.fixed[static_cast<std::size_t>(v)], std::abs(x[0]) < 1e-12 ? 1 : 2) << v;
    }
  }
  EXPECT_EQ(corners, 1);
  EXPECT_TRUE(sn.projected.empty());
}

// A free body without gravity, a nominal traction on its base and a pressure on its top (the
// turned rectangle, so the pressure's direction is the turned normal): with lumped mass the
// grid forces of every step sum to the internal forces (zero by the partition of unity) plus the
// load, so the momentum after s steps is s dt F with F = tau |base| - p |top| n_top, to
// round-off, whatever the deformation.
TEST(MeshBoundaries, ALoadedBoundaryAddsItsForceToTheMomentum) {
  const double angle = 0.4;
  const Mat<2> R = rotation(angle);
  const std::string file = turned_rectangle(angle, "loaded");
  const Vec<2> tau(3e4, -1e4);
  const double p = 5e4;
  for (const std::string basis : {"p1_triangles", "powell_sabin"}) {
    SCOPED_TRACE(basis);
    auto r = on_mesh(file, {"method.basis=" + basis, "boundary.loaded=base, top",
                            fmt::format("traction.loaded=[\"{}\", \"{}\"]", tau[0], tau[1]),
                            fmt::format("pressure.loaded={}", p)});
    // Both boundaries carry the traction; the pressure pushes the base up, the top down.
    const Vec<2> n_top = R * Vec<2>(0, 1), n_base = R * Vec<2>(0, -1);
    const Vec<2> F = 2.0 * tau - p * 1.0 * n_top - p * 1.0 * n_base;
    const double dt = 1e-4;
    const int steps = 30;
    for (int s = 0; s < steps; ++s) r->stepper->step(dt);
    const auto& P = r->stepper->state().particles;
    Vec<2> momentum = Vec<2>::Zero();
    double mass = 0.0;
    for (std::size_t i = 0; i < P.x.size(); ++i) {
      momentum += P.mass[i] * P.v[i];
      mass += P.mass[i];
    }
    EXPECT_NEAR(mass, 1000.0 * 0.5, 1e-10);
    const Vec<2> expected = steps * dt * F;
    EXPECT_LT((momentum - expected).norm(), 1e-11 * expected.norm())
        << momentum.transpose() << " against " << expected.transpose();
  }
  std::filesystem::remove(file);
}

// examples/incline_pressure_2d.toml: a block on a frictionless 30-degree incline (a roller along
// the inclined base) under a pressure on its top raised smoothly over about nine periods of its
// first mode, on an unstructured mesh, against the quasi-static uniaxial solution
// sigma = -p n n^T (exact.* keys; top displacement about 4.5e-4 m). The bounds are about twice
// the errors measured when the example was written (stress: P1 0.37 % lumped and 0.41 %
// consistent, PS 6.9 %, the particles' quadrature error of PS: docs/verification.md;
// displacement at most 1.4e-6 m).
TEST(MeshBoundaries, ABlockPressedOnAnInclineMatchesTheQuasiStaticSolution) {
  const std::string example = std::string(MPM_SOURCE_DIR) + "/examples/incline_pressure_2d.toml";
  for (const auto& [basis, mass, bound] :
       {std::tuple{"p1_triangles", "lumped", 0.01}, std::tuple{"p1_triangles", "consistent", 0.01},
        std::tuple{"powell_sabin", "lumped", 0.15}}) {
    SCOPED_TRACE(std::string(basis) + " " + mass);
    const auto r = run(Config::load(example, {std::string("method.basis=") + basis,
                                              std::string("method.mass=") + mass, "output.frames=0",
                                              "output.csv=false", "output.vtk=false"}),
                       RunOptions{});
    ASSERT_EQ(r.exit_code, 0) << r.failure;
    ASSERT_TRUE(r.errors.stress_rel_l2 && r.errors.displacement_rms);
    std::printf("incline, %s %s: stress rel L2 %.4g, displacement RMS %.4g m\n", basis, mass,
                *r.errors.stress_rel_l2, *r.errors.displacement_rms);
    EXPECT_LT(*r.errors.stress_rel_l2, bound);
    EXPECT_LT(*r.errors.displacement_rms, 3e-6);
    EXPECT_LT(r.diag.max_rel_mass_error, 1e-12);
  }
}

// A pull on the top of a body that fills its mesh moves the loaded points off the mesh at once:
// the run stops naming the particle and the point instead of dropping the load.
TEST(MeshBoundaries, ALoadedPointThatLeavesTheMeshStopsTheRun) {
  const std::string file = turned_rectangle(0.2, "pull");
  auto r = on_mesh(file, {"method.basis=p1_triangles", "boundary.loaded=top",
                          "pressure.loaded=-1e5", "boundary.roller=base"});
  const std::string what = test::message_of([&] {
    for (int s = 0; s < 5; ++s) r->stepper->step(1e-4);
  });
  EXPECT_NE(what.find("the loaded face of the body (particle"), std::string::npos) << what;
  EXPECT_NE(what.find("left the mesh (no triangle holds it)"), std::string::npos) << what;
  std::filesystem::remove(file);
}

// A named line through the mesh's inside has no outward normal: a load on it is refused (a
// pressure there gave a net force from nothing).
TEST(MeshBoundaries, ALoadOnAnInteriorLineIsRefused) {
  const TriangleMesh m =
      structured_triangles(Vec<2>(0, 0), Vec<2>(1, 0.5), {4, 2}, TrianglePattern::right);
  // The vertical line x = 0.5 (vertex columns: 5 per row), between the triangles either side.
  std::vector<TriangleMesh::Edge> middle = {{2, 7}, {7, 12}};
  const std::string file =
      test::write_msh(m, "interior", {}, {{"middle", middle}, {"top", m.boundary("y+").edges}});
  const auto why = test::message_of([&] {
    (void)on_mesh(file,
                  {"method.basis=p1_triangles", "boundary.loaded=middle", "pressure.loaded=1"});
  });
  EXPECT_NE(why.find("boundary \"middle\""), std::string::npos) << why;
  EXPECT_NE(why.find("runs through the mesh's inside"), std::string::npos) << why;
  EXPECT_NE(why.find("boundary.loaded"), std::string::npos) << why;
  // The top is on the outer boundary: loaded as before.
  EXPECT_NO_THROW((void)on_mesh(
      file, {"method.basis=p1_triangles", "boundary.loaded=top", "pressure.loaded=1"}));
  std::filesystem::remove(file);
}

// Loads that do not fit are refused with the key.
TEST(MeshBoundaries, LoadsThatDoNotFitAreRefused) {
  const std::string file = turned_rectangle(0.0, "refuse");
  const std::string tri = "method.basis=p1_triangles";
  auto refusal = [&](std::vector<std::string> sets) {
    return test::message_of([&] { (void)on_mesh(file, std::move(sets)); });
  };
  EXPECT_NE(refusal({tri, "boundary.loaded=roof", "pressure.loaded=1"})
                .find("boundary.loaded: mesh file \"" + file +
                      "\" has no boundary \"roof\"; its boundaries: \"base\", \"left\""),
            std::string::npos);
  EXPECT_NE(refusal({tri, "pressure.loaded=1"})
                .find("pressure.loaded loads the boundaries that boundary.loaded names, and it "
                      "names none"),
            std::string::npos);
  EXPECT_NE(refusal({tri, "boundary.loaded=top"})
                .find("traction.loaded and pressure.loaded are both zero"),
            std::string::npos);
  EXPECT_NE(refusal({tri, "boundary.loaded=top", "traction.loaded=[\"x\", \"0\"]"})
                .find("may depend on t only"),
            std::string::npos);
  // A load that is not a finite number: refused at set-up when it is not at t = 0, and the run
  // stops naming the key at the first step where it is not (exit_code::kNonFinite).
  EXPECT_NE(refusal({tri, "boundary.loaded=top", "pressure.loaded=1/0"})
                .find("the load of key 'pressure.loaded' is not a finite number at t = 0"),
            std::string::npos);
  EXPECT_NE(refusal({tri, "boundary.loaded=top", "traction.loaded=[\"1e308*1e308\", \"0\"]"})
                .find("the load of key 'traction.loaded' is not a finite number at t = 0"),
            std::string::npos);
  try {
    auto r = on_mesh(file, {tri, "boundary.loaded=top", "pressure.loaded=t > 2.5e-4 ? 1/0 : 1"});
    auto& sim = r->stepper->state();
    for (int s = 0; s < 5; ++s) {
      r->stepper->step(1e-4);
      sim.step = s + 1;
      sim.time = 1e-4 * (s + 1);
    }
    ADD_FAILURE() << "a load that became infinite was applied";
  } catch (const RunError& e) {
    EXPECT_EQ(e.exit_code(), exit_code::kNonFinite);
    EXPECT_NE(std::string(e.what()).find("key 'pressure.loaded' is not a finite number at t = "),
              std::string::npos)
        << e.what();
  }
  // A body that does not reach the loaded boundary.
  EXPECT_NE(refusal({tri, "boundary.loaded=top", "pressure.loaded=1", "particles.per_triangle=0",
                     "particles.per_cell=2", "grid.min=[0, 0]", "grid.max=[1, 0.5]",
                     "body.min=[0, 0]", "body.max=[1, 0.25]"})
                .find("holds no particle; a loaded boundary needs the body along it"),
            std::string::npos);
  std::filesystem::remove(file);
  // Without a mesh file, and in a problem that sets its own conditions.
  const std::string custom = std::string(MPM_SOURCE_DIR) + "/examples/custom_plate_2d.toml";
  EXPECT_NE(
      test::message_of([&] {
        (void)make_problem(Config::load(custom, {"boundary.loaded=top", "pressure.loaded=1"}));
      }).find("boundary.loaded names boundaries of a mesh file (grid.mesh)"),
      std::string::npos);
  const std::string plate = std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml";
  EXPECT_NE(test::message_of([&] {
              (void)make_problem(Config::load(plate, {"pressure.loaded=1"}));
            }).find("key 'pressure.loaded' is read by benchmark = \"custom\" only"),
            std::string::npos);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
