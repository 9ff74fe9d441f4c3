#pragma once
// Taylor least-squares (TLS) reconstruction in one, two and three dimensions and the TLS
// particle-to-grid mapping (D 5.2-5.3 and ch. 6, 000 sec. 2-4, 004 4.4).
//
// BasicTlsReconstruction<Dim> fits, per cell of a uniform Grid<Dim> (an element: an interval in
// 1D, a rectangle in 2D, a hexahedron in 3D), a short Taylor expansion to scattered data (D eq.
// 5.1-5.5, 6.1-6.13; 3D is the same construction with the ten terms of the complete quadratic,
// the analogue of D 6.1.1 that D does not write down).
// Fields are either plain least squares (all coefficients free, D eq. 5.1) or conservative:
// a_1 = c_e / |Omega_e| is fixed by the element integral c_e and the other coefficients fit
// f - a_1 (D eq. 5.8-5.9, 5.3.1). The least-squares matrices depend only on the point
// positions, so they are built and factorised once per point set and reused for every field.
// The reconstruction is element-local and discontinuous across element faces.
//
// TlsMapping uses it as the particle-to-grid mapping of MPM (D 5.3.1, 6.3, 004 4.4.3): density,
// momentum density and body-force density are reconstructed conservatively, stress by plain least
// squares (each component separately, D 6.3), and all are integrated with n Gauss points per
// direction in every active element (D eq. 5.12-5.17, 6.19-6.20), which conserves mass and
// momentum to round-off (D eq. 5.19-5.21, Table 6.1).
#include <fmt/format.h>

#include <Eigen/Dense>
#include <any>
#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "mapping/mapping.hpp"
#include "mapping/quadrature.hpp"
#include "mapping/tls_triangle.hpp"
#include "state/simulation.hpp"

namespace mpm {

// What an element does when its data cannot support the requested Taylor basis (D 5.2.3, 6.3.2;
// registry::kTlsCompletions holds the user-facing names).
enum class TlsCompletion {
  None,       // report failure (the MPM mapping stops the run, exit code 6)
  Reduce,     // fewer Taylor terms (1D: 3 -> 2 -> 1; 2D: 6 -> 3 -> 1; 3D: 10 -> 4 -> 1)
  Virtual,    // virtual points on the faces, valued by the neighbours' reconstructions
  Neighbour,  // borrow the nearest points of the adjacent elements (faces, edges, corners)
  // Triangles only (mapping/tls_triangle.hpp, TlsTriangleStrategy): truncated SVD of the data
  // matrix with the minimum-norm coefficients, or resolved towards the lowest degree (graded).
  MinimumNorm,
  Graded,
};

// "none", "reduce", "virtual", "neighbour", "min_norm", "graded" (registry::kTlsCompletions;
// "auto" is resolved by the run set-up). Throws InputError.
TlsCompletion parse_tls_completion(std::string_view name);
std::string_view tls_completion_name(TlsCompletion c);

// Taylor terms of the complete quadratic basis: 3 in 1D (D 5.2.2), 6 in 2D (D eq. 6.1-6.6), 10
// in 3D (1, 3 linear, 3 squares, 3 products).
template <int Dim>
inline constexpr int kTaylorTerms = Dim == 1   ? 3
                                    : Dim == 2 ? 6
                                               : 10;
template <int Dim>
using TaylorVector = Eigen::Matrix<double, kTaylorTerms<Dim>, 1>;

struct TlsSettings {
  // n_b: Taylor basis functions per element. 1D: 1..3; 2D: 1 (constant), 3 (linear) or 6
  // (quadratic); 3D: 1, 4 or 10; the complete polynomial spaces. 0: the quadratic basis of the
  // dimension (3 in 1D as in D 5.3.1, 6 in 2D as in D 6.2, 10 in 3D).
  int terms = 0;
  TlsCompletion completion = TlsCompletion::Virtual;
  // Largest cond(D) accepted before an element counts as deficient (D 5.2.3). D is the normal
  // matrix sum phi phi^T of the Taylor basis made orthonormal over the element (phi_k = psi_k /
  // ||psi_k||, the mean-square norms over [-1, 1]^Dim: 1, 1/3 per linear term, 1/45 per square,
  // 1/9 for s t, s u, t u; the psi_k are already orthogonal there), as on triangles
  // (tls_triangle.hpp):
  // cond = 1 for points that sample the element as well as uniformly spread ones, whatever the
  // element's size, and 1 / lambda_min bounds how much a fit can grow from the points to the
  // element (Cohen, Davenport and Leviatan 2013). The raw basis gives 45 for such points.
  // The run set-up's default: 1e8 in 1D, 10 in 2D and 3D (method.tls_max_condition).
  double max_condition = 1e8;
  // Positivity of the conservative fields (Zhang and Shu 2010, J. Comput. Phys. 229:3091): in an
  // element whose density reconstruction is negative at a Gauss point, the terms beyond a_1 of
  // the density, momentum and body-force densities (and of the surface stress) are scaled by the
  // largest theta in [0, 1] that makes the density there non-negative. a_1 is untouched, so mass
  // and momentum stay conserved, and the lumped nodal masses stay non-negative.
  bool positivity = false;
  // Elements at a free surface (one of the 3^Dim - 1 elements around them holds no particle)
  // integrate the stress of their material, not of the whole element: the stress is fitted
  // conservatively with the element integral sum_p V_p sigma_p, as the density with sum_p m_p.
  // The plain fit of D 6.3 integrates sigma^ over the whole element, i.e. as if an element cut by
  // the surface were full, which overstates the internal forces there by |Omega_e| / sum V_p.
  bool surface_volume = false;
  // The element integrals of the conservative fits (a_1 = c_e / |Omega_e|, D eq. 5.9) from the
  // particles' domains instead of their centres: each particle's value is split among the active
  // elements its domain overlaps, by the overlap (the domain is the cpGIMP box, side F_dd l0_d:
  // V_p in 1D). D's sum over the particles whose centre lies in the element is the content of the
  // material region those particles span, not of the element: under a strain u_X it is off by a
  // relative u_X, whatever h, so refinement stalls at an error proportional to the amplitude
  // (docs/verification.md, "The conservative constant of TLS"). The split keeps sum_e c_e =
  // sum_p value_p (each particle's fractions sum to one).
  bool domain_integrals = false;
  // Gauss points per direction of every active element for the mapping; 0: 2, exact for
  // quadratic TLS (D 5.3.1; 2 x 2 in 2D, 2 x 2 x 2 in 3D).
  int gauss_points = 0;
  // Neighbour completion: most points borrowed by one element; 0: the terms of the quadratic
  // basis (3 in 1D, 6 in 2D, 10 in 3D).
  int max_borrowed = 0;
  // The point sets serve conservative fits only (a_1 given, D eq. 5.9): well-posedness is then
  // judged on the fitted terms 2..n_b alone, and fit_plain is unavailable. D 6.2.1 needs this:
  // its six points per element lie on two lines x_1 = const, where psi_4 is constant, so the
  // full normal matrix is singular while the conservative fit of psi_2..psi_6 is well posed.
  bool conservative_only = false;
  // Every element's condition number from the eigenvalues of D (TlsElementInfo::condition,
  // TlsReport::max_condition). false: an element whose bound ||D||_inf ||D^{-1}||_inf (on the
  // orthonormal basis, at least cond_2) already meets max_condition keeps the bound, which saves
  // the 6 x 6 eigensolve that was a quarter of a 2D TLS step; otherwise a failed Cholesky pivot
  // rejects, and brackets of lambda_max(D) and lambda_max(D^{-1}), narrowed by shifted Cholesky
  // tests, settle nearly all of the rest (condition()). The decisions are the same (a bound is
  // only used where it proves cond <= max_condition or cond > max_condition), the numbers
  // reported are then bounds. The 2D MPM runs use false (method_settings.cpp).
  bool exact_condition = true;
  // The particles' velocity gradients for the stress update as the adjoint of the force
  // (docs/verification.md, "A TLS whose strain rate is the adjoint of its
  // force"): the force is f_i = -sum_g w_g sigma^(x_g) grad phi_i(x_g) with sigma^(x_g) =
  // sum_p R_gp sigma_p (the stress fit, linear in the particle stresses), so the rate whose power
  // the force does is L_p = sum_g R_gp w_g L(x_g) / omega_p, L(x_g) = sum_i v_i grad phi_i(x_g)^T
  // the grid's velocity gradient at the Gauss points and omega_p = sum_g R_gp w_g the particle's
  // effective weight in the fit. Then f . v = -sum_p omega_p sigma_p : L_p, so the linearised
  // step is symmetric (neutral) where every omega_p > 0, and L_p = A for any uniform gradient A
  // (sum_g R_gp w_g A / omega_p). The stress is then fitted conservatively in every element
  // (c_e = sum_p V_p sigma_p, as surface_volume does at a surface), which makes omega_p = V_p:
  // a plain fit's weights vary (-0.8 to 1.5 V_p on a stretched layout of the plate). false:
  // L_p = sum_i v_i grad phi_i(x_p)^T (D eq. 2.52) and the stress fit of surface_volume.
  bool adjoint_strain_rate = false;

