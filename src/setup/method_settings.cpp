#include "setup/method_settings.hpp"

#include <string>
#include <string_view>

#include "methods/kinds.hpp"

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

namespace {
// The bases on triangles, as "a" or "b" (messages).
std::string triangle_bases() {
  return basis_names_where([](const auto& k) { return k.kOnTriangles; });
}
}  // namespace

TlsSettings tls_settings_for_basis(const Config& cfg, const TlsSettings& chosen, bool triangles,
                                   std::string_view basis) {
  TlsSettings ts = chosen;
  const std::string completion = cfg.get_string("method.tls_completion");
  const bool triangle_only =
      ts.completion == TlsCompletion::MinimumNorm || ts.completion == TlsCompletion::Graded;
  if (!triangles && triangle_only)
    throw InputError(fmt::format(
        "{}: method.tls_completion = \"{}\" works on triangles (method.basis = {}); on the "
        "grid's cells choose one of: none, reduce, virtual, neighbour, auto",
        cfg.where("method.tls_completion"), completion, triangle_bases()));
  // Both limits are measured in the orthonormal Taylor basis of their element, but each was
  // chosen for its own elements, so each is refused where it does not apply; so are the
  // rectangles' positivity and surface stress on triangles.
  const char* other = triangles ? "method.tls_max_condition" : "method.tls_triangle_max_condition";
  const KeySpec* spec = find_key(other);
  if (spec != nullptr && spec->default_value &&
      cfg.get_real(other) != std::get<double>(*spec->default_value))
    throw InputError(fmt::format(
        "{}: {} applies to {}; this run's basis \"{}\" uses {}", cfg.where(other), other,
        triangles ? "the grid's cells" : fmt::format("triangles ({})", triangle_bases()), basis,
        triangles ? "method.tls_triangle_max_condition" : "method.tls_max_condition"));
  if (triangles) {
    for (const char* key :
         {"method.tls_positivity", "method.tls_surface_stress", "method.tls_cell_integrals"})
      if (cfg.get_string(key) != "auto")
        throw InputError(fmt::format(
            "{}: {} applies to the grid's cells; this run's basis \"{}\" uses triangles, "
            "whose TLS keeps the plain stress fit, D's element integrals and no positivity "
            "scaling (leave it \"auto\")",
            cfg.where(key), key, basis));
    if (ts.adjoint_strain_rate)
      throw InputError(fmt::format(
          "{}: method.tls_strain_rate = \"adjoint\" is defined on the grid's cells; this "
          "run's basis \"{}\" uses triangles (choose \"gradient\")",
          cfg.where("method.tls_strain_rate"), basis));
    ts.positivity = false;
    ts.surface_volume = false;
    ts.domain_integrals = false;
    ts.max_condition = cfg.get_real("method.tls_triangle_max_condition");
    try {
      (void)tls_triangle_settings(ts);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}", cfg.where("method.tls_completion"), e.what()));
    }
  }
  return ts;
}

}  // namespace mpm
