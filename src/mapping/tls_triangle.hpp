#pragma once
// Taylor least-squares (TLS) reconstruction on triangular meshes (D 6.1.2, 6.3; the 1D and
// rectangle versions are BasicTlsReconstruction in mapping/tls.hpp). Standalone: not yet a
// particle-to-grid mapping of an MPM run.
//
// Each triangle e is the image of the reference triangle {xi, eta >= 0, xi + eta <= 1} under the
// affine map x = x_0 + A (xi, eta)^T, A = [x_1 - x_0, x_2 - x_0] with x_0, x_1, x_2 the vertices
// in TriangleMesh::cell_vertices order (D eq. 6.14-6.15 writes the inverse map). The Taylor basis
// is defined in reference coordinates (D 6.1.2, eq. 6.16-6.18), so it is the same polynomial
// family in every element and cond(D) is invariant under the element's size and shape (it
// depends only on the reference coordinates of the points). A function integrates over e to
// |Omega_e| times its mean over the reference triangle (the Jacobian is constant), so
// int_e psi_1 = |Omega_e| and int_e psi_k = 0 for k > 1 (D eq. 5.7) hold in every element.
//
// Fits per element (D 5.2.1, 5.2.3): plain least squares of all coefficients (D eq. 5.1), or
// conservative: a_1 = c_e / |Omega_e| fixed by the element integral c_e (D eq. 5.8-5.9) and
// a_2..a_n least squares of f - a_1 with psi_2..psi_n only. The least-squares operators depend
// only on the point positions; set_points() builds them once, every fit is then one small
// matrix-vector product per element.
//
// Robustness (D 6.3.1: runs with 12 or 16 particles per triangle stop because
// D = sum_p psi(x_p) psi(x_p)^T loses rank; D 6.3.2 asks for a study): D is singular exactly
// when a nonzero polynomial of the fitted space vanishes at every point of the element, e.g.
// (x - a)(x - b) for points on two parallel lines, or a conic through all points. Whatever the
// strategy, a field stays finite and the conservative fit keeps int_e f^ = c_e to round-off.
#include <Eigen/Dense>
#include <span>
#include <string_view>
#include <vector>

#include "core/types.hpp"
#include "grid/triangle_mesh.hpp"

