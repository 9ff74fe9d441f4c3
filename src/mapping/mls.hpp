#pragma once
// Moving least squares (MLS, 001 eq. 6-17) and improved moving least squares (IMLS, 003
// eq. 1-17) reconstruction in one, two and three dimensions, and the particle-to-grid mappings
// built on them (001 eq. 18-37, 003 eq. 23-40).
//
// MovingLeastSquares<Dim> fits, at each evaluation point x, a polynomial of degree 1 or 2 to the
// scattered data within the support of a weight w(x - x_p) and evaluates it at x (eq. 13).
//   MLS: a = A^{-1} B U with the moment matrix A(x) = sum_p w p(x_p) p(x_p)^T (001 eq. 10-14).
//   IMLS: the monomials are orthogonalised by Gram-Schmidt under the weighted discrete inner
//     product <f, g> = sum_p w(x - x_p) f(x_p) g(x_p) (003 eq. 7, 16), a_i = <p_i, u> / <p_i, p_i>
//     (eq. 11). Terms with <p_i, p_i> <= kDropTolerance <p_1, p_1> are dropped (eq. 17): the
//     fit never inverts a matrix, one particle gives its value, two particles a straight line.
//     Terms the data resolve too poorly at x (kMaxAmplification) are dropped as well.
// The monomials, ordered by total degree ([1, x, y, x^2, xy, y^2], 003 eq. 15; [1, x, x^2] in
// 1D), are those of s = (x_p - x) / l per direction (l_d the cell size): the same polynomial
// space as in x (so the same reconstruction, and the same dropped spans in IMLS) but scaled to
// O(1) and centred at the evaluation point, where p(x) = (1, 0, ..., 0).
// In 2D the weight is the tensor product w(x - x_p) = w(r_x) w(r_y) (001 eq. 16); in 3D the same
// product over the three directions (001 and 003 are 2D; 3D is their direct extension).
//
// The reconstruction is linear in the data: at each evaluation point the shape functions
// phi_p(x) (eq. 14) are computed once and stored (ShapeTable), then every field is a dot product.
// Particles are binned by cell (ElementBins); an evaluation visits only the cells within the
// support of the weight (7 per direction for the quadratic spline, 3 for the linear weight).
#include <fmt/format.h>

#include <Eigen/Dense>
#include <any>
#include <array>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <vector>

#include "mapping/mapping.hpp"
#include "mapping/quadrature.hpp"
#include "state/simulation.hpp"