  int gauss_points_used() const { return gauss_points > 0 ? gauss_points : 2; }
  int terms_used(int dim) const { return terms > 0 ? terms : quadratic_terms(dim); }
  int max_borrowed_used(int dim) const {
    return max_borrowed > 0 ? max_borrowed : quadratic_terms(dim);
  }
  static constexpr int quadratic_terms(int dim) { return dim == 1 ? 3 : dim == 2 ? 6 : 10; }
};

// Throws InputError for settings outside the documented ranges of dimension `dim` (1 to 3),
// including Gauss rules that do not integrate the Taylor basis exactly (D 5.3.2: n Gauss points
// per direction integrate degree 2n - 1, the basis must be integrated exactly, otherwise mass and
// momentum are not conserved; in 2D and 3D the quadratic terms need 2 points per direction).
void validate(const TlsSettings& s, int dim = 1);

// What one point set (one MPM step) needed. An element can count in several of reduced,
// with_virtual and with_neighbours (e.g. completed with one virtual point and still reduced).
struct TlsReport {
  Index elements = 0;         // cells of the grid
  Index active = 0;           // elements with at least one point of their own
  Index full = 0;             // all n_b terms from their own points
  Index reduced = 0;          // fitted with fewer than n_b terms
  Index with_virtual = 0;     // data completed with virtual face points
  Index with_neighbours = 0;  // data completed with points borrowed from adjacent elements
  Index failed = 0;           // deficient with completion None: not fitted
  Index truncated = 0;        // triangles (min_norm, graded): fitted with rank below the terms
  Index limited = 0;          // positivity: elements whose higher terms were scaled down
  Index surface = 0;          // surface_volume: elements at a free surface
  Index outside = 0;          // points outside the grid, ignored (standalone input only)
  // TlsSettings::adjoint_strain_rate: particles (particle-steps in the run totals) whose weight
  // omega_p in the fits was not positive, so their rate is the gradient at x_p.
  Index unweighted = 0;
  int min_terms = 0;  // fewest terms of a fitted element (0: none fitted)
  // Largest cond(D) of a fitted element's final system (with TlsSettings::exact_condition =
  // false an upper bound of it, at most max_condition).
  double max_condition = 0.0;
  // The first failed element, for the error message: its own points and cond(D) with n_b terms
  // (infinite when singular).
  Index failed_element = -1;
  Index failed_points = 0;
  double failed_condition = 0.0;
};

// Sums the counts (element-steps over a run), keeps the extreme condition and terms.
void accumulate(TlsReport& total, const TlsReport& step);
// The reports of the processes of a distributed run, each over its own elements
// (BasicTlsReconstruction::set_focus), as one report of the whole grid: counts summed, the
// extremes taken, the first failed element the lowest of any process. Collective.
TlsReport over_ranks(const Comm& comm, const TlsReport& mine);

// The run stops (exit code kReconstruction) when a step's fits failed (rep.failed > 0): names the
// first element that could not be fitted (`noun` "element" or "triangle", `which` its
// description), how many more did, and the completions of that mesh that would fit them.
[[noreturn]] void throw_fit_failure(Index step, double time, const TlsReport& rep,
                                    std::string_view noun, const std::string& which,
                                    std::string_view completions);

// Per element, after set_points().
struct TlsElementInfo {
  Index points = 0;          // own data points
  Index virtual_points = 0;  // virtual face points added
  Index borrowed = 0;        // points borrowed from adjacent elements
  int terms = 0;             // Taylor terms fitted; 0 when inactive or failed
  double condition = 0.0;    // cond(D) of the final system (own data and n_b terms if failed;
                             // an upper bound where TlsSettings::exact_condition allows)
  bool failed = false;
};

// Taylor basis at the element coordinate s = (x - x_c) / dx in [-1, 1], dx the half-width
// (D 5.2.2 with the volume average restored, METHODS.md errata): psi_1 = 1, psi_2 = s,
// psi_3 = ((x - x_c)^2 - mean((x - x_c)^2)) / (2 dx^2) = (s^2 - 1/3) / 2, since the mean of s^2
// over [-1, 1] is 1/3. psi_2 and psi_3 integrate to zero over the element (D eq. 5.7).
inline Eigen::Vector3d taylor_basis(double s) {
  return {1.0, s, 0.5 * (s * s - 1.0 / 3.0)};
}

// The 2D basis on a rectangle (D eq. 6.1-6.13, overline restored as in 1D): s = (x_1 - x_1c) /
// dx_1, t = (x_2 - x_2c) / dx_2 in [-1, 1]; psi_4 = (s^2 - 1/3) / 2, psi_5 = (t^2 - 1/3) / 2 and
// psi_6 = s t - mean(s t) = s t (the mean vanishes by symmetry, D eq. 6.12-6.13). psi_2..psi_6
// integrate to zero over the element.
inline TaylorVector<2> taylor_basis(double s, double t) {
  TaylorVector<2> psi;
  psi << 1.0, s, t, 0.5 * (s * s - 1.0 / 3.0), 0.5 * (t * t - 1.0 / 3.0), s * t;
  return psi;
}

// The 3D basis on a hexahedron, the 2D one extended by the third coordinate u = (x_3 - x_3c) /
// dx_3: 1, s, t, u, the three centred squares, s t, s u, t u (the products' means vanish by
// symmetry). psi_2..psi_10 integrate to zero over the element. psi_2..psi_{1+Dim} are the
// coordinates in every dimension (coincides() relies on it).
inline TaylorVector<3> taylor_basis(double s, double t, double u) {
  TaylorVector<3> psi;
  psi << 1.0, s, t, u, 0.5 * (s * s - 1.0 / 3.0), 0.5 * (t * t - 1.0 / 3.0),
      0.5 * (u * u - 1.0 / 3.0), s * t, s * u, t * u;
  return psi;
}

// The basis of dimension Dim at the element coordinates s.
template <int Dim>
TaylorVector<Dim> taylor_basis_at(const Vec<Dim>& s) {
  static_assert(Dim >= 1 && Dim <= 3, "TLS is implemented in 1D to 3D (grid cells)");
  if constexpr (Dim == 1)
    return taylor_basis(s[0]);
  else if constexpr (Dim == 2)
    return taylor_basis(s[0], s[1]);
  else
    return taylor_basis(s[0], s[1], s[2]);
}

// Taylor coefficients a_1..a_K of every element (zero beyond the element's terms; zero in
// inactive elements; NaN in failed ones).
template <int Dim>
using BasicTlsCoefficients = std::vector<TaylorVector<Dim>>;
using TlsCoefficients = BasicTlsCoefficients<1>;
using TlsCoefficients2D = BasicTlsCoefficients<2>;
using TlsCoefficients3D = BasicTlsCoefficients<3>;

template <int Dim>
class BasicTlsReconstruction {
 public:
  static constexpr int kDim = Dim;
  static constexpr int K = kTaylorTerms<Dim>;  // storage size of the coefficient vectors
  // A position: a number in 1D, a vector in 2D and 3D.
  using Point = std::conditional_t<Dim == 1, double, Vec<Dim>>;
  using Taylor = TaylorVector<Dim>;
  using Coefficients = BasicTlsCoefficients<Dim>;

