// Gmsh meshes through Gmsh's library (setup/gmsh_mesh.hpp): the same mesh in MSH 4.1, 2.2 and
// 4.1 binary, its named and unnamed boundary groups, and the refusals with their reasons
// (tests/data/meshes/README.md says how the files were made).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "setup/gmsh_mesh.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

std::string mesh_path(const std::string& name) {
  return std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

std::string refusal(const std::string& path) {
  try {
    read_gmsh_mesh(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(GmshMesh, TheSameSquareFromEveryFormat) {
  const auto a = read_gmsh_mesh(mesh_path("square_v41.msh"));
  double area = 0.0;
  for (Index c = 0; c < a.num_cells(); ++c) area += a.cell_volume(c);
  EXPECT_NEAR(area, 1.0, 1e-14);
  EXPECT_GT(a.num_cells(), 20);
  // Euler's formula for a triangulated disc: V - E + F = 1 with 3F = 2E - (boundary edges).
  const auto boundary_edges =
      static_cast<Index>(a.boundary("bottom").edges.size() + a.boundary("right").edges.size() +
                         a.boundary("top_left").edges.size());
  const Index edges = (3 * a.num_cells() + boundary_edges) / 2;
  EXPECT_EQ(a.num_vertices() - edges + a.num_cells(), 1);
  EXPECT_EQ(a.boundary_names(), (std::vector<std::string>{"7", "bottom", "right", "top_left"}));
  for (Index v : a.boundary_vertices("bottom")) EXPECT_EQ(a.vertex(v)[1], 0.0);
  for (Index v : a.boundary_vertices("right")) EXPECT_EQ(a.vertex(v)[0], 1.0);
  for (Index v : a.boundary_vertices("7")) EXPECT_EQ(a.vertex(v)[0], 0.0);  // the unnamed group
  EXPECT_EQ(a.boundary_vertices("bottom").size(), 5u);  // mesh size 0.25 on a unit side
  // "top_left" joins two sides: both corners (0, 1) and (1, 1) and the ends (0, 0), (1, 1).
  EXPECT_EQ(a.boundary_vertices("top_left").size(), 9u);
  for (const std::string other : {"square_v22.msh", "square_v41_binary.msh"}) {
    const auto b = read_gmsh_mesh(mesh_path(other));
    ASSERT_EQ(b.num_vertices(), a.num_vertices()) << other;
    ASSERT_EQ(b.num_cells(), a.num_cells()) << other;
    // ASCII files hold 16 significant digits, binary ones every bit: the same to round-off.
    for (Index v = 0; v < a.num_vertices(); ++v)
      EXPECT_LE((b.vertex(v) - a.vertex(v)).norm(), 1e-15) << other;
    for (Index c = 0; c < a.num_cells(); ++c)
      EXPECT_EQ(b.cell_vertices(c), a.cell_vertices(c)) << other;
    EXPECT_EQ(b.boundary_names(), a.boundary_names()) << other;
    for (const auto& name : a.boundary_names())
      EXPECT_EQ(b.boundary_vertices(name), a.boundary_vertices(name)) << other << " " << name;
  }
  // Point location on the read mesh: the centre lies in some triangle, a point outside in none.
  EXPECT_GE(a.cell_index(Vec<2>(0.5, 0.5)), 0);
  EXPECT_EQ(a.cell_index(Vec<2>(1.01, 0.5)), -1);
}

TEST(GmshMesh, RefusalsNameTheFileAndTheReason) {
  const std::string missing = mesh_path("no_such_mesh.msh");
  EXPECT_EQ(refusal(missing), "mesh file \"" + missing + "\": cannot be opened for reading");
  const auto quads = refusal(mesh_path("square_quads.msh"));
  EXPECT_NE(quads.find("no 3-node triangles"), std::string::npos) << quads;
  EXPECT_NE(quads.find("Quadrilateral 4 (Gmsh type 3)"), std::string::npos) << quads;
  const auto order2 = refusal(mesh_path("square_order2.msh"));
  EXPECT_NE(order2.find("Triangle 6 (Gmsh type 9)"), std::string::npos) << order2;
  EXPECT_NE(order2.find("Mesh.ElementOrder = 1"), std::string::npos) << order2;
  // Not a mesh: Gmsh's parser message, with the file named; the next read still works.
  const std::string garbage = mesh_path("../bad_choice.toml");
  const auto bad = refusal(garbage);
  EXPECT_EQ(bad.rfind("mesh file \"" + garbage + "\": Gmsh could not read it", 0), 0u) << bad;
  EXPECT_GT(read_gmsh_mesh(mesh_path("square_v22.msh")).num_cells(), 0);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
