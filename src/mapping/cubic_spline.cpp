// Natural cubic spline (D 3.2.1) and the set-up of the CS mapping (D 3.2.3).
#include "mapping/cubic_spline.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace mpm {

namespace {

// Insertion sort of `order` by key[order[i]], giving up after `budget` element moves. O(M) on
// an already sorted order (the usual case: 1D particles keep their order between steps).
// Returns false when it gave up; `order` is then still a permutation.
bool insertion_sort_bounded(std::vector<std::size_t>& order, const std::vector<double>& key,
                            std::size_t budget) {
  std::size_t moves = 0;
  for (std::size_t i = 1; i < order.size(); ++i) {
    const std::size_t item = order[i];
    const double k = key[item];
    std::size_t j = i;
    while (j > 0 && key[order[j - 1]] > k) {
      order[j] = order[j - 1];
      --j;
      if (++moves > budget) {
        order[j] = item;
        return false;
      }
    }
    order[j] = item;
  }
  return true;
}

}  // namespace

void NaturalCubicSpline::build_knots() {
  const std::size_t n = xd_.size();
  auto by_x = [this](std::size_t a, std::size_t b) { return xd_[a] < xd_[b]; };
  if (order_.size() != n) {
    order_.resize(n);
    std::iota(order_.begin(), order_.end(), std::size_t{0});
    std::sort(order_.begin(), order_.end(), by_x);
  } else if (!insertion_sort_bounded(order_, xd_, 4 * n + 16)) {
    std::sort(order_.begin(), order_.end(), by_x);
  }

  // Group abscissae equal to round-off into one knot at their mean.
  x_.clear();
  group_.clear();
  group_.push_back(0);
  if (n > 0) {
    const double lo = xd_[order_.front()], hi = xd_[order_.back()];
    const double tol = kMergeTolerance * std::max({hi - lo, std::abs(lo), std::abs(hi)});
    std::size_t start = 0;
    double sum = 0.0;
    for (std::size_t i = 0; i <= n; ++i) {
      if (i == n || xd_[order_[i]] - xd_[order_[start]] > tol) {
        x_.push_back(sum / static_cast<double>(i - start));
        group_.push_back(i);
        start = i;
        sum = 0.0;
      }
      if (i < n) sum += xd_[order_[i]];
    }
  }

  // Interior rows j = 1 .. nk-2 of the second-derivative system (M_0 = M_{nk-1} = 0):
  //   h_{j-1} M_{j-1} + 2 (h_{j-1} + h_j) M_j + h_j M_{j+1}
  //     = 6 ((y_{j+1} - y_j) / h_j - (y_j - y_{j-1}) / h_{j-1}).
  // Strictly diagonally dominant, so the Thomas algorithm needs no pivoting. The factors depend
  // only on the knots: computed here once, reused by every fit().
  const std::size_t nk = x_.size();
  h_.resize(nk > 0 ? nk - 1 : 0);
  for (std::size_t j = 0; j + 1 < nk; ++j) h_[j] = x_[j + 1] - x_[j];
  lower_.assign(nk, 0.0);
  inv_pivot_.assign(nk, 0.0);
  if (nk >= 3) {
    double pivot = 2.0 * (h_[0] + h_[1]);
    inv_pivot_[1] = 1.0 / pivot;
    for (std::size_t j = 2; j + 1 < nk; ++j) {
      lower_[j] = h_[j - 1] / pivot;
      pivot = 2.0 * (h_[j - 1] + h_[j]) - lower_[j] * h_[j - 1];
      inv_pivot_[j] = 1.0 / pivot;
    }
  }
}

void NaturalCubicSpline::solve() {
  if (fd_.size() != xd_.size())
    throw std::invalid_argument(
        fmt::format("NaturalCubicSpline::fit: {} values for {} abscissae", fd_.size(), xd_.size()));
  const std::size_t nk = x_.size();
  // At least two entries so that evaluate() can always read k and k + 1.
  y_.assign(std::max<std::size_t>(nk, 2), 0.0);
  m_.assign(std::max<std::size_t>(nk, 2), 0.0);
  for (std::size_t j = 0; j < nk; ++j) {
    double sum = 0.0;
    for (std::size_t i = group_[j]; i < group_[j + 1]; ++i) sum += fd_[order_[i]];
    y_[j] = sum / static_cast<double>(group_[j + 1] - group_[j]);
  }
  if (nk == 1) y_[1] = y_[0];
  if (nk < 3) return;  // constant or straight line: M = 0
  rhs_.resize(nk);
  for (std::size_t j = 1; j + 1 < nk; ++j)
    rhs_[j] = 6.0 * ((y_[j + 1] - y_[j]) / h_[j] - (y_[j] - y_[j - 1]) / h_[j - 1]);
  for (std::size_t j = 2; j + 1 < nk; ++j) rhs_[j] -= lower_[j] * rhs_[j - 1];
  m_[nk - 2] = rhs_[nk - 2] * inv_pivot_[nk - 2];
  for (std::size_t j = nk - 2; j-- > 1;) m_[j] = (rhs_[j] - h_[j] * m_[j + 1]) * inv_pivot_[j];
}