  explicit BasicTlsReconstruction(const TlsSettings& s = {});

  // Scattered points x (any order; outside the grid: ignored and counted). A point on an interior
  // element face belongs to the upper element (Grid::cell_of); with share_face_points it belongs
  // to all elements sharing that face (or corner), as the point at pi in D 5.2.3.
  const TlsReport& set_points(const Grid<Dim>& g, std::span<const Point> x,
                              bool share_face_points = false);
  // The particles of an MPM step (all inside the grid), binned with ElementBins. Ties between
  // equally near points (neighbour completion) are broken by particle id, not by index, so that
  // the order of the particles in memory (re-sorting, processes) does not change the fits.
  const TlsReport& set_points(const Grid<Dim>& g, const Particles<Dim>& P);
  // The elements the report counts (default: all): a process of a distributed run reports only
  // the elements it integrates (RunState::own_cells); every element with points is still fitted,
  // as the completions of those elements read their neighbours.
  void set_focus(const CellBox<Dim>& own) { focus_ = own; }

  // f: one value per point of set_points. integrals: c_e per element; a_1 = c_e / |Omega_e|
  // (D eq. 5.9) whatever the data, which (own and completion points alike) fit a_2.. only, so
  // int_e f^ = c_e to round-off.
  //
  // done (fit_conservative, fit_fields): called once for every element when its coefficients
  // are final, and, without the virtual completion (whose elements read their neighbours'
  // coefficients), right after they are, in the same parallel loop; done(e) may change element
  // e's coefficients and read no other element's (TlsMapping's positivity limit and values at
  // the Gauss points: a parallel region and a sweep over the elements saved per fit).
  using ElementDone = std::function<void(Index)>;
  void fit_conservative(std::span<const double> f, std::span<const double> integrals,
                        Coefficients& a, const ElementDone& done = nullptr) const;
  // All coefficients from least squares (D eq. 5.1). Not with settings().conservative_only.
  void fit_plain(std::span<const double> f, Coefficients& a) const;
  // Conservative in the elements with conservative[e] != 0 (integral integrals[e]), plain in the
  // others.
  void fit_mixed(std::span<const double> f, std::span<const double> integrals,
                 std::span<const unsigned char> conservative, Coefficients& a) const;

  // One field of fit_fields: conservative with integrals (and, with conservative, only in the
  // elements where conservative[e] != 0, plain in the others), plain without; a receives the
  // coefficients.
  struct Field {
    const double* integrals = nullptr;
    const unsigned char* conservative = nullptr;
    Coefficients* a = nullptr;
  };
  // The stress components and the body-force density of TlsMapping::fit_forces: 6 in 1D and 2D
  // (as before 3D), 9 in 3D.
  static constexpr int kMaxFields = Dim == 3 ? 9 : 6;
  // Up to kMaxFields fields of the same points in one pass over the element data: field j's
  // value at point p is f[p * fields.size() + j]. The same numbers as one fit per field (each
  // field's sums run in the same order); it reads the data once instead of once per field.
  void fit_fields(std::span<const double> f, std::span<const Field> fields,
                  const ElementDone& done = nullptr) const;
  // The transpose of fit_fields for nf fields fitted alike (each plain, or conservative in the
  // elements with conservative[e] != 0 when conservative is given): abar[j][e] is the derivative
  // of a functional with respect to element e's coefficients of field j (used as scratch:
  // completion points push their part to the elements that value them). On return z[p * nf + j]
  // holds its derivative with respect to the value of field j at point p, and ibar[j * E + e]
  // (E elements) with respect to element e's integral (zero where e is fitted plainly).
  void fit_transpose(std::span<Coefficients> abar, const unsigned char* conservative,
                     std::span<double> z, std::span<double> ibar) const;
  // The number of points of the current point set (own and ghost particles).
  Index num_points() const { return static_cast<Index>(x_.size()); }

