// Conjugate gradients and p-multigrid (solver/iterative.hpp; 004 sections 4.6-4.7).
#include "solver/iterative.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace mpm {

std::string_view name_of(Smoother s) {
  return s == Smoother::GaussSeidel ? "gauss-seidel" : "jacobi";
}
std::string_view name_of(Restriction r) {
  return r == Restriction::Transpose ? "transpose" : "projection";
}

IterationReport conjugate_gradient(const SparseMatrixD& A, const Eigen::VectorXd& b,
                                   Eigen::VectorXd& x, double tolerance, int max_iterations) {
  return conjugate_gradient(
      [&A](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y.noalias() = A * v; }, b, x, tolerance,
      max_iterations);
}

IterationReport conjugate_gradient(const LinearOperator& A, const Eigen::VectorXd& b,
                                   Eigen::VectorXd& x, double tolerance, int max_iterations) {
  return conjugate_gradient(
      A, b, x, tolerance, max_iterations,
      [](const Eigen::VectorXd& u, const Eigen::VectorXd& v) { return u.dot(v); });
}

IterationReport conjugate_gradient(const LinearOperator& A, const Eigen::VectorXd& b,
                                   Eigen::VectorXd& x, double tolerance, int max_iterations,
                                   const InnerProduct& dot) {
  IterationReport rep;
  if (x.size() != b.size()) x = Eigen::VectorXd::Zero(b.size());
  Eigen::VectorXd Ax(b.size());
  A(x, Ax);
  Eigen::VectorXd r = b - Ax;
  const double r0 = std::sqrt(dot(r, r));
  rep.history.push_back(1.0);
  if (r0 == 0.0) {
    rep.converged = true;
    return rep;
  }
  Eigen::VectorXd d = r, Ad(b.size());
  double rr = dot(r, r);
  while (rep.iterations < max_iterations) {
    A(d, Ad);
    const double dAd = dot(d, Ad);
    if (!(dAd > 0.0)) break;  // not positive definite (or a breakdown): not converged
    const double alpha = rr / dAd;
    x += alpha * d;
    r -= alpha * Ad;
    ++rep.iterations;
    const double rr_new = dot(r, r);
    rep.relative_residual = std::sqrt(rr_new) / r0;
    rep.history.push_back(rep.relative_residual);
    if (rep.relative_residual < tolerance) {
      rep.converged = true;
      break;
    }
    d = r + (rr_new / rr) * d;
    rr = rr_new;
  }
  return rep;
}

double power_start(Index g) {
  const double t = static_cast<double>(g) * 0.6180339887498949;
  return 1.0 + (t - std::floor(t));
}

double jacobi_damping(const LinearOperator& A, const Eigen::VectorXd& inv_diag,
                      Eigen::VectorXd start, const InnerProduct& dot) {
  Eigen::VectorXd& v = start;
  const double vv = dot(v, v);
  if (!(vv > 0.0)) return 1.0;  // no function in the system: nothing to smooth
  v /= std::sqrt(vv);
  Eigen::VectorXd Av(v.size());
  double lambda = 1.0;
  for (int it = 0; it < 50; ++it) {
    A(v, Av);
    Av = inv_diag.cwiseProduct(Av);
    lambda = std::sqrt(dot(Av, Av));  // |v| = 1
    if (!(lambda > 0.0)) return 1.0;
    v = Av / lambda;
  }
  return 1.0 / (1.05 * lambda);
}

namespace {
void vcycle(const std::vector<PmgLevelOps>& levels, const PmgSettings& s, std::size_t k,
            const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, long& coarse) {
  const PmgLevelOps& L = levels[k];
  Eigen::VectorXd r(L.size);
  if (k + 1 == levels.size()) {
    // The coarsest level: CG on the residual equation from zero (004), to 1e-4 when there are
    // finer levels; a one-level hierarchy (p = 1) is solved to the outer tolerance.
    L.A(x, r);
    r = b - r;
    Eigen::VectorXd e = Eigen::VectorXd::Zero(L.size);
    const double tol = levels.size() == 1 ? tolerance : s.coarse_tolerance;
    const IterationReport rep = conjugate_gradient(L.A, r, e, tol, s.coarse_max_iterations, L.dot);
    coarse += rep.iterations;
    x += e;
    return;
  }
  L.smooth(b, x, s.pre, true);
  if (!s.coarse_correction) {
    L.smooth(b, x, s.post, false);
    return;
  }
  L.A(x, r);
  r = b - r;
  const PmgLevelOps& C = levels[k + 1];
  Eigen::VectorXd rc(C.size), ec = Eigen::VectorXd::Zero(C.size);
  L.restriction(r, rc);
  vcycle(levels, s, k + 1, rc, ec, tolerance, coarse);
  L.prolong(ec, r);
  x += r;
  L.smooth(b, x, s.post, false);
}
}  // namespace