namespace mpm {

// Taylor coefficients a_1..a_6 of a triangle (zero beyond the terms fitted).
using TriangleTaylor = Eigen::Matrix<double, 6, 1>;
using TlsTriangleCoefficients = std::vector<TriangleTaylor>;

// The Taylor basis on the reference triangle at (xi, eta) (D 6.1.2): the rectangle formulas
// (D eq. 6.1-6.6) with centroid (1/3, 1/3) and Delta x_1 = Delta x_2 = 1/2, i.e. in
// s = 2 (xi - 1/3), t = 2 (eta - 1/3):
//   psi_1 = 1, psi_2 = s, psi_3 = t,
//   psi_4 = s^2 / 2 - mean(s^2) / 2 = 2 (xi - 1/3)^2 - 1/9            (D eq. 6.16),
//   psi_5 = t^2 / 2 - mean(t^2) / 2 = 2 (eta - 1/3)^2 - 1/9           (D eq. 6.17),
//   psi_6 = s t - mean(s t)         = 4 (xi - 1/3)(eta - 1/3) + 1/9.
// The means over the reference triangle (area 1/2): mean(xi) = mean(eta) = 1/3,
// mean((xi - 1/3)^2) = mean((eta - 1/3)^2) = 1/18, so mean(s^2) = mean(t^2) = 2/9, and
// mean((xi - 1/3)(eta - 1/3)) = 1/12 - 1/9 = -1/36, so mean(s t) = -1/9. D eq. 6.18 prints
// + 1/18 for psi_6, which does not integrate to zero (its integral is |Omega_e| / 18); the
// overline of the volume average is lost in D eq. 6.4-6.6 as well (METHODS.md errata).
inline TriangleTaylor triangle_taylor_basis(double xi, double eta) {
  const double s = 2.0 * xi - 2.0 / 3.0, t = 2.0 * eta - 2.0 / 3.0;
  TriangleTaylor psi;
  psi << 1.0, s, t, 0.5 * s * s - 1.0 / 9.0, 0.5 * t * t - 1.0 / 9.0, s * t + 1.0 / 9.0;
  return psi;
}

// What an element does when its points cannot support the requested terms, i.e. when cond(D)
// of the fitted terms exceeds TlsTriangleSettings::max_condition (infinite when D is singular).
// The plain and the conservative systems of an element are judged separately: the conservative
// one fits psi_2..psi_n only, so e.g. points on a conic q = 0 with a nonzero mean of q make the
// plain D singular and leave the conservative one regular.
enum class TlsTriangleStrategy {
  // (a) The baseline of D 6.3.1: the element is reported failed (the caller stops, as D's runs
  // did). Its field is the constant fit (conservative: a_1 = c_e / |Omega_e|; plain: the mean of
  // the data), so that it stays finite and conservative.
  None,
  // (b) Order reduction: the most terms among n_b, 3, 1 (complete polynomial spaces of degree
  // 2, 1, 0) whose cond(D) is within the limit, as the rectangles' TlsCompletion::Reduce.
  Reduce,
  // (c) Truncated SVD of the data matrix B (rows psi(x_p)^T): singular values below
  // sigma_max / sqrt(max_condition) are dropped (cond(D) = cond(B)^2) and the minimum-norm
  // least-squares coefficients are taken. Conservative fits truncate B without psi_1, so a_1
  // stays exact.
  MinimumNorm,
  // (d) As MinimumNorm, but of all the truncated least-squares solutions the one with the
  // smallest quadratic coefficients (a_4..a_6), then the smallest linear ones (a_2, a_3), then
  // a_1 (a lexicographic minimum norm by degree): the undetermined directions are resolved
  // towards the lowest degree. Unlike MinimumNorm it reproduces linear data exactly wherever the
  // linear terms are determined (points not collinear), and unlike Reduce it keeps the quadratic
  // information the points do determine.
  Graded,
};

// "none", "reduce", "min-norm", "graded". Throws InputError.
TlsTriangleStrategy parse_tls_triangle_strategy(std::string_view name);
std::string_view tls_triangle_strategy_name(TlsTriangleStrategy s);

struct TlsTriangleSettings {
  // n_b: 1 (constant), 3 (linear) or 6 (quadratic), the complete polynomial spaces; 0: 6.
  int terms = 0;
  TlsTriangleStrategy strategy = TlsTriangleStrategy::Graded;
  // Largest cond(D) = lambda_max / lambda_min of the normal matrix of the fitted terms accepted
  // as well posed (D 5.2.3); equivalently, singular values of B below sigma_max / 1e4 count as
  // zero. The basis is O(1) on the reference triangle, so the number is independent of the
  // element's size and shape. The same default as TlsSettings::max_condition.
  double max_condition = 1e8;

  int terms_used() const { return terms > 0 ? terms : 6; }
};

// Throws InputError for settings outside the documented ranges.
void validate(const TlsTriangleSettings& s);

// One kind of fit (plain or conservative) over all elements of a point set.
struct TlsTriangleFitReport {
  Index full = 0;       // active elements whose requested terms are well posed
  Index deficient = 0;  // active elements with cond(D) of the requested terms above the limit
  Index reduced = 0;    // Reduce: fitted with fewer terms than requested
  Index truncated = 0;  // MinimumNorm, Graded: fitted with rank below the terms
  Index failed = 0;     // None: deficient, given the constant fit
  int min_rank = 0;     // smallest rank of an active element's fit, a_1 included (0: none active)
  // Largest cond(D) of the requested terms over the active elements (infinite when singular),
  // and of what was actually solved (Reduce: the reduced terms; MinimumNorm, Graded: the kept
  // singular values, so at most max_condition).
  double max_condition = 0.0;
  double max_condition_solved = 0.0;
  Index first_deficient = -1;  // lowest deficient element (-1: none)
};

struct TlsTriangleReport {
  Index elements = 0;  // triangles of the mesh
  Index active = 0;    // with at least one point
  Index outside = 0;   // points outside the mesh (or not finite), ignored
  TlsTriangleFitReport plain, conservative;
};

// One element system after set_points(). For the conservative system a_1 counts as a term and
// as one rank (it is given), so rank == terms when the requested terms are well posed.
struct TlsTriangleSystemInfo {
  int terms = 0;                  // Taylor terms of the fit (0: inactive element)
  int rank = 0;                   // independent directions fitted, a_1 included
  double condition = 0.0;         // cond(D) of the requested terms (infinite: singular)
  double condition_solved = 0.0;  // cond(D) of the part solved
  bool deficient = false;         // condition > max_condition
  bool failed = false;            // deficient with strategy None
};

struct TlsTriangleElementInfo {
  Index points = 0;
  TlsTriangleSystemInfo plain, conservative;
};

class TlsTriangleReconstruction {
 public:
  using Coefficients = TlsTriangleCoefficients;

