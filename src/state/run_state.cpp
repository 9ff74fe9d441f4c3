// RunState's per-run set-up of velocity conditions (state/simulation.hpp), compiled once per
// dimension here rather than in every stepper unit.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "state/run_state.hpp"

namespace mpm {

template <int Dim>
void RunState<Dim>::refresh_per_component() {
  constexpr std::uint8_t kAll = (1u << Dim) - 1u;
  const auto& fixed = this->nodes.fixed;
  this->consistent_per_component =
      std::any_of(fixed.begin(), fixed.end(), [](std::uint8_t f) { return f != 0 && f != kAll; });
}

template <int Dim>
void RunState<Dim>::constrain(const std::vector<Index>& dofs, const Mat<Dim>& c) {
  auto& nd = this->nodes;
  auto& proj = nd.projected;
  for (Index i : dofs) {
    auto& bits = nd.fixed[static_cast<std::size_t>(i)];
    const auto it = std::lower_bound(proj.begin(), proj.end(), i,
                                     [](const auto& e, Index k) { return e.dof < k; });
    const bool has = it != proj.end() && it->dof == i;
    Mat<Dim> sum = c;
    if (has) sum += Mat<Dim>::Identity() - it->free;
    for (int d = 0; d < Dim; ++d)
      if (bits & (1u << d)) sum(d, d) += 1.0;
    // The orthogonal projector onto range(sum): its eigenvectors of non-zero eigenvalue
    // (eigenvalues are 0 or at least 1 - 1e-12 here: sums of unit projectors).
    const Eigen::SelfAdjointEigenSolver<Mat<Dim>> eig(sum);
    Mat<Dim> con = Mat<Dim>::Zero();
    for (int k = 0; k < Dim; ++k)
      if (eig.eigenvalues()[k] > 1e-9)
        con += eig.eigenvectors().col(k) * eig.eigenvectors().col(k).transpose();
    std::uint8_t axes = 0;
    bool axis_aligned = true;
    for (int a = 0; a < Dim; ++a)
      for (int b = 0; b < Dim; ++b) {
        const double want = a == b && std::abs(con(a, a) - 1.0) < 1e-12 ? 1.0 : 0.0;
        if (std::abs(con(a, b) - want) > 1e-12) axis_aligned = false;
        if (a == b && want == 1.0) axes |= static_cast<std::uint8_t>(1u << a);
      }
    if (axis_aligned) {
      bits = axes;
      if (has) proj.erase(it);
    } else {
      bits = 0;
      const Mat<Dim> free = Mat<Dim>::Identity() - con;
      if (has)
        it->free = free;
      else
        proj.insert(it, {i, free});
    }
  }
}

template <int Dim>
void RunState<Dim>::fit_dof_window() {
  if (this->comm == nullptr) return;
  const auto [lo, hi] = this->scatter.ranges.span();
  if (lo > hi) {  // no particle: nothing is summed here
    this->nodes.set_window(0, 0);
    return;
  }
  const Index n = this->nodes.size();
  // The DOFs of one layer of grid vertices across the cuts (rounded up): a B-spline's DOFs per
  // layer, a triangle basis's corners and centres of a row of cells.
  const Index cuts = this->grid.cells[Dim - 1] + 1;
  const Index layer = (n + cuts - 1) / cuts;
  const auto [first, end] = this->nodes.window();
  const bool covers = first <= std::max<Index>(0, lo - layer) && std::min(n, hi + 1 + layer) <= end;
  if (covers && end - first <= hi + 1 - lo + 8 * layer) return;
  this->nodes.set_window(std::max<Index>(0, lo - 2 * layer), std::min(n, hi + 1 + 2 * layer));
}

template struct RunState<1>;
template struct RunState<2>;
template struct RunState<3>;

}  // namespace mpm
