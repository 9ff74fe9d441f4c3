#pragma once
// Cubic-spline (CS) reconstruction mapping (D 3.2, eq. 3.1-3.10; D 5.4 for its conservation).
// The density, momentum density, stress and body-force density are interpolated through the
// scattered particle data by one global natural cubic spline per field (D 3.2.1), evaluated at
// n Gauss points in each half of every element that holds particles (D 3.2.3, Fig. 3.4) and
// integrated against the basis there (D eq. 3.7-3.9). One-dimensional, as in D.
//
// The mapping interpolates, it does not conserve: sum_i m_i = int rho_hat differs from
// sum_p m_p unless rho_hat integrates exactly to the particle masses (D Tables 5.3, 5.5, 5.7).
#include <any>
#include <array>
#include <concepts>
#include <cstddef>
#include <limits>
#include <span>
#include <string_view>
#include <vector>

#include "mapping/mapping.hpp"
#include "mapping/quadrature.hpp"
#include "state/simulation.hpp"

namespace mpm {

// What the spline does outside [x_1, x_M], the range of its data.
//   kLinear: z(x) = z(x_end) + z'(x_end) (x - x_end). The natural spline is the minimiser of
//     int z''^2 over the whole real line among the interpolants, and that minimiser is linear
//     outside the data, so this is the natural spline's own extension: C^2 at x_1 and x_M
//     (z'' = 0 on both sides) and bounded growth far from the data. D says only that the
//     reconstruction "involves extrapolation at the right boundary" (3.2.1, Fig. 3.3); which
//     extension D used cannot be read from the text, so this is the default. On the D 5.2.3
//     example (sin x + 2, 11 random points) it was never less accurate than kCubic in our
//     trials (16 random layouts), with up to 2.4x smaller RMS error where the last point is far
//     from 4 pi.
//   kCubic: the end cubic pieces continued (what scipy's CubicSpline does by default). Also C^2
//     at the ends; differs from kLinear by z''' d^3 / 6 at a distance d beyond the end knot.
// In an MPM body the end particles lie half a particle spacing inside the body's ends, so the
// two differ little there (the D Table 5.3 bar gives the same diagnostics to five digits).
enum class SplineExtrapolation { kLinear, kCubic };

// The spline at one point as a combination of the knot data of one interval k:
//   z(x) = c[0] y_k + c[1] y_{k+1} + c[2] M_k + c[3] M_{k+1},
// y the knot values, M the second derivatives. The coefficients depend only on the knots, so
// fields sharing the abscissae are evaluated at a fixed point set by four multiply-adds each.
struct SplineSample {
  std::size_t k = 0;
  std::array<double, 4> c{};
};

// Natural cubic spline interpolant through scattered 1D data (D 3.2.1):
//   z(x_p) = f(x_p), z cubic between consecutive knots, C^2, z''(x_1) = z''(x_M) = 0.
// Usage: set_abscissae() once for a set of positions (sorts, merges coincident points, factors
// the tridiagonal system), then fit() per field (one O(M) Thomas solve each) and evaluate.
// Buffers are kept between calls: no allocation once sizes have been reached.
//
// Degenerate data: no point gives z = 0, one distinct abscissa a constant, two a straight line.
// Coincident abscissae (equal to within kMergeTolerance of the data scale) form one knot whose
// value is the mean of their values: an interpolant cannot take two values at one x, and
// nearly equal abscissae would make the slopes (f_2 - f_1) / (x_2 - x_1) arbitrarily large.
class NaturalCubicSpline {
 public:
  // Relative to max(x_M - x_1, |x_1|, |x_M|): far above round-off of positions (~1e-16
  // relative), far below any particle spacing.
  static constexpr double kMergeTolerance = 1e-12;

  explicit NaturalCubicSpline(SplineExtrapolation e = SplineExtrapolation::kLinear)
      : extrapolation_(e) {}

  // Abscissae of the data points, in data order; must be finite. The sort starts from the order
  // of the previous call when the number of points is unchanged: particles in 1D keep their
  // order from step to step, so this costs O(M) instead of O(M log M).
  void set_abscissae(std::span<const double> x) {
    xd_.assign(x.begin(), x.end());
    build_knots();
  }
  // The same with x_of(i) giving the abscissa of data point i = 0 .. n - 1.
  template <class XOf>
  void set_abscissae(std::size_t n, XOf&& x_of) {
    xd_.resize(n);
    for (std::size_t i = 0; i < n; ++i) xd_[i] = x_of(i);
    build_knots();
  }

