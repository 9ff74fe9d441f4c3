// Partial lumping of the consistent mass matrix (method.partial_lumping; D 7.2;
// solver/mass_matrix.hpp, scheme/partial_lumping.hpp): the lumped rows keep every row sum (the
// lumped masses, hence the conserved totals) and the matrix its symmetry, the entries between
// two kept DOFs are untouched and the smallest eigenvalue does not fall; a particle matrix that is
// singular becomes positive definite; runs that the consistent matrix stops at its first step
// (a partly filled top row of cells with Powell-Sabin splines) or later (TLS on the vortex) run
// and conserve mass and momentum to round-off; a body that fills its cells lumps nothing.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "driver/run.hpp"
#include "setup/config.hpp"
#include "solver/mass_matrix.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// The hats of nodes 0..n on [0, 1] (h = 1 / n) at x.
double hat(int i, int n, double x) {
  return std::max(0.0, 1.0 - std::abs(x * n - i));
}

// sum_p m_p N_i(x_p) N_j(x_p) of the hats, each pair's triplets in both orders with one value.
void assemble(ConsistentMass& M, int n, const std::vector<double>& x, double mp) {
  M.begin(n + 1);
  for (double xp : x)
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        const double v = mp * hat(i, n, xp) * hat(j, n, xp);
        if (v != 0.0) M.add(i, j, v);
      }
}

Eigen::MatrixXd dense(const Eigen::SparseMatrix<double>& A) {
  return Eigen::MatrixXd(A);
}

TEST(PartialLumping, LumpedRowsKeepTheirSumsAndTheMatrixItsSymmetry) {
  // Eight cells, particles over [0, 0.45): node 3 (x = 0.375) is cut by the body's end, node 4
  // (x = 0.5) reached by its last particles only.
  const int n = 8;
  std::vector<double> x;
  for (int p = 0; p < 18; ++p) x.push_back((p + 0.5) * 0.025);
  ConsistentMass plain, lumped;
  assemble(plain, n, x, 0.7);
  assemble(lumped, n, x, 0.7);
  std::vector<unsigned char> rows(n + 1, 0);
  rows[3] = rows[4] = 1;
  lumped.set_lumped(rows);
  const Eigen::MatrixXd A = dense(plain.assembled()), B = dense(lumped.assembled());
  for (int i = 0; i <= n; ++i) {
    EXPECT_NEAR(B.row(i).sum(), A.row(i).sum(), 1e-15 * A.row(i).sum()) << "row " << i;
    for (int j = 0; j <= n; ++j) {
      EXPECT_EQ(B(i, j), B(j, i));
      if (i != j && (rows[i] || rows[j])) {
        EXPECT_EQ(B(i, j), 0.0) << i << ", " << j;
      } else if (i != j) {
        EXPECT_EQ(B(i, j), A(i, j)) << i << ", " << j;  // untouched, to the bit
      }
    }
  }
  EXPECT_GT(B(3, 3), A(3, 3));
  // The DOFs that hold mass (0..4): the smallest eigenvalue does not fall.
  const Eigen::MatrixXd a = A.topLeftCorner(5, 5), b = B.topLeftCorner(5, 5);
  const double la = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a).eigenvalues()[0];
  const double lb = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(b).eigenvalues()[0];
  EXPECT_GE(lb, la);
  EXPECT_GT(lb, 0.0);
  // Without lumped rows the matrix is the assembly's, to the bit.
  ConsistentMass again;
  assemble(again, n, x, 0.7);
  again.set_lumped(std::vector<unsigned char>(n + 1, 0));
  EXPECT_EQ(dense(again.assembled()), A);
}

// One particle in the first cell: m [N0^2, N0 N1; N0 N1, N1^2] has rank one (its smallest
// eigenvalue is round-off); with both rows lumped it is diag(m N0, m N1) and the solve gives
// y_i = r_i / m_i, the lumped mass's.
TEST(PartialLumping, ASingularParticleMatrixBecomesPositiveDefinite) {
  const int n = 4;
  const auto keep = [](Index i) { return i <= 1; };
  ConsistentMass M;
  assemble(M, n, {0.1}, 2.0);
  const Eigen::MatrixXd A = dense(M.assembled()).topLeftCorner(2, 2);
  const auto la = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues();
  EXPECT_LT(std::abs(la[0]), 1e-15 * la[1]);
  // Unlumped, the direct factorisation finds it singular: its second pivot is round-off (it was
  // a positive 1e-17 relative, which a test of the pivots' signs alone accepted).
  EXPECT_FALSE(M.factorize(keep));
  assemble(M, n, {0.1}, 2.0);
  std::vector<unsigned char> rows(n + 1, 0);
  rows[0] = rows[1] = 1;
  M.set_lumped(rows);
  ASSERT_TRUE(M.factorize(keep));
  Eigen::VectorXd r = Eigen::VectorXd::Zero(n + 1);
  r[0] = 0.3;
  r[1] = -0.5;
  const Eigen::VectorXd y = M.solve(r);
  EXPECT_NEAR(y[0], 0.3 / (2.0 * hat(0, n, 0.1)), 1e-15);
  EXPECT_NEAR(y[1], -0.5 / (2.0 * hat(1, n, 0.1)), 1e-15);
}

// A run of examples/`example` without output files, with consistent mass and
// method.partial_lumping = `lump`, then `sets` (which may override them).
RunResult run_example(const std::string& example, std::vector<std::string> sets,
                      const std::string& lump) {
  sets.insert(sets.begin(), {"output.frames=0", "output.csv=false", "output.vtk=false",
                             "method.mass=consistent", "method.partial_lumping=" + lump});
  RunOptions ro;
  ro.quiet = true;
  return run(Config::load(std::string(MPM_SOURCE_DIR) + "/examples/" + example, sets), ro);
}