  // The reconstruction at x: element-local; an interior face belongs to the upper element, like
  // Grid::cell_of. Zero outside the grid.
  double evaluate(const Coefficients& a, const Point& x) const;
  // The reconstruction of element e at x (x need not lie in e: its Taylor polynomial extended).
  double evaluate(const Coefficients& a, Index e, const Point& x) const {
    return a[static_cast<std::size_t>(e)].dot(basis(e, x));
  }
  // The Taylor basis of element e at x.
  Taylor basis(Index e, const Point& x) const { return taylor_basis_at<Dim>(local(e, as_vec(x))); }
  // int_e f^ = a_1 |Omega_e| (D eq. 5.8, 6.7).
  double integral(const Coefficients& a, Index e) const {
    return a[static_cast<std::size_t>(e)][0] * grid_.cell_volume();
  }

  const TlsSettings& settings() const { return settings_; }
  int terms() const { return nb_; }  // n_b requested (settings().terms resolved)
  const TlsReport& report() const { return report_; }
  const TlsElementInfo& element(Index e) const { return info_[static_cast<std::size_t>(e)]; }
  bool active(Index e) const { return info_[static_cast<std::size_t>(e)].points > 0; }
  const Grid<Dim>& grid() const { return grid_; }
  Index num_elements() const { return grid_.num_cells(); }
  // Own points of each element (for element sums such as c_e = sum m_p).
  const ElementBins<Dim>& bins() const { return bins_; }
  // Cell indices of element e (x fastest, as Grid::cell_index).
  IVec<Dim> cell(Index e) const {
    IVec<Dim> c{};
    for (int d = 0; d < Dim; ++d) {
      c[d] = e % grid_.cells[d];
      e /= grid_.cells[d];
    }
    return c;
  }
  // "e" in 1D, "e at cell (i, j)" in 2D, "(i, j, k)" in 3D: for messages.
  std::string describe(Index e) const;
  Point centre(Index e) const { return from_vec(centre_vec(e)); }
  Point half_width() const { return from_vec(half_width_vec()); }
  Vec<Dim> centre_vec(Index e) const {
    const IVec<Dim> c = cell(e);
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d)
      x[d] = grid_.origin[d] + (static_cast<double>(c[d]) + 0.5) * grid_.h[d];
    return x;
  }
  Vec<Dim> half_width_vec() const { return 0.5 * grid_.h; }
  // Element coordinates of x in element e: (x - x_c) / dx per direction.
  Vec<Dim> local(Index e, const Vec<Dim>& x) const {
    const Vec<Dim> c = centre_vec(e), hw = half_width_vec();
    Vec<Dim> s;
    for (int d = 0; d < Dim; ++d) s[d] = (x[d] - c[d]) / hw[d];
    return s;
  }

 private:
  using Taylor1 = Eigen::Matrix<double, K - 1, 1>;  // terms 2..K
  using Matrix = Eigen::Matrix<double, K, K>;
  using Matrix1 = Eigen::Matrix<double, K - 1, K - 1>;

  static Vec<Dim> as_vec(const Point& x) {
    if constexpr (Dim == 1)
      return Vec<1>(x);
    else
      return x;
  }
  static Point from_vec(const Vec<Dim>& x) {
    if constexpr (Dim == 1)
      return x[0];
    else
      return x;
  }

  // One least-squares datum of an element: a point (own or borrowed) or a virtual face point
  // (its source in from_, at the same index). 56 bytes in 2D, 88 in 3D: what a fit reads.
  struct Datum {
    Taylor psi;   // Taylor basis of the fitted element at the datum (psi_2.. = position)
    Index point;  // index of the value in f; -1 for a virtual point
  };
  struct DatumSource {
    Index source;       // the neighbour whose reconstruction gives the value
    Vec<Dim> s_source;  // the point in the neighbour's coordinates
  };
  // The least-squares problems are solved by the normal equations, a = D^{-1} B^T f, the
  // solution of D eq. 5.1, with D^{-1} formed per element once per point set from the Cholesky
  // factor D = R^T R (factorise), so that each field's fit is the sum B^T f and one 6 x 6
  // product (two triangular solves per field were half the fit's time: chains of dependent
  // operations). The rounding error grows like cond(D) eps (a QR factorisation of B: cond(B)
  // eps = cond(D)^(1/2) eps), which well_posed bounds by max_condition (default 10 in 2D, 1e8
  // in 1D; at most 1e14, validate): at 1e8 that is 2e-8, below what the fit's own sensitivity,
  // cond(B) = 1e4 times the data's discretisation error, makes of the data.
  struct System {
    Index begin = 0, end = 0;  // data_[begin, end)
    int terms = 0;
    bool has_virtual = false;  // fitted after its neighbours
    Matrix inv;                // D^{-1} of terms 1..t (zero beyond): plain fits
    Matrix1 inv_c;             // the inverse of D's block of terms 2..t: conservative fits
  };
  // Element data from its own points alone (first pass).
  struct Own {
    Matrix D;
    // The inverse of the fitted block of D on the orthonormal basis (terms 1..n_b, or 2..n_b
    // with conservative_only), when condition() formed it for its bound: factorise reuses it.
    Matrix s_inv;
    bool has_s_inv = false;
    int distinct = 0;  // distinct positions, counted up to n_b
    double condition = 0.0;
    bool ok = false;  // n_b terms are well posed without completion
  };