  // Values at the data points, in the order of set_abscissae (size must match).
  void fit(std::span<const double> f) {
    fd_.assign(f.begin(), f.end());
    solve();
  }
  // The same with f_of(i) giving the value of data point i.
  template <class FOf>
  requires std::invocable<FOf&, std::size_t>
  void fit(FOf&& f_of) {
    fd_.resize(xd_.size());
    for (std::size_t i = 0; i < fd_.size(); ++i) fd_[i] = f_of(i);
    solve();
  }

  // z, z', z'' at any x (binary search for the interval).
  double value(double x) const { return evaluate(sample(x, 0)); }
  double slope(double x) const { return evaluate(sample(x, 1)); }
  double curvature(double x) const { return evaluate(sample(x, 2)); }

  // Coefficients of the derivative of order 0, 1 or 2 at x.
  SplineSample sample(double x, int order = 0) const;
  // The same for many points; O(points + knots) when xs is ascending (Gauss points in element
  // order), a binary search per point otherwise.
  void sample_all(std::span<const double> xs, std::vector<SplineSample>& out) const;
  double evaluate(const SplineSample& s) const {
    return s.c[0] * y_[s.k] + s.c[1] * y_[s.k + 1] + s.c[2] * m_[s.k] + s.c[3] * m_[s.k + 1];
  }

  std::size_t num_data() const { return xd_.size(); }
  std::size_t num_knots() const { return x_.size(); }   // distinct abscissae
  std::span<const double> knots() const { return x_; }  // ascending [m]
  std::span<const double> knot_values() const { return {y_.data(), x_.size()}; }
  std::span<const double> second_derivatives() const { return {m_.data(), x_.size()}; }
  // Data indices in ascending order of abscissa.
  std::span<const std::size_t> order() const { return order_; }
  SplineExtrapolation extrapolation() const { return extrapolation_; }

 private:
  void build_knots();
  void solve();
  SplineSample sample_in(std::size_t k, double x, int order) const;
  std::size_t interval_of(double x) const;

  SplineExtrapolation extrapolation_;
  std::vector<double> xd_, fd_;     // data abscissae and values, data order
  std::vector<std::size_t> order_;  // data indices sorted by abscissa
  std::vector<std::size_t> group_;  // knot j holds order_[group_[j] .. group_[j + 1])
  std::vector<double> x_;           // knots x_j
  std::vector<double> h_;           // h_j = x_{j+1} - x_j
  std::vector<double> lower_;       // Thomas factors of the interior rows (see solve())
  std::vector<double> inv_pivot_;
  std::vector<double> y_, m_;  // values and second derivatives, at least 2 entries
  std::vector<double> rhs_;
};

// Settings of the CS mapping, given by the run set-up (method.gauss_points).
struct CubicSplineSettings {
  static constexpr int kDefaultGaussPointsPerHalf = 2;  // D 3.2.3, Fig. 3.4: 2 per half span
  // Gauss points in each half of an element; 0 selects D's 2 (method.gauss_points = 0).
  int gauss_points_per_half = kDefaultGaussPointsPerHalf;
  SplineExtrapolation extrapolation = SplineExtrapolation::kLinear;
};

// The CS mapping (D 3.2.3). map_mass must be the first mapping call of a step (the schemes
// guarantee it): it sorts the particles, places the quadrature points and evaluates the basis
// there; map_forces and map_momentum of the same step reuse both, since particles do not move
// between the mapping calls of a step (only the fitted values change: stress, velocity, density).
class CubicSplineMapping {
 public:
  static constexpr std::string_view kName = "cubic_spline";
  static constexpr std::string_view kDescription =
      "global natural cubic spline through particle values, 2x2 Gauss points per element (D 3.2)";
  using Settings = CubicSplineSettings;
  // D formulates the reconstruction in one dimension only (3.2: "presented for one-dimensional
  // problems"); the run set-up rejects other dimensions with this before instantiating.
  static constexpr bool supports_dimension(int dim) { return dim == 1; }
  // Capabilities (mapping/mapping.hpp).
  static constexpr bool kFusedScatter = false, kRunTotals = false, kGhostParticles = true,
                        kStrainRates = false, kCellQuadrature = true;

  // The spline is one fit through all the particles: in a distributed run every process reads
  // all of them (every cell layer), fits the same spline and integrates its own elements. A
  // 1D problem's particles are few; the fit itself is serial anyway.
  template <class Sim>
  double ghost_reach(const Sim& sim) const {
    return static_cast<double>(sim.grid.cells[Sim::kDim - 1]);
  }

