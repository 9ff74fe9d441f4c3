#pragma once
// Whether a sparse LDL^T factorisation found a positive definite matrix to working precision:
// every pivot above its round-off. Each pivot is what is left of its (permuted) diagonal entry
// after the elimination of the rows before it, a Schur complement: computed, it carries a
// round-off of about the number of entries of its row times epsilon times that diagonal entry. A
// pivot no larger than that is zero to working precision, whatever its sign: the matrix is
// singular. (LDL^T of a rank-one 2 x 2 particle matrix returned a tiny positive second pivot,
// which the test of the signs alone accepted and the solve then divided by:
// PartialLumping.ASingularParticleMatrixBecomesPositiveDefinite.) Both in the order of the pivots
// (P M P^T is factorised; permutationP() * diag(M) is its diagonal). Used by the consistent mass
// (solver/mass_matrix.cpp) and `mpm massmatrix` (app/massmatrix.cpp).
#include <Eigen/SparseCholesky>
#include <limits>

namespace mpm {

template <class Factorisation, class Matrix>
bool ldlt_pivots_above_roundoff(const Factorisation& f, const Matrix& M) {
  if (f.info() != Eigen::Success) return false;
  Eigen::VectorXd roundoff(M.rows());
  for (Eigen::Index j = 0; j < M.rows(); ++j)
    roundoff[j] = static_cast<double>(M.innerVector(j).nonZeros()) *
                  std::numeric_limits<double>::epsilon() * M.coeff(j, j);
  roundoff = f.permutationP() * roundoff;
  const Eigen::VectorXd& pivot = f.vectorD();
  for (Eigen::Index i = 0; i < M.rows(); ++i)
    if (!(pivot[i] > roundoff[i])) return false;
  return true;
}

}  // namespace mpm
