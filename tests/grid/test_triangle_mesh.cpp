// The triangular mesh (grid/triangle_mesh.hpp): structured triangulations, validation of bad
// input, and point location through the bucket grid checked against a search over every
// triangle on a randomly distorted mesh.
#include <gtest/gtest.h>

#include <random>

#include "grid/triangle_mesh.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

double total_area(const TriangleMesh& m) {
  double a = 0.0;
  for (Index c = 0; c < m.num_cells(); ++c) a += m.cell_volume(c);
  return a;
}

// Every triangle containing x (barycentric coordinates >= -tol), by brute force.
std::vector<Index> containing(const TriangleMesh& m, const Vec<2>& x, double tol) {
  std::vector<Index> out;
  for (Index c = 0; c < m.num_cells(); ++c) {
    const auto l = m.barycentric(c, x);
    if (l[0] >= -tol && l[1] >= -tol && l[2] >= -tol) out.push_back(c);
  }
  return out;
}

TEST(TriangleMesh, StructuredPatternsCountsAreasAndBoundaries) {
  const Vec<2> lo(-1.0, 0.5), hi(2.0, 1.5);
  for (auto pattern : {TrianglePattern::right, TrianglePattern::criss_cross}) {
    const auto m = structured_triangles(lo, hi, {6, 4}, pattern);
    const bool right = pattern == TrianglePattern::right;
    EXPECT_EQ(m.num_cells(), right ? 48 : 96);
    EXPECT_EQ(m.num_vertices(), right ? 35 : 35 + 24);
    EXPECT_NEAR(total_area(m), 3.0, 1e-13);
    EXPECT_EQ(m.boundary_names(), (std::vector<std::string>{"x+", "x-", "y+", "y-"}));
    EXPECT_EQ(m.boundary_vertices("y-").size(), 7u);
    EXPECT_EQ(m.boundary("x+").edges.size(), 4u);
    for (Index v : m.boundary_vertices("x-")) EXPECT_EQ(m.vertex(v)[0], -1.0);
    for (Index v : m.boundary_vertices("y+")) EXPECT_EQ(m.vertex(v)[1], 1.5);
    // Every triangle counter-clockwise with positive area (the constructor's orientation).
    for (Index c = 0; c < m.num_cells(); ++c) {
      const auto& t = m.cell_vertices(c);
      const Vec<2> a = m.vertex(t[1]) - m.vertex(t[0]), b = m.vertex(t[2]) - m.vertex(t[0]);
      EXPECT_GT(a[0] * b[1] - a[1] * b[0], 0.0);
    }
  }
}

TEST(TriangleMesh, BadInputIsRefusedWithTheReason) {
  const std::vector<Vec<2>> v{{0, 0}, {1, 0}, {0, 1}, {2, 0}};
  auto message = [&](std::vector<TriangleMesh::Triangle> t,
                     std::map<std::string, std::vector<TriangleMesh::Edge>> b = {}) {
    try {
      TriangleMesh m(v, std::move(t), std::move(b), "test mesh");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message({{0, 1, 5}}).find("triangle 0 refers to vertex 5, outside 0..3"),
            std::string::npos);
  EXPECT_NE(message({{0, 1, 3}}).find("triangle 0 (vertices 0, 1, 3) has zero area"),
            std::string::npos);
  EXPECT_NE(message({{0, 1, 2}}, {{"wall", {{0, 9}}}}).find("boundary \"wall\" refers to vertex 9"),
            std::string::npos);
  EXPECT_NE(message({}).find("no triangles"), std::string::npos);
  // Vertex 3 = (2, 0) moved to (-0.5, 0.5): triangle (1, 3, 2) folds over (0, 1, 2).
  const std::vector<Vec<2>> folded{{0, 0}, {1, 0}, {0, 1}, {-0.5, 0.5}};
  try {
    TriangleMesh m(folded, {{0, 1, 2}, {1, 3, 2}}, {}, "test mesh");
    ADD_FAILURE() << "a folded mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("triangles 0 and 1 lie on the same side of their common "
                                         "edge (1, 2)"),
              std::string::npos)
        << e.what();
  }
  // A clockwise triangle is turned around.
  TriangleMesh m(v, {{0, 2, 1}}, {{"wall", {{0, 1}}}}, "test mesh");
  EXPECT_EQ(m.cell_vertices(0), (TriangleMesh::Triangle{0, 1, 2}));
  EXPECT_DOUBLE_EQ(m.cell_volume(0), 0.5);
  try {
    m.boundary_vertices("floor");
    ADD_FAILURE() << "an unknown boundary name was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("no boundary named \"floor\"; its boundaries are \"wall\""),
        std::string::npos)
        << e.what();
  }
}

