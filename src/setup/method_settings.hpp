#pragma once
// The settings of the method components from the configuration (set-up layer): the numerics
// take typed settings (TlsSettings, MlsSettings, CubicSplineSettings) and never see Config.
#include <fmt/format.h>
#include <string_view>
#include <type_traits>

#include "mapping/cubic_spline.hpp"
#include "mapping/mls.hpp"
#include "mapping/tls.hpp"
#include "setup/config.hpp"

namespace mpm {

// method.tls_terms, method.tls_completion, method.tls_max_condition, method.gauss_points,
// validated for `dim` (InputError).
TlsSettings tls_settings(const Config& cfg, int dim);
// TLS's settings for the run's basis (`basis`, its name): the grid's cells and triangles
// (`triangles`) take different completions, condition limits (method.tls_max_condition,
// method.tls_triangle_max_condition) and robustness measures; a key that does not apply to the
// basis is refused (InputError naming it and its line). All of TLS's keys are read here.
TlsSettings tls_settings_for_basis(const Config& cfg, const TlsSettings& chosen, bool triangles,
                                   std::string_view basis);
// method.mls_degree, method.gauss_points, method.mls_dilation; IMLS (improved) also needs
// method.mass = lumped (003 eq. 32).
MlsSettings mls_settings(const Config& cfg, bool improved);
// method.gauss_points (Gauss points per half element, 0: D's 2).
CubicSplineSettings cubic_spline_settings(const Config& cfg);

// The mapping with its settings from the configuration, validated for the problem's dimension;
// errors name method.mapping.
template <int Dim, class Mapping>
Mapping make_mapping(const Config& cfg) {
  try {
    if constexpr (std::is_same_v<Mapping, TlsMapping>)
      return TlsMapping(tls_settings(cfg, Dim), Dim);
    else if constexpr (std::is_same_v<Mapping, MlsMapping>)
      return MlsMapping(mls_settings(cfg, false));
    else if constexpr (std::is_same_v<Mapping, ImlsMapping>)
      return ImlsMapping(mls_settings(cfg, true));
    else if constexpr (std::is_same_v<Mapping, CubicSplineMapping>)
      return CubicSplineMapping(cubic_spline_settings(cfg));
    else
      return Mapping{};
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", cfg.where("method.mapping"), e.what()));
  }
}

}  // namespace mpm
