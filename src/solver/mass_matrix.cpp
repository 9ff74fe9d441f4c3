#include "solver/mass_matrix.hpp"

#include <stdexcept>

namespace mpm {

bool ConsistentMass::factorize_kept(int slot) {
  const auto keep = [&](Index i) { return kept_[static_cast<std::size_t>(i)] != 0; };
  std::vector<Triplet> t;
  t.reserve(triplets_.size() + static_cast<std::size_t>(n_));
  for (const auto& e : triplets_)
    if (keep(e.row()) && keep(e.col())) t.push_back(e);
  for (Index i = 0; i < n_; ++i)
    if (!keep(i)) t.emplace_back(i, i, 1.0);
  const auto s = static_cast<std::size_t>(slot);
  auto& M = M_[s];
  M.resize(n_, n_);
  M.setFromTriplets(t.begin(), t.end());
  switch (settings_.kind) {
    case MassSolver::Direct: {
      auto& solver = solver_[s];
      solver.compute(M);
      return solver.info() == Eigen::Success && (solver.vectorD().array() > 0.0).all();
    }
    case MassSolver::Cg:
      return (M.diagonal().array() > 0.0).all();
    case MassSolver::Pmg: {
      if (!pmg_builder) throw std::logic_error("ConsistentMass: pmg without a hierarchy builder");
      if (!(M.diagonal().array() > 0.0).all()) return false;
      kept_index_[s].clear();
      for (Index i = 0; i < n_; ++i)
        if (keep(i)) kept_index_[s].push_back(i);
      // The fine level is the assembled matrix itself (whatever the mapping assembled).
      SparseMatrixD fine(n_, n_);
      fine.setFromTriplets(triplets_.begin(), triplets_.end());
      pmg_[s] = std::make_unique<PMultigrid>(pmg_builder(kept_, slot, fine));
      return true;
    }
  }
  return false;
}

Eigen::VectorXd ConsistentMass::solve(const Eigen::VectorXd& rhs, int slot,
                                      IterationReport* report) const {
  const auto s = static_cast<std::size_t>(slot);
  IterationReport rep;
  Eigen::VectorXd x;
  switch (settings_.kind) {
    case MassSolver::Direct:
      return solver_[s].solve(rhs);
    case MassSolver::Cg:
      x = Eigen::VectorXd::Zero(rhs.size());
      rep = conjugate_gradient(M_[s], rhs, x, settings_.tolerance, settings_.max_iterations);
      break;
    case MassSolver::Pmg: {
      const auto& idx = kept_index_[s];
      Eigen::VectorXd b(static_cast<Index>(idx.size())), y;
      for (std::size_t k = 0; k < idx.size(); ++k) b[static_cast<Index>(k)] = rhs[idx[k]];
      rep = pmg_[s]->solve(b, y, settings_.tolerance, settings_.max_iterations);
      x = Eigen::VectorXd::Zero(rhs.size());
      for (std::size_t k = 0; k < idx.size(); ++k) x[idx[k]] = y[static_cast<Index>(k)];
      break;
    }
  }
  if (report) *report = std::move(rep);
  return x;
}

}  // namespace mpm
