#pragma once
// Taylor least-squares (TLS) reconstruction in one dimension and the TLS particle-to-grid mapping
// (D 5.2-5.3, 000 sec. 2-4, 004 4.4).
//
// TlsReconstruction fits, per cell of a Grid<1> (an element), a short Taylor expansion to
// scattered data (D eq. 5.1-5.5). Fields are either plain least squares (all coefficients free,
// D eq. 5.1) or conservative: a_1 = c_e / |Omega_e| is fixed by the element integral c_e and the
// other coefficients fit f - a_1 (D eq. 5.8-5.9, 5.3.1). The least-squares matrices depend only on
// the point positions, so they are built and factorised once per point set and reused for every
// field. The reconstruction is element-local and discontinuous across element faces.
//
// TlsMapping uses it as the particle-to-grid mapping of MPM (D 5.3.1, 004 4.4.3): density,
// momentum density and body-force density are reconstructed conservatively, stress by plain least
// squares, and all are integrated with n Gauss points per active element (D eq. 5.12-5.17), which
// conserves mass and momentum to round-off (D eq. 5.19-5.21).
#include <fmt/format.h>

#include <Eigen/Dense>
#include <any>
#include <limits>
#include <span>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/simulation.hpp"
#include "mapping/quadrature.hpp"

namespace mpm {

class Config;

// What an element does when its data cannot support the requested Taylor basis (D 5.2.3;
// registry::kTlsCompletions holds the user-facing names).
enum class TlsCompletion {
  None,       // report failure (the MPM mapping stops the run, exit code 6)
  Reduce,     // fewer Taylor terms (3 -> 2 -> 1) until the fit is well posed
  Virtual,    // virtual points at the faces, valued by the neighbours' reconstructions
  Neighbour,  // borrow the nearest points of the adjacent elements
};

// "none", "reduce", "virtual", "neighbour" (registry::kTlsCompletions). Throws InputError.
TlsCompletion parse_tls_completion(std::string_view name);
std::string_view tls_completion_name(TlsCompletion c);

struct TlsSettings {
  int terms = 3;  // n_b: Taylor basis functions per element, 1..3 (D 5.3.1 uses 3)
  TlsCompletion completion = TlsCompletion::Virtual;
  // Largest cond(D) accepted before an element counts as deficient (D 5.2.3). D is the normal
  // matrix sum psi psi^T of the Taylor basis, which is already scaled by the element half-width,
  // so the number does not depend on the element size.
  double max_condition = 1e8;
  // Gauss points per active element for the mapping; 0: 2, exact for quadratic TLS (D 5.3.1).
  int gauss_points = 0;
  // Neighbour completion: most points borrowed by one element.
  int max_borrowed = 3;

  int gauss_points_used() const { return gauss_points > 0 ? gauss_points : 2; }
};

// Throws InputError for settings outside the documented ranges, including Gauss rules that do
// not integrate the Taylor basis exactly (D 5.3.2 needs n_b <= 2 x Gauss points per element,
// otherwise mass and momentum are not conserved).
void validate(const TlsSettings& s);

// The method.tls_* and method.gauss_points keys of a run configuration (io/keys.cpp).
TlsSettings tls_settings_from_config(const Config& cfg);

// What one point set (one MPM step) needed. An element can count in several of reduced,
// with_virtual and with_neighbours (e.g. completed with one virtual point and still reduced).
struct TlsReport {
  Index elements = 0;          // cells of the grid
  Index active = 0;            // elements with at least one point of their own
  Index full = 0;              // all n_b terms from their own points
  Index reduced = 0;           // fitted with fewer than n_b terms
  Index with_virtual = 0;      // data completed with virtual face points
  Index with_neighbours = 0;   // data completed with points borrowed from adjacent elements
  Index failed = 0;            // deficient with completion None: not fitted
  Index outside = 0;           // points outside the grid, ignored (standalone input only)
  int min_terms = 0;           // fewest terms of a fitted element (0: none fitted)
  double max_condition = 0.0;  // largest cond(D) of a fitted element's final system
  // The first failed element, for the error message: its own points and cond(D) with n_b terms
  // (infinite when singular).
  Index failed_element = -1;
  Index failed_points = 0;
  double failed_condition = 0.0;
};

// Sums the counts (element-steps over a run), keeps the extreme condition and terms.
void accumulate(TlsReport& total, const TlsReport& step);

// Per element, after set_points().
struct TlsElementInfo {
  Index points = 0;          // own data points
  Index virtual_points = 0;  // virtual face points added
  Index borrowed = 0;        // points borrowed from adjacent elements
  int terms = 0;             // Taylor terms fitted; 0 when inactive or failed
  double condition = 0.0;    // cond(D) of the final system (own data and n_b terms if failed)
  bool failed = false;
};

// Taylor basis at the element coordinate s = (x - x_c) / dx in [-1, 1], dx the half-width
// (D 5.2.2 with the volume average restored, METHODS.md errata): psi_1 = 1, psi_2 = s,
// psi_3 = ((x - x_c)^2 - mean((x - x_c)^2)) / (2 dx^2) = (s^2 - 1/3) / 2, since the mean of s^2
// over [-1, 1] is 1/3. psi_2 and psi_3 integrate to zero over the element (D eq. 5.7).
inline Eigen::Vector3d taylor_basis(double s) {
  return {1.0, s, 0.5 * (s * s - 1.0 / 3.0)};
}

// Taylor coefficients a_1..a_3 of every element (zero beyond the element's terms; zero in
// inactive elements; NaN in failed ones).
using TlsCoefficients = std::vector<Eigen::Vector3d>;

class TlsReconstruction {
 public:
  explicit TlsReconstruction(const TlsSettings& s = {});

