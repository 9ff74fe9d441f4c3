// Partition of unity, zero derivative sum and linear reproduction of the P1 basis (D 2.5,
// properties P.1-P.3), in 1D and 2D, at many points including nodes and the boundary.
#include <gtest/gtest.h>

#include <random>

#include "basis/linear.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

template <int Dim>
void check_basis(const Grid<Dim>& g, int samples) {
  LinearBasis<Dim> basis(g);
  Particles<Dim> P;
  P.resize(1);
  std::mt19937 rng(42);
  typename LinearBasis<Dim>::StencilT s;
  for (int k = 0; k < samples; ++k) {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) {
      std::uniform_real_distribution<double> u(g.origin[d], g.upper()[d]);
      // Every fourth sample snaps to a node (including both ends) to test knots.
      if (k % 4 == 0) {
        std::uniform_int_distribution<Index> n(0, g.cells[d]);
        x[d] = g.origin[d] + g.h[d] * static_cast<double>(n(rng));
      } else {
        x[d] = u(rng);
      }
    }
    P.x[0] = x;
    ASSERT_TRUE(g.inside(x));
    basis.evaluate(P, 0, s);
    double sum = 0.0;
    Vec<Dim> gsum = Vec<Dim>::Zero(), xr = Vec<Dim>::Zero();
    Mat<Dim> gr = Mat<Dim>::Zero();
    for (int a = 0; a < s.kSize; ++a) {
      EXPECT_GE(s.w[a], 0.0);
      ASSERT_GE(s.dof[a], 0);
      ASSERT_LT(s.dof[a], basis.num_dofs());
      sum += s.w[a];
      gsum += s.grad[a];
      const Vec<Dim> xi = basis.dof_position(s.dof[a]);
      xr += s.w[a] * xi;
      gr += xi * s.grad[a].transpose();
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    EXPECT_LT(gsum.norm(), 1e-10 * g.h.cwiseInverse().norm());
    EXPECT_LT((xr - x).norm(), 1e-13);                     // sum phi_i x_i = x
    EXPECT_LT((gr - Mat<Dim>::Identity()).norm(), 1e-12);  // sum x_i grad phi_i^T = I
  }
}

TEST(LinearBasis, PartitionOfUnityAndLinearReproduction1D) {
  check_basis<1>(Grid<1>(Vec<1>(-0.3), Vec<1>(1.7), IVec<1>{13}), 2000);
}

TEST(LinearBasis, PartitionOfUnityAndLinearReproduction2D) {
  check_basis<2>(Grid<2>(Vec<2>(0.0, -1.0), Vec<2>(2.0, 0.5), IVec<2>{7, 5}), 2000);
}

TEST(LinearBasis, BoundaryDofsAreTheEndNodes) {
  LinearBasis<1> b(Grid<1>(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{10}));
  EXPECT_EQ(b.boundary_dofs(0, 0), std::vector<Index>{0});
  EXPECT_EQ(b.boundary_dofs(0, 1), std::vector<Index>{10});
  LinearBasis<2> b2(Grid<2>(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{3, 2}));
  EXPECT_EQ(b2.boundary_dofs(0, 1).size(), 3u);  // x = 1: one node per row of 3 rows
  EXPECT_EQ(b2.boundary_dofs(1, 0).size(), 4u);  // y = 0: 4 nodes
}

TEST(Grid, CellOfHandlesBoundsAndNaN) {
  Grid<1> g(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{4});
  EXPECT_EQ(g.cell_of(0.0, 0), 0);
  EXPECT_EQ(g.cell_of(1.0, 0), 3);  // upper end belongs to the last cell
  EXPECT_EQ(g.cell_of(0.26, 0), 1);
  EXPECT_FALSE(g.inside(Vec<1>(-1e-12)));
  EXPECT_FALSE(g.inside(Vec<1>(1.0 + 1e-12)));
  EXPECT_FALSE(g.inside(Vec<1>(std::nan(""))));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
