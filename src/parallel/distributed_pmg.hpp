#pragma once
// p-multigrid for consistent mass on distributed vectors (004 sections 4.6-4.7): the
// cycle of solver/iterative.hpp (pmg_cycles) on operators each process applies with the matrices
// of its own particles, summed over the processes that share a function (state/dof_sharing.hpp),
// the way the distributed CG applies the mass matrix (scheme/grid_stages.cpp).
//
// The hierarchy is the one process's (spline_pmg): the fine level is the matrix the mapping
// assembled, the levels of degree p-1 .. 1 are rediscretised at the particles with their masses
// as weights, the prolongation is (M_q^L)^-1 M_{q,q-1} and the restriction its transpose (or the
// lumped projection the other way), the coarsest level is solved by CG to 1e-4. Each process
// holds every level's vectors over the whole grid and works on its window of them, the
// functions its particles touch on that level (a DofRanges per level). A kept function is the
// one process's: active and not fixed on the fine level, with mass and off the sides that the
// fixed DOFs cover on the coarse ones. Every inner product sums over the functions each process
// owns, combined in rank order, so every process takes the same cycles and the answers are the
// one process's to round-off.
//
// The smoother is Jacobi's, whose sweeps are such products; Gauss-Seidel's sweeps are sequential
// through the whole numbering and are refused on several processes (driver/stepper_impl.hpp).
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "solver/iterative.hpp"
#include "state/simulation.hpp"

namespace mpm {

// The sides (direction, side) of the degree-p grid of functions on which every DOF is fixed in
// the components `bit`: their functions are left out of the coarse levels (spline_pmg's
// fixed_sides).
template <int Dim>
std::vector<std::pair<int, int>> spline_fixed_sides(const RunState<Dim>& sim, std::uint8_t bit);

template <int Dim>
class DistributedPmg {
 public:
  // The levels from this process's own particles and its part of the assembled consistent
  // matrix, after the nodal masses are shared and the active DOFs set (stages::after_mass).
  // Collective.
  explicit DistributedPmg(RunState<Dim>& sim);
  // Whether every kept fine function has a positive diagonal entry on every process (else the
  // matrix is singular: the run stops as with one process).
  bool positive() const { return positive_; }
  // x = M^-1 b on the kept fine functions of `slot` (a velocity component with its own fixed
  // DOFs, or 0 for all): b and x over all the fine functions, read and written on this
  // process's window. Collective.
  IterationReport solve(int slot, const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  // CG iterations of the coarse solves of the last solve().
  long coarse_iterations() const { return coarse_iterations_; }

 private:
  struct Level {
    int degree = 1;
    SparseMatrixD M;       // this process's part (the fine level: what the mapping assembled)
    SparseMatrixD cross;   // M_{q,q-1} of this process's particles (not on the coarsest)
    SparseMatrixD crossT;  // its transpose
    DofRanges ranges;      // every process's window on this level
    Index first = 0, end = 0;
    std::vector<unsigned char> owned;  // per function of the window: counted here in sums
    Eigen::VectorXd inv_lumped;        // 1 / (M_q^L)_ii on the window (0 without mass)
    Eigen::VectorXd diag;              // M_ii on the window
    Index size() const { return M.rows(); }
  };
  struct Slot {
    std::vector<std::vector<unsigned char>> keep;  // per level, over the level (0 off the window)
    std::vector<Eigen::VectorXd> inv_diag;         // per level: 1 / A_ii on kept functions, else 0
    std::vector<double> omega;                     // per level: Jacobi's damping
  };

  void share(const Level& L, Eigen::VectorXd& v, int tag) const;
  std::vector<PmgLevelOps> operators(const Slot& s) const;

  const Comm* comm_;
  PmgSettings pmg_;
  double tolerance_;
  int max_cycles_;
  std::vector<Level> levels_;
  std::array<Slot, 3> slots_;
  bool positive_ = true;
  mutable long coarse_iterations_ = 0;
};

}  // namespace mpm
