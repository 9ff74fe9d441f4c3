#pragma once
// Grid solves M y = r for one right-hand side per direction (D eq. 2.34-2.35, 2.46, 2.49).
// Lumped: y_i = r_i / m_i on active DOFs. Consistent: the sparse symmetric matrix assembled by
// the mapping, with Dirichlet DOFs and inactive DOFs eliminated, solved by method.mass_solver:
//   direct  Eigen's simplicial LDL^T, factorised once per step (the matrix is banded with
//           bandwidth given by the basis support): exact to round-off;
//   cg      conjugate gradients from zero to a relative residual (004 eq. 4.53);
//   pmg     p-multigrid V-cycles over the B-spline degrees p .. 1 (solver/iterative.hpp), the
//           coarse matrices rediscretised at the particles.
// Where the Dirichlet conditions differ between velocity components (a roller fixes only the
// normal one), each component has its own elimination (slot = component).
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <array>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "grid/grid_state.hpp"
#include "solver/iterative.hpp"

namespace mpm {

enum class MassSolver { Direct, Cg, Pmg };

struct MassSolverSettings {
  MassSolver kind = MassSolver::Direct;
  double tolerance = 1e-12;   // relative residual of cg and pmg
  int max_iterations = 5000;  // CG iterations or V-cycles before the run stops
  PmgSettings pmg;
};

class ConsistentMass {
 public:
  using Triplet = Eigen::Triplet<double>;
  // The p-multigrid hierarchy for the kept DOFs of a slot (keep[i] != 0) and the fine matrix
  // (all DOFs): set by the stage that knows the grid, the basis degree and the particles
  // (scheme/grid_stages.cpp).
  using PmgBuilder = std::function<PMultigrid(const std::vector<unsigned char>& keep, int slot,
                                              const SparseMatrixD& fine)>;

  void begin(Index ndofs) {
    n_ = ndofs;
    triplets_.clear();
    lumped_.clear();
    summed_ = false;
  }
  void add(Index i, Index j, double value) { triplets_.emplace_back(i, j, value); }

  // Partial lumping (method.partial_lumping; D 7.2): the rows and columns of the DOFs with
  // rows[i] != 0 are lumped in the next assembly (empty: none). Each off-diagonal entry M_ij
  // with i or j lumped moves onto the diagonal M_ii (and M_ji onto M_jj): every row keeps its
  // sum (the lumped mass m_i, hence the conserved totals), the matrix stays symmetric, and a
  // lumped DOF's row is its lumped mass alone. For a matrix with non-negative entries (particle
  // quadrature of non-negative bases) the change is the sum of M_ij (e_i - e_j)(e_i - e_j)^T,
  // positive semi-definite: the smallest eigenvalue does not fall. Set after the mapping's
  // begin() and before factorize (scheme/grid_stages.cpp).
  void set_lumped(std::vector<unsigned char> rows) {
    lumped_ = std::move(rows);
    summed_ = false;
  }

  static constexpr int kSlots = 3;

  void configure(const MassSolverSettings& s) { settings_ = s; }
  const MassSolverSettings& settings() const { return settings_; }
  PmgBuilder pmg_builder;

  // Assemble with DOF `i` kept when keep(i), eliminated (identity row) otherwise; factorise
  // (direct) or prepare (cg: the matrix; pmg: the hierarchy) into `slot` (0 .. kSlots - 1).
  // Returns false when the matrix is not positive definite (a singular particle distribution;
  // for cg and pmg: a non-positive diagonal entry).
  template <class Keep>
  bool factorize(Keep&& keep, int slot = 0) {
    kept_.resize(static_cast<std::size_t>(n_));
    for (Index i = 0; i < n_; ++i) kept_[static_cast<std::size_t>(i)] = keep(i) ? 1 : 0;
    return factorize_kept(slot);
  }

  // All velocity components in one system, for DOFs whose admissible velocities are not a set
  // of components (a roller on an inclined boundary; GridState::projected): with P the
  // block-diagonal orthogonal projector onto the admissible velocities (`projector`: per DOF a
  // dim x dim block, row-major; zero for an eliminated DOF), the Galerkin system on them is
  //   A y = P r,  A = P (M (x) I_dim) P + (I - P),
  // symmetric positive definite when M is on the kept DOFs; its solution has (I - P) y = 0.
  // Unknown a of DOF i is entry dim i + a. Factorised (direct) or kept (cg) in slot kCoupled;
  // pmg has no hierarchy for it (logic_error: the run settings refuse the combination).
  static constexpr int kCoupled = kSlots;
  bool factorize_coupled(int dim, std::span<const double> projector);

  // y = M^-1 rhs with the factorisation (or hierarchy) of `slot`. For cg and pmg `report`, when
  // given, receives the iterations and residuals (converged false: the caller stops the run).
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs, int slot = 0,
                        IterationReport* report = nullptr) const;
  // The sum of the triplets since begin(), over all DOFs, without eliminations: in a
  // distributed run the matrix of this rank's particles, which the distributed CG applies
  // (scheme/grid_stages.cpp).
  const Eigen::SparseMatrix<double>& assembled() { return summed(); }
  const Eigen::SparseMatrix<double>& matrix(int slot = 0) const {
    return M_[static_cast<std::size_t>(slot)];
  }

 private:
  // Out of line (mass_matrix.cpp): the sparse factorisation is a large share of the compile
  // time of every unit that steps a simulation.
  bool factorize_kept(int slot);
  // The particles' contributions summed into one sparse matrix over all DOFs, once per
  // assembly: the slots (components with their own Dirichlet DOFs) and pmg's fine level start
  // from it instead of each summing the triplets again (the per-particle triplets, 27^2 per
  // particle for quadratic B-splines in 3D, were 60 % of a consistent-mass step).
  const Eigen::SparseMatrix<double>& summed();
  void lump_rows();  // set_lumped's change of summed_matrix_
  Eigen::SparseMatrix<double> summed_matrix_;
  bool summed_ = false;

  Index n_ = 0;
  MassSolverSettings settings_;
  std::vector<Triplet> triplets_;
  std::vector<unsigned char> kept_;                        // keep(i) of the latest factorize
  std::vector<unsigned char> lumped_;                      // set_lumped
  std::array<Eigen::SparseMatrix<double>, kSlots + 1> M_;  // [kCoupled]: the coupled system
  std::array<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>, kSlots + 1> solver_;
  bool factorize_matrix(int slot);
  // pmg: per slot the kept DOFs (increasing) and the hierarchy over them.
  std::array<std::vector<Index>, kSlots> kept_index_;
  std::array<std::unique_ptr<PMultigrid>, kSlots> pmg_;
};

}  // namespace mpm