  void bin_points(bool share_face_points);
  void build_systems();
  bool coincides(const System& sys, const Vec<Dim>& s) const;
  // Puts a datum at s (element coordinates) into the element's next slot: a point (source -1)
  // or a virtual point valued by element `source` at s_source.
  void place(System& sys, const Vec<Dim>& s, Index point, Index source = -1,
             const Vec<Dim>& s_source = Vec<Dim>::Zero());
  void add_datum(System& sys, Matrix& D, const Vec<Dim>& s, Index point, Index source = -1,
                 const Vec<Dim>& s_source = Vec<Dim>::Zero());
  void add_virtual_points(Index e, System& sys, Matrix& D, int& distinct);
  void borrow_points(Index e, System& sys, Matrix& D, int& distinct);
  // s_inv (optional): receives the inverse that condition() formed for its bound, if it did
  // (*has_s_inv).
  bool well_posed(const Matrix& D, int distinct, int t, double& cond, Matrix* s_inv = nullptr,
                  bool* has_s_inv = nullptr) const;
  double condition(const Matrix& D, int t, Matrix* s_inv = nullptr,
                   bool* has_s_inv = nullptr) const;
  // The orthonormal basis's scales: phi_k = l_k psi_k (condition()).
  static const Taylor& scales();
  // s_inv: the inverse of the fitted block of D on the orthonormal basis, if known (Own).
  void factorise(System& sys, const Matrix& D, const Matrix* s_inv = nullptr) const;
  void fit(std::span<const double> f, std::span<const Field> fields,
           const ElementDone& done = nullptr) const;

  TlsSettings settings_;
  int nb_ = 0;  // terms requested
  // Positions of the virtual points along a face, per face direction (2D, 3D: tensor product).
  std::vector<double> face_xi_;
  Grid<Dim> grid_;
  std::vector<Vec<Dim>> x_;  // positions of the current point set [m]
  // The order of the points for ties (particle ids; empty: their indices).
  std::vector<CompactIndex> key_;
  std::optional<CellBox<Dim>> focus_;  // none: every element
  ElementBins<Dim> bins_;
  std::vector<Own> own_;
  std::vector<System> systems_;
  std::vector<TlsElementInfo> info_;
  std::vector<Datum> data_;
  std::vector<DatumSource> from_;  // data_[k] virtual: its source
  std::vector<Index> fill_;        // binning cursors (standalone point sets)
  std::vector<Index> slots_;       // build_systems: each element's first slot in data_ (CSR)
  TlsReport report_;
};

extern template class BasicTlsReconstruction<1>;
extern template class BasicTlsReconstruction<2>;
extern template class BasicTlsReconstruction<3>;
using TlsReconstruction = BasicTlsReconstruction<1>;
using TlsReconstruction2D = BasicTlsReconstruction<2>;
using TlsReconstruction3D = BasicTlsReconstruction<3>;

// What the TLS mapping keeps per dimension: the reconstruction, the Gauss rule of an element in
// its coordinates (n^Dim points, x fastest) with the Taylor basis there, and the fields at the
// Gauss points of a step.
template <int Dim>
struct TlsMappingState {
  BasicTlsReconstruction<Dim> recon;
  std::vector<Vec<Dim>> xi;            // Gauss points in [-1, 1]^Dim
  std::vector<Vec<Dim>> w;             // their 1D weights per direction (product: the weight)
  std::vector<TaylorVector<Dim>> psi;  // Taylor basis at xi
  // Per element of the last fit_mass's range (the span of RunState::own_cells): its first Gauss
  // point, -1 for none (an element without particles or outside the box).
  std::vector<Index> gauss_first;
  std::array<Index, 2> gauss_range{0, 0};  // that range of elements [first, end)
  BasicTlsCoefficients<Dim> coef;
  // The fields fitted together (TlsMapping::fit_momentum, fit_forces): at most the stress
  // components and the body-force density.
  std::array<BasicTlsCoefficients<Dim>, BasicTlsReconstruction<Dim>::kMaxFields> fields;
  std::vector<double> rho;  // at the Gauss points of the step
  std::vector<Vec<Dim>> rhov, rhob;
  std::vector<Mat<Dim>> sigma;
  // TlsSettings::adjoint_strain_rate: w_g L(x_g) at the Gauss points, the transposed fit's
  // element data (Dim^2 velocity-gradient components and the weight), point and integral
  // derivatives (BasicTlsReconstruction::fit_transpose).
  std::vector<Mat<Dim>> wgrad;
  std::vector<BasicTlsCoefficients<Dim>> abar;
  std::vector<double> zbar, ibar;
  std::vector<unsigned char> conservative;  // 1 per element: the stress fits' flags
  std::vector<double> omega;  // omega_p [m^Dim] of the last strain_rates, per particle
  // Per element, set by the density fit of the step: the positivity factor theta (1: not
  // limited) and whether the element lies at a free surface (TlsSettings).
  std::vector<double> theta;
  std::vector<unsigned char> surface;

  explicit TlsMappingState(const TlsSettings& s) : recon(s) {
    const GaussRule rule = gauss_legendre(s.gauss_points_used());
    const int n = static_cast<int>(rule.xi.size());
    int count = 1;
    for (int d = 0; d < Dim; ++d) count *= n;
    for (int k = 0; k < count; ++k) {
      Vec<Dim> x, wk;
      for (int d = 0, r = k; d < Dim; ++d, r /= n) {
        x[d] = rule.xi[static_cast<std::size_t>(r % n)];
        wk[d] = rule.w[static_cast<std::size_t>(r % n)];
      }
      xi.push_back(x);
      w.push_back(wk);
      psi.push_back(taylor_basis_at<Dim>(x));
    }
  }
};

// The TLS mapping on a triangular mesh (a basis with kTriangleMesh: P1, Powell-Sabin; D 6.1.2,
// 6.3): the reconstruction per triangle and a Gauss rule on each polynomial piece of the basis
// (P1: the triangle; PS: its six mini-triangles), so that the products of the basis functions
// are integrated piece by piece. The rule is the collapsed (conical) product of n-point
// Gauss-Legendre rules on the reference triangle, (xi, eta) = (u, v (1 - u)) with weight
// w_u w_v (1 - u) on [0, 1]^2: exact for total degree 2n - 2, so n = 2 (4 points per piece)
// integrates the quadratic Taylor basis exactly, which conservation needs (D eq. 5.19-5.21).
// Weights sum to 1/2, the reference area; a piece's are 2 |piece| times these.
struct TlsTriangleMappingState {
  TlsTriangleReconstruction recon;
  int per_cell = 1;                           // pieces per triangle
  std::vector<std::array<Vec<2>, 3>> pieces;  // piece k of triangle c at c * per_cell + k
  std::vector<Vec<2>> ref;                    // Gauss points (xi, eta) of a piece
  std::vector<double> ref_w;                  // their weights
  std::vector<TriangleTaylor> psi;            // Taylor basis at the Gauss points of the step
  TlsTriangleCoefficients coef;
  std::vector<double> rho;  // at the Gauss points of the step
  std::vector<Vec<2>> rhov, rhob;
  std::vector<Mat<2>> sigma;
  std::vector<double> values, integrals;  // per particle, per triangle
  // Per triangle: 1 where this process integrates it (Gauss points, report). On one process every
  // triangle holding particles; in a distributed run those whose particle of the lowest id is
  // one of this process's own, so that each is integrated by exactly one process (tls_triangle_
  // mapping.cpp, fit_mass_triangles).
  std::vector<unsigned char> integrated;