std::size_t NaturalCubicSpline::interval_of(double x) const {
  const std::size_t nk = x_.size();
  if (nk < 3 || x <= x_[1]) return 0;
  if (x >= x_[nk - 2]) return nk - 2;
  const auto it = std::upper_bound(x_.begin(), x_.end(), x);
  return static_cast<std::size_t>(it - x_.begin()) - 1;
}

SplineSample NaturalCubicSpline::sample_in(std::size_t k, double x, int order) const {
  const std::size_t nk = x_.size();
  SplineSample s;
  s.k = k;
  if (nk < 2) {  // constant (or zero without data)
    if (order == 0) s.c = {1.0, 0.0, 0.0, 0.0};
    return s;
  }
  const double h = h_[k];
  if (extrapolation_ == SplineExtrapolation::kLinear && x < x_.front()) {
    // z(x_1) + z'(x_1) d, z'(x_1) = (y_2 - y_1) / h - h (2 M_1 + M_2) / 6.
    const double d = x - x_.front();
    if (order == 0) s.c = {1.0 - d / h, d / h, -d * h / 3.0, -d * h / 6.0};
    if (order == 1) s.c = {-1.0 / h, 1.0 / h, -h / 3.0, -h / 6.0};
    return s;
  }
  if (extrapolation_ == SplineExtrapolation::kLinear && x > x_.back()) {
    // z(x_M) + z'(x_M) d, z'(x_M) = (y_M - y_{M-1}) / h + h (M_{M-1} + 2 M_M) / 6.
    const double d = x - x_.back();
    if (order == 0) s.c = {-d / h, 1.0 + d / h, d * h / 6.0, d * h / 3.0};
    if (order == 1) s.c = {-1.0 / h, 1.0 / h, h / 6.0, h / 3.0};
    return s;
  }
  // Interval k (or its continuation with kCubic): with a = (x_{k+1} - x) / h, b = (x - x_k) / h,
  // z = a y_k + b y_{k+1} + ((a^3 - a) M_k + (b^3 - b) M_{k+1}) h^2 / 6.
  const double a = (x_[k + 1] - x) / h, b = (x - x_[k]) / h;
  if (order == 0) s.c = {a, b, (a * a * a - a) * h * h / 6.0, (b * b * b - b) * h * h / 6.0};
  if (order == 1)
    s.c = {-1.0 / h, 1.0 / h, -(3.0 * a * a - 1.0) * h / 6.0, (3.0 * b * b - 1.0) * h / 6.0};
  if (order == 2) s.c = {0.0, 0.0, a, b};
  return s;
}

SplineSample NaturalCubicSpline::sample(double x, int order) const {
  return sample_in(interval_of(x), x, order);
}

void NaturalCubicSpline::sample_all(std::span<const double> xs,
                                    std::vector<SplineSample>& out) const {
  out.resize(xs.size());
  const std::size_t nk = x_.size();
  std::size_t k = 0;
  for (std::size_t g = 0; g < xs.size(); ++g) {
    const double x = xs[g];
    if (nk >= 3) {
      if (k > 0 && x < x_[k])
        k = interval_of(x);  // not ascending: search again
      else
        while (k + 2 < nk && x > x_[k + 1]) ++k;
    }
    out[g] = sample_in(k, x, 0);
  }
}

CubicSplineMapping::CubicSplineMapping(const Settings& s) : settings_(s), spline_(s.extrapolation) {
  if (settings_.gauss_points_per_half < 0)
    throw InputError(
        fmt::format("the cubic-spline mapping needs a positive number of Gauss "
                    "points per half element (0: D's {}), not {}",
                    Settings::kDefaultGaussPointsPerHalf, settings_.gauss_points_per_half));
  if (settings_.gauss_points_per_half == 0)
    settings_.gauss_points_per_half = Settings::kDefaultGaussPointsPerHalf;
  rule_ = gauss_legendre(settings_.gauss_points_per_half);
}