namespace mpm {

enum class MlsWeight {
  // 003 eq. 27 / 001 eq. 17: w(r), r = |x - x_p| / (a l), nonzero for |x - x_p| < 1.5 a l (per
  // direction; 001 eq. 16 multiplies the directions). The dilation a is 2 in 001 eq. 16 and 003
  // (a support 6 cells wide); method.mls_dilation changes it.
  QuadraticSpline,
  // The P1 hat centred at x: w = 1 - |x - x_p| / l for |x - x_p| < l (003 eq. 31 velocity),
  // tensor product in 2D.
  Linear,
};

// The published dilation of the quadratic-spline weight (001 eq. 16, 003 eq. 27: r = dx / (2 l)).
inline constexpr double kMlsDilation = 2.0;
// w(x - x_p) for a cell size l (one direction).
double mls_weight(MlsWeight kind, double distance, double cell, double dilation = kMlsDilation);
// Support radius per direction: 1.5 a l (quadratic spline; 3 l for a = 2) or l (linear).
inline double mls_support(MlsWeight kind, double cell, double dilation = kMlsDilation) {
  return kind == MlsWeight::QuadraticSpline ? 1.5 * dilation * cell : cell;
}
// Number of monomials of total degree <= degree (1 or 2) in dim variables: 2, 3 in 1D;
// 3, 6 in 2D (001 eq. 15, 003 eq. 15); 4, 10 in 3D.
constexpr int mls_terms(int dim, int degree) {
  return degree == 1 ? dim + 1 : (dim + 1) * (dim + 2) / 2;
}

struct MlsReport {
  Index points = 0;            // evaluation points
  Index empty = 0;             // no particle in the support: value 0
  Index ill_conditioned = 0;   // MLS: cond(A) > max_condition (still solved)
  Index singular = 0;          // MLS: A singular (fewer distinct points than terms): value 0
  Index reduced = 0;           // IMLS: fewer terms than the full basis (eq. 17, kMaxAmplification)
  Index widened = 0;           // linear weight without data: quadratic-spline weight used instead
  double max_condition = 0.0;  // MLS: largest cond(A) (infinite when singular)
  double worst_x = 0.0;        // MLS: where it occurred, first coordinate [m]
  double worst_y = 0.0;        // MLS: second coordinate (2D, 3D; 0 in 1D) [m]
  double worst_z = 0.0;        // MLS: third coordinate (3D; 0 otherwise) [m]
};

void accumulate(MlsReport& total, const MlsReport& step);
// The reports of the processes of a distributed run as one (collective): counts summed, the
// largest condition number with its place (the lowest rank's on ties). IMLS's nodal rows are
// counted by every process that holds mass at the node.
MlsReport over_ranks(const Comm& comm, const MlsReport& mine);

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
  // sum_p phi_p(x_r) f(p); T is double or a fixed-size Eigen vector or matrix (all components
  // of a field in one pass over the row).
  template <class T = double, class F>
  T apply(std::size_t r, F&& f) const {
    T s;
    if constexpr (std::is_arithmetic_v<T>)
      s = 0.0;
    else
      s.setZero();
    for (std::size_t k = start[r]; k < start[r + 1]; ++k)
      s += phi[k] * f(static_cast<std::size_t>(point[k]));
    return s;
  }
};

// The rows of many evaluation points computed in parallel (MovingLeastSquares::add_rows): the
// rows are split into the fixed chunks of ParticleChunks over the row count (a function of the
// count only, not of the threads), chunk c holding rows begin(rows, c, k) .. begin(rows, c + 1, k)
// as local rows 0, 1, ... of its own table. Each chunk is computed by one thread with its own
// scratch, so the tables are the same for any thread count and a row is bitwise the row
// add_row gives.
struct ShapeTables {
  Index rows = 0;
  std::vector<ShapeTable> chunk;

  int chunks() const { return ParticleChunks::count(rows); }
  // f(r, table, local row) for every row r, chunks in parallel (f must only write row r's
  // results).
  template <class F>
  void for_each_row(F&& f) const {
    for_each_chunk(rows, [&](int c, Index b, Index e) {
      const ShapeTable& t = chunk[static_cast<std::size_t>(c)];
      for (Index r = b; r < e; ++r)
        f(static_cast<std::size_t>(r), t, static_cast<std::size_t>(r - b));
    });
  }
};

template <int Dim = 1>
class MovingLeastSquares {
  static_assert(Dim >= 1 && Dim <= 3, "MLS is implemented in 1D, 2D and 3D");

 public:
  // Relative tolerance on <p_i, p_i> / <p_1, p_1> below which IMLS drops p_i (003 eq. 17). The
  // ratio is the weighted mean square of p_i in units of l^(2 deg p_i): 1e-10 drops a linear
  // term when the particles in the support spread less than ~1e-5 l in that direction, far
  // above round-off (~1e-32) and far below any particle spacing of a run.
  static constexpr double kDropTolerance = 1e-10;
  // IMLS also drops p_i when |p_i(x)| > kMaxAmplification rms(p_i), rms(p_i)^2 = <p_i, p_i> /
  // <p_1, p_1>. By Cauchy-Schwarz that term's share of the amplification sum_p |phi_p(x)| is at
  // most |p_i(x)| / rms(p_i), so the kept terms give sum_p |phi_p| <= 1 + (m - 1) 1e3. Eq. 17
  // only drops terms that vanish exactly; nearly dependent data keep a tiny but non-zero
  // <p_i, p_i> and the fit then extrapolates with a huge coefficient. In 2D this happens at free
  // edges: the linear-weight support of a B-spline DOF outside the body holds one column of
  // particles, which the deformation bends slightly (~1e-6 l), and the nodal velocity (003
  // eq. 31) jumped to 1e4 v0 within one step (free block, MUSL). Measured ratios: at most ~25 on
  // random data with every term resolved (the reproduction tests, 3 or 9 particles per cell,
  // degree 2, linear weight), 2e6 to 9e6 where such runs blew up; 1e3 separates them with a wide
  // margin on both sides. The 1D mms_1d errors (docs/verification.md) are unchanged.
  static constexpr double kMaxAmplification = 1e3;
  // MLS: A is treated as singular when lambda_min <= kSingular lambda_max.
  static constexpr double kSingular = 1e-14;
  // Largest number of polynomial terms (degree 2).
  static constexpr int kMaxTerms = mls_terms(Dim, 2);

