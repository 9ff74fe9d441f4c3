// The mesh interface of the uniform grid (grid/mesh.hpp): vertices, the cell containing a point
// and its vertices, named boundary vertex sets.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "grid/grid.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(Mesh, GridCellVerticesBracketEveryPointInside) {
  const Grid<2> g(Vec<2>(-1.0, 0.5), Vec<2>(2.0, 2.5), IVec<2>{6, 4});
  ASSERT_EQ(g.num_vertices(), 7 * 5);
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> ux(-1.0, 2.0), uy(0.5, 2.5);
  for (int k = 0; k < 500; ++k) {
    const Vec<2> x(ux(gen), uy(gen));
    ASSERT_TRUE(g.inside(x));
    const auto v = g.cell_vertices(g.cell_index(x));
    // Lower-left first, x fastest: v[0] <= x <= v[3] componentwise, the others are the corners.
    const Vec<2> lo = g.vertex(v[0]), hi = g.vertex(v[3]);
    EXPECT_LE(lo[0], x[0]);
    EXPECT_LE(lo[1], x[1]);
    EXPECT_GE(hi[0], x[0]);
    EXPECT_GE(hi[1], x[1]);
    EXPECT_NEAR(hi[0] - lo[0], g.h[0], 1e-14);
    EXPECT_NEAR(hi[1] - lo[1], g.h[1], 1e-14);
    EXPECT_EQ(g.vertex(v[1])[0], hi[0]);
    EXPECT_EQ(g.vertex(v[1])[1], lo[1]);
    EXPECT_EQ(g.vertex(v[2])[0], lo[0]);
    EXPECT_EQ(g.vertex(v[2])[1], hi[1]);
  }
  EXPECT_DOUBLE_EQ(g.cell_volume(3), 0.5 * 0.5);
}

TEST(Mesh, GridBoundaryVertexSetsByName) {
  const Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(3.0, 2.0), IVec<2>{3, 2});
  EXPECT_EQ(g.boundary_names(), (std::vector<std::string>{"x-", "x+", "y-", "y+"}));
  auto on = [&](std::string_view name, int d, double value) {
    const auto ids = g.boundary_vertices(name);
    std::size_t expected = 0;
    for (Index i = 0; i < g.num_vertices(); ++i) expected += g.vertex(i)[d] == value ? 1 : 0;
    EXPECT_EQ(ids.size(), expected) << name;
    for (Index i : ids) EXPECT_EQ(g.vertex(i)[d], value) << name;
  };
  on("x-", 0, 0.0);
  on("x+", 0, 3.0);
  on("y-", 1, 0.0);
  on("y+", 1, 2.0);
  try {
    (void)g.boundary_vertices("z+");
    FAIL() << "z+ accepted on a 2D grid";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("\"y+\""), std::string::npos) << e.what();
  }
  const Grid<1> g1(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{4});
  EXPECT_EQ(g1.boundary_vertices("x+"), std::vector<Index>{4});
  EXPECT_EQ(g1.boundary_vertices("x-"), std::vector<Index>{0});
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
