#pragma once
// `mpm reconstruct`: the reconstruction playground (D 5.2.3, Table 5.1). A function given as an
// expression of x is sampled at points of a 1D grid and reconstructed with a mapping's
// reconstruction; the RMS error over many Gauss points per element and the relative error of the
// integral (by the mapping's own quadrature) are reported.
#include <string>
#include <vector>

#include "core/types.hpp"

namespace mpm {

struct ReconstructOptions {
  std::string function = "sin(x) + 2";      // f(x), muparser syntax
  std::string lower = "0", upper = "4*pi";  // domain ends (expressions of constants)
  Index cells = 4;
  std::string mapping = "tls";  // tls | cubic_spline | mls | imls
  int terms = 3;                // TLS Taylor terms
  std::string completion = "virtual";
  double max_condition = 1e8;
  int mls_degree = 1;        // MLS/IMLS polynomial degree (1 or 2); weight support from the cell
  bool conservative = true;  // TLS: keep the exact element integrals (D eq. 5.9)
  // uniform:N (N evenly spaced per element), random:N (N per element, --seed), or
  // list:X1,X2,... (expressions); a point on an interior face belongs to both elements when
  // share_faces is set (as the point at pi in D 5.2.3).
  std::string points = "uniform:3";
  unsigned seed = 1;
  bool share_faces = false;
  int error_points = 100;      // Gauss points per element for the RMS error (D: 100)
  int integration_points = 2;  // Gauss points per element for the integral (D: 2)
};

struct ReconstructResult {
  std::vector<double> x;  // the data points
  double rms_error = 0.0;
  double integral_exact = 0.0;  // 20-point Gauss per element of f
  double integral_reconstructed = 0.0;
  double relative_integral_error = 0.0;
  std::string details;  // per-element report (points, terms, completion, condition)
};

// Throws InputError for bad options (unknown mapping, bad point list, expression errors).
ReconstructResult reconstruct(const ReconstructOptions& opt);

}  // namespace mpm