  // improved: IMLS, else MLS; degree 1 or 2 (throws InputError otherwise). max_condition:
  // MLS points with a larger cond(A) are counted as ill-conditioned. dilation: a of the
  // quadratic-spline weight (MlsWeight), > 0.
  explicit MovingLeastSquares(bool improved = false, int degree = 1, double max_condition = 1e8,
                              double dilation = kMlsDilation);

  // Positions of the data (standalone use); points outside the grid are ignored and counted.
  void set_points(const Grid<Dim>& g, std::span<const Vec<Dim>> x);
  // The 1D conveniences are member templates so that the explicit instantiation of the 2D
  // class (mls.cpp) does not instantiate them (clang 14 instantiates constrained non-template
  // members whose constraint fails).
  template <int D = Dim>
  requires(D == 1) void set_points(const Grid<1>& g, std::span<const double> x) {
    x_.resize(x.size());
    for (std::size_t p = 0; p < x.size(); ++p) x_[p][0] = x[p];
    bin(g);
  }
  // The particles of an MPM step.
  void set_points(const Grid<Dim>& g, const Particles<Dim>& P) { set_points(g, std::span(P.x)); }

  // Appends the shape functions at x to t (an empty row where no particle is in the support).
  // widen: a Linear weight without data in its support falls back to the quadratic spline
  // (counted in widened): B-spline DOFs sit at Greville points, which may lie more than one
  // cell from the body although the DOF carries mass.
  void add_row(const Vec<Dim>& x, MlsWeight weight, ShapeTable& t, bool widen = false);
  template <int D = Dim>
  requires(D == 1) void add_row(double x, MlsWeight weight, ShapeTable& t, bool widen = false) {
    add_row(Vec<1>(x), weight, t, widen);
  }
  // The rows of n points x_of(0) .. x_of(n - 1) (x_of(i) -> Vec<Dim>, called concurrently) into
  // t, chunks in parallel (ShapeTables); the report counts them as n add_row calls in order.
  template <class XOf>
  void add_rows(Index n, XOf&& x_of, MlsWeight weight, ShapeTables& t, bool widen = false) {
    const int k = ParticleChunks::count(n);
    const auto ks = static_cast<std::size_t>(k);
    t.rows = n;
    if (t.chunk.size() < ks) t.chunk.resize(ks);
    if (scratch_.size() < ks) scratch_.resize(ks);
    std::array<MlsReport, ParticleChunks::kMax> rep{};
    const double per_row = expected_row_length(weight);
    for_each_chunk(n, [&](int c, Index b, Index e) {
      const auto cc = static_cast<std::size_t>(c);
      ShapeTable& tc = t.chunk[cc];
      tc.clear();
      // Capacity for the expected entries (+10 %) at once: growing a table of tens of MB by
      // doubling copied and page-faulted it several times in the first step of every run.
      const auto rows = static_cast<std::size_t>(e - b);
      tc.start.reserve(rows + 1);
      tc.point.reserve(static_cast<std::size_t>(1.1 * per_row * static_cast<double>(rows)));
      tc.phi.reserve(tc.point.capacity());
      for (Index i = b; i < e; ++i) row(x_of(i), weight, widen, scratch_[cc], tc, rep[cc]);
    });
    // Chunk order: counts add exactly, and the first largest condition number wins as in a
    // serial loop (accumulate keeps the earlier one on ties).
    for (std::size_t c = 0; c < ks; ++c) accumulate(report_, rep[c]);
  }
  // The reconstruction of the data f (one value per point of set_points) at x.
  double evaluate(const Vec<Dim>& x, MlsWeight weight, std::span<const double> f);
  template <int D = Dim>
  requires(D == 1) double evaluate(double x, MlsWeight weight, std::span<const double> f) {
    return evaluate(Vec<1>(x), weight, f);
  }