  // The mesh must outlive the reconstruction. Validates the settings (InputError).
  explicit TlsTriangleReconstruction(const TriangleMesh& mesh, const TlsTriangleSettings& s = {});

  // Scattered points x (any order). A point goes to TriangleMesh::cell_index(x) (on a shared
  // edge: the lowest-numbered triangle); points outside the mesh are ignored and counted.
  const TlsTriangleReport& set_points(std::span<const Vec<2>> x);

  // f: one value per point of set_points; integrals: c_e per element. a_1 = c_e / |Omega_e|
  // in every element, with or without points (D eq. 5.9), so int_e f^ = c_e to round-off; the
  // other coefficients fit f - a_1 (zero in elements without points).
  void fit_conservative(std::span<const double> f, std::span<const double> integrals,
                        Coefficients& a) const;
  // All coefficients by least squares (D eq. 5.1); zero in elements without points.
  void fit_plain(std::span<const double> f, Coefficients& a) const;

  // The reconstruction at x (its element by TriangleMesh::cell_index); zero outside the mesh.
  double evaluate(const Coefficients& a, const Vec<2>& x) const;
  // Element e's Taylor polynomial at x (x need not lie in e).
  double evaluate(const Coefficients& a, Index e, const Vec<2>& x) const {
    return a[static_cast<std::size_t>(e)].dot(basis(e, x));
  }
  // Reference coordinates (xi, eta) of x in element e: A^{-1} (x - x_0).
  Vec<2> reference(Index e, const Vec<2>& x) const {
    const auto ei = static_cast<std::size_t>(e);
    return inverse_[ei] * (x - origin_[ei]);
  }
  TriangleTaylor basis(Index e, const Vec<2>& x) const {
    const Vec<2> r = reference(e, x);
    return triangle_taylor_basis(r[0], r[1]);
  }
  // int_e f^ = a_1 |Omega_e| (D eq. 5.8).
  double integral(const Coefficients& a, Index e) const {
    return a[static_cast<std::size_t>(e)][0] * mesh_->cell_volume(e);
  }

  const TlsTriangleSettings& settings() const { return settings_; }
  int terms() const { return nb_; }  // n_b requested
  const TlsTriangleReport& report() const { return report_; }
  const TlsTriangleElementInfo& element(Index e) const {
    return info_[static_cast<std::size_t>(e)];
  }
  const TriangleMesh& mesh() const { return *mesh_; }
  Index num_elements() const { return mesh_->num_cells(); }
  // Indices (into the x of set_points) of element e's points, ascending.
  std::span<const Index> points(Index e) const {
    const auto ei = static_cast<std::size_t>(e);
    return {order_.data() + start_[ei], static_cast<std::size_t>(start_[ei + 1] - start_[ei])};
  }

 private:
  const TriangleMesh* mesh_;
  TlsTriangleSettings settings_;
  int nb_ = 6;
  std::vector<Vec<2>> origin_;   // x_0 per element
  std::vector<Mat<2>> inverse_;  // A^{-1} per element
  TlsTriangleReport report_;
  std::vector<TlsTriangleElementInfo> info_;
  std::size_t num_points_ = 0;        // size of the x of set_points
  std::vector<Index> start_, order_;  // points by element (compressed rows)
  // Per entry of order_: the column of the element's least-squares operator for that point,
  // plain (coefficients a_1..a_n) and conservative (entries 1..n-1: a_2..a_n; entry 0 unused),
  // so a = sum_p q_p f_p and a_2.. = sum_p qc_p (f_p - a_1).
  std::vector<TriangleTaylor> q_, qc_;
};

}  // namespace mpm