TEST(TriangleMesh, PointLocationMatchesBruteForceOnADistortedMesh) {
  // Criss-cross mesh of [0, 2] x [0, 1] with every interior vertex moved by up to 0.2 h in each
  // direction (a centre vertex lies h/2 from its rectangle's sides: the triangles stay valid).
  const auto base =
      structured_triangles({0.0, 0.0}, {2.0, 1.0}, {16, 8}, TrianglePattern::criss_cross);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> shift(-0.2 * 0.125, 0.2 * 0.125);
  std::vector<Vec<2>> v;
  for (Index i = 0; i < base.num_vertices(); ++i) {
    Vec<2> x = base.vertex(i);
    const bool boundary = x[0] == 0.0 || x[0] == 2.0 || x[1] == 0.0 || x[1] == 1.0;
    if (!boundary) x += Vec<2>(shift(rng), shift(rng));
    v.push_back(x);
  }
  std::vector<TriangleMesh::Triangle> t;
  for (Index c = 0; c < base.num_cells(); ++c) t.push_back(base.cell_vertices(c));
  const TriangleMesh m(v, t, {}, "distorted");
  EXPECT_NEAR(total_area(m), 2.0, 1e-13);
  std::uniform_real_distribution<double> ux(-0.1, 2.1), uy(-0.1, 1.1);
  int inside = 0;
  for (int k = 0; k < 5000; ++k) {
    // Every fifth point is a vertex or an edge midpoint (shared by several triangles).
    Vec<2> x(ux(rng), uy(rng));
    if (k % 5 == 0) {
      const auto& tri =
          m.cell_vertices(static_cast<Index>(rng() % static_cast<unsigned>(m.num_cells())));
      x = k % 10 == 0 ? m.vertex(tri[0]) : Vec<2>(0.5 * (m.vertex(tri[0]) + m.vertex(tri[1])));
    }
    const auto all = containing(m, x, 1e-12);
    const Index c = m.cell_index(x);
    if (all.empty()) {
      EXPECT_EQ(c, -1) << x.transpose();
    } else {
      ++inside;
      EXPECT_EQ(c, all.front()) << x.transpose();  // the lowest-numbered containing triangle
    }
  }
  EXPECT_GT(inside, 3750);
  EXPECT_EQ(m.cell_index(Vec<2>(std::nan(""), 0.5)), -1);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// The smallest altitude is the CFL length of the structured patterns' stability factors
// (triangle_stability_factor: altitude over h), here on cells of side 0.25.
TEST(TriangleMesh, SmallestAltitudeIsTheStructuredStabilityLength) {
  for (auto pattern : {TrianglePattern::right, TrianglePattern::criss_cross}) {
    const auto m = structured_triangles(Vec<2>(0, 0), Vec<2>(1, 1), {4, 4}, pattern);
    EXPECT_NEAR(m.min_altitude(), 0.25 * triangle_stability_factor(pattern), 1e-15);
  }
}

// A mesh that names other boundaries gets the sides of its bounding box as the grid's: the
// boundary edges on x = lo, ..., with their vertices; a side the mesh only touches at a vertex
// (a diamond) is not added, and a name the mesh already has is kept.
TEST(TriangleMesh, BoxSidesAreTheBoundaryEdgesOnTheBoundingBox) {
  // The unit square as four triangles around its centre, with one named side.
  const std::vector<Vec<2>> v{{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5}};
  const std::vector<TriangleMesh::Triangle> t{{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  const TriangleMesh square(v, t, {{"inlet", {{3, 0}}}}, "square");
  const TriangleMesh s = with_box_sides(square);
  EXPECT_EQ(s.boundary_names(), (std::vector<std::string>{"inlet", "x+", "x-", "y+", "y-"}));
  EXPECT_EQ(s.boundary_vertices("x+"), (std::vector<Index>{1, 2}));
  EXPECT_EQ(s.boundary_vertices("x-"), (std::vector<Index>{0, 3}));
  EXPECT_EQ(s.boundary_vertices("y-"), (std::vector<Index>{0, 1}));
  EXPECT_EQ(s.boundary_vertices("y+"), (std::vector<Index>{2, 3}));
  EXPECT_EQ(s.boundary("x-").edges.size(), 1u);
  EXPECT_EQ(s.source(), "square");
  // A boundary named like a side would take its place in the conditions on sides: refused.
  const TriangleMesh named(v, t, {{"x+", {{1, 2}}}}, "square");
  EXPECT_THROW(with_box_sides(named), InputError);
  // The diamond touches each side of its box at one vertex only.
  const std::vector<Vec<2>> d{{0.5, 0}, {1, 0.5}, {0.5, 1}, {0, 0.5}, {0.5, 0.5}};
  const TriangleMesh diamond = with_box_sides(TriangleMesh(d, t, {}, "diamond"));
  EXPECT_TRUE(diamond.boundary_names().empty());
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