  bool improved() const { return improved_; }
  int degree() const { return degree_; }
  double dilation() const { return dilation_; }
  int terms() const { return terms_; }
  Index outside() const { return outside_; }
  // The data binned by grid cell (valid after set_points).
  const ElementBins<Dim>& bins() const { return bins_; }
  const MlsReport& report() const { return report_; }
  void reset_report() { report_ = {}; }

 private:
  // Scratch of one evaluation point (no allocation once the capacity is reached); one per chunk
  // of add_rows, so that chunks can run concurrently.
  struct Scratch {
    // The first n entries hold the points in the support (gather); the vectors only grow.
    std::size_t n = 0;
    std::vector<Index> near;
    std::vector<Vec<Dim>> s;  // (x_p - x) / l per direction
    std::vector<double> w;
    std::vector<double> phi;  // the row's shape functions
    std::vector<double> p;    // IMLS: p[n i + k]: monomial / orthogonal p_i at point k
  };

  // Points in the support of a weight centred in the body: the mean points per occupied cell
  // times the support area in cells, (2 R / l)^Dim (a capacity hint, no effect on results).
  double expected_row_length(MlsWeight weight) const {
    Index occupied = 0;
    for (Index e = 0; e < grid_.num_cells(); ++e) occupied += bins_.count(e) > 0 ? 1 : 0;
    double cells = 1.0;
    for (int d = 0; d < Dim; ++d)
      cells *= 2.0 * mls_support(weight, grid_.h[d], dilation_) / grid_.h[d];
    return occupied > 0
               ? cells * static_cast<double>(bins_.order.size()) / static_cast<double>(occupied)
               : 0.0;
  }
  void bin(const Grid<Dim>& g);                                         // x_ into bins_
  void gather(const Vec<Dim>& x, MlsWeight weight, Scratch& sc) const;  // n, near, s, w
  // One row appended to t, counted in rep.
  void row(const Vec<Dim>& x, MlsWeight weight, bool widen, Scratch& sc, ShapeTable& t,
           MlsReport& rep) const;
  // IMLS: the row's shape functions into sc.phi.
  void imls_row(Scratch& sc, MlsReport& rep) const;

  bool improved_;
  int degree_;
  int terms_;
  double max_condition_;
  double dilation_;
  Grid<Dim> grid_;
  std::vector<Vec<Dim>> x_;
  std::vector<Vec<Dim>> xb_;  // x_ in bin order (bins_.order)
  ElementBins<Dim> bins_;
  Index outside_ = 0;
  std::vector<Scratch> scratch_;  // scratch_[0]: add_row and evaluate; scratch_[c]: chunk c
  ShapeTable scratch_table_;
  MlsReport report_;
};

extern template class MovingLeastSquares<1>;
extern template class MovingLeastSquares<2>;
extern template class MovingLeastSquares<3>;

struct MlsSettings {
  int degree = 1;        // method.mls_degree: 1 (001 eq. 15) or 2
  int gauss_points = 0;  // per active element; 0: 2
  double max_condition = 1e8;
  double dilation = kMlsDilation;  // method.mls_dilation
  // method.mls_conservative: shift the reconstructed densities in each element so that they
  // integrate to the particles' mass, momentum and body force there (conserve_by_element), and
  // IMLS's nodal velocities by one common vector so that the nodal momenta add up to the
  // particles'. false: 001's and 003's definitions, which conserve neither.
  bool conservative = false;
  int gauss_points_used() const { return gauss_points > 0 ? gauss_points : 2; }
};