  TlsTriangleMappingState(const TriangleMesh& mesh, const TlsSettings& s, int per_cell,
                          std::vector<std::array<Vec<2>, 3>> pieces);
};

// The settings of the triangles' reconstruction from the mapping's: the completion becomes the
// strategy (none, reduce, min_norm, graded); virtual and neighbour, which place points on the
// faces of rectangles, are refused (InputError), as is a Gauss rule that does not integrate the
// Taylor basis exactly (n = 1 with linear or quadratic terms).
TlsTriangleSettings tls_triangle_settings(const TlsSettings& s);

// The TLS particle-to-grid mapping (D 5.3.1, 6.3, 004 4.4.3) in 1D, 2D and 3D (the grid's cells;
// 2D also triangles). map_mass,
// the first mapping call of every step, bins the particles, factorises the element systems and
// places the Gauss points; map_momentum and map_forces of the same step reuse them (positions do
// not change within a step, only the particle values). The mapping is not a template on the
// dimension (it is one alternative of the run's mapping variant); it keeps one state per
// dimension, created for `dim` at construction and for another dimension at its first map_mass.
class TlsMapping {
 public:
  static constexpr std::string_view kName = "tls";
  static constexpr std::string_view kDescription =
      "Taylor least squares per element, mass and momentum conservative (D 5.3, 000, 004 4.4)";
  // The run set-up rejects other dimensions with a clear message before instantiating.
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  // Capabilities (mapping/mapping.hpp).
  static constexpr bool kFusedScatter = false, kRunTotals = true, kGhostParticles = true,
                        kStrainRates = true, kCellQuadrature = true;

  TlsMapping() : TlsMapping(TlsSettings{}) {}
  // Validates s for dimension dim (throws InputError).
  explicit TlsMapping(const TlsSettings& s, int dim = 1) : settings_(s), dim_(dim) {
    validate(s, dim);
    if (dim == 3)
      state3_.emplace(s);
    else if (dim == 2)
      state2_.emplace(s);
    else
      state1_.emplace(s);
  }

  const TlsSettings& settings() const { return settings_; }
  // Gauss points per direction of an element (MappingFor's kCellQuadrature).
  int gauss_points() const { return settings_.gauss_points_used(); }
  // The reconstruction of the last step (before the first step: of the constructor's dimension).
  template <int Dim = 1>
  const BasicTlsReconstruction<Dim>& reconstruction() const {
    const auto& st = slot<Dim>();
    if (!st) throw std::logic_error(fmt::format("TlsMapping: no {}D reconstruction yet", Dim));
    return st->recon;
  }
  // The cells around this process's elements whose particles (of the other processes) this
  // mapping reads in a distributed run (MappingFor's kGhostParticles), along every axis: 1, as
  // the completions and the free-surface test look one element across; with domain_integrals
  // at least 2 ceil(r), r the largest half-side of a particle's box in cells along any axis (a
  // particle that far reaches this process's elements, and its fractions depend on the
  // elements its box overlaps, as far again). tls_mapping.cpp.
  // On triangles: every particle of a triangle that holds one of this process's, the most cells
  // a triangle spans along an axis (1 on the grid's triangles; a mesh from a file may have
  // larger ones).
  template <class Sim>
  double ghost_reach(const Sim& sim) const {
    if constexpr (Sim::BasisT::kTriangleMesh)
      return triangle_reach(sim.basis.mesh(), sim.grid);
    else
      return reach<Sim::kDim>(sim);
  }

  const TlsReport& last_report() const {
    if (triangles_) return triangle_report_;
    return dim_ == 3   ? reconstruction<3>().report()
           : dim_ == 2 ? reconstruction<2>().report()
                       : reconstruction<1>().report();
  }
  // Whether the last step ran on a triangular mesh, and its reconstruction there.
  bool on_triangles() const { return triangles_.has_value(); }
  const TlsTriangleReconstruction& triangle_reconstruction() const {
    if (!triangles_) throw std::logic_error("TlsMapping: no triangle reconstruction yet");
    return triangles_->recon;
  }
  // TlsSettings::adjoint_strain_rate: each particle's weight omega_p [m^Dim] in the stress fits
  // at the last strain_rates (sum_g R_gp w_g; its volume V_p where the fits are conservative).
  template <int Dim>
  const std::vector<double>& adjoint_weights() const {
    const auto& st = slot<Dim>();
    if (!st) throw std::logic_error(fmt::format("TlsMapping: no {}D adjoint weights yet", Dim));
    return st->omega;
  }
  // Counts summed over the steps so far (element-steps), largest condition number of the run.
  const TlsReport& totals() const { return totals_; }
  // Checkpoint restart: the sums continue from a saved run. save_totals() gives the bytes that
  // the checkpoint stores (core/bytes.hpp); load_totals() reads them back, InputError naming
  // `what` when they are not those of a TLS run.
  void set_totals(const TlsReport& t) { totals_ = t; }
  std::string save_totals() const;
  void load_totals(std::string_view bytes, const std::string& what);

  // The basis enters only through the quadrature stencils: the reconstructions are compiled once
  // per dimension (tls_mapping.cpp), the assembly once per basis.
  // rho^ conservative with c_e = sum m_p and data rho_p; lumped masses and, with consistent
  // mass, M_ij = sum_g phi_i rho^ phi_j w_g (D eq. 5.14, 5.17).
  // On a triangular mesh (kTriangleMesh) the elements are its triangles (D 6.1.2, 6.3).
  template <class Sim>
  void map_mass(Sim& sim) {
    constexpr int Dim = Sim::kDim;
    auto& q = quad_.prepare<Sim>();
    if constexpr (Sim::BasisT::kTriangleMesh) {
      const auto& b = sim.basis;
      // The mesh is the basis's; a new one (a restored or copied state) gets new operators.
      if (!triangles_ || &triangles_->recon.mesh() != &b.mesh()) {
        std::vector<std::array<Vec<2>, 3>> pieces;
        for (Index c = 0; c < b.mesh().num_cells(); ++c)
          for (int k = 0; k < b.pieces(); ++k) pieces.push_back(b.piece(c, k));
        triangles_.emplace(b.mesh(), settings_, b.pieces(), std::move(pieces));
      }
      fit_mass_triangles(sim, q);
      q.evaluate(sim.basis, sim.step, sim.time);
      sim.quadrature_dofs = q.ranges.span();  // shared with the particles' DOFs
      assemble_mass(sim, q, triangles_->rho);
    } else {
      fit_mass<Dim>(sim, q);
      q.evaluate(sim.basis, sim.step, sim.time);
      sim.quadrature_dofs = q.ranges.span();  // shared with the particles' DOFs
      assemble_mass(sim, q, state<Dim>().rho);
    }
  }

