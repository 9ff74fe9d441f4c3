// B-spline mass matrices, conjugate gradients and p-multigrid (src/solver/spline_matrices.hpp,
// src/solver/iterative.hpp; 004 sections 4.6-4.7): the assembled matrices against their exact
// properties (partition of unity, symmetry, the Kronecker structure that `mpm massmatrix` uses
// for the condition number), 004 Table 4.2 at h = 1/8, CG within the bound of 004 eq. 4.57,
// both solvers against the direct solution, the V-cycle count of p = 3 not growing with 1/h, and
// the coarse-grid correction on an error it should remove.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <unsupported/Eigen/KroneckerProduct>

#include "../support/examples.hpp"
#include "app/massmatrix.hpp"
#include "driver/run.hpp"
#include "setup/config.hpp"
#include "solver/iterative.hpp"
#include "solver/spline_matrices.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

Grid<1> unit1(Index n) {
  return Grid<1>(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{n});
}
Grid<2> unit2(Index n) {
  return Grid<2>(Vec<2>::Zero(), Vec<2>::Ones(), IVec<2>{n, n});
}

std::vector<unsigned char> interior(const auto& g, int p) {
  std::vector<unsigned char> keep(static_cast<std::size_t>(spline_count(g, p)), 1);
  for (Index i : spline_boundary_functions(g, p)) keep[static_cast<std::size_t>(i)] = 0;
  return keep;
}

Eigen::VectorXd kept_vector(const Eigen::VectorXd& v, const std::vector<unsigned char>& keep) {
  Eigen::VectorXd out(std::count(keep.begin(), keep.end(), 1));
  for (Index i = 0, k = 0; i < v.size(); ++i)
    if (keep[static_cast<std::size_t>(i)]) out[k++] = v[i];
  return out;
}

// Partition of unity: sum_ij M_ij = int rho = rho |Omega|, and M_pq 1 = int phi^p_i (the mixed
// matrices too); symmetric; in 2D the Kronecker product of the 1D matrices (tensor-product
// functions and a separable integrand), which `mpm massmatrix` uses for kappa.
TEST(SplineMatrices, MassMatrixExactProperties) {
  for (int p = 1; p <= 5; ++p) {
    const Grid<1> g1 = unit1(7);
    const Grid<2> g2 = unit2(7);
    const SparseMatrixD M1 = spline_mass_exact(g1, p, p, 2.5);
    const SparseMatrixD M2 = spline_mass_exact(g2, p, p);
    EXPECT_NEAR(Eigen::MatrixXd(M1).sum(), 2.5, 1e-13) << p;
    EXPECT_NEAR(Eigen::MatrixXd(M2).sum(), 1.0, 1e-13) << p;
    EXPECT_LT((Eigen::MatrixXd(M2) - Eigen::MatrixXd(M2).transpose()).norm(), 1e-16) << p;
    const Eigen::MatrixXd m1 = Eigen::MatrixXd(spline_mass_exact(g1, p, p));
    const Eigen::MatrixXd kron = Eigen::kroneckerProduct(m1, m1).eval();
    EXPECT_LT((Eigen::MatrixXd(M2) - kron).cwiseAbs().maxCoeff(), 1e-16) << p;
    // Integrals of the functions: M 1 (rows of degree p) = load vector of f = 1.
    const Eigen::VectorXd load = spline_load_exact(g2, p, 1.0);
    if (p > 1) {
      const SparseMatrixD Mx = spline_mass_exact(g2, p, p - 1);
      EXPECT_LT((Mx * Eigen::VectorXd::Ones(Mx.cols()) - load).cwiseAbs().maxCoeff(), 1e-15);
    }
    EXPECT_LT((M2 * Eigen::VectorXd::Ones(M2.cols()) - load).cwiseAbs().maxCoeff(), 1e-15);
  }
}