// The MLS (001 eq. 18-33) and IMLS (003 eq. 23-36) mappings
// in 1D, 2D and 3D. map_mass, the first mapping call of a step, bins the particles, places n Gauss
// points per direction in every element holding a particle (n^Dim per element, 001: 2 x 2) and
// stores the shape functions there (quadratic-spline weight); map_forces and map_momentum reuse
// them. Every vector and tensor component is reconstructed with the same shape functions.
//   mass: rho^ (data rho_p); lumped, or consistent for MLS.
//   forces: sigma^ (data sigma_p) and b^ (data b_p), body-force density rho^ b^ at the Gauss
//     points (001 eq. 20, 24 / 003 eq. 25, 29 reconstruct b; the density factor they leave out
//     is the reconstructed one, so a uniform b gives f_i = m_i b exactly).
//   momentum: MLS: (rho v)^ (data rho_p v_p), q_i = sum_g phi_i (rho v)^ w_g (001 eq. 19, 23).
//     IMLS: v_i = the IMLS fit with the linear weight at the node (003 eq. 31), q_i = m_i v_i so
//     that solve_velocity's M^-1 q returns v_i; needs lumped mass (003 eq. 32). Only DOFs with
//     mass get a value; one with no particle within a cell (possible for B-splines, whose DOFs
//     sit at Greville points) uses the quadratic-spline weight instead (report().widened).
// Settings::conservative adds the conservation that 001 and 003 lack, by the smallest
// corrections of the reconstructed fields that make their totals the particles':
//   rho~_g = rho^_g M / sum_g w_g rho^_g, M = sum_p m_p: the minimiser of
//     sum_g w_g (rho~_g - rho^_g)^2 / rho^_g under sum_g w_g rho~_g = M (a Lagrange multiplier
//     gives rho~ proportional to rho^), so the shape of the fit is kept and its sign too;
//   (rho v)~_g = (rho v)^_g + rho~_g delta, delta = (sum_p m_p v_p - sum_g w_g (rho v)^_g) / M:
//     the minimiser of sum_g w_g |(rho v)~_g - (rho v)^_g|^2 / rho~_g under the momentum total,
//     a common velocity added to the whole body (Galilean: it leaves relative motion alone);
//   (rho b)~ likewise with sum_p m_p b_p.
// The basis is a partition of unity at every Gauss point, so sum_i m_i = sum_p m_p,
// sum_i q_i = sum_p m_p v_p and the external forces add up to sum_p m_p b_p to round-off;
// internal forces add up to zero as before. IMLS's momentum is nodal (003 eq. 31): its nodal
// velocities get the common shift (sum_p m_p v_p - sum_i m_i v_i) / sum_i m_i, the same
// correction at the nodes. A per-element version (each element's integral set to its own
// particles' mass, the constraint of conservative TLS, D eq. 5.8-5.9) was tried and rejected: the
// particle mass in an element jumps by a whole m_p whenever a particle crosses a cell face, which
// brought back the grid-crossing noise that the MLS smoothing removes (mms_1d, P1 and B2 with MLS
// and P1 with IMLS on 16, 32, 64 cells: 5 of the 9 runs stopped, the others had errors 4-18x
// those of 001's and 003's definitions).
//
// MlsFamilyMapping runs both; `improved` chooses IMLS. The two differ in a few choices per step
// (the nodal rows, what map_momentum assembles), not in a per-particle loop, so the choice is
// made at run time and the steppers compile one Simulation for the two (driver/stepper_impl.hpp,
// stepped_mapping_t): one stepper instantiation less per (dimension, basis); a 2D B2 stepper unit
// compiles in about 14.5 s against 15.5 s with two.
// MovingLeastSquaresMapping<Improved> (MlsMapping, ImlsMapping) are the two named alternatives of
// the configuration (MappingKind), each this class with its flag.
class MlsFamilyMapping {
 public:
  // For the MappingFor concept; the configuration names the two alternatives below.
  static constexpr std::string_view kName = "mls or imls";
  using Settings = MlsSettings;
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  // Capabilities (mapping/mapping.hpp).
  static constexpr bool kFusedScatter = false, kRunTotals = true, kGhostParticles = true,
                        kStrainRates = false, kCellQuadrature = true;

