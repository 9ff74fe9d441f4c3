#include "setup/method_settings.hpp"

namespace mpm {

TlsSettings tls_settings(const Config& cfg, int dim) {
  TlsSettings s;
  s.terms = static_cast<int>(cfg.get_int("method.tls_terms"));
  // "auto": reduce in 2D (and 3D, which has no study of its own yet), the most accurate completion
  // of the studies in docs/verification.md (triangles: D 6.3.1's plate with 12, 16, 24 particles
  // per triangle, A = 0.05 and 0.1 m; the grid's cells: the plate at A = 0.05 m and the generalized
  // vortex); virtual in 1D, D 5.2.3's, whose results the report reproduces.
  const std::string completion = cfg.get_string("method.tls_completion");
  s.completion = completion != "auto" ? parse_tls_completion(completion)
                 : dim >= 2           ? TlsCompletion::Reduce
                                      : TlsCompletion::Virtual;
  // 0: 1e8 in 1D (D 5.2.3's "nearly singular"), 10 in 2D (the study of docs/verification.md,
  // as on triangles) and in 3D (the same orthonormal measure; no 3D study yet).
  s.max_condition = cfg.get_real("method.tls_max_condition");
  if (s.max_condition == 0.0) s.max_condition = dim == 1 ? 1e8 : 10.0;
  const std::string positivity = cfg.get_string("method.tls_positivity");
  s.positivity = positivity == "on" || (positivity == "auto" && dim >= 2);
  const std::string surface = cfg.get_string("method.tls_surface_stress");
  s.surface_volume = surface == "volume" || (surface == "auto" && dim >= 2);
  const std::string integrals = cfg.get_string("method.tls_cell_integrals");
  s.domain_integrals = integrals == "domains" || (integrals == "auto" && dim >= 2);
  s.adjoint_strain_rate = cfg.get_string("method.tls_strain_rate") == "adjoint";
  s.gauss_points = static_cast<int>(cfg.get_int("method.gauss_points"));
  // 2D, 3D: the summary's max_condition is an upper bound where a cheap bound proves the element
  // well posed (TlsSettings::exact_condition), which saves the 6 x 6 eigensolves; 1D keeps the
  // exact values (3 x 3; `mpm reconstruct` reports exact values in both).
  s.exact_condition = dim == 1;
  validate(s, dim);
  return s;
}

MlsSettings mls_settings(const Config& cfg, bool improved) {
  MlsSettings s;
  s.degree = static_cast<int>(cfg.get_int("method.mls_degree"));
  s.gauss_points = static_cast<int>(cfg.get_int("method.gauss_points"));
  s.dilation = cfg.get_real("method.mls_dilation");
  s.conservative = cfg.get_bool("method.mls_conservative");
  if (improved && cfg.get_string("method.mass") != "lumped")
    throw InputError("method.mapping = imls needs method.mass = lumped (003 eq. 32)");
  return s;
}

CubicSplineSettings cubic_spline_settings(const Config& cfg) {
  CubicSplineSettings s;
  s.gauss_points_per_half = static_cast<int>(cfg.get_int("method.gauss_points"));
  return s;
}

}  // namespace mpm