// The matrix-free application equals the assembled matrix times the vector (Gauss points and a
// particle-like point set, boundary functions eliminated), and CG with it takes the same path.
TEST(SplineMatrices, MatrixFreeOperatorEqualsTheAssembledMatrix) {
  for (int p = 1; p <= 4; ++p) {
    const Grid<2> g = unit2(6);
    const auto keep = interior(g, p);
    for (const PointSet<2>& pts : {gauss_points(g, p + 1), gauss_points(g, 2, 3.0)}) {
      const SparseMatrixD M = kept_submatrix(spline_mass(g, p, p, pts), keep, keep);
      const SplineMassOperator<2> op(g, p, pts, keep);
      ASSERT_EQ(op.size(), M.rows());
      const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(M.rows(), -1.0, 2.0).array().sin();
      Eigen::VectorXd y;
      op.apply(x, y);
      EXPECT_LT((y - M * x).norm(), 1e-15 * (M * x).norm() * 10) << p;
      const Eigen::VectorXd f = kept_vector(spline_load_exact(g, p, -9.81), keep);
      Eigen::VectorXd a, b;
      const IterationReport ra = conjugate_gradient(M, f, a, 1e-10, 1000);
      const IterationReport rb = conjugate_gradient(
          [&op](const Eigen::VectorXd& v, Eigen::VectorXd& w) { op.apply(v, w); }, f, b, 1e-10,
          1000);
      EXPECT_TRUE(ra.converged && rb.converged);
      EXPECT_LE(std::abs(ra.iterations - rb.iterations), 1) << p;
      EXPECT_LT((a - b).norm(), 1e-8 * a.norm()) << p;
    }
  }
}

// 004 Table 4.2, h^-1 = 8, with the boundary functions eliminated (the reading that reproduces
// it; `mpm massmatrix --boundary free` gives about twice these): dense eigenvalues of the
// assembled 2D matrix, and kappa_2D = kappa_1D^2.
TEST(SplineMatrices, ConditionNumbersOf004Table42) {
  const double published[5] = {7.38, 52.1, 440, 3770, 33000};
  for (int p = 1; p <= 5; ++p) {
    const Grid<2> g = unit2(8);
    const auto keep = interior(g, p);
    const Eigen::MatrixXd M(kept_submatrix(spline_mass_exact(g, p, p), keep, keep));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(M, Eigen::EigenvaluesOnly);
    const double kappa = es.eigenvalues().maxCoeff() / es.eigenvalues().minCoeff();
    EXPECT_NEAR(kappa / published[p - 1], 1.0, 0.005) << "p = " << p << ": kappa " << kappa;
    const Grid<1> g1 = unit1(8);
    const auto k1 = interior(g1, p);
    const Eigen::MatrixXd M1(kept_submatrix(spline_mass_exact(g1, p, p), k1, k1));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> e1(M1, Eigen::EigenvaluesOnly);
    EXPECT_NEAR(std::pow(e1.eigenvalues().maxCoeff() / e1.eigenvalues().minCoeff(), 2), kappa,
                1e-8 * kappa);
  }
}

