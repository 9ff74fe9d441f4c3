// p-multigrid on distributed vectors (parallel/distributed_pmg.hpp, issue 21) on one process,
// where its sums over the processes are plain copies: it must be the matrix hierarchy of
// spline_pmg with Jacobi smoothing (the same kept functions, transfers, damping and cycles), so
// that on several processes it differs from one process by round-off alone (checked under mpirun
// in Mpi.SameAnswersAsOneProcess).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/comm.hpp"
#include "parallel/distributed_pmg.hpp"
#include "solver/spline_matrices.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(DistributedPmg, OneProcessIsTheMatrixHierarchy) {
  // Cubic B-splines (three levels) on 6 x 5 cells; particles, 3 x 3 per cell of unequal mass,
  // fill the cells with x < 4 cells and y < 4 cells (a partly filled grid: inactive functions and
  // coarse functions without mass; functions below 1e-2 of the largest mass are left out, as
  // method.mass_tolerance does). Jacobi cycles to 1e-4: 323 and 374 for the two slots (to 1e-6,
  // 839 and 993: 21 s under the sanitizers; with functions down to 1e-4 of the largest mass and
  // to 1e-10, 4,193 and 4,551: 90 s). Every cycle's residual is compared, so fewer of them
  // check the same steps.
  // Side x = 0 is fixed in component x only (a roller): two slots with their own kept functions and
  // coarse sides.
  const Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.2, 1.0), IVec<2>{6, 5});
  const int p = 3;
  Particles<2> P;
  P.resize(4 * 4 * 9);
  std::size_t k = 0;
  for (int cy = 0; cy < 4; ++cy)
    for (int cx = 0; cx < 4; ++cx)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i, ++k) {
          P.x[k] = Vec<2>((cx + (i + 0.5) / 3.0) * 0.2, (cy + (j + 0.5) / 3.0) * 0.2);
          P.mass[k] = 1.0 + 0.3 * std::sin(static_cast<double>(k));
        }
  PointSet<2> pts;
  pts.x = P.x;
  pts.w = P.mass;
  const SparseMatrixD M = spline_mass(g, p, p, pts);
  const Index n = M.rows();

  RunState<2> sim(g, std::move(P), NeoHookean{});
  sim.spline_degree = p;
  sim.nodes.resize(n);
  const Eigen::VectorXd lumped = M * Eigen::VectorXd::Ones(n);
  Index lo = n, hi = -1;
  for (Index i = 0; i < n; ++i) {
    const auto I = static_cast<std::size_t>(i);
    sim.nodes.active[I] = lumped[i] > 1e-2 * lumped.maxCoeff() ? 1 : 0;
    sim.nodes.fixed[I] = i % (g.cells[0] + p) == 0 ? 1 : 0;
    if (lumped[i] > 0.0) {
      lo = std::min(lo, i);
      hi = std::max(hi, i);
    }
  }
  sim.consistent_per_component = true;
  MassSolverSettings s;
  s.kind = MassSolver::Pmg;
  s.tolerance = 1e-4;
  s.pmg.smoother = Smoother::Jacobi;
  sim.consistent.configure(s);
  sim.consistent.begin(n);
  for (Index c = 0; c < M.outerSize(); ++c)
    for (SparseMatrixD::InnerIterator it(M, c); it; ++it)
      sim.consistent.add(it.row(), it.col(), it.value());
  sim.comm = &Comm::world();
  sim.shared.lo = {lo};
  sim.shared.hi = {hi};

  const DistributedPmg<2> dist(sim);
  ASSERT_TRUE(dist.positive());
  for (int slot = 0; slot < 2; ++slot) {
    const auto bit = static_cast<std::uint8_t>(1u << slot);
    std::vector<unsigned char> keep(static_cast<std::size_t>(n));
    for (std::size_t i = 0; i < keep.size(); ++i)
      keep[i] = sim.nodes.active[i] && !(sim.nodes.fixed[i] & bit);
    const PMultigrid mg = spline_pmg(g, p, pts, keep, spline_fixed_sides(sim, bit), s.pmg, &M);
    ASSERT_EQ(mg.levels().size(), 3u);
    // A right-hand side on the kept functions, compressed for the matrix hierarchy.
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n), bk(mg.levels()[0].A.rows());
    Index m = 0;
    for (Index i = 0; i < n; ++i)
      if (keep[static_cast<std::size_t>(i)]) {
        b[i] = std::cos(0.7 * static_cast<double>(i)) * lumped[i];
        bk[m++] = b[i];
      }
    ASSERT_EQ(m, bk.size());
    Eigen::VectorXd y, x = Eigen::VectorXd::Zero(n);
    const IterationReport one = mg.solve(bk, y, s.tolerance, s.max_iterations);
    const IterationReport many = dist.solve(slot, b, x);
    ASSERT_TRUE(one.converged);
    ASSERT_TRUE(many.converged);
    EXPECT_EQ(many.iterations, one.iterations) << slot;
    EXPECT_EQ(dist.coarse_iterations(), mg.coarse_iterations()) << slot;
    for (std::size_t c = 0; c < one.history.size(); ++c)
      EXPECT_NEAR(many.history[c], one.history[c], 1e-12) << slot << " " << c;
    // The same solution, zero off the kept functions, and it solves the kept system of the
    // assembled matrix to the tolerance (a residual of the matrix, not of the operators).
    m = 0;
    double err = 0.0;
    Eigen::VectorXd xk(bk.size());
    for (Index i = 0; i < n; ++i)
      if (keep[static_cast<std::size_t>(i)]) {
        err = std::max(err, std::abs(x[i] - y[m]));
        xk[m++] = x[i];
      } else {
        EXPECT_EQ(x[i], 0.0);
      }
    EXPECT_LT(err, 1e-12 * y.cwiseAbs().maxCoeff()) << slot;
    const SparseMatrixD A = kept_submatrix(M, keep, keep);
    EXPECT_LT((A * xk - bk).norm(), s.tolerance * bk.norm()) << slot;
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