  // (rho v)^ conservative per component with c_e = sum m_p v_p and data rho_p v_p (D eq. 5.14,
  // 5.16; both directions in 2D, D 6.3).
  template <class Sim>
  void map_momentum(Sim& sim) {
    constexpr int Dim = Sim::kDim;
    const auto& q = quad_.prepared<Sim>();
    if constexpr (Sim::BasisT::kTriangleMesh) {
      fit_momentum_triangles(sim, q);
      assemble_momentum(sim, q, triangles_->rhov);
    } else {
      fit_momentum<Dim>(sim, q);
      assemble_momentum(sim, q, state<Dim>().rhov);
    }
  }

  // sigma^ by plain least squares per component (D eq. 5.12-5.13, 6.19-6.20); the body-force
  // density (rho b)^ conservative per component with c_e = sum m_p b_p and data rho_p b_p;
  // f_i = sum_g (phi_i (rho b)^ - sigma^ grad phi_i) w_g.
  template <class Sim>
  void map_forces(Sim& sim) {
    constexpr int Dim = Sim::kDim;
    const auto& q = quad_.prepared<Sim>();
    if constexpr (Sim::BasisT::kTriangleMesh) {
      fit_forces_triangles(sim, q);
      assemble_forces(sim, q, triangles_->rhob, triangles_->sigma);
    } else {
      fit_forces<Dim>(sim, q);
      const auto& st = state<Dim>();
      assemble_forces(sim, q, st.rhob, st.sigma);
    }
  }

  // TlsSettings::adjoint_strain_rate: the velocity gradients of the particles for the stress
  // update that follows, from the grid velocity and this step's fits, into
  // sim.mapped_gradient (stages::mapped_strain_rates); nothing otherwise. On the grid's cells
  // (the run set-up refuses triangles); in a distributed run the transposed fits reach the ghost
  // particles, whose parts go back to their processes (adjoint_gradients).
  template <class Sim>
  void strain_rates(Sim& sim) {
    if (!settings_.adjoint_strain_rate) return;
    constexpr int Dim = Sim::kDim;
    if constexpr (Sim::BasisT::kTriangleMesh) {
      throw std::logic_error("TLS: the adjoint strain rate is defined on the grid's cells");
    } else {
      const auto& q = quad_.prepared<Sim>();
      auto& st = state<Dim>();
      const auto& v = sim.nodes.velocity;
      st.wgrad.resize(q.size());
      parallel_for(static_cast<Index>(q.size()), [&](Index gi) {
        const auto g = static_cast<std::size_t>(gi);
        const auto& s = q.stencil[g];
        Mat<Dim> L = Mat<Dim>::Zero();
        for (int a = 0; a < s.kSize; ++a) L.noalias() += v[s.dof[a]] * s.grad[a].transpose();
        st.wgrad[g] = q.w[g] * L;
      });
      // A particle without a positive weight in the fits (omega_p <= 0: possible where a fit
      // extrapolates) has no adjoint rate; it takes its gradient at x_p (D eq. 2.52).
      for (const Index p : adjoint_gradients<Dim>(sim, q)) {
        const auto i = static_cast<std::size_t>(p);
        Mat<Dim> L = Mat<Dim>::Zero();
        for_each_entry(sim.stencils[i], sim.dof_stride,
                       [&](Index dof, double, const Vec<Dim>& grad) {
                         L.noalias() += v[static_cast<std::size_t>(dof)] * grad.transpose();
                       });
        sim.mapped_gradient[i] = L;
      }
    }
  }