// CG and p-multigrid reach the direct solution within their tolerance (both boundary readings),
// and CG needs no more iterations than 004 eq. 4.57 allows.
TEST(Iterative, CgAndPMultigridReachTheDirectSolution) {
  for (bool dirichlet : {true, false})
    for (int p = 1; p <= 4; ++p) {
      const Grid<2> g = unit2(12);
      std::vector<unsigned char> keep =
          dirichlet ? interior(g, p)
                    : std::vector<unsigned char>(static_cast<std::size_t>(spline_count(g, p)), 1);
      const SparseMatrixD M = kept_submatrix(spline_mass_exact(g, p, p), keep, keep);
      const Eigen::VectorXd f = kept_vector(spline_load_exact(g, p, -9.81), keep);
      const Eigen::VectorXd exact = Eigen::SimplicialLDLT<SparseMatrixD>(M).solve(f);
      Eigen::VectorXd x;
      const IterationReport cg = conjugate_gradient(M, f, x, 1e-10, 10000);
      ASSERT_TRUE(cg.converged);
      EXPECT_LT((M * x - f).norm(), 1e-10 * f.norm());
      const Eigen::MatrixXd D(M);
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(D, Eigen::EigenvaluesOnly);
      const double kappa = es.eigenvalues().maxCoeff() / es.eigenvalues().minCoeff();
      const double rho = (std::sqrt(kappa) - 1.0) / (std::sqrt(kappa) + 1.0);
      // ||r|| <= sqrt(kappa) ||e||_A-ratio bound: n with 2 rho^n sqrt(kappa) <= tol suffices.
      const double bound = std::log(1e-10 / (2.0 * std::sqrt(kappa))) / std::log(rho);
      EXPECT_LE(cg.iterations, bound) << p;
      // ||e|| / ||x|| <= kappa ||r|| / ||b||
      EXPECT_LT((x - exact).norm(), kappa * 1e-10 * exact.norm()) << p;
      std::vector<std::pair<int, int>> sides;
      if (dirichlet) sides = {{0, 0}, {0, 1}, {1, 0}, {1, 1}};
      const PMultigrid mg = spline_pmg(g, p, gauss_points(g, p + 1), keep, sides, PmgSettings{});
      Eigen::VectorXd y;
      const IterationReport v = mg.solve(f, y, 1e-10, 2000);
      ASSERT_TRUE(v.converged) << p;
      EXPECT_LT((y - exact).norm(), kappa * 1e-10 * exact.norm()) << p;
      PmgSettings jac;
      jac.smoother = Smoother::Jacobi;
      const PMultigrid mj = spline_pmg(g, p, gauss_points(g, p + 1), keep, sides, jac);
      Eigen::VectorXd z;
      const IterationReport vj = mj.solve(f, z, 1e-10, 20000);
      ASSERT_TRUE(vj.converged) << p;
      EXPECT_LT((z - exact).norm(), kappa * 1e-10 * exact.norm()) << p;
    }
}

// 004's h-independence: the V-cycles of p = 3 do not grow from h^-1 = 16 to 64 (both readings).
TEST(Iterative, PMultigridCyclesDoNotGrowWithTheGrid) {
  for (const char* boundary : {"dirichlet", "free"}) {
    MassMatrixOptions opt;
    opt.degrees = {3};
    opt.cells = {16, 64};
    opt.boundary = boundary;
    const auto rows = massmatrix_study(opt);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_TRUE(rows[0].pmg_converged && rows[1].pmg_converged);
    EXPECT_LE(rows[1].pmg_cycles, rows[0].pmg_cycles) << boundary;
    EXPECT_LT(rows[1].pmg_error, rows[1].kappa * opt.tolerance);
    EXPECT_LT(rows[1].cg_error, rows[1].kappa * opt.tolerance);
  }
}

