#pragma once
// Iterative solvers for (B-spline) mass matrices (004 sections 4.6-4.7): conjugate gradients
// and a p-multigrid V-cycle over the degrees p -> p-1 -> ... -> 1 on the same knot spans.
//
// Conjugate gradients stop at ||r_k||_2 / ||r_0||_2 < tolerance (004 eq. 4.53). Their error
// after n iterations is bounded by 2 ((sqrt(kappa) - 1) / (sqrt(kappa) + 1))^n in the energy
// norm (004 eq. 4.57), so the iterations grow with the condition number, which B-spline mass
// matrices raise about 8x per degree (004 Table 4.2).
//
// p-multigrid (004 eq. 4.59-4.62, after Tielen et al.): nu_1 pre-smoothing steps, the residual
// restricted to degree p-1, the residual equation solved there recursively, the correction
// prolongated and added, nu_2 post-smoothing steps; on the level of degree 1 (the coarsest of a
// hierarchy with more than one level) CG to a relative residual of 1e-4 (004); the matrices of
// every level by rediscretisation on the same point set. The spline spaces of consecutive
// degree with maximal continuity are not nested (a C^{p-2} spline of degree p-1 is not a C^{p-1}
// spline of degree p), so there is no exact embedding: the prolongation is the L2 projection
// with the lumped mass of the fine space, I_{p-1}^p = (M_p^L)^{-1} M_{p,p-1} (Tielen et al.; the
// consistent M_p would need the solve being accelerated). The restriction of a residual is the
// transpose of the prolongation (the variational choice for a residual, which is a functional:
// it keeps the coarse correction an energy-norm projection up to the rediscretised coarse
// matrix), or, as an option, the lumped L2 projection the other way (M_{p-1}^L)^{-1} M_{p-1,p}.
#include <Eigen/Sparse>
#include <functional>
#include <string_view>
#include <utility>
#include <vector>

#include "grid/grid.hpp"
#include "solver/spline_matrices.hpp"

namespace mpm {

struct IterationReport {
  bool converged = false;
  int iterations = 0;            // CG iterations or V-cycles
  double relative_residual = 0;  // ||b - A x|| / ||b - A x_0|| at the end
  std::vector<double> history;   // the same after each iteration (history[0] = 1)
};

// CG from the given x (004 uses x = 0) until ||r|| / ||r_0|| < tolerance or max_iterations.
IterationReport conjugate_gradient(const SparseMatrixD& A, const Eigen::VectorXd& b,
                                   Eigen::VectorXd& x, double tolerance, int max_iterations);
// The same with the matrix given by its application y = A x (a matrix-free operator).
using LinearOperator = std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& y)>;
IterationReport conjugate_gradient(const LinearOperator& A, const Eigen::VectorXd& b,
                                   Eigen::VectorXd& x, double tolerance, int max_iterations);
// The same with the inner product given: a vector distributed over processes (each holds its
// DOFs and copies of its neighbours') takes the sum over the DOFs it owns, summed over the ranks
// in a fixed order, so every rank takes the same steps (scheme/grid_stages.cpp).
using InnerProduct = std::function<double(const Eigen::VectorXd& a, const Eigen::VectorXd& b)>;
IterationReport conjugate_gradient(const LinearOperator& A, const Eigen::VectorXd& b,
                                   Eigen::VectorXd& x, double tolerance, int max_iterations,
                                   const InnerProduct& dot);

enum class Smoother { GaussSeidel, Jacobi };
enum class Restriction { Transpose, Projection };

std::string_view name_of(Smoother s);
std::string_view name_of(Restriction r);

struct PmgSettings {
  int pre = 8, post = 8;  // nu_1, nu_2 (004)
  // Gauss-Seidel: forward sweeps before the coarse correction, backward after (a symmetric
  // cycle). Jacobi: x += omega D^-1 (b - A x) with omega = 1 / lambda_max(D^-1 A) (estimated by
  // power iteration), which parallelises and converges for any SPD A.
  Smoother smoother = Smoother::GaussSeidel;
  Restriction restriction = Restriction::Transpose;
  double coarse_tolerance = 1e-4;  // CG on the degree-1 level (004)
  // false: the cycle is the smoothing alone (no restriction, coarse solve or prolongation), to
  // measure what the coarse levels contribute (`mpm massmatrix --no-coarse-correction`).
  bool coarse_correction = true;
  int coarse_max_iterations = 100000;
};