  // Scattered points x (any order; outside the grid: ignored and counted). A point on an interior
  // element face belongs to the upper element (Grid::cell_of); with share_face_points it belongs
  // to both adjacent elements, as the point at pi in D 5.2.3.
  const TlsReport& set_points(const Grid<1>& g, std::span<const double> x,
                              bool share_face_points = false);
  // The particles of an MPM step (all inside the grid), binned with ElementBins.
  const TlsReport& set_points(const Grid<1>& g, const Particles<1>& P);

  // f: one value per point of set_points. integrals: c_e per element; a_1 = c_e / |Omega_e|
  // (D eq. 5.9) whatever the data, which (own and completion points alike) fit a_2.. only, so
  // int_e f^ = c_e to round-off.
  void fit_conservative(std::span<const double> f, std::span<const double> integrals,
                        TlsCoefficients& a) const;
  // All coefficients from least squares (D eq. 5.1).
  void fit_plain(std::span<const double> f, TlsCoefficients& a) const;

  // The reconstruction at x: element-local; an interior face belongs to the upper element, like
  // Grid::cell_of. Zero outside the grid.
  double evaluate(const TlsCoefficients& a, double x) const;
  // The reconstruction of element e at x (x need not lie in e: its Taylor polynomial extended).
  double evaluate(const TlsCoefficients& a, Index e, double x) const {
    return a[static_cast<std::size_t>(e)].dot(taylor_basis((x - centre(e)) / half_width()));
  }
  // int_e f^ = a_1 |Omega_e| (D eq. 5.8).
  double integral(const TlsCoefficients& a, Index e) const {
    return a[static_cast<std::size_t>(e)][0] * grid_.h[0];
  }

  const TlsSettings& settings() const { return settings_; }
  const TlsReport& report() const { return report_; }
  const TlsElementInfo& element(Index e) const { return info_[static_cast<std::size_t>(e)]; }
  bool active(Index e) const { return info_[static_cast<std::size_t>(e)].points > 0; }
  const Grid<1>& grid() const { return grid_; }
  Index num_elements() const { return grid_.num_cells(); }
  // Own points of each element (for element sums such as c_e = sum m_p).
  const ElementBins<1>& bins() const { return bins_; }
  double centre(Index e) const {
    return grid_.origin[0] + (static_cast<double>(e) + 0.5) * grid_.h[0];
  }
  double half_width() const { return 0.5 * grid_.h[0]; }

 private:
  // One least-squares datum of an element: a point (own or borrowed) or a virtual face point.
  struct Datum {
    Eigen::Vector3d psi;  // Taylor basis of the fitted element at the datum
    Eigen::Vector3d q;    // row of Q in B^T = Q R, terms 1..t (plain fits)
    Eigen::Vector2d qc;   // row of Q_c in B_c^T = Q_c R_c, terms 2..t (conservative fits)
    Index point;          // index of the value in f; -1 for a virtual point
    Index source;         // virtual: the neighbour whose reconstruction gives the value
    double s_source;      // virtual: the face in the neighbour's coordinate (-1 or +1)

