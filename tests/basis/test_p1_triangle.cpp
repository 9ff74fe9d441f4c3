// P1 on triangles (basis/p1_triangle.hpp): partition of unity, zero gradient sum, linear
// reproduction of values and gradients, and C0 continuity across every interior edge, on a
// criss-cross mesh and on a Gmsh mesh.
#include <gtest/gtest.h>

#include <random>

#include "basis/p1_triangle.hpp"
#include "setup/gmsh_mesh.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

void check_p1(const TriangleMesh& m) {
  const P1TriangleBasis basis(m);
  ASSERT_EQ(basis.num_dofs(), m.num_vertices());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec<2> a(0.3, -1.7);  // f(x) = 2.5 + a . x
  P1TriangleBasis::StencilT s;
  int evaluated = 0;
  for (Index c = 0; c < m.num_cells(); ++c)
    for (int k = 0; k < 20; ++k) {
      // A random point of triangle c (k = 0: a vertex; k = 1: an edge midpoint).
      double r1 = u(rng), r2 = u(rng);
      if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;
      if (k == 0) r1 = r2 = 0.0;
      if (k == 1) r1 = 0.5, r2 = 0.0;
      const auto& t = m.cell_vertices(c);
      const Vec<2> x = m.vertex(t[0]) + r1 * (m.vertex(t[1]) - m.vertex(t[0])) +
                       r2 * (m.vertex(t[2]) - m.vertex(t[0]));
      ASSERT_TRUE(basis.evaluate_point(x, s));
      ++evaluated;
      double sum = 0.0, f = 0.0;
      Vec<2> gsum = Vec<2>::Zero(), gf = Vec<2>::Zero();
      Mat<2> xg = Mat<2>::Zero();  // sum_i x_i grad phi_i^T = I (linear reproduction of x)
      for (int i = 0; i < 3; ++i) {
        const Vec<2> xi = basis.dof_position(s.dof[static_cast<std::size_t>(i)]);
        const double w = s.w[static_cast<std::size_t>(i)];
        const Vec<2>& g = s.grad[static_cast<std::size_t>(i)];
        EXPECT_GE(w, -1e-12);
        sum += w;
        gsum += g;
        f += w * (2.5 + a.dot(xi));
        gf += (2.5 + a.dot(xi)) * g;
        xg += xi * g.transpose();
      }
      const double scale = 1.0 / std::sqrt(m.cell_volume(c));  // gradients ~ 1/h
      EXPECT_NEAR(sum, 1.0, 1e-14);
      EXPECT_NEAR(gsum.norm(), 0.0, 1e-12 * scale);
      EXPECT_NEAR(f, 2.5 + a.dot(x), 1e-13);
      EXPECT_NEAR((gf - a).norm(), 0.0, 1e-12 * scale);
      EXPECT_NEAR((xg - Mat<2>::Identity()).norm(), 0.0, 1e-12);
      // C0 across edges: the value of every vertex function at x is the same from every
      // triangle that contains x (x on an edge or at a vertex lies in several).
      for (Index other = 0; other < m.num_cells(); ++other) {
        const auto l = m.barycentric(other, x);
        if (other == c || l[0] < -1e-12 || l[1] < -1e-12 || l[2] < -1e-12) continue;
        P1TriangleBasis::StencilT s2;
        basis.evaluate_in(other, x, s2);
        for (int i = 0; i < 3; ++i) {
          double from_s = 0.0;  // the same vertex's value in s (0 if not a vertex of that cell)
          for (int j = 0; j < 3; ++j)
            if (s.dof[static_cast<std::size_t>(j)] == s2.dof[static_cast<std::size_t>(i)])
              from_s = s.w[static_cast<std::size_t>(j)];
          EXPECT_NEAR(s2.w[static_cast<std::size_t>(i)], from_s, 1e-13);
        }
      }
    }
  EXPECT_EQ(evaluated, 20 * m.num_cells());
  EXPECT_FALSE(basis.evaluate_point(m.upper() + Vec<2>(1.0, 1.0), s));
}

TEST(P1Triangle, PartitionOfUnityLinearReproductionAndContinuityCrissCross) {
  check_p1(structured_triangles({0.0, 0.0}, {1.0, 0.5}, {4, 3}, TrianglePattern::criss_cross));
}

TEST(P1Triangle, PartitionOfUnityLinearReproductionAndContinuityGmsh) {
  check_p1(read_gmsh_mesh(std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/square_v41.msh"));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