 private:
  // tls_mapping.cpp: strain_rates' transpose of the stress fit, from st.wgrad, into
  // sim.mapped_gradient; returns the particles whose weight omega_p is not positive (their
  // entries left for the caller). Counts them in totals_.unweighted.
  template <int Dim>
  const std::vector<Index>& adjoint_gradients(RunState<Dim>& sim, const GaussPoints<Dim>& q);
  std::vector<Index> no_weight_;
  // The slot of dimension Dim's state (empty until its first use).
  template <int Dim>
  std::optional<TlsMappingState<Dim>>& slot() {
    if constexpr (Dim == 1)
      return state1_;
    else if constexpr (Dim == 2)
      return state2_;
    else
      return state3_;
  }
  template <int Dim>
  const std::optional<TlsMappingState<Dim>>& slot() const {
    return const_cast<TlsMapping*>(this)->slot<Dim>();
  }
  // The state of dimension Dim, created (and the settings validated for Dim) on first use.
  template <int Dim>
  TlsMappingState<Dim>& state() {
    static_assert(Dim >= 1 && Dim <= 3, "the TLS mapping is implemented in 1D to 3D");
    dim_ = Dim;
    auto& st = slot<Dim>();
    if (!st) {
      validate(settings_, Dim);
      st.emplace(settings_);
    }
    return *st;
  }
  // For the n fields j: integrals_[j * E + e] = sum over the element's particles of value(p, j)
  // (E elements); with TlsSettings::domain_integrals (on the grid's cells), sum over the
  // particles whose domain overlaps e of value(p, j) times the overlap fraction (split_, built
  // by split_domains). One pass over the particle lists for all fields. And values_[i * nv + j] =
  // point(i, j) for the N particles and nv fields (values() is that part of values_), in the
  // same parallel region (parallel_for_both).
  template <class Recon, class Point, class Value>
  void values_and_sums(const Recon& recon, std::size_t N, int nv, Point&& point, int n,
                       Value&& value) {
    const auto& bins = recon.bins();
    const auto ne = static_cast<std::size_t>(recon.num_elements());
    integrals_.resize(ne * static_cast<std::size_t>(n));
    constexpr int kMax = 9;  // the stress and body-force density in 3D (fit_forces)
    if (n > kMax) throw std::logic_error("TlsMapping::values_and_sums: too many fields");
    // The buffer only grows: the three fits of a step use 1, Dim and Dim (Dim + 1) / 2 + Dim
    // fields, and resizing it up again each step zeroed what is written next (1 % of a TLS
    // step, serial).
    values_used_ = N * static_cast<std::size_t>(nv);
    if (values_.size() < values_used_) values_.resize(values_used_);
    auto fill = [&](Index i) {
      const auto p = static_cast<std::size_t>(i);
      for (int j = 0; j < nv; ++j) values_[p * static_cast<std::size_t>(nv) + j] = point(p, j);
    };
    auto sum = [&](Index e, auto&& each) {
      std::array<double, kMax> c{};
      each([&](std::size_t p, double fraction) {
        for (int j = 0; j < n; ++j) c[static_cast<std::size_t>(j)] += value(p, j) * fraction;
      });
      for (int j = 0; j < n; ++j)
        integrals_[static_cast<std::size_t>(j) * ne + static_cast<std::size_t>(e)] =
            c[static_cast<std::size_t>(j)];
    };
    if (settings_.domain_integrals) {
      parallel_for_both(static_cast<Index>(N), fill, recon.num_elements(), [&](Index e) {
        const auto ei = static_cast<std::size_t>(e);
        sum(e, [&](auto&& add) {
          for (std::size_t k = split_.start[ei]; k < split_.start[ei + 1]; ++k)
            add(static_cast<std::size_t>(split_.point[k]), split_.fraction[k]);
        });
      });
      return;
    }
    parallel_for_both(static_cast<Index>(N), fill, recon.num_elements(), [&](Index e) {
      sum(e, [&](auto&& add) {
        for (const Index* p = bins.begin(e); p != bins.end(e); ++p)
          add(static_cast<std::size_t>(*p), 1.0);
      });
    });
  }
  // The integrals of field j of the last values_and_sums.
  const double* integrals_of(int j, Index elements) const {
    return integrals_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(elements);
  }
  // TlsSettings::domain_integrals: the overlap fractions of the particles' domains with the
  // active elements, by element (CSR), rebuilt by fit_mass each step (tls_mapping.cpp).
  template <int Dim>
  void split_domains(const RunState<Dim>& sim, const BasicTlsReconstruction<Dim>& recon);
  std::span<const double> values() const { return std::span(values_).first(values_used_); }
  // store(g, k) for the Gauss points g of element e, k its local point (fit_mass places n^Dim
  // consecutive points from st.gauss_first in each active element of its range; none elsewhere).
  template <int Dim, class Store>
  static void gauss_points_of(const TlsMappingState<Dim>& st, Index e, Store&& store) {
    const Index k0 = e - st.gauss_range[0];
    if (k0 < 0 || e >= st.gauss_range[1]) return;
    const Index first = st.gauss_first[static_cast<std::size_t>(k0)];
    if (first < 0) return;
    const auto g0 = static_cast<std::size_t>(first);
    for (std::size_t k = 0; k < st.psi.size(); ++k) store(g0 + k, k);
  }

  // tls_mapping.cpp, for Dim 1 to 3: the fits of map_mass (binning, element systems, Gauss
  // points placed in q, rho^ there), map_momentum ((rho v)^) and map_forces (sigma^, (rho b)^).
  template <int Dim>
  void fit_mass(RunState<Dim>& sim, GaussPoints<Dim>& q);
  // tls_mapping.cpp: TlsSettings::surface_volume's flag and positivity's theta of element e
  // (from the density fit in st.coef), sized by prepare_flags; count_flags: how many elements of
  // `own` (RunState::own_cells) each flagged or limited. apply_theta: theta applied to element
  // e of a conservative fit.
  template <int Dim>
  void prepare_flags(TlsMappingState<Dim>& st);
  template <int Dim>
  void flag_element(TlsMappingState<Dim>& st, Index e) const;
  template <int Dim>
  std::array<Index, 2> count_flags(const TlsMappingState<Dim>& st, const CellBox<Dim>& own) const;
  template <int Dim>
  double reach(const RunState<Dim>& sim) const;
  // reach's value for the step reach_step_ (-1: none yet): one reach for all the ghost exchanges
  // of a step (tls_mapping.cpp).
  mutable Index reach_step_ = -1;
  mutable double reach_ = 1.0;
  // The most cell layers between the lowest and the highest corner of a triangle (at least 1),
  // computed once for the mesh triangle_reach_mesh_ (tls_triangle_mapping.cpp).
  double triangle_reach(const TriangleMesh& mesh, const Grid<2>& grid) const;
  mutable const TriangleMesh* triangle_reach_mesh_ = nullptr;
  mutable double triangle_reach_ = 1.0;
  template <int Dim>
  void apply_theta(const TlsMappingState<Dim>& st, BasicTlsCoefficients<Dim>& coef,
                   const unsigned char* only, Index e) const;
  template <int Dim>
  void fit_momentum(RunState<Dim>& sim, const GaussPoints<Dim>& q);
  template <int Dim>
  void fit_forces(RunState<Dim>& sim, const GaussPoints<Dim>& q);
  // tls_triangle_mapping.cpp: the same on the triangles of `mesh` (the basis's).
  void fit_mass_triangles(RunState<2>& sim, GaussPoints<2>& q);
  void fit_momentum_triangles(RunState<2>& sim, const GaussPoints<2>& q);
  void fit_forces_triangles(RunState<2>& sim, const GaussPoints<2>& q);

  TlsSettings settings_;
  int dim_ = 1;  // dimension of the last step
  std::optional<TlsMappingState<1>> state1_;
  std::optional<TlsMappingState<2>> state2_;
  std::optional<TlsMappingState<3>> state3_;
  std::optional<TlsTriangleMappingState> triangles_;  // on a triangular mesh
  TlsReport triangle_report_;                         // of the last step there
  QuadratureStore quad_;
  std::vector<double> values_, integrals_;  // per particle, per element
  std::size_t values_used_ = 0;             // of values_: the last values_and_sums
  struct DomainSplit {
    std::vector<std::size_t> start;  // element e: entries start[e] .. start[e + 1]
    std::vector<Index> point;        // particle
    std::vector<double> fraction;    // of the particle's domain in e (sum over e: 1)
    std::vector<std::size_t> next;   // fill cursors of the counting sort
    // What one chunk of the binned particles (ParticleChunks over bins.order) splits: its
    // entries in bin order, the elements [lo, hi] they fall in, and per element of that band
    // first its entry count, then the chunk's first slot in the sorted arrays.
    struct Entry {
      Index element, point;
      double fraction;
    };
    struct Chunk {
      std::vector<Entry> entries;
      Index lo = 0, hi = -1;
      std::vector<std::size_t> slot;
    };
    std::array<Chunk, ParticleChunks::kMax> chunks;
  } split_;
  TlsReport totals_;
};

}  // namespace mpm