    static Datum real(double s, Index point) {
      return {taylor_basis(s), Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero(), point, -1, 0.0};
    }
    static Datum virtual_point(double s, Index source, double s_source) {
      return {taylor_basis(s), Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero(), -1, source,
              s_source};
    }
  };
  // The least-squares problems are solved by a thin QR factorisation of the data matrix
  // (Gram-Schmidt, twice), a = R^{-1} Q^T f: the same solution as D eq. 5.1, a = D^{-1} B U with
  // D = R^T R, but with errors growing like cond(B) = cond(D)^(1/2) instead of cond(D).
  struct System {
    Index begin = 0, end = 0;  // data_[begin, end)
    int terms = 0;
    bool has_virtual = false;  // fitted after its neighbours
    Eigen::Matrix3d R;         // upper triangular, terms 1..t
    Eigen::Matrix2d Rc;        // upper triangular, terms 2..t
  };
  // Element data from its own points alone (first pass).
  struct Own {
    Eigen::Matrix3d D;
    int distinct = 0;  // distinct positions, counted up to n_b
    double condition = 0.0;
    bool ok = false;  // n_b terms are well posed without completion
  };

  void build_systems();
  bool coincides(const System& sys, double s) const;
  void add_datum(System& sys, Eigen::Matrix3d& D, const Datum& d);
  void add_virtual_points(Index e, System& sys, Eigen::Matrix3d& D, int& distinct);
  void borrow_points(Index e, System& sys, Eigen::Matrix3d& D, int& distinct);
  void factorise(System& sys);
  void fit(std::span<const double> f, const double* integrals, TlsCoefficients& a) const;

  TlsSettings settings_;
  Grid<1> grid_;
  std::vector<double> x_;  // positions of the current point set [m]
  ElementBins<1> bins_;
  std::vector<Own> own_;
  std::vector<System> systems_;
  std::vector<TlsElementInfo> info_;
  std::vector<Datum> data_;
  TlsReport report_;
};

// The TLS particle-to-grid mapping (D 5.3.1, 004 4.4.3), one-dimensional. map_mass, the first
// mapping call of every step, bins the particles, factorises the element systems and places the
// Gauss points; map_momentum and map_forces of the same step reuse them (positions do not change
// within a step, only the particle values).
class TlsMapping {
 public:
  static constexpr std::string_view kName = "tls";
  // The run set-up rejects other dimensions with a clear message before instantiating.
  static constexpr bool supports_dimension(int dim) { return dim == 1; }

  TlsMapping() : TlsMapping(TlsSettings{}) {}
  explicit TlsMapping(const TlsSettings& s) : recon_(s) {
    const GaussRule rule = gauss_legendre(s.gauss_points_used());
    xi_ = rule.xi;
    w_ = rule.w;
    for (double xi : xi_) psi_gauss_.push_back(taylor_basis(xi));
  }

  const TlsSettings& settings() const { return recon_.settings(); }
  const TlsReconstruction& reconstruction() const { return recon_; }
  const TlsReport& last_report() const { return recon_.report(); }
  // Counts summed over the steps so far (element-steps), largest condition number of the run.
  const TlsReport& totals() const { return totals_; }
  // Checkpoint restart: the sums continue from a saved run (io/checkpoint.hpp).
  void set_totals(const TlsReport& t) { totals_ = t; }

  // rho^ conservative with c_e = sum m_p and data rho_p; lumped masses and, with consistent
  // mass, M_ij = sum_g phi_i rho^ phi_j w_g (D eq. 5.14, 5.17).
  template <class Sim>
  void map_mass(Sim& sim) {
    static_assert(Sim::kDim == 1, "the TLS mapping is one-dimensional (D ch. 5)");
    const auto& P = sim.particles;
    const TlsReport& rep = recon_.set_points(sim.grid, P);
    accumulate(totals_, rep);
    if (rep.failed > 0)
      throw RunError(
          exit_code::kReconstruction,
          fmt::format("step {}, t = {:.9g} s: TLS cannot fit element {} ({} particles, condition "
                      "number {:.3g}){}; set method.tls_completion = reduce, virtual or neighbour",
                      sim.step, sim.time, rep.failed_element, rep.failed_points,
                      rep.failed_condition,
                      rep.failed > 1 ? fmt::format(" and {} more element(s)", rep.failed - 1)
                                     : std::string()));
    auto& q = quad_.prepare<Sim>();
    q.clear();
    const double dx = recon_.half_width();
    for (Index e = 0; e < recon_.num_elements(); ++e) {
      if (!recon_.active(e)) continue;  // no particles: no reconstruction, no mass
      const double xc = recon_.centre(e);
      for (std::size_t k = 0; k < xi_.size(); ++k) q.add(Vec<1>(xc + dx * xi_[k]), dx * w_[k], e);
    }
    q.evaluate(sim);

    element_sums([&](std::size_t i) { return P.mass[i]; });
    recon_.fit_conservative(P.density, integrals_, coef_);
    rho_.resize(q.size());
    at_gauss(q, [&](std::size_t g, double v) { rho_[g] = v; });
    assemble_mass(sim, q, rho_);
  }