// examples/custom_plate_2d.toml (a column under ramped gravity on 4 x 22 cells of 0.05 m, free
// top) with its top at 0.96 m: the cell row below the top filled to 20 % (docs/verification.md,
// "PS-MPM with partially filled elements"), over `end` seconds.
RunResult column(std::vector<std::string> extra, const std::string& end, const std::string& lump) {
  extra.insert(extra.begin(), {"body.max=[0.2, 0.96]", "constants.H=0.96", "particles.per_cell=4",
                               "time.dt=1e-4", "time.end=" + end});
  return run_example("custom_plate_2d.toml", extra, lump);
}

void expect_conserving_run(const RunResult& r) {
  ASSERT_EQ(r.exit_code, exit_code::kOk) << r.failure;
  EXPECT_GT(r.summary["method"]["partially_lumped_dofs_max"].get<Index>(), 0);
  EXPECT_LT(r.diag.max_rel_mass_error, 1e-13);
  EXPECT_LT(r.diag.max_rel_momentum_error, 1e-13);
}

// The consistent PS matrix of the column stops the run at step 0 (singular); with the DOFs of
// the top row lumped it runs, and conserves.
TEST(PartialLumping, PowellSabinColumnWithAFifthFilledTopRowRuns) {
  const RunResult stops = column({"method.basis=powell_sabin"}, "2e-3", "0");
  EXPECT_EQ(stops.exit_code, exit_code::kNonFinite);
  EXPECT_NE(stops.failure.find("step 0,"), std::string::npos) << stops.failure;
  EXPECT_NE(stops.failure.find("method.partial_lumping"), std::string::npos) << stops.failure;
  expect_conserving_run(column({"method.basis=powell_sabin"}, "0.02", "0.5"));
}

// TLS with consistent mass (issue 22 item 1): on the vortex (A = 0.1 rad, quadratic B-splines,
// 16 cells, the default TLS settings) the consistent matrix turns singular at t = 0.942 s,
// where the annulus's edges cut cells; with partial lumping the run reaches its end. (B-spline
// TLS with consistent mass is refused unless method.allow_unstable: it flutters under load.)
TEST(PartialLumping, TlsWithConsistentMassRunsTheVortex) {
  const auto vortex = [](const std::string& lump) {
    return run_example("vortex_2d.toml",
                       {"vortex.amplitude=0.1", "grid.cells=16", "method.mapping=tls",
                        "method.basis=bspline", "method.degree=2", "method.allow_unstable=true"},
                       lump);
  };
  const RunResult stops = vortex("0");
  EXPECT_EQ(stops.exit_code, exit_code::kNonFinite);
  EXPECT_NE(stops.failure.find("consistent mass matrix is singular"), std::string::npos)
      << stops.failure;
  expect_conserving_run(vortex("0.5"));
}

// On the plate MMS (the body fills the grid; 5 steps) no DOF is lumped and the run is the
// consistent one to the bit.
TEST(PartialLumping, ABodyThatFillsItsCellsLumpsNothing) {
  const auto plate = [](const std::string& lump) {
    return run_example("plate_mms_2d.toml",
                       {"time.end=5e-5", "method.basis=bspline", "method.degree=2"}, lump);
  };
  const RunResult with = plate("0.5"), without = plate("0");
  ASSERT_EQ(with.exit_code, exit_code::kOk) << with.failure;
  ASSERT_EQ(without.exit_code, exit_code::kOk) << without.failure;
  EXPECT_EQ(with.summary["method"]["partially_lumped_dofs_max"].get<Index>(), 0);
  EXPECT_EQ(with.summary["errors"], without.summary["errors"]);
}

// Powell-Sabin splines with consistent mass stop below about 12 particles per triangle, partial
// lumping or not (docs/verification.md, "D Fig. 3.9 on unstructured meshes"): set-up warns, with
// the median count, in the run's warnings (summary.json), and not at 24 per triangle.
TEST(PartialLumping, PowellSabinWithFewParticlesPerTriangleIsWarnedOf) {
  const auto plate = [](const std::string& per_triangle, const std::string& lump) {
    return run_example("plate_ps_unstructured_2d.toml",
                       {"time.end=2e-5", "particles.per_triangle=" + per_triangle}, lump);
  };
  for (const std::string lump : {"0", "0.5"}) {
    const RunResult few = plate("6", lump);
    ASSERT_EQ(few.exit_code, exit_code::kOk) << few.failure;
    ASSERT_EQ(few.warnings.size(), 1u);
    EXPECT_NE(few.warnings[0].find("median of 6 particles per triangle"), std::string::npos)
        << few.warnings[0];
    EXPECT_NE(few.warnings[0].find("particles.per_triangle"), std::string::npos);
    EXPECT_EQ(few.summary["warnings"][0].get<std::string>(), few.warnings[0]);
  }
  EXPECT_TRUE(plate("24", "0").warnings.empty());
}

// Lumped mass has no matrix to lump: refused, naming the key and what to change.
TEST(PartialLumping, RefusedWithLumpedMass) {
  try {
    column({"method.mass=lumped"}, "2e-3", "0.5");
    FAIL() << "no input error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("method.partial_lumping"), std::string::npos) << what;
    EXPECT_NE(what.find("method.mass = \"lumped\""), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