// The coarse-grid correction with an exact coarse solve removes most of an error that lies in
// the range of the prolongation and is smooth (the degree-(p-1) interpolant of a sine): the
// transfers and the rediscretised coarse matrix fit together.
TEST(Iterative, CoarseCorrectionRemovesASmoothError) {
  const int p = 3;
  const Grid<2> g = unit2(16);
  const auto keep = interior(g, p);
  PmgSettings s;
  s.pre = s.post = 0;
  s.coarse_tolerance = 1e-12;
  const PMultigrid mg =
      spline_pmg(g, p, gauss_points(g, p + 1), keep, {{0, 0}, {0, 1}, {1, 0}, {1, 1}}, s);
  ASSERT_EQ(mg.levels().size(), 3u);
  const auto& L0 = mg.levels()[0];
  // A smooth coarse function: sin(pi x) sin(pi y) at the Greville points of degree p - 1.
  const auto keep1 = interior(g, p - 1);
  Eigen::VectorXd ec(L0.prolong.cols());
  const Index n1 = g.cells[0] + p - 1;
  for (Index i = 0, k = 0; i < n1 * n1; ++i) {
    if (!keep1[static_cast<std::size_t>(i)]) continue;
    const double x = (static_cast<double>(i % n1) + 0.5) / static_cast<double>(n1);
    const double y = (static_cast<double>(i / n1) + 0.5) / static_cast<double>(n1);
    ec[k++] = std::sin(M_PI * x) * std::sin(M_PI * y);
  }
  const Eigen::VectorXd err = L0.prolong * ec;  // x = exact + err with exact = 0, b = 0
  Eigen::VectorXd x = err;
  const Eigen::VectorXd b = Eigen::VectorXd::Zero(err.size());
  (void)mg.solve(b, x, 0.0, 1);  // one V-cycle
  const double before = std::sqrt(err.dot(L0.A * err)), after = std::sqrt(x.dot(L0.A * x));
  EXPECT_LT(after, 0.1 * before) << "energy norm " << before << " -> " << after;
}

// Why the V-cycle count is the smoother's (docs/verification.md): after the 16 Gauss-Seidel
// sweeps of a cycle, the error left from a random start lies at the bottom of the spectrum of
// the mass matrix (its Rayleigh quotient falls below 2 % of lambda_max; p = 3, kappa = 420: a
// few lambda_min), and a coarse correction with an exact
// coarse solve removes little of that error, where it removes most of a smooth one (above).
TEST(Iterative, SmoothedErrorIsWhatTheCoarseLevelsCannotReach) {
  const int p = 3;
  const Grid<2> g = unit2(16);
  const auto keep = interior(g, p);
  const std::vector<std::pair<int, int>> sides = {{0, 0}, {0, 1}, {1, 0}, {1, 1}};
  PmgSettings smooth_only;
  smooth_only.coarse_correction = false;
  const PMultigrid s = spline_pmg(g, p, gauss_points(g, p + 1), keep, sides, smooth_only);
  const SparseMatrixD& A = s.levels()[0].A;
  std::srand(7);
  Eigen::VectorXd e = Eigen::VectorXd::Random(A.rows());  // b = 0: x is the error
  const double rq0 = e.dot(A * e) / e.squaredNorm();
  const Eigen::VectorXd b = Eigen::VectorXd::Zero(A.rows());
  (void)s.solve(b, e, 0.0, 1);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Eigen::MatrixXd(A),
                                                          Eigen::EigenvaluesOnly);
  const double lmin = es.eigenvalues().minCoeff(), lmax = es.eigenvalues().maxCoeff();
  const double rq = e.dot(A * e) / e.squaredNorm();
  // From the middle of the spectrum to its bottom: lambda_max / 420 = lambda_min here.
  EXPECT_LT(rq, 0.1 * rq0);
  EXPECT_LT(rq, 0.02 * lmax) << "Rayleigh quotient " << rq << ", lambda in [" << lmin << ", "
                             << lmax << "]";
  PmgSettings coarse_only;
  coarse_only.pre = coarse_only.post = 0;
  coarse_only.coarse_tolerance = 1e-12;
  const PMultigrid c = spline_pmg(g, p, gauss_points(g, p + 1), keep, sides, coarse_only);
  Eigen::VectorXd x = e;
  (void)c.solve(b, x, 0.0, 1);
  const double before = std::sqrt(e.dot(A * e)), after = std::sqrt(x.dot(A * x));
  EXPECT_GT(after, 0.8 * before) << "energy norm " << before << " -> " << after;
}

// method.mass_solver in MPM runs: CG and p-multigrid give the direct solve's results to their
// tolerance (1D bar with cubic B-splines, 2D plate with quadratic ones and rollers, which solve
// per component), and count their iterations; the run stops with exit code 11 and the residual
// history when a solve does not converge; the combinations that cannot work are refused.
using test::run_example;

