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

// A box of cells (the elements a process of a distributed run integrates): its span of the
// linear numbering runs from its first cell to its last, and holds picks its cells out of it,
// against the cells' coordinates one by one.
TEST(Mesh, GridCellBoxSpanHoldsItsCellsAlone) {
  const Grid<3> g(Vec<3>(0.0, 0.0, 0.0), Vec<3>(4.0, 3.0, 5.0), IVec<3>{4, 3, 5});
  CellBox<3> box = g.all_cells();
  box.lo = {1, 0, 2};
  box.hi = {3, 2, 4};
  const auto span = box.span();
  EXPECT_EQ(span[0], g.cell_index(IVec<3>{1, 0, 2}));
  EXPECT_EQ(span[1], g.cell_index(IVec<3>{2, 1, 3}) + 1);
  Index held = 0;
  for (Index e = 0; e < g.num_cells(); ++e) {
    const IVec<3> c = g.cell_coords(e);
    EXPECT_EQ(g.cell_index(c), e);
    const bool inside = c[0] >= 1 && c[0] < 3 && c[1] < 2 && c[2] >= 2 && c[2] < 4;
    EXPECT_EQ(box.holds(e), inside) << e;
    if (inside) {
      EXPECT_GE(e, span[0]);
      EXPECT_LT(e, span[1]);
    }
    held += inside;
  }
  EXPECT_EQ(held, 8);
  EXPECT_FALSE(box.empty());
  EXPECT_EQ(g.all_cells().span(), (std::array<Index, 2>{0, g.num_cells()}));
  box.hi[1] = 0;  // no cells along y
  EXPECT_TRUE(box.empty());
  EXPECT_EQ(box.span(), (std::array<Index, 2>{0, 0}));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