IterationReport pmg_cycles(const std::vector<PmgLevelOps>& levels, const PmgSettings& s,
                           const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                           int max_cycles, long& coarse_iterations) {
  IterationReport rep;
  coarse_iterations = 0;
  const PmgLevelOps& F = levels.front();
  if (x.size() != b.size()) x = Eigen::VectorXd::Zero(b.size());
  Eigen::VectorXd r(b.size());
  const auto residual = [&] {
    F.A(x, r);
    r = b - r;
    return std::sqrt(F.dot(r, r));
  };
  const double r0 = residual();
  rep.history.push_back(1.0);
  if (r0 == 0.0) {
    rep.converged = true;
    return rep;
  }
  while (rep.iterations < max_cycles) {
    vcycle(levels, s, 0, b, x, tolerance, coarse_iterations);
    ++rep.iterations;
    rep.relative_residual = residual() / r0;
    rep.history.push_back(rep.relative_residual);
    if (rep.relative_residual < tolerance) {
      rep.converged = true;
      break;
    }
    if (!std::isfinite(rep.relative_residual)) break;
  }
  return rep;
}

PMultigrid::PMultigrid(std::vector<PmgLevel> levels, const PmgSettings& s)
    : levels_(std::move(levels)), s_(s) {
  const InnerProduct dot = [](const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
    return u.dot(v);
  };
  for (auto& L : levels_) {
    L.inv_diag = L.A.diagonal().cwiseInverse();
    if (s_.smoother == Smoother::Jacobi) {
      Eigen::VectorXd start(L.A.rows());
      for (Index i = 0; i < start.size(); ++i)
        start[i] = power_start(L.functions.empty() ? i : L.functions[static_cast<std::size_t>(i)]);
      L.omega = jacobi_damping(
          [&L](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y.noalias() = L.A * v; }, L.inv_diag,
          std::move(start), dot);
    }
  }
}

void PMultigrid::smooth(const PmgLevel& L, const Eigen::VectorXd& b, Eigen::VectorXd& x, int steps,
                        bool forward) const {
  const SparseMatrixD& A = L.A;  // symmetric: column i holds row i
  const Index n = A.cols();
  for (int k = 0; k < steps; ++k) {
    if (s_.smoother == Smoother::Jacobi) {
      x += L.omega * L.inv_diag.cwiseProduct(b - A * x);
      continue;
    }
    for (Index t = 0; t < n; ++t) {
      const Index i = forward ? t : n - 1 - t;
      double sum = b[i], diag = 0.0;
      for (SparseMatrixD::InnerIterator it(A, i); it; ++it) {
        if (it.row() == i)
          diag = it.value();
        else
          sum -= it.value() * x[it.row()];
      }
      x[i] = sum / diag;
    }
  }
}

IterationReport PMultigrid::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                                  int max_cycles) const {
  // The operations bound to this hierarchy's matrices, for this solve (a PMultigrid moves).
  std::vector<PmgLevelOps> ops(levels_.size());
  for (std::size_t k = 0; k < levels_.size(); ++k) {
    const PmgLevel& L = levels_[k];
    PmgLevelOps& o = ops[k];
    o.size = L.A.rows();
    o.A = [&L](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y.noalias() = L.A * v; };
    o.dot = [](const Eigen::VectorXd& u, const Eigen::VectorXd& v) { return u.dot(v); };
    o.smooth = [this, &L](const Eigen::VectorXd& rhs, Eigen::VectorXd& v, int steps, bool fwd) {
      smooth(L, rhs, v, steps, fwd);
    };
    if (k + 1 == levels_.size()) continue;
    o.prolong = [&L](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y.noalias() = L.prolong * v; };
    o.restriction = [&L](const Eigen::VectorXd& v, Eigen::VectorXd& y) {
      y.noalias() = L.restriction * v;
    };
  }
  return pmg_cycles(ops, s_, b, x, tolerance, max_cycles, coarse_iterations_);
}

SparseMatrixD kept_submatrix(const SparseMatrixD& A, const std::vector<unsigned char>& keep_rows,
                             const std::vector<unsigned char>& keep_cols) {
  std::vector<Index> row_to(keep_rows.size(), -1), col_to(keep_cols.size(), -1);
  Index nr = 0, nc = 0;
  for (std::size_t i = 0; i < keep_rows.size(); ++i)
    if (keep_rows[i]) row_to[i] = nr++;
  for (std::size_t j = 0; j < keep_cols.size(); ++j)
    if (keep_cols[j]) col_to[j] = nc++;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(A.nonZeros()));
  for (Index j = 0; j < A.outerSize(); ++j)
    for (SparseMatrixD::InnerIterator it(A, j); it; ++it) {
      const Index r = row_to[static_cast<std::size_t>(it.row())];
      const Index c = col_to[static_cast<std::size_t>(it.col())];
      if (r >= 0 && c >= 0) t.emplace_back(r, c, it.value());
    }
  SparseMatrixD out(nr, nc);
  out.setFromTriplets(t.begin(), t.end());
  return out;
}