TEST(MassSolver, IterativeSolvesGiveTheDirectResults) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"vibrating_bar_small",
       {"method.basis=bspline", "method.degree=3", "method.mass=consistent", "grid.cells=12"}},
      {"plate_mms_2d",
       {"method.basis=bspline", "method.degree=2", "method.mass=consistent", "grid.cells=8",
        "mms.amplitude=1e-4", "time.end=2e-4"}}};
  for (const auto& [example, sets] : cases) {
    const RunResult direct = run_example(example, sets);
    ASSERT_EQ(direct.exit_code, 0) << direct.failure;
    for (const char* solver : {"cg", "pmg"}) {
      auto s = sets;
      s.push_back(std::string("method.mass_solver=") + solver);
      const RunResult r = run_example(example, s);
      ASSERT_EQ(r.exit_code, 0) << solver << ": " << r.failure;
      EXPECT_GT(r.diag.mass_solver_iterations, 0) << solver;
      EXPECT_GT(r.diag.max_mass_solver_iterations, 0) << solver;
      EXPECT_NEAR(*r.errors.displacement_rms / *direct.errors.displacement_rms, 1.0, 1e-8)
          << example << " " << solver;
      EXPECT_NEAR(*r.errors.stress_rms / *direct.errors.stress_rms, 1.0, 1e-8)
          << example << " " << solver;
    }
  }
}

TEST(MassSolver, NonConvergenceStopsTheRun) {
  for (const char* solver : {"cg", "pmg"}) {
    const RunResult r = run_example(
        "vibrating_bar_small",
        {"method.basis=bspline", "method.degree=3", "method.mass=consistent",
         std::string("method.mass_solver=") + solver, "method.mass_solver_max_iterations=1"});
    EXPECT_EQ(r.exit_code, exit_code::kSolver) << solver << ": " << r.failure;
    EXPECT_NE(r.failure.find("did not converge"), std::string::npos) << r.failure;
    EXPECT_NE(r.failure.find("residual history"), std::string::npos) << r.failure;
    EXPECT_NE(r.failure.find("step 0,"), std::string::npos) << r.failure;  // the first step
  }
}

// One particle per cell with cubic B-splines: the particle mass matrix is singular (fewer
// particles than functions); every solver stops the run rather than report a result
// (docs/verification.md).
TEST(MassSolver, SingularParticleMatrixStopsEverySolver) {
  for (const auto& [solver, code] :
       {std::pair{"direct", exit_code::kNonFinite}, std::pair{"cg", exit_code::kSolver},
        std::pair{"pmg", exit_code::kSolver}}) {
    const RunResult r =
        run_example("vibrating_bar_small",
                    {"particles.per_cell=1", "method.basis=bspline", "method.degree=3",
                     "method.mass=consistent", std::string("method.mass_solver=") + solver});
    EXPECT_EQ(r.exit_code, code) << solver << ": " << r.failure;
    // The direct factorisation says why, in the first step.
    if (std::string(solver) == "direct") {
      EXPECT_NE(r.failure.find("consistent mass matrix is singular"), std::string::npos)
          << r.failure;
      EXPECT_NE(r.failure.find("step 0,"), std::string::npos) << r.failure;
    }
  }
}

TEST(MassSolver, InputsAreRefused) {
  auto error = [](std::vector<std::string> sets) {
    try {
      (void)run_example("vibrating_bar_small", std::move(sets));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error({"method.mass_solver=cg"}).find("method.mass = \"lumped\""), std::string::npos);
  EXPECT_NE(error({"method.mass=consistent", "method.mass_solver=pmg"})
                .find("method.basis = \"bspline\""),
            std::string::npos);
  EXPECT_NE(error({"method.mass_solver=multigrid"}).find("direct, cg, pmg"), std::string::npos);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