  CubicSplineMapping() : CubicSplineMapping(Settings{}) {}
  // Throws InputError for a negative number of Gauss points.
  explicit CubicSplineMapping(const Settings& s);

  const Settings& settings() const { return settings_; }
  int gauss_points_per_half() const { return static_cast<int>(rule_.xi.size()); }
  // Gauss points per element (MappingFor's kCellQuadrature; 1D, where no face has a patch).
  int gauss_points() const { return 2 * gauss_points_per_half(); }
  // The spline of the last fitted field (for diagnostics and tests).
  const NaturalCubicSpline& spline() const { return spline_; }
  // Quadrature points of the current step; nullptr before the first map_mass for this Sim.
  template <class Sim>
  const QuadraturePointsOf<Sim>* quadrature() const {
    return quad_.get<Sim>();
  }

  // The basis enters only through the quadrature stencils: the spline fits are compiled once
  // (cubic_spline.cpp), the assembly once per basis.
  // rho_hat through (x_p, rho_p); m_i = sum_g phi_i rho_hat w_g and, with consistent mass,
  // M_ij = sum_g phi_i rho_hat phi_j w_g (D eq. 3.9).
  template <class Sim>
  void map_mass(Sim& sim) {
    static_assert(Sim::kDim == 1, "the cubic-spline mapping is one-dimensional (D 3.2)");
    auto& q = quad_.prepare<Sim>();
    fit_mass(sim, q);
    q.evaluate(sim.basis, sim.step, sim.time);
    sim.quadrature_dofs = q.ranges.span();  // shared with the particles' DOFs
    assemble_mass(sim, q, rho_g_);
  }

  // (rho v)_hat through (x_p, rho_p v_p); q_i = sum_g phi_i (rho v)_hat w_g (D eq. 3.8).
  template <class Sim>
  void map_momentum(Sim& sim) {
    static_assert(Sim::kDim == 1, "the cubic-spline mapping is one-dimensional (D 3.2)");
    const auto& q = quad_.prepared<Sim>();
    fit_momentum(sim);
    assemble_momentum(sim, q, vec_g_);
  }

  // sigma_hat through (x_p, sigma_p) and (rho b)_hat through (x_p, rho_p b_p);
  // f_i = sum_g ( phi_i (rho b)_hat - sigma_hat dphi_i/dx ) w_g (D eq. 3.7, body force alike).
  template <class Sim>
  void map_forces(Sim& sim) {
    static_assert(Sim::kDim == 1, "the cubic-spline mapping is one-dimensional (D 3.2)");
    const auto& q = quad_.prepared<Sim>();
    fit_forces(sim);
    assemble_forces(sim, q, vec_g_, sig_g_);
  }

 private:
  // cubic_spline.cpp. fit_mass: knots from the particle positions, the Gauss points placed in q
  // and the spline coefficients at them, rho_hat there (rho_g_). fit_momentum: (rho v)_hat
  // (vec_g_). fit_forces: sigma_hat (sig_g_) and (rho b)_hat (vec_g_).
  void fit_mass(const RunState<1>& sim, GaussPoints<1>& q);
  void fit_momentum(const RunState<1>& sim);
  void fit_forces(const RunState<1>& sim);

  // store(g, z(x_g)) for the fitted spline at every quadrature point (independent: parallel).
  // The fit itself, a tridiagonal (Thomas) solve along the knots, stays serial.
  template <class Store>
  void at_points(Store&& store) const {
    parallel_for(static_cast<Index>(samples_.size()), [&](Index g) {
      const auto gi = static_cast<std::size_t>(g);
      store(gi, spline_.evaluate(samples_[gi]));
    });
  }

  Settings settings_;
  GaussRule rule_;  // on [-1, 1], settings_.gauss_points_per_half points
  NaturalCubicSpline spline_;
  ElementBins<1> bins_;
  QuadratureStore quad_;
  std::vector<double> xg_;             // Gauss abscissae [m], ascending
  std::vector<SplineSample> samples_;  // spline coefficients at xg_
  std::vector<double> rho_g_;          // rho_hat at xg_ [kg/m^3]
  std::vector<Vec<1>> vec_g_;          // (rho v)_hat [kg/(m^2 s)] or (rho b)_hat [N/m^3]
  std::vector<Mat<1>> sig_g_;          // sigma_hat [Pa]
};

}  // namespace mpm
