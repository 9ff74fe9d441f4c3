// Local max-ent basis (basis/maxent.hpp): the prior, the Newton iteration for the Lagrange
// multipliers, the gradients, the failure record and the explicit stability factor. Compiled once
// per dimension: the per-point work is the Newton iteration, not code the compiler could fuse
// with the particle loops.
#include "basis/maxent.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "basis/stability.hpp"

namespace mpm {

// D eq. 4.48; the second branch 4/3 - 4r + 4r^2 - 4/3 r^3 written as 4/3 (1 - r)^3, which is
// the same polynomial but never negative from round-off near r = 1 (the expanded form gives
// -2.2e-16 at r = 1).
double maxent_prior(double r) {
  if (r <= 0.5) return 2.0 / 3.0 - 4.0 * r * r + 4.0 * r * r * r;
  if (r < 1.0) return 4.0 / 3.0 * (1.0 - r) * (1.0 - r) * (1.0 - r);
  return 0.0;
}

// dw/dr; the second branch -4 + 8r - 4r^2 = -4 (1 - r)^2 (D eq. 4.49 prints -12 r^2).
double maxent_prior_slope(double r) {
  if (r <= 0.5) return -8.0 * r + 12.0 * r * r;
  if (r < 1.0) return -4.0 * (1.0 - r) * (1.0 - r);
  return 0.0;
}

namespace {

// ln Z(lambda) of D eq. 4.41-4.42 and q_i = exp(-lambda . y_i) / Z (so that phi_i = w_i q_i),
// with the largest exponent factored out so that no exp overflows.
template <int Dim>
double log_partition(int n, const Vec<Dim>* y, const double* w, const Vec<Dim>& lambda, double* q) {
  double top = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) top = std::max(top, -lambda.dot(y[i]));
  double z = 0.0;
  for (int i = 0; i < n; ++i) {
    q[i] = std::exp(-lambda.dot(y[i]) - top);
    z += w[i] * q[i];
  }
  for (int i = 0; i < n; ++i) q[i] /= z;
  return top + std::log(z);
}

}  // namespace

