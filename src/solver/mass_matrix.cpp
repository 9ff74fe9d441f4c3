#include "solver/mass_matrix.hpp"

namespace mpm {

bool ConsistentMass::factorize_kept(int slot) {
  const auto keep = [&](Index i) { return kept_[static_cast<std::size_t>(i)] != 0; };
  std::vector<Triplet> t;
  t.reserve(triplets_.size() + static_cast<std::size_t>(n_));
  for (const auto& e : triplets_)
    if (keep(e.row()) && keep(e.col())) t.push_back(e);
  for (Index i = 0; i < n_; ++i)
    if (!keep(i)) t.emplace_back(i, i, 1.0);
  auto& M = M_[static_cast<std::size_t>(slot)];
  auto& solver = solver_[static_cast<std::size_t>(slot)];
  M.resize(n_, n_);
  M.setFromTriplets(t.begin(), t.end());
  solver.compute(M);
  return solver.info() == Eigen::Success && (solver.vectorD().array() > 0.0).all();
}

Eigen::VectorXd ConsistentMass::solve(const Eigen::VectorXd& rhs, int slot) const {
  return solver_[static_cast<std::size_t>(slot)].solve(rhs);
}

}  // namespace mpm
