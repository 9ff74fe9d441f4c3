// p-multigrid on distributed vectors (parallel/distributed_pmg.hpp; 004 section 4.7).
#include "parallel/distributed_pmg.hpp"

#include <algorithm>
#include <cmath>

#include "core/parallel.hpp"
#include "solver/spline_matrices.hpp"

namespace mpm {

template <int Dim>
std::vector<std::pair<int, int>> spline_fixed_sides(const RunState<Dim>& sim, std::uint8_t bit) {
  const int p = sim.spline_degree;
  IVec<Dim> n;
  for (int d = 0; d < Dim; ++d) n[d] = sim.grid.cells[d] + p;
  const auto& fixed = sim.nodes.fixed;
  std::vector<std::pair<int, int>> sides;
  for (int d = 0; d < Dim; ++d)
    for (int side = 0; side < 2; ++side) {
      bool all = true;
      for (Index i = 0; i < static_cast<Index>(fixed.size()) && all; ++i) {
        Index rem = i, c = 0;
        for (int e = 0; e <= d; ++e) {
          c = rem % n[e];
          rem /= n[e];
        }
        if (c == (side == 0 ? 0 : n[d] - 1))
          all = (fixed[static_cast<std::size_t>(i)] & bit) == bit;
      }
      if (all) sides.emplace_back(d, side);
    }
  return sides;
}

namespace {
// [lo, hi] of the rows of a symmetric matrix that hold an entry (lo > hi: none).
std::array<Index, 2> rows_used(const SparseMatrixD& M) {
  Index lo = M.rows(), hi = -1;
  for (Index k = 0; k < M.outerSize(); ++k)
    if (SparseMatrixD::InnerIterator(M, k)) {
      lo = std::min(lo, k);
      hi = std::max(hi, k);
    }
  return {lo, hi};
}
}  // namespace

template <int Dim>
DistributedPmg<Dim>::DistributedPmg(RunState<Dim>& sim)
    : comm_(sim.comm),
      pmg_(sim.consistent.settings().pmg),
      tolerance_(sim.consistent.settings().tolerance),
      max_cycles_(sim.consistent.settings().max_iterations) {
  const Comm& comm = *comm_;
  const int me = comm.rank();
  const int p = sim.spline_degree;
  // The rediscretisation points: this process's own particles (not the ghosts a reconstruction
  // mapping borrows), their masses as weights.
  PointSet<Dim> pts;
  const auto own = static_cast<std::size_t>(sim.own_particles());
  pts.x.assign(sim.particles.x.begin(), sim.particles.x.begin() + static_cast<std::ptrdiff_t>(own));
  pts.w.assign(sim.particles.mass.begin(),
               sim.particles.mass.begin() + static_cast<std::ptrdiff_t>(own));
  levels_.resize(static_cast<std::size_t>(p));
  for (int k = 0; k < p; ++k) {
    Level& L = levels_[static_cast<std::size_t>(k)];
    const int q = p - k;
    L.degree = q;
    if (k == 0) {
      L.M = sim.consistent.assembled();
      L.ranges = sim.shared;  // the DOFs of the mapping's sums
    } else {
      L.M = spline_mass(sim.grid, q, q, pts);
      L.ranges = DofRanges::gather(comm, rows_used(L.M));
    }
    if (k + 1 < p) {
      L.cross = spline_mass(sim.grid, q, q - 1, pts);
      L.crossT = SparseMatrixD(L.cross.transpose());
    }
    const auto [first, end] = L.ranges.window(me);
    L.first = first;
    L.end = end;
    L.owned.resize(static_cast<std::size_t>(end - first));
    for (Index i = first; i < end; ++i)
      L.owned[static_cast<std::size_t>(i - first)] = L.ranges.owns(me, i) ? 1 : 0;
    // The lumped masses (row sums) and the diagonal, summed over the processes.
    Eigen::VectorXd lumped = L.M * Eigen::VectorXd::Ones(L.size());
    L.diag = L.M.diagonal();
    share(L, lumped, 600 + k);
    share(L, L.diag, 610 + k);
    L.inv_lumped = Eigen::VectorXd::Zero(L.size());
    for (Index i = first; i < end; ++i)
      if (lumped[i] > 0.0) L.inv_lumped[i] = 1.0 / lumped[i];
  }
  // The kept functions and the smoother of each slot (per velocity component when some DOF is
  // fixed in only some of them).
  constexpr std::uint8_t kAll = (1u << Dim) - 1u;
  const int nslots = sim.consistent_per_component ? Dim : 1;
  bool positive = true;
  for (int s = 0; s < nslots; ++s) {
    const auto bit = static_cast<std::uint8_t>(sim.consistent_per_component ? 1u << s : kAll);
    const auto sides = spline_fixed_sides(sim, bit);
    Slot& S = slots_[static_cast<std::size_t>(s)];
    S.keep.resize(levels_.size());
    S.inv_diag.resize(levels_.size());
    S.omega.assign(levels_.size(), 1.0);
    for (std::size_t k = 0; k < levels_.size(); ++k) {
      const Level& L = levels_[k];
      auto& keep = S.keep[k];
      keep.assign(static_cast<std::size_t>(L.size()), 0);
      IVec<Dim> n;
      for (int d = 0; d < Dim; ++d) n[d] = sim.grid.cells[d] + L.degree;
      for (Index i = L.first; i < L.end; ++i) {
        const auto I = static_cast<std::size_t>(i);
        keep[I] = k == 0 ? sim.nodes.active[I] && !(sim.nodes.fixed[I] & bit)
                         : L.inv_lumped[i] > 0.0 && !on_spline_side<Dim>(i, n, sides);
      }
      S.inv_diag[k] = Eigen::VectorXd::Zero(L.size());
      for (Index i = L.first; i < L.end; ++i)
        if (keep[static_cast<std::size_t>(i)]) {
          if (!(L.diag[i] > 0.0)) positive = false;
          S.inv_diag[k][i] = 1.0 / L.diag[i];
        }
    }
    if (pmg_.smoother == Smoother::Jacobi) {
      const std::vector<PmgLevelOps> ops = operators(S);
      for (std::size_t k = 0; k < levels_.size(); ++k) {
        Eigen::VectorXd start = Eigen::VectorXd::Zero(levels_[k].size());
        for (Index i = levels_[k].first; i < levels_[k].end; ++i)
          if (S.keep[k][static_cast<std::size_t>(i)]) start[i] = power_start(i);
        S.omega[k] = jacobi_damping(ops[k].A, S.inv_diag[k], std::move(start), ops[k].dot);
      }
    }
  }
  positive_ = !comm.any(!positive);
}

template <int Dim>
void DistributedPmg<Dim>::share(const Level& L, Eigen::VectorXd& v, int tag) const {
  sum_over_sharing_ranks(*comm_, L.ranges, 1, tag, [&](Index i, auto&& f) { f(v[i]); });
}

template <int Dim>
std::vector<PmgLevelOps> DistributedPmg<Dim>::operators(const Slot& S) const {
  std::vector<PmgLevelOps> ops(levels_.size());
  for (std::size_t k = 0; k < levels_.size(); ++k) {
    const Level& L = levels_[k];
    const std::vector<unsigned char>& keep = S.keep[k];
    PmgLevelOps& o = ops[k];
    o.size = L.size();
    // MPI tags: 500 + 10 k, + 1, + 2 for level k's operator, prolongation and restriction
    // (600 + k, 610 + k: the set-up's sums; the grid sums use 100, the CG 200, partial lumping's
    // covers 250, particles 300-400).
    const int tag = 500 + 10 * static_cast<int>(k);
    // y = A x: the kept rows and columns of the summed matrix; zero elsewhere.
    o.A = [this, &L, &keep, tag](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
      Eigen::VectorXd t = Eigen::VectorXd::Zero(L.size());
      for (Index i = L.first; i < L.end; ++i)
        if (keep[static_cast<std::size_t>(i)]) t[i] = x[i];
      y.noalias() = L.M * t;
      share(L, y, tag);
      for (Index i = L.first; i < L.end; ++i)
        if (!keep[static_cast<std::size_t>(i)]) y[i] = 0.0;
    };
    o.dot = [this, &L](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
      return comm_->sum(deterministic_sum(L.end - L.first, 0.0, [&](Index j) {
        return L.owned[static_cast<std::size_t>(j)] ? a[L.first + j] * b[L.first + j] : 0.0;
      }));
    };
    // Jacobi: x += omega D^-1 (b - A x) (PmgSettings::smoother).
    o.smooth = [A = o.A, &inv = S.inv_diag[k], omega = S.omega[k]](
                   const Eigen::VectorXd& b, Eigen::VectorXd& x, int steps, bool) {
      Eigen::VectorXd Ax(x.size());
      for (int s = 0; s < steps; ++s) {
        A(x, Ax);
        x += omega * inv.cwiseProduct(b - Ax);
      }
    };
    if (k + 1 == levels_.size()) continue;
    const Level& C = levels_[k + 1];
    const std::vector<unsigned char>& keepc = S.keep[k + 1];
    // coarser -> this: (M_q^L)^-1 M_{q,q-1} on the kept functions of both.
    o.prolong = [this, &L, &C, &keep, &keepc, tag](const Eigen::VectorXd& xc, Eigen::VectorXd& y) {
      Eigen::VectorXd t = Eigen::VectorXd::Zero(C.size());
      for (Index j = C.first; j < C.end; ++j)
        if (keepc[static_cast<std::size_t>(j)]) t[j] = xc[j];
      y.noalias() = L.cross * t;
      share(L, y, tag + 1);
      for (Index i = L.first; i < L.end; ++i)
        y[i] = keep[static_cast<std::size_t>(i)] ? y[i] * L.inv_lumped[i] : 0.0;
    };
    // this -> coarser: the prolongation's transpose, or (M_{q-1}^L)^-1 M_{q-1,q}.
    const bool transpose = pmg_.restriction == Restriction::Transpose;
    o.restriction = [this, &L, &C, &keep, &keepc, tag, transpose](const Eigen::VectorXd& x,
                                                                  Eigen::VectorXd& yc) {
      Eigen::VectorXd t = Eigen::VectorXd::Zero(L.size());
      for (Index i = L.first; i < L.end; ++i)
        if (keep[static_cast<std::size_t>(i)]) t[i] = transpose ? x[i] * L.inv_lumped[i] : x[i];
      yc.noalias() = L.crossT * t;
      share(C, yc, tag + 2);
      for (Index j = C.first; j < C.end; ++j)
        yc[j] = keepc[static_cast<std::size_t>(j)] ? (transpose ? yc[j] : yc[j] * C.inv_lumped[j])
                                                   : 0.0;
    };
  }
  return ops;
}

template <int Dim>
IterationReport DistributedPmg<Dim>::solve(int slot, const Eigen::VectorXd& b,
                                           Eigen::VectorXd& x) const {
  const std::vector<PmgLevelOps> ops = operators(slots_[static_cast<std::size_t>(slot)]);
  return pmg_cycles(ops, pmg_, b, x, tolerance_, max_cycles_, coarse_iterations_);
}

template std::vector<std::pair<int, int>> spline_fixed_sides<1>(const RunState<1>&, std::uint8_t);
template std::vector<std::pair<int, int>> spline_fixed_sides<2>(const RunState<2>&, std::uint8_t);
template std::vector<std::pair<int, int>> spline_fixed_sides<3>(const RunState<3>&, std::uint8_t);
template class DistributedPmg<1>;
template class DistributedPmg<2>;
template class DistributedPmg<3>;

}  // namespace mpm