// Newton's method on the dual problem lambda = argmin ln Z (D eq. 4.42), in units of zeta:
// gradient r = -sum phi_i y_i (minus the affine-reproduction residual of eq. 4.38), Hessian the
// covariance sum phi_i y_i y_i^T - r r^T (positive definite when the nodes of nonzero prior
// span the space around x). Safeguard: a backtracking line search on ln Z (Armijo), which is
// convex, so every accepted step decreases it; a step that cannot decrease it, a singular
// Hessian or the iteration cap ends the iteration unconverged.
//
// Gradients: with y_i = x_i - x, differentiating phi_i = w_i exp(-lambda . y_i) / Z and the
// constraint sum phi_j y_j = 0 in x gives
//   grad phi_i = phi_i (grad w_i / w_i - sum_j phi_j grad w_j / w_j + (I - A'^T) H^-1 y_i),
//   H = sum_j phi_j y_j y_j^T (D eq. 4.44), A' = sum_j phi_j y_j (grad w_j / w_j)^T = -A (4.45).
// This is D eq. 4.43 with the opposite sign (D writes the first two terms and the H^-1 term as
// -grad w_i / w_i + sum ... and (x - x_i) . (H^-1 - H^-1 A)); with two nodes and a constant
// prior, where phi_1 = x on [0, 1], D's form gives -1 for the slope. The finite-difference test
// in tests/basis/test_maxent.cpp checks this form.
template <int Dim>
MaxEntStatus maxent_solve(int n, const Vec<Dim>* y, const double* w, const Vec<Dim>* dw,
                          const std::array<bool, Dim>& fixed, const MaxEntSettings& s, double* phi,
                          Vec<Dim>* grad) {
  constexpr int kMax = 216;  // 6^3: the largest window (basis/maxent.hpp)
  std::array<double, kMax> q{}, q_try{};
  MaxEntStatus st;
  if (n <= 0 || n > kMax) return st;
  Vec<Dim> lambda = Vec<Dim>::Zero();
  double f = log_partition<Dim>(n, y, w, lambda, q.data());
  for (st.iterations = 0;; ++st.iterations) {
    Vec<Dim> r = Vec<Dim>::Zero();
    Mat<Dim> H = Mat<Dim>::Zero();
    for (int i = 0; i < n; ++i) {
      const double p = w[i] * q[i];
      r -= p * y[i];
      H += p * y[i] * y[i].transpose();
    }
    H -= r * r.transpose();
    for (int d = 0; d < Dim; ++d)
      if (fixed[d]) {
        r[d] = 0.0;
        H.row(d).setZero();
        H.col(d).setZero();
        H(d, d) = 1.0;
      }
    st.residual = r.norm();
    if (st.residual <= s.tolerance) {
      st.converged = true;
      break;
    }
    if (st.iterations >= s.max_iterations) break;
    const Eigen::LDLT<Mat<Dim>> ldlt(H);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) break;
    const Vec<Dim> step = ldlt.solve(-r);
    const double slope = r.dot(step);  // < 0: a descent direction
    if (!(slope < 0.0)) break;
    double t = 1.0;
    bool accepted = false;
    for (int k = 0; k < 60; ++k, t *= 0.5) {
      const Vec<Dim> trial = lambda + t * step;
      const double f_try = log_partition<Dim>(n, y, w, trial, q_try.data());
      // Armijo's decrease of ln Z; or, where the decrease is below the round-off of ln Z (close
      // to the solution, and near the boundary where phi concentrates on a few nodes), a halving
      // of the residual.
      Vec<Dim> r_try = Vec<Dim>::Zero();
      for (int i = 0; i < n; ++i) r_try -= w[i] * q_try[i] * y[i];
      for (int d = 0; d < Dim; ++d)
        if (fixed[d]) r_try[d] = 0.0;
      if (std::isfinite(f_try) &&
          (f_try <= f + 1e-4 * t * slope || r_try.norm() <= 0.5 * st.residual)) {
        lambda = trial;
        f = f_try;
        q = q_try;
        accepted = true;
        break;
      }
    }
    if (!accepted) break;
  }
  for (int i = 0; i < n; ++i) phi[i] = st.converged ? w[i] * q[i] : std::nan("");
  if (!grad || !st.converged) return st;

  Mat<Dim> H = Mat<Dim>::Zero(), A = Mat<Dim>::Zero();
  Vec<Dim> b = Vec<Dim>::Zero();
  for (int i = 0; i < n; ++i) {
    H += phi[i] * y[i] * y[i].transpose();
    A += q[i] * y[i] * dw[i].transpose();  // phi_i grad w_i / w_i = q_i grad w_i
    b += q[i] * dw[i];
  }
  const Mat<Dim> T = (Mat<Dim>::Identity() - A.transpose()) * H.inverse();
  Vec<Dim> sum = Vec<Dim>::Zero();
  for (int i = 0; i < n; ++i) {
    grad[i] = q[i] * dw[i] - phi[i] * b + phi[i] * (T * y[i]);
    sum += grad[i];
  }
  // The gradients sum to zero analytically (the partition of unity), which momentum conservation
  // rests on. Close to the boundary H is nearly singular and amplifies the Newton residual (H ~
  // delta^2 at a distance delta from the hull: about 1e-7 at delta = 1e-5 zeta), so the sum is
  // restored exactly; the correction phi_i sum_j grad phi_j is of the size of that residual.
  for (int i = 0; i < n; ++i) grad[i] -= phi[i] * sum;
  return st;
}

template <int Dim>
MaxEntBasis<Dim>::MaxEntBasis(const Grid<Dim>& g, const MaxEntSettings& s)
    : grid_(g), settings_(s) {
  if (!(s.dmax > 1.0 && s.dmax <= 3.0))
    throw InputError(fmt::format(
        "method.maxent_dmax = {}: the max-ent support d_max zeta must be in (1, 3] cell sizes "
        "(the node window holds the nodes closer than 3 zeta)",
        s.dmax));
  for (int d = 0; d < Dim; ++d) {
    n_[d] = g.cells[d] + 1;
    if (n_[d] < kWindow)
      throw InputError(fmt::format(
          "method.basis = \"maxent\" needs at least {} cells in every direction (its node "
          "window is {} nodes wide); the grid has {} in direction {}",
          kWindow - 1, kWindow, g.cells[d], "xyz"[d]));
  }
  stride_ = dof_strides<Dim>(n_);
  zeta_ = g.h.minCoeff();  // the nearest-neighbour distance of every node of a uniform grid
}

