#pragma once
// Grid solves M y = r for one right-hand side per direction (D eq. 2.34-2.35, 2.46, 2.49).
// Lumped: y_i = r_i / m_i on active DOFs. Consistent: the sparse symmetric matrix assembled by
// the mapping, factorised once per step (Eigen's simplicial LDL^T; the matrix is banded with
// bandwidth given by the basis support), Dirichlet DOFs and inactive DOFs eliminated.
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
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

  // Assemble with DOF `i` kept when keep(i), eliminated (identity row) otherwise; factorise.
  // Returns false when the matrix is not positive definite (a singular particle distribution).
  template <class Keep>
  bool factorize(Keep&& keep) {
    std::vector<Triplet> t;
    t.reserve(triplets_.size() + static_cast<std::size_t>(n_));
    for (const auto& e : triplets_)
      if (keep(e.row()) && keep(e.col())) t.push_back(e);
    for (Index i = 0; i < n_; ++i)
      if (!keep(i)) t.emplace_back(i, i, 1.0);
    M_.resize(n_, n_);
    M_.setFromTriplets(t.begin(), t.end());
    solver_.compute(M_);
    return solver_.info() == Eigen::Success && (solver_.vectorD().array() > 0.0).all();
  }

  Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const { return solver_.solve(rhs); }
  const Eigen::SparseMatrix<double>& matrix() const { return M_; }

 private:
  Index n_ = 0;
  std::vector<Triplet> triplets_;
  Eigen::SparseMatrix<double> M_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver_;
};

}  // namespace mpm