  // The cells (along every axis) around this process's elements whose particles of the other
  // processes this mapping reads in a distributed run (MappingFor's kGhostParticles): the
  // quadratic-spline weight's support, 1.5 a cells (a the dilation), from the Gauss points in
  // this process's elements, plus one for the cell the support starts in; IMLS's nodal rows sit at
  // the DOFs of those elements' stencils, up to `per_dim` cells further (the stencil's nodes per
  // direction).
  template <class Sim>
  double ghost_reach(const Sim&) const {
    constexpr int kSize = Sim::BasisT::StencilT::kSize;
    int per_dim = 1;
    while (ipow(per_dim + 1, Sim::kDim) <= kSize) ++per_dim;
    return std::ceil(1.5 * settings_.dilation) + 1.0 + (improved_ ? per_dim : 0);
  }

  // Throws InputError for a degree other than 1, 2 or negative Gauss points.
  MlsFamilyMapping(const Settings& s, bool improved)
      : settings_(s),
        improved_(improved),
        work_(Work<1>(s, improved), Work<2>(s, improved), Work<3>(s, improved)) {
    if (s.gauss_points < 0) throw InputError("method.gauss_points must be >= 0");
    rule_ = gauss_legendre(s.gauss_points_used());
  }

  const Settings& settings() const { return settings_; }
  // Gauss points per direction of an element (MappingFor's kCellQuadrature).
  int gauss_points() const { return settings_.gauss_points_used(); }
  template <int Dim = 1>
  const MovingLeastSquares<Dim>& reconstruction() const {
    return std::get<Dim - 1>(work_).mls;
  }
  // The last step (Gauss points and, IMLS, nodes) and the sums over the run.
  const MlsReport& last_report() const {
    return dim_ == 3   ? reconstruction<3>().report()
           : dim_ == 2 ? reconstruction<2>().report()
                       : reconstruction<1>().report();
  }
  const MlsReport& totals() const { return totals_; }
  // Checkpoint restart: the sums continue from a saved run. save_totals() gives the bytes that
  // the checkpoint stores (core/bytes.hpp); load_totals() reads them back, InputError naming
  // `what` when they are not those of an MLS run.
  void set_totals(const MlsReport& t) { totals_ = t; }
  std::string save_totals() const;
  void load_totals(std::string_view bytes, const std::string& what);
  template <class Sim>
  const QuadraturePointsOf<Sim>* quadrature() const {
    return quad_.get<Sim>();
  }

  // The basis enters only through the quadrature stencils and the nodal positions (IMLS): the
  // reconstructions are compiled once per dimension (mls.cpp), the assembly once per basis.
  template <class Sim>
  void map_mass(Sim& sim) {
    constexpr int Dim = Sim::kDim;
    static_assert(Dim >= 1 && Dim <= 3, "the MLS/IMLS mappings are 1D, 2D and 3D");
    auto& q = quad_.prepare<Sim>();
    fit_mass<Dim>(sim, q);
    q.evaluate(sim.basis, sim.step, sim.time);
    sim.quadrature_dofs = q.ranges.span();  // shared with the particles' DOFs
    assemble_mass(sim, q, rho_);
    if (improved_) {
      // Nodal rows (003 eq. 31) for the DOFs that carry mass.
      node_dof_.clear();
      node_mass_.clear();
      auto& xn = std::get<Dim - 1>(work_).node_x;
      xn.clear();
      // The DOFs of the grid arrays' window (every DOF on one process; the sums of a
      // distributed run's process lie in it).
      const auto& m = sim.nodes.mass;
      for (Index i = m.first(); i < m.stop(); ++i)
        if (m[i] > 0.0) {
          node_dof_.push_back(i);
          node_mass_.push_back(m[i]);
          xn.push_back(sim.basis.dof_position(i));
        }
    }
    finish_mass<Dim>(sim);
  }

  template <class Sim>
  void map_momentum(Sim& sim) {
    constexpr int Dim = Sim::kDim;
    const auto& q = quad_.prepared<Sim>();
    fit_momentum<Dim>(sim, q);
    if (!improved_) assemble_momentum(sim, q, std::get<Dim - 1>(work_).vec);
  }