// One level of the cycle through its operations on the level's vectors. A matrix hierarchy
// (PMultigrid) binds them to its matrices; a distributed run to each process's part of the
// level's matrices, summed over the processes that share a function, and to inner products over
// the functions each process owns (parallel/distributed_pmg.hpp).
struct PmgLevelOps {
  Index size = 0;
  LinearOperator A;            // y = A x
  LinearOperator prolong;      // coarser -> this (none on the coarsest level)
  LinearOperator restriction;  // this -> coarser
  InnerProduct dot;            // for the coarse CG and the outer residual
  // `steps` sweeps of the smoother on A x = b from x; forward before the coarse correction.
  std::function<void(const Eigen::VectorXd& b, Eigen::VectorXd& x, int steps, bool forward)> smooth;
};

// V-cycles (004 eq. 4.59-4.62) over `levels` (finest first) from x until the relative residual
// (in levels[0].dot's norm) is below tolerance or max_cycles; coarse_iterations receives the
// CG iterations of the coarse solves.
IterationReport pmg_cycles(const std::vector<PmgLevelOps>& levels, const PmgSettings& s,
                           const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                           int max_cycles, long& coarse_iterations);

// Jacobi's damping omega = 1 / (1.05 lambda_max(D^-1 A)), lambda_max by 50 power iterations from
// `start` (the 1.05 covers the iteration's underestimate, so omega lambda_max < 1 and the
// smoother contracts); inv_diag is zero on the functions outside the system.
double jacobi_damping(const LinearOperator& A, const Eigen::VectorXd& inv_diag,
                      Eigen::VectorXd start, const InnerProduct& dot);
// The power iteration's start on function g of a level: 1 + frac(g / golden ratio). It depends
// on the function, not on its position in a vector, so a distributed run starts from the same
// vector as one process; the sequence is equidistributed, so it holds the oscillating modes whose
// eigenvalues are the largest (a smooth start would hold little of them).
double power_start(Index g);

// One level: the matrix on the kept functions, and the transfers to and from the next coarser
// level (empty on the coarsest).
struct PmgLevel {
  int degree = 1;
  SparseMatrixD A;
  SparseMatrixD prolong;      // coarser -> this
  SparseMatrixD restriction;  // this -> coarser
  Eigen::VectorXd inv_diag;
  double omega = 1.0;            // Jacobi damping
  std::vector<Index> functions;  // the function of each row (empty: the row itself)
};

class PMultigrid {
 public:
  PMultigrid(std::vector<PmgLevel> levels, const PmgSettings& s);
  // V-cycles from x until ||r|| / ||r_0|| < tolerance or max_cycles.
  IterationReport solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                        int max_cycles) const;
  const std::vector<PmgLevel>& levels() const { return levels_; }
  // Total CG iterations of the coarse solves of the last solve().
  long coarse_iterations() const { return coarse_iterations_; }

 private:
  void smooth(const PmgLevel& L, const Eigen::VectorXd& b, Eigen::VectorXd& x, int steps,
              bool forward) const;

  std::vector<PmgLevel> levels_;
  PmgSettings s_;
  mutable long coarse_iterations_ = 0;
};

// The hierarchy of the B-splines of degree p, p-1, ..., 1 on g with matrices
// sum_k w_k phi_i(x_k) phi_j(x_k) over the point set (exact Gauss points: 004; particles and
// their masses: MPM). keep_fine[i] != 0 keeps function i of degree p; on the coarser levels a
// function is kept when it has mass and is not on a side of `fixed_sides` ((direction, side)
// pairs; the functions that do not vanish there). The solution vectors are over the kept
// functions of degree p, in increasing order. `fine`, when given, replaces the degree-p matrix
// of the point set (all functions; an MPM run's assembled matrix, whatever its mapping).
template <int Dim>
PMultigrid spline_pmg(const Grid<Dim>& g, int p, const PointSet<Dim>& pts,
                      const std::vector<unsigned char>& keep_fine,
                      const std::vector<std::pair<int, int>>& fixed_sides, const PmgSettings& s,
                      const SparseMatrixD* fine = nullptr);

// Whether function i of a tensor grid of n[d] functions per direction (x fastest) lies on one of
// the sides (direction, side 0: lower / 1: upper): a coarse level leaves these out (spline_pmg,
// parallel/distributed_pmg.cpp).
template <int Dim>
bool on_spline_side(Index i, const IVec<Dim>& n, const std::vector<std::pair<int, int>>& sides) {
  for (int d = 0; d < Dim; ++d) {
    const Index c = i % n[d];
    i /= n[d];
    for (const auto& [dir, side] : sides)
      if (dir == d && c == (side == 0 ? 0 : n[d] - 1)) return true;
  }
  return false;
}

// The kept rows and columns of A (keep[i] != 0), in increasing order.
SparseMatrixD kept_submatrix(const SparseMatrixD& A, const std::vector<unsigned char>& keep_rows,
                             const std::vector<unsigned char>& keep_cols);

}  // namespace mpm
