#pragma once
// Moving least squares (MLS, 001 eq. 6-17) and improved moving least squares (IMLS, 003
// eq. 1-17) reconstruction in one dimension, and the particle-to-grid mappings built on them
// (001 eq. 18-37, 003 eq. 23-40).
//
// MovingLeastSquares fits, at each evaluation point x, a polynomial of degree 1 or 2 to the
// scattered data within the support of a weight w(x - x_p) and evaluates it at x (eq. 13).
//   MLS: a = A^{-1} B U with the moment matrix A(x) = sum_p w p(x_p) p(x_p)^T (001 eq. 10-14).
//   IMLS: the monomials are orthogonalised by Gram-Schmidt under the weighted discrete inner
//     product <f, g> = sum_p w(x - x_p) f(x_p) g(x_p) (003 eq. 7, 16), a_i = <p_i, u> / <p_i, p_i>
//     (eq. 11). Terms with <p_i, p_i> <= kDropTolerance <p_1, p_1> are dropped (eq. 17): the
//     fit never inverts a matrix, one particle gives its value, two particles a straight line.
// The monomials are those of s = (x_p - x) / l (l the cell size): the same polynomial space as
// 1, x, x^2 (so the same reconstruction, and the same dropped spans in IMLS) but scaled to O(1)
// and centred at the evaluation point, where p(x) = (1, 0, 0).
//
// The reconstruction is linear in the data: at each evaluation point the shape functions
// phi_p(x) (eq. 14) are computed once and stored (ShapeTable), then every field is a dot product.
#include <fmt/format.h>

#include <Eigen/Dense>
#include <any>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/simulation.hpp"
#include "mapping/quadrature.hpp"

namespace mpm {

class Config;

enum class MlsWeight {
  // 003 eq. 27 / 001 eq. 17: w(r), r = |x - x_p| / (2 l), nonzero for |x - x_p| < 3 l.
  QuadraticSpline,
  // The P1 hat centred at x: w = 1 - |x - x_p| / l for |x - x_p| < l (003 eq. 31 velocity).
  Linear,
};

// w(x - x_p) for a cell size l.
double mls_weight(MlsWeight kind, double distance, double cell);
// Support radius: 3 l (quadratic spline) or l (linear).
inline double mls_support(MlsWeight kind, double cell) {
  return kind == MlsWeight::QuadraticSpline ? 3.0 * cell : cell;
}

struct MlsReport {
  Index points = 0;            // evaluation points
  Index empty = 0;             // no particle in the support: value 0
  Index ill_conditioned = 0;   // MLS: cond(A) > max_condition (still solved)
  Index singular = 0;          // MLS: A singular (fewer distinct points than terms): value 0
  Index reduced = 0;           // IMLS: fewer terms than degree + 1 (eq. 17)
  Index widened = 0;           // linear weight without data: quadratic-spline weight used instead
  double max_condition = 0.0;  // MLS: largest cond(A) (infinite when singular)
  double worst_x = 0.0;        // MLS: where it occurred [m]
};

void accumulate(MlsReport& total, const MlsReport& step);

// Shape functions phi_p(x) at a list of evaluation points (compressed rows).
struct ShapeTable {
  std::vector<std::size_t> start{0};  // row r: entries start[r] .. start[r + 1]
  std::vector<Index> point;
  std::vector<double> phi;

  void clear() {
    start.assign(1, 0);
    point.clear();
    phi.clear();
  }
  std::size_t rows() const { return start.size() - 1; }
  // sum_p phi_p(x_r) f(p).
  template <class F>
  double apply(std::size_t r, F&& f) const {
    double s = 0.0;
    for (std::size_t k = start[r]; k < start[r + 1]; ++k)
      s += phi[k] * f(static_cast<std::size_t>(point[k]));
    return s;
  }
};

class MovingLeastSquares {
 public:
  // Relative tolerance on <p_i, p_i> / <p_1, p_1> below which IMLS drops p_i (003 eq. 17). The
  // ratio is the weighted mean square of p_i in units of l^(2(i-1)): 1e-10 drops a linear term
  // when the particles in the support spread less than ~1e-5 l, far above round-off (~1e-32) and
  // far below any particle spacing of a run.
  static constexpr double kDropTolerance = 1e-10;
  // MLS: A is treated as singular when lambda_min <= kSingular lambda_max.
  static constexpr double kSingular = 1e-14;

  // improved: IMLS, else MLS; degree 1 or 2 (throws InputError otherwise). max_condition:
  // MLS points with a larger cond(A) are counted as ill-conditioned.
  explicit MovingLeastSquares(bool improved = false, int degree = 1, double max_condition = 1e8);

  // Positions of the data (standalone use); points outside the grid are ignored and counted.
  void set_points(const Grid<1>& g, std::span<const double> x);
  // The particles of an MPM step.
  void set_points(const Grid<1>& g, const Particles<1>& P);