  // (rho v)^ conservative with c_e = sum m_p v_p and data rho_p v_p (D eq. 5.14, 5.16).
  template <class Sim>
  void map_momentum(Sim& sim) {
    static_assert(Sim::kDim == 1, "the TLS mapping is one-dimensional (D ch. 5)");
    const auto& P = sim.particles;
    const auto& q = quad_.prepared<Sim>();
    values_.resize(P.x.size());
    for (std::size_t i = 0; i < values_.size(); ++i) values_[i] = P.density[i] * P.v[i][0];
    element_sums([&](std::size_t i) { return P.mass[i] * P.v[i][0]; });
    recon_.fit_conservative(values_, integrals_, coef_);
    rhov_.resize(q.size());
    at_gauss(q, [&](std::size_t g, double v) { rhov_[g][0] = v; });
    assemble_momentum(sim, q, rhov_);
  }

  // sigma^ by plain least squares (D eq. 5.12-5.13); the body-force density (rho b)^ conservative
  // with c_e = sum m_p b_p and data rho_p b_p; f_i = sum_g (phi_i (rho b)^ - sigma^ dphi_i) w_g.
  template <class Sim>
  void map_forces(Sim& sim) {
    static_assert(Sim::kDim == 1, "the TLS mapping is one-dimensional (D ch. 5)");
    const auto& P = sim.particles;
    const auto& q = quad_.prepared<Sim>();
    values_.resize(P.x.size());
    for (std::size_t i = 0; i < values_.size(); ++i) values_[i] = P.stress[i](0, 0);
    recon_.fit_plain(values_, coef_);
    sigma_.resize(q.size());
    at_gauss(q, [&](std::size_t g, double v) { sigma_[g](0, 0) = v; });

    for (std::size_t i = 0; i < values_.size(); ++i) values_[i] = P.density[i] * P.body[i][0];
    element_sums([&](std::size_t i) { return P.mass[i] * P.body[i][0]; });
    recon_.fit_conservative(values_, integrals_, coef_);
    rhob_.resize(q.size());
    at_gauss(q, [&](std::size_t g, double v) { rhob_[g][0] = v; });
    assemble_forces(sim, q, rhob_, sigma_);
  }

 private:
  // integrals_[e] = sum over the element's particles of value(p).
  template <class Value>
  void element_sums(Value&& value) {
    const auto& bins = recon_.bins();
    integrals_.assign(static_cast<std::size_t>(recon_.num_elements()), 0.0);
    for (Index e = 0; e < recon_.num_elements(); ++e) {
      double c = 0.0;
      for (const Index* p = bins.begin(e); p != bins.end(e); ++p)
        c += value(static_cast<std::size_t>(*p));
      integrals_[static_cast<std::size_t>(e)] = c;
    }
  }
  // The reconstruction coef_ at every Gauss point: element e, local point k = g mod n.
  template <class Sim, class Store>
  void at_gauss(const QuadraturePoints<Sim>& q, Store&& store) const {
    const std::size_t n = psi_gauss_.size();
    for (std::size_t g = 0; g < q.size(); ++g)
      store(g, coef_[static_cast<std::size_t>(q.element[g])].dot(psi_gauss_[g % n]));
  }

  TlsReconstruction recon_;
  std::vector<double> xi_, w_;              // Gauss rule on [-1, 1]
  std::vector<Eigen::Vector3d> psi_gauss_;  // Taylor basis at the Gauss points (s = xi)
  QuadratureStore quad_;
  std::vector<double> values_, integrals_;  // per particle, per element
  TlsCoefficients coef_;
  std::vector<double> rho_;  // at the Gauss points
  std::vector<Vec<1>> rhov_, rhob_;
  std::vector<Mat<1>> sigma_;
  TlsReport totals_;
};

}  // namespace mpm
