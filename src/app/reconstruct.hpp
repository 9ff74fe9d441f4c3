#pragma once
// `mpm reconstruct`: the reconstruction playground (D 5.2.3, Table 5.1; D 6.2.1 in 2D, D 6.2.2
// on triangles). A function
// given as an expression of x (and y) is sampled at points of a 1D grid (or a square 2D grid of
// rectangles) and reconstructed with a mapping's reconstruction; the RMS error over Gauss points
// per element and the relative error of the integral (by the mapping's own quadrature) are
// reported.
#include <string>
#include <vector>

#include "core/types.hpp"
#include "grid/grid.hpp"
#include "mapping/cubic_spline.hpp"
#include "mapping/mls.hpp"
#include "mapping/tls.hpp"

namespace mpm {

struct ReconstructOptions {
  // 1: f(x) on [lower, upper]; 2: f(x, y) on [lower, upper]^2 with cells x cells elements
  // (TLS only, D 6.2.1).
  int dim = 1;
  std::string function = "sin(x) + 2";      // f(x) or f(x, y), muparser syntax
  std::string lower = "0", upper = "4*pi";  // domain ends (expressions of constants)
  Index cells = 4;                          // per direction
  std::string mapping = "tls";              // tls | cubic_spline | mls | imls
  int terms = 3;                            // TLS Taylor terms (1D 1-3; 2D 1, 3 or 6; 0: quadratic)
  std::string completion = "virtual";
  double max_condition = 1e8;
  int mls_degree = 1;        // MLS/IMLS polynomial degree (1 or 2); weight support from the cell
  bool conservative = true;  // TLS: keep the exact element integrals (D eq. 5.9)
  // uniform:N (N evenly spaced per element), random:N (N per element, --seed), or
  // list:X1,X2,... (expressions); a point on an interior face belongs to both elements when
  // share_faces is set (as the point at pi in D 5.2.3). 2D: uniform:N or uniform:NXxNY ((k + 1/2)
  // / n per direction), inner:NXxNY (k / (n + 1), k = 1..n; D 6.2.1 is inner:2x3), random:N,
  // list:X1;Y1,X2;Y2,...
  std::string points = "uniform:3";
  unsigned seed = 1;
  bool share_faces = false;
  // Gauss points per element (2D: per direction) for the RMS error (D 5.2.3: 100; D 6.2.1: 2)
  // and for the integral (D: 2).
  int error_points = 100;
  int integration_points = 2;
  // 2D on triangles (TLS only, D 6.2.2): "right" or "criss-cross" (cells x cells squares of
  // [lower, upper]^2, triangulated), or a Gmsh file; empty: rectangles. Points random:N (N
  // uniformly distributed per triangle) or domain:N (N uniformly distributed over the domain's
  // bounding box, kept where they fall inside the mesh), and the strategy for deficient
  // elements (none, reduce, min-norm, graded). The error is taken at the 6 points of the
  // degree-4 rule per triangle (--error-points and --integration-points do not apply).
  std::string mesh;
  std::string strategy = "graded";
};

struct ReconstructResult {
  std::vector<double> x;   // the data points (1D)
  std::vector<Vec<2>> xy;  // the data points (2D)
  double rms_error = 0.0;
  double integral_exact = 0.0;  // 20-point Gauss per element of f
  double integral_reconstructed = 0.0;
  double relative_integral_error = 0.0;
  std::string details;  // per-element report (points, terms, completion, condition)
};

// The 1D reconstruction of values f_k at points x_k on the elements of g by opt.mapping (tls,
// cubic_spline, mls or imls, with opt's settings): what `mpm reconstruct` fits, and what
// mpmlab.reconstruct evaluates at the caller's points. element_integrals: TLS's conservative
// fit keeps them (D eq. 5.9); empty: the plain fit. InputError for bad options or data (a point
// outside g, a value that is not finite, a TLS element that cannot be fitted).
class Reconstruction1D {
 public:
  Reconstruction1D(const ReconstructOptions& opt, const Grid<1>& g, const std::vector<double>& x,
                   const std::vector<double>& f, const std::vector<double>& element_integrals);
  // The reconstruction at x in element e (TLS: element e's polynomial; the cubic spline and MLS
  // are one function over the elements).
  double value(Index e, double x);
  // Per element (TLS: points, virtual and borrowed points, terms, condition), or a line.
  std::string details() const;

 private:
  std::string mapping_;
  int mls_degree_ = 1;
  std::size_t points_ = 0;
  std::vector<double> f_;
  std::string details_;
  TlsReconstruction tls_;
  TlsCoefficients coeffs_;
  NaturalCubicSpline spline_;
  MovingLeastSquares<1> mls_;
};

// The 2D TLS reconstruction on the rectangles of g (D 6.2.1; opt.mapping must be tls), as
// Reconstruction1D: what `mpm reconstruct --dim 2` fits and mpmlab.reconstruct evaluates.
class Reconstruction2D {
 public:
  Reconstruction2D(const ReconstructOptions& opt, const Grid<2>& g, const std::vector<Vec<2>>& x,
                   const std::vector<double>& f, const std::vector<double>& element_integrals);
  // Element e's polynomial at x.
  double value(Index e, const Vec<2>& x) const;
  // Per element: cell, points, virtual and borrowed points, terms, condition.
  const std::string& details() const { return details_; }

 private:
  TlsReconstruction2D tls_;
  TlsCoefficients2D coeffs_;
  std::string details_;
};

// Throws InputError for bad options (unknown mapping, bad point list, expression errors).
ReconstructResult reconstruct(const ReconstructOptions& opt);

}  // namespace mpm