// Knots from the particle positions; n Gauss points in each half of every element holding a
// particle (D Fig. 3.4), ascending; the spline coefficients at them, then rho_hat. The n-point
// rule is exact for degree 2n - 1 on each half; rho_hat has knots at the particles inside the
// halves and phi_i rho_hat has degree 3 + p, so the integrals are accurate, not exact (D 3.2.2).
void CubicSplineMapping::fit_mass(const RunState<1>& sim, GaussPoints<1>& q) {
  const auto& P = sim.particles;
  const auto& grid = sim.grid;
  spline_.set_abscissae(static_cast<std::size_t>(P.size()),
                        [&](std::size_t i) { return P.x[i][0]; });
  bins_.build(grid, P);
  q.clear();
  xg_.clear();
  // The integrals run over the material domain: each active element clipped to the extent of
  // the particle domains [min(x_p - V_p/2), max(x_p + V_p/2)] (1D: V_p is a length), so a
  // partly filled element at a free surface does not integrate the extrapolated spline over
  // empty space (the column's top; D Table 5.7 reports mass errors ~1e-6 there, which whole
  // elements would not give). Where the body fills its elements this is D 3.2.3 exactly.
  // At a fixed grid end the body is attached to the wall and extends to it (the particle
  // domains there do not add up to the wall position exactly once deformed); this reproduces
  // D Table 5.3 for the fixed-end bar, as the clipping at the free top reproduces Table 5.7.
  double body_lo = std::numeric_limits<double>::infinity(), body_hi = -body_lo;
  for (Index p = 0; p < P.size(); ++p) {
    const auto i = static_cast<std::size_t>(p);
    body_lo = std::min(body_lo, P.x[i][0] - 0.5 * P.volume[i]);
    body_hi = std::max(body_hi, P.x[i][0] + 0.5 * P.volume[i]);
  }
  // Only a body end inside the wall's own cell is taken to touch the wall.
  if (!sim.nodes.fixed.empty()) {
    if (sim.nodes.fixed.front() && body_lo < grid.origin[0] + grid.h[0])
      body_lo = std::min(body_lo, grid.origin[0]);
    if (sim.nodes.fixed.back() && body_hi > grid.upper()[0] - grid.h[0])
      body_hi = std::max(body_hi, grid.upper()[0]);
  }
  const std::size_t n = rule_.xi.size();
  // A process of a distributed run integrates its own elements (the spline reads all particles).
  const std::array<Index, 2> own = sim.own_cells().span();  // one dimension: the box is its span
  for (Index e = own[0]; e < own[1]; ++e) {
    if (bins_.count(e) == 0) continue;
    const double lo_e = grid.origin[0] + static_cast<double>(e) * grid.h[0];
    const double lo = std::max(lo_e, body_lo), hi = std::min(lo_e + grid.h[0], body_hi);
    if (!(hi > lo)) continue;
    const double half = 0.5 * (hi - lo);  // [m]
    for (int part = 0; part < 2; ++part) {
      const double centre = lo + (static_cast<double>(part) + 0.5) * half;
      for (std::size_t k = 0; k < n; ++k) {
        const double xg = centre + 0.5 * half * rule_.xi[k];
        q.add(Vec<1>(xg), 0.5 * half * rule_.w[k], e);
        xg_.push_back(xg);
      }
    }
  }
  spline_.sample_all(xg_, samples_);
  spline_.fit([&](std::size_t i) { return P.density(i); });
  rho_g_.resize(samples_.size());
  at_points([&](std::size_t g, double v) { rho_g_[g] = v; });
}

void CubicSplineMapping::fit_momentum(const RunState<1>& sim) {
  const auto& P = sim.particles;
  spline_.fit([&](std::size_t i) { return P.density(i) * P.v[i][0]; });
  vec_g_.resize(samples_.size());
  at_points([&](std::size_t g, double v) { vec_g_[g][0] = v; });
}

void CubicSplineMapping::fit_forces(const RunState<1>& sim) {
  const auto& P = sim.particles;
  const std::size_t ng = samples_.size();
  spline_.fit([&](std::size_t i) { return P.stress[i](0, 0); });
  sig_g_.resize(ng);
  at_points([&](std::size_t g, double v) { sig_g_[g](0, 0) = v; });
  spline_.fit([&](std::size_t i) { return P.density(i) * P.body[i][0]; });
  vec_g_.resize(ng);
  at_points([&](std::size_t g, double v) { vec_g_[g][0] = v; });
}

}  // namespace mpm