template <int Dim>
PMultigrid spline_pmg(const Grid<Dim>& g, int p, const PointSet<Dim>& pts,
                      const std::vector<unsigned char>& keep_fine,
                      const std::vector<std::pair<int, int>>& fixed_sides, const PmgSettings& s,
                      const SparseMatrixD* fine) {
  if (p < 1 || p > 5) throw InputError(fmt::format("p-multigrid: degree {} (1 to 5)", p));
  // Per degree q = p .. 1: the full mass matrix, its lumped diagonal and the kept functions.
  const int nlev = p;
  std::vector<SparseMatrixD> M(static_cast<std::size_t>(nlev));
  std::vector<Eigen::VectorXd> lumped(static_cast<std::size_t>(nlev));
  std::vector<std::vector<unsigned char>> keep(static_cast<std::size_t>(nlev));
  for (int k = 0; k < nlev; ++k) {
    const int q = p - k;
    const auto K = static_cast<std::size_t>(k);
    M[K] = k == 0 && fine ? *fine : spline_mass(g, q, q, pts);
    lumped[K] = M[K] * Eigen::VectorXd::Ones(M[K].cols());
    if (k == 0) {
      if (static_cast<Index>(keep_fine.size()) != M[K].rows())
        throw std::logic_error("spline_pmg: keep_fine has the wrong size");
      keep[K] = keep_fine;
      continue;
    }
    keep[K].assign(static_cast<std::size_t>(M[K].rows()), 1);
    IVec<Dim> n;
    for (int d = 0; d < Dim; ++d) n[d] = g.cells[d] + q;
    for (Index i = 0; i < M[K].rows(); ++i)
      if (!(lumped[K][i] > 0.0) || on_spline_side<Dim>(i, n, fixed_sides))
        keep[K][static_cast<std::size_t>(i)] = 0;
  }
  std::vector<PmgLevel> levels(static_cast<std::size_t>(nlev));
  for (int k = 0; k < nlev; ++k) {
    const auto K = static_cast<std::size_t>(k);
    levels[K].degree = p - k;
    levels[K].A = kept_submatrix(M[K], keep[K], keep[K]);
    for (std::size_t i = 0; i < keep[K].size(); ++i)
      if (keep[K][i]) levels[K].functions.push_back(static_cast<Index>(i));
    if (k + 1 == nlev) continue;
    // I_{q-1}^{q} = (M_q^L)^-1 M_{q,q-1} (the lumped L2 projection onto the finer space).
    const int q = p - k;
    const SparseMatrixD Mx = spline_mass(g, q, q - 1, pts);
    Eigen::VectorXd inv = lumped[K];
    for (Index i = 0; i < inv.size(); ++i) inv[i] = inv[i] > 0.0 ? 1.0 / inv[i] : 0.0;
    const SparseMatrixD P = inv.asDiagonal() * Mx;
    levels[K].prolong = kept_submatrix(P, keep[K], keep[K + 1]);
    if (s.restriction == Restriction::Transpose) {
      levels[K].restriction = levels[K].prolong.transpose();
    } else {
      Eigen::VectorXd invc = lumped[K + 1];
      for (Index i = 0; i < invc.size(); ++i) invc[i] = invc[i] > 0.0 ? 1.0 / invc[i] : 0.0;
      const SparseMatrixD R = invc.asDiagonal() * SparseMatrixD(Mx.transpose());
      levels[K].restriction = kept_submatrix(R, keep[K + 1], keep[K]);
    }
  }
  return PMultigrid(std::move(levels), s);
}

template PMultigrid spline_pmg<1>(const Grid<1>&, int, const PointSet<1>&,
                                  const std::vector<unsigned char>&,
                                  const std::vector<std::pair<int, int>>&, const PmgSettings&,
                                  const SparseMatrixD*);
template PMultigrid spline_pmg<2>(const Grid<2>&, int, const PointSet<2>&,
                                  const std::vector<unsigned char>&,
                                  const std::vector<std::pair<int, int>>&, const PmgSettings&,
                                  const SparseMatrixD*);
template PMultigrid spline_pmg<3>(const Grid<3>&, int, const PointSet<3>&,
                                  const std::vector<unsigned char>&,
                                  const std::vector<std::pair<int, int>>&, const PmgSettings&,
                                  const SparseMatrixD*);

}  // namespace mpm