  // Appends the shape functions at x to t (an empty row where no particle is in the support).
  // widen: a Linear weight without data in its support falls back to the quadratic spline
  // (counted in widened): B-spline DOFs sit at Greville points, which may lie more than one
  // cell from the body although the DOF carries mass.
  void add_row(double x, MlsWeight weight, ShapeTable& t, bool widen = false);
  // The reconstruction of the data f (one value per point of set_points) at x.
  double evaluate(double x, MlsWeight weight, std::span<const double> f);

  bool improved() const { return improved_; }
  int degree() const { return degree_; }
  Index outside() const { return outside_; }
  const MlsReport& report() const { return report_; }
  void reset_report() { report_ = {}; }

 private:
  void bin(const Grid<1>& g);
  void gather(double x, MlsWeight weight);  // near_, s_, w_

  bool improved_;
  int degree_;
  double max_condition_;
  Grid<1> grid_{Vec<1>(0.0), Vec<1>(1.0), IVec<1>{1}};
  std::vector<double> x_;
  std::vector<std::size_t> start_;  // bins: points of cell c are order_[start_[c] .. start_[c+1])
  std::vector<Index> order_;
  std::vector<std::size_t> fill_;
  Index outside_ = 0;
  // Scratch of one evaluation point (no allocation once the capacity is reached).
  std::vector<Index> near_;
  std::vector<double> s_, w_, p_;  // p_[3 k + i]: orthogonal p_i at point k (IMLS)
  ShapeTable scratch_;
  MlsReport report_;
};

struct MlsSettings {
  int degree = 1;        // method.mls_degree: 1 (001 eq. 15) or 2
  int gauss_points = 0;  // per active element; 0: 2
  double max_condition = 1e8;
  int gauss_points_used() const { return gauss_points > 0 ? gauss_points : 2; }
};

// The MLS (Improved = false, 001 eq. 18-33) and IMLS (Improved = true, 003 eq. 23-36) mappings,
// one-dimensional. map_mass, the first mapping call of a step, bins the particles, places
// n Gauss points in every element holding a particle and stores the shape functions there
// (quadratic-spline weight); map_forces and map_momentum reuse them.
//   mass: rho^ (data rho_p); lumped, or consistent for MLS.
//   forces: sigma^ (data sigma_p) and b^ (data b_p), body-force density rho^ b^ at the Gauss
//     points (001 eq. 20, 24 / 003 eq. 25, 29 reconstruct b; the density factor they leave out
//     is the reconstructed one, so a uniform b gives f_i = m_i b exactly).
//   momentum: MLS: (rho v)^ (data rho_p v_p), q_i = sum_g phi_i (rho v)^ w_g (001 eq. 19, 23).
//     IMLS: v_i = the IMLS fit with the linear weight at the node (003 eq. 31), q_i = m_i v_i so
//     that solve_velocity's M^-1 q returns v_i; needs lumped mass (003 eq. 32). Only DOFs with
//     mass get a value; one with no particle within a cell (possible for B-splines, whose DOFs
//     sit at Greville points) uses the quadratic-spline weight instead (report().widened).
template <bool Improved>
class MovingLeastSquaresMapping {
 public:
  static constexpr std::string_view kName = Improved ? "imls" : "mls";
  using Settings = MlsSettings;
  static constexpr bool supports_dimension(int dim) { return dim == 1; }

  MovingLeastSquaresMapping() : MovingLeastSquaresMapping(Settings{}) {}
  // Throws InputError for a degree other than 1, 2 or negative Gauss points.
  explicit MovingLeastSquaresMapping(const Settings& s)
      : settings_(s), mls_(Improved, s.degree, s.max_condition) {
    if (s.gauss_points < 0) throw InputError("method.gauss_points must be >= 0");
    rule_ = gauss_legendre(s.gauss_points_used());
  }
  // method.mls_degree and method.gauss_points; IMLS also checks method.mass = lumped.
  static MovingLeastSquaresMapping from_config(const Config& cfg);

  const Settings& settings() const { return settings_; }
  const MovingLeastSquares& reconstruction() const { return mls_; }
  // The last step (Gauss points and, IMLS, nodes) and the sums over the run.
  const MlsReport& last_report() const { return mls_.report(); }
  const MlsReport& totals() const { return totals_; }
  // Checkpoint restart: the sums continue from a saved run (io/checkpoint.hpp).
  void set_totals(const MlsReport& t) { totals_ = t; }
  template <class Sim>
  const QuadraturePoints<Sim>* quadrature() const {
    return quad_.get<Sim>();
  }