  template <class Sim>
  void map_forces(Sim& sim) {
    constexpr int Dim = Sim::kDim;
    const auto& q = quad_.prepared<Sim>();
    fit_forces<Dim>(sim, q);
    assemble_forces(sim, q, std::get<Dim - 1>(work_).vec, std::get<Dim - 1>(work_).sig);
  }

 private:
  // The reconstruction and the Gauss-point fields of one dimension (the mapping is chosen before
  // the dimension is known, so it holds all three; the unused ones stay empty).
  template <int Dim>
  struct Work {
    Work(const Settings& s, bool improved) : mls(improved, s.degree, s.max_condition, s.dilation) {}
    MovingLeastSquares<Dim> mls;
    std::vector<Vec<Dim>> vec;
    std::vector<Mat<Dim>> sig;
    std::vector<Vec<Dim>> node_x;  // IMLS: positions of the DOFs node_dof_
  };

  // mls.cpp, for Dim 1 to 3. fit_mass: bins the particles, places the Gauss points in q, their
  // shape functions and rho^ there (rho_). finish_mass: the IMLS nodal rows (node_x) and the
  // report, stopping the run on a singular moment matrix. fit_momentum: (rho v)^ at the Gauss
  // points (vec), or for IMLS the nodal momenta m_i v_i. fit_forces: sigma^ (sig) and (rho b)^
  // (vec) at the Gauss points.
  template <int Dim>
  void fit_mass(RunState<Dim>& sim, GaussPoints<Dim>& q);
  template <int Dim>
  void finish_mass(RunState<Dim>& sim);
  template <int Dim>
  void fit_momentum(RunState<Dim>& sim, const GaussPoints<Dim>& q);
  template <int Dim>
  void fit_forces(RunState<Dim>& sim, const GaussPoints<Dim>& q);
  // Settings::conservative: f_g + rho_g delta with the common delta that makes
  // sum_g w_g f_g = total (mls.hpp).
  // comm: the processes of a distributed run (the sums over all of them), or null.
  template <int Dim, class V>
  void conserve_with_density(const GaussPoints<Dim>& q, std::vector<V>& f, const V& total,
                             const Comm* comm) const;

  Settings settings_;
  bool improved_ = false;
  std::tuple<Work<1>, Work<2>, Work<3>> work_;
  int dim_ = 1;  // dimension of the last map_mass
  GaussRule rule_;
  QuadratureStore quad_;
  ShapeTables gauss_, nodes_;  // rows at the Gauss points and (IMLS) at the nodes
  std::vector<Index> node_dof_;
  // IMLS: the nodal masses of node_dof_ as this mapping assembled them: in a distributed run this
  // process's partial sums m_i^r, so that its momenta m_i^r v_i add up to m_i v_i in the
  // exchange (sim.nodes.mass holds the totals once the masses were exchanged).
  std::vector<double> node_mass_;
  std::vector<double> rho_;
  MlsReport totals_;
};

template <bool Improved>
class MovingLeastSquaresMapping : public MlsFamilyMapping {
 public:
  static constexpr std::string_view kName = Improved ? "imls" : "mls";
  static constexpr std::string_view kDescription =
      Improved
          ? "improved MLS: Gram-Schmidt orthogonal basis, no moment-matrix inverse (003 eq. 1-40)"
          : "moving least squares at Gauss points, quadratic-spline weight (001 eq. 6-37)";
  MovingLeastSquaresMapping() : MovingLeastSquaresMapping(Settings{}) {}
  explicit MovingLeastSquaresMapping(const Settings& s) : MlsFamilyMapping(s, Improved) {}
};

using MlsMapping = MovingLeastSquaresMapping<false>;
using ImlsMapping = MovingLeastSquaresMapping<true>;

// The steppers run both as MlsFamilyMapping (above).
template <bool Improved>
struct stepped_mapping<MovingLeastSquaresMapping<Improved>> {
  using type = MlsFamilyMapping;
};

}  // namespace mpm