template <int Dim>
bool MaxEntBasis<Dim>::compute(const Vec<Dim>& x, StencilT& s, MaxEntStatus& status,
                               int& nodes) const {
  constexpr int N = StencilT::kSize;
  IVec<Dim> first, c;
  std::array<bool, Dim> fixed{};
  std::array<Index, Dim> boundary_node{};
  for (int d = 0; d < Dim; ++d) {
    c[d] = std::clamp<Index>(grid_.cell_of(x[d], d), 0, grid_.cells[d] - 1);
    first[d] = std::clamp<Index>(c[d] - (kWindow / 2 - 1), 0, n_[d] - kWindow);
    // On the grid's boundary (the nodes' convex hull) only the nodes on that side carry weight
    // (weak Kronecker-delta property), and lambda_d is not solved for.
    if (x[d] <= grid_.origin[d]) {
      fixed[d] = true;
      boundary_node[d] = 0;
    } else if (x[d] >= grid_.origin[d] + grid_.h[d] * static_cast<double>(grid_.cells[d])) {
      fixed[d] = true;
      boundary_node[d] = n_[d] - 1;
    }
  }
  std::array<Vec<Dim>, N> y, dw;
  std::array<double, N> w, phi;
  std::array<Vec<Dim>, N> grad;
  std::array<int, N> slot;  // window entry of each node of nonzero prior
  int n = 0;
  const double inv_zeta = 1.0 / zeta_, dmax = settings_.dmax;
  for (int k = 0; k < N; ++k) {
    int rem = k;
    Index dof = 0;
    Vec<Dim> yk;
    bool on_side = true;
    for (int d = 0; d < Dim; ++d) {
      const Index i = first[d] + rem % kWindow;
      rem /= kWindow;
      dof += i * stride_[d];
      yk[d] = (grid_.origin[d] + grid_.h[d] * static_cast<double>(i) - x[d]) * inv_zeta;
      if (fixed[d]) {
        on_side = on_side && i == boundary_node[d];
        yk[d] = 0.0;
      }
    }
    s.dof[k] = dof;
    s.w[k] = 0.0;
    s.grad[k].setZero();
    if (!on_side) continue;
    const double dist = yk.norm(), r = dist / dmax;
    const double wk = maxent_prior(r);
    if (!(wk > 0.0)) continue;
    y[n] = yk;
    w[n] = wk;
    // grad w_i in units of zeta: dw/dr dr/dx, dr/dx = (x - x_i) / (d_max |x - x_i|) = -y / ...
    dw[n] = dist > 0.0 ? Vec<Dim>(-maxent_prior_slope(r) / (dmax * dist) * yk) : Vec<Dim>::Zero();
    slot[n] = k;
    ++n;
  }
  nodes = n;
  const bool on_boundary = std::any_of(fixed.begin(), fixed.end(), [](bool f) { return f; });
  status = maxent_solve<Dim>(n, y.data(), w.data(), dw.data(), fixed, settings_, phi.data(),
                             on_boundary ? nullptr : grad.data());
  if (!status.converged) {
    for (int k = 0; k < N; ++k) s.w[k] = std::nan("");
    return false;
  }
  for (int j = 0; j < n; ++j) {
    s.w[slot[j]] = phi[j];
    if (!on_boundary) s.grad[slot[j]] = grad[j] * inv_zeta;
  }
  if (on_boundary) {
    // The gradient on the grid's boundary: that of the point a millionth of zeta inside (the
    // gradients are continuous up to the boundary; the error is of that order).
    Vec<Dim> inner = x;
    for (int d = 0; d < Dim; ++d)
      if (fixed[d]) inner[d] += (boundary_node[d] == 0 ? 1e-6 : -1e-6) * zeta_;
    StencilT t;
    MaxEntStatus inner_status;
    int inner_nodes = 0;
    if (!compute(inner, t, inner_status, inner_nodes)) {
      status = inner_status;
      nodes = inner_nodes;
      for (int k = 0; k < N; ++k) s.w[k] = std::nan("");
      return false;
    }
    for (int k = 0; k < N; ++k) s.grad[k] = t.grad[k];  // the same window (first[d] as for x)
  }
  return true;
}

template <int Dim>
void MaxEntBasis<Dim>::evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
  const auto i = static_cast<std::size_t>(p);
  MaxEntStatus status;
  int nodes = 0;
  if (!compute(P.x[i], s, status, nodes)) record(P.x[i], p, P.id[i], status, nodes);
}