  template <class Sim>
  void map_mass(Sim& sim) {
    static_assert(Sim::kDim == 1, "the MLS/IMLS mappings are one-dimensional");
    if (Improved && sim.mass_type == MassType::Consistent)
      throw InputError("method.mapping = imls needs method.mass = lumped (003 eq. 32)");
    const auto& P = sim.particles;
    const auto& grid = sim.grid;
    mls_.set_points(grid, P);
    auto& q = quad_.prepare<Sim>();
    q.clear();
    gauss_.clear();
    const double h = grid.h[0], half = 0.5 * h;
    active_.assign(static_cast<std::size_t>(grid.num_cells()), 0);
    for (const auto& x : P.x) active_[static_cast<std::size_t>(grid.cell_index(x))] = 1;
    for (Index e = 0; e < grid.num_cells(); ++e) {
      if (!active_[static_cast<std::size_t>(e)]) continue;
      const double xc = grid.origin[0] + (static_cast<double>(e) + 0.5) * h;
      for (std::size_t k = 0; k < rule_.xi.size(); ++k) {
        const double xg = xc + half * rule_.xi[k];
        q.add(Vec<1>(xg), half * rule_.w[k], e);
        mls_.add_row(xg, MlsWeight::QuadraticSpline, gauss_);
      }
    }
    q.evaluate(sim);
    rho_.resize(q.size());
    for (std::size_t g = 0; g < q.size(); ++g)
      rho_[g] = gauss_.apply(g, [&](std::size_t p) { return P.density[p]; });
    assemble_mass(sim, q, rho_);
    if constexpr (Improved) {
      // Nodal rows (003 eq. 31) for the DOFs that carry mass.
      nodes_.clear();
      node_dof_.clear();
      const auto& m = sim.nodes.mass;
      for (Index i = 0; i < sim.basis.num_dofs(); ++i) {
        if (!(m[static_cast<std::size_t>(i)] > 0.0)) continue;
        node_dof_.push_back(i);
        mls_.add_row(sim.basis.dof_position(i)[0], MlsWeight::Linear, nodes_, true);
      }
    }
    const MlsReport& rep = mls_.report();
    accumulate(totals_, rep);
    if (rep.singular > 0)
      throw RunError(exit_code::kReconstruction,
                     fmt::format("step {}, t = {:.9g} s: the MLS moment matrix is singular at {} "
                                 "point(s) (first near x = {:.6g}): too few distinct particles "
                                 "for method.mls_degree = {}; use method.mapping = imls",
                                 sim.step, sim.time, rep.singular, rep.worst_x, settings_.degree));
  }

  template <class Sim>
  void map_momentum(Sim& sim) {
    static_assert(Sim::kDim == 1, "the MLS/IMLS mappings are one-dimensional");
    const auto& P = sim.particles;
    const auto& q = quad_.prepared<Sim>();
    if constexpr (Improved) {
      auto& out = sim.nodes.momentum;
      std::fill(out.begin(), out.end(), Vec<1>::Zero());
      for (std::size_t r = 0; r < node_dof_.size(); ++r) {
        const auto i = static_cast<std::size_t>(node_dof_[r]);
        const double v = nodes_.apply(r, [&](std::size_t p) { return P.v[p][0]; });
        out[i][0] = sim.nodes.mass[i] * v;
      }
    } else {
      vec_.resize(q.size());
      for (std::size_t g = 0; g < q.size(); ++g)
        vec_[g][0] = gauss_.apply(g, [&](std::size_t p) { return P.density[p] * P.v[p][0]; });
      assemble_momentum(sim, q, vec_);
    }
  }

  template <class Sim>
  void map_forces(Sim& sim) {
    static_assert(Sim::kDim == 1, "the MLS/IMLS mappings are one-dimensional");
    const auto& P = sim.particles;
    const auto& q = quad_.prepared<Sim>();
    sig_.resize(q.size());
    vec_.resize(q.size());
    for (std::size_t g = 0; g < q.size(); ++g) {
      sig_[g](0, 0) = gauss_.apply(g, [&](std::size_t p) { return P.stress[p](0, 0); });
      vec_[g][0] = rho_[g] * gauss_.apply(g, [&](std::size_t p) { return P.body[p][0]; });
    }
    assemble_forces(sim, q, vec_, sig_);
  }

 private:
  Settings settings_;
  MovingLeastSquares mls_;
  GaussRule rule_;
  QuadratureStore quad_;
  std::vector<char> active_;
  ShapeTable gauss_, nodes_;
  std::vector<Index> node_dof_;
  std::vector<double> rho_;
  std::vector<Vec<1>> vec_;
  std::vector<Mat<1>> sig_;
  MlsReport totals_;
};

using MlsMapping = MovingLeastSquaresMapping<false>;
using ImlsMapping = MovingLeastSquaresMapping<true>;

// Settings from method.mls_degree, method.gauss_points (and method.mass for IMLS).
MlsSettings mls_settings_from_config(const Config& cfg, bool improved);

template <bool Improved>
MovingLeastSquaresMapping<Improved> MovingLeastSquaresMapping<Improved>::from_config(
    const Config& cfg) {
  return MovingLeastSquaresMapping(mls_settings_from_config(cfg, Improved));
}

}  // namespace mpm
