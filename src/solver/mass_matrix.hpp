#pragma once
// Grid solves M y = r for one right-hand side per direction (D eq. 2.34-2.35, 2.46, 2.49).
// Lumped: y_i = r_i / m_i on active DOFs. Consistent: the sparse symmetric matrix assembled by
// the mapping, factorised once per step (Eigen's simplicial LDL^T; the matrix is banded with
// bandwidth given by the basis support), Dirichlet DOFs and inactive DOFs eliminated. Where the
// Dirichlet conditions differ between velocity components (a roller fixes only the normal one),
// each component has its own elimination and factorisation (slot = component).
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <array>
#include <vector>

#include "grid/grid_state.hpp"

namespace mpm {

class ConsistentMass {
 public:
  using Triplet = Eigen::Triplet<double>;

  void begin(Index ndofs) {
    n_ = ndofs;
    triplets_.clear();
  }
  void add(Index i, Index j, double value) { triplets_.emplace_back(i, j, value); }

  static constexpr int kSlots = 3;

  // Assemble with DOF `i` kept when keep(i), eliminated (identity row) otherwise; factorise into
  // `slot` (0 .. kSlots - 1). Returns false when the matrix is not positive definite (a singular
  // particle distribution).
  template <class Keep>
  bool factorize(Keep&& keep, int slot = 0) {
    kept_.resize(static_cast<std::size_t>(n_));
    for (Index i = 0; i < n_; ++i) kept_[static_cast<std::size_t>(i)] = keep(i) ? 1 : 0;
    return factorize_kept(slot);
  }

  // y = M^-1 rhs with the factorisation of `slot`.
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs, int slot = 0) const;
  const Eigen::SparseMatrix<double>& matrix(int slot = 0) const {
    return M_[static_cast<std::size_t>(slot)];
  }

 private:
  // Out of line (mass_matrix.cpp): the sparse factorisation is a large share of the compile
  // time of every unit that steps a simulation.
  bool factorize_kept(int slot);

  Index n_ = 0;
  std::vector<Triplet> triplets_;
  std::vector<unsigned char> kept_;  // keep(i) of the latest factorize
  std::array<Eigen::SparseMatrix<double>, kSlots> M_;
  std::array<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>, kSlots> solver_;
};

}  // namespace mpm