template <int Dim>
void MaxEntBasis<Dim>::evaluate_point(const Vec<Dim>& x, StencilT& s) const {
  MaxEntStatus status;
  int nodes = 0;
  if (!compute(x, s, status, nodes)) record(x, -1, -1, status, nodes);
}

template <int Dim>
void MaxEntBasis<Dim>::record(const Vec<Dim>& x, Index particle, Index id,
                              const MaxEntStatus& status, int nodes) const {
  FailureLog& log = *failures_;
  const std::lock_guard<std::mutex> lock(log.mutex);
  ++log.count;
  // The first by particle index, else by coordinates: the same report whatever the threads.
  const bool first = !log.any || (particle >= 0 ? particle < log.first.particle
                                                : std::lexicographical_compare(
                                                      x.data(), x.data() + Dim, log.first.x.data(),
                                                      log.first.x.data() + Dim));
  if (first) log.first = Failure{x, particle, id, status, nodes};
  log.any = true;
}

template <int Dim>
void MaxEntBasis<Dim>::throw_if_failed(Index step, double time, std::string_view where) const {
  FailureLog& log = *failures_;
  if (!log.any) return;
  const Failure f = log.first;
  const Index count = log.count;
  log.any = false;
  log.count = 0;
  std::string point;
  for (int d = 0; d < Dim; ++d) point += fmt::format("{}{:.17g}", d ? ", " : "", f.x[d]);
  // The node set: the window's nodes of nonzero prior at the point.
  StencilT s;
  MaxEntStatus again;
  int nodes = 0;
  (void)compute(f.x, s, again, nodes);
  std::string list;
  int listed = 0;
  for (int k = 0; k < StencilT::kSize; ++k) {
    const Vec<Dim> xi = dof_position(s.dof[k]);
    if (!(maxent_prior((xi - f.x).norm() / (settings_.dmax * zeta_)) > 0.0)) continue;
    std::string pos;
    for (int d = 0; d < Dim; ++d) pos += fmt::format("{}{:.6g}", d ? ", " : "", xi[d]);
    list += fmt::format("{}{} ({})", listed++ ? ", " : "", s.dof[k], pos);
  }
  throw RunError(
      exit_code::kBasis,
      fmt::format("{}: the max-ent basis could not be evaluated at {} of the "
                  "{}: at the first, {} ({}), Newton's method for the Lagrange multipliers did "
                  "not converge in {} iteration(s); last residual |sum phi_i (x_i - x)| / zeta = "
                  "{:.3g} (method.maxent_tolerance = {:.3g}, method.maxent_max_iterations = {}); "
                  "{} node(s) of nonzero prior (d_max = {}, zeta = {:.6g} m): {}",
                  step >= 0 ? fmt::format("step {}, t = {:.9g} s", step, time)
                            : std::string("before the first step"),
                  count, where,
                  f.particle >= 0 ? fmt::format("particle {}", f.id) : std::string("point"), point,
                  f.status.iterations, f.status.residual, settings_.tolerance,
                  settings_.max_iterations, f.nodes, settings_.dmax, zeta_, list));
}

// As bspline_stability_factor (basis/bspline.cpp): Gershgorin's bound of M_L^-1 K on a uniform
// 1D bar (E = rho = h = 1) of 4 kWindow + 4 cells, the integrals by 8-point Gauss quadrature per
// cell (the functions are smooth but not polynomial).
double maxent_stability_factor(const MaxEntSettings& s) {
  constexpr Index n = 4 * MaxEntBasis<1>::kWindow + 4;
  const MaxEntBasis<1> basis(stability_bar(n), s);
  return gershgorin_stability_factor(
      basis, n, 8, [&] { basis.throw_if_failed(-1, 0.0, "points of the stability estimate"); });
}

template class MaxEntBasis<1>;
template class MaxEntBasis<2>;
template MaxEntStatus maxent_solve<1>(int, const Vec<1>*, const double*, const Vec<1>*,
                                      const std::array<bool, 1>&, const MaxEntSettings&, double*,
                                      Vec<1>*);
template MaxEntStatus maxent_solve<2>(int, const Vec<2>*, const double*, const Vec<2>*,
                                      const std::array<bool, 2>&, const MaxEntSettings&, double*,
                                      Vec<2>*);

}  // namespace mpm
