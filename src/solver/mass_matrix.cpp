#include "solver/mass_matrix.hpp"

#include <algorithm>
#include <stdexcept>

#include "solver/ldlt_pivots.hpp"

namespace mpm {

const Eigen::SparseMatrix<double>& ConsistentMass::summed() {
  if (!summed_) {
    summed_matrix_.resize(n_, n_);
    summed_matrix_.setFromTriplets(triplets_.begin(), triplets_.end());
    summed_ = true;
    if (std::find(lumped_.begin(), lumped_.end(), 1) != lumped_.end()) lump_rows();
  }
  return summed_matrix_;
}

void ConsistentMass::lump_rows() {
  if (static_cast<Index>(lumped_.size()) != n_)
    throw std::logic_error("ConsistentMass: set_lumped does not cover every DOF");
  const auto lumped = [&](Index i) { return lumped_[static_cast<std::size_t>(i)] != 0; };
  // Entry (i, j) moves onto row i's diagonal, so each row keeps its sum to round-off even where
  // the assembly is symmetric only to round-off (TLS's (w_a rw) w_b against (w_b rw) w_a); the
  // moved entries are summed in the order of the stored entries, the same on every run.
  std::vector<double> moved(static_cast<std::size_t>(n_), 0.0);
  std::vector<Triplet> t;
  t.reserve(static_cast<std::size_t>(summed_matrix_.nonZeros()));
  for (Index k = 0; k < summed_matrix_.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(summed_matrix_, k); it; ++it) {
      const Index i = it.row(), j = it.col();
      if (i != j && (lumped(i) || lumped(j)))
        moved[static_cast<std::size_t>(i)] += it.value();
      else
        t.emplace_back(i, j, it.value());
    }
  for (Index j = 0; j < n_; ++j)
    if (moved[static_cast<std::size_t>(j)] != 0.0)
      t.emplace_back(j, j, moved[static_cast<std::size_t>(j)]);
  summed_matrix_.setFromTriplets(t.begin(), t.end());
}

bool ConsistentMass::factorize_kept(int slot) {
  const auto keep = [&](Index i) { return kept_[static_cast<std::size_t>(i)] != 0; };
  // The kept entries of the summed matrix: each is the sum of the same triplets, in the same
  // order, as when the kept triplets themselves were summed (an entry's triplets are all kept
  // or all dropped), so the matrix is the same to the last bit.
  const auto& all = summed();
  std::vector<Triplet> t;
  t.reserve(static_cast<std::size_t>(all.nonZeros() + n_));
  for (Index k = 0; k < all.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(all, k); it; ++it)
      if (keep(it.row()) && keep(it.col())) t.emplace_back(it.row(), it.col(), it.value());
  for (Index i = 0; i < n_; ++i)
    if (!keep(i)) t.emplace_back(i, i, 1.0);
  const auto s = static_cast<std::size_t>(slot);
  auto& M = M_[s];
  M.resize(n_, n_);
  M.setFromTriplets(t.begin(), t.end());
  switch (settings_.kind) {
    case MassSolver::Direct:
    case MassSolver::Cg:
      return factorize_matrix(slot);
    case MassSolver::Pmg: {
      if (!pmg_builder) throw std::logic_error("ConsistentMass: pmg without a hierarchy builder");
      if (!(M.diagonal().array() > 0.0).all()) return false;
      kept_index_[s].clear();
      for (Index i = 0; i < n_; ++i)
        if (keep(i)) kept_index_[s].push_back(i);
      // The fine level is the assembled matrix itself (whatever the mapping assembled).
      pmg_[s] = std::make_unique<PMultigrid>(pmg_builder(kept_, slot, summed()));
      return true;
    }
  }
  return false;
}

bool ConsistentMass::factorize_matrix(int slot) {
  const auto s = static_cast<std::size_t>(slot);
  const auto& M = M_[s];
  if (settings_.kind == MassSolver::Cg) return (M.diagonal().array() > 0.0).all();
  auto& solver = solver_[s];
  solver.compute(M);
  // Singular when a pivot is zero to working precision, whatever its sign (ldlt_pivots.hpp).
  return ldlt_pivots_above_roundoff(solver, M);
}

bool ConsistentMass::factorize_coupled(int dim, std::span<const double> projector) {
  if (settings_.kind == MassSolver::Pmg)
    throw std::logic_error("ConsistentMass: pmg has no hierarchy for the coupled system");
  const auto d = static_cast<std::size_t>(dim), dd = d * d;
  const auto block = [&](Index i) { return projector.data() + static_cast<std::size_t>(i) * dd; };
  auto zero = [&](Index i) {
    const double* p = block(i);
    return std::all_of(p, p + dd, [](double v) { return v == 0.0; });
  };
  std::vector<unsigned char> eliminated(static_cast<std::size_t>(n_));
  for (Index i = 0; i < n_; ++i) eliminated[static_cast<std::size_t>(i)] = zero(i) ? 1 : 0;
  const auto& all = summed();
  std::vector<Triplet> t;
  t.reserve(static_cast<std::size_t>(all.nonZeros()) * dd + static_cast<std::size_t>(n_) * dd);
  for (Index k = 0; k < all.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(all, k); it; ++it) {
      const Index i = it.row(), j = it.col();
      if (eliminated[static_cast<std::size_t>(i)] || eliminated[static_cast<std::size_t>(j)])
        continue;
      // Block (i, j) of P (M (x) I) P: M_ij P_i P_j.
      const double *pi = block(i), *pj = block(j);
      for (std::size_t a = 0; a < d; ++a)
        for (std::size_t b = 0; b < d; ++b) {
          double v = 0.0;
          for (std::size_t c = 0; c < d; ++c) v += pi[a * d + c] * pj[c * d + b];
          if (v != 0.0)
            t.emplace_back(static_cast<Index>(d) * i + static_cast<Index>(a),
                           static_cast<Index>(d) * j + static_cast<Index>(b), it.value() * v);
        }
    }
  for (Index i = 0; i < n_; ++i) {  // I - P_i
    const double* p = block(i);
    for (std::size_t a = 0; a < d; ++a)
      for (std::size_t b = 0; b < d; ++b) {
        const double v = (a == b ? 1.0 : 0.0) - p[a * d + b];
        if (v != 0.0)
          t.emplace_back(static_cast<Index>(d) * i + static_cast<Index>(a),
                         static_cast<Index>(d) * i + static_cast<Index>(b), v);
      }
  }
  auto& M = M_[static_cast<std::size_t>(kCoupled)];
  M.resize(static_cast<Index>(d) * n_, static_cast<Index>(d) * n_);
  M.setFromTriplets(t.begin(), t.end());
  return factorize_matrix(kCoupled);
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
