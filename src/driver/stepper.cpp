#include "driver/stepper.hpp"

#include <fmt/format.h>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "mpm/stepper_units.hpp"

namespace mpm::driver {

// The generated units (CMakeLists.txt, MPM_BASIS_KIND_UNITS) instantiate make_stepper_for<Dim, I>
// for the kinds by unit name; the list names every alternative of BasisKind once, in its order,
// and gives each the dimensions of its supports_dimension.
static_assert(std::variant_size_v<BasisKind> == MPM_BASIS_KINDS,
              "CMakeLists.txt, MPM_BASIS_KIND_UNITS: one entry per BasisKind alternative");
template <std::size_t... I>
constexpr bool kinds_match_units(std::index_sequence<I...>) {
  return (
      (basis_kind_index(kStepperUnitNames[I]) == I &&
       kStepperKinds[0][I] == supports_dimension<std::variant_alternative_t<I, BasisKind>>(1) &&
       kStepperKinds[1][I] == supports_dimension<std::variant_alternative_t<I, BasisKind>>(2) &&
       kStepperKinds[2][I] == supports_dimension<std::variant_alternative_t<I, BasisKind>>(3)) &&
      ...);
}
static_assert(kinds_match_units(std::make_index_sequence<std::variant_size_v<BasisKind>>{}),
              "CMakeLists.txt, MPM_BASIS_KIND_UNITS: the kinds by unit name in the order of "
              "BasisKind (methods/kinds.hpp), each with the dimensions of its "
              "supports_dimension");

bool stepper_compiled(int dim, std::size_t kind) {
  return dim >= 1 && dim <= 3 && kind < std::variant_size_v<BasisKind> &&
         kStepperUnits[dim - 1][kind];
}

template <int Dim, std::size_t I>
std::unique_ptr<Stepper<Dim>> stepper_of_kind(const StepperInput<Dim>& in) {
  using Kind = std::variant_alternative_t<I, BasisKind>;
  if constexpr (!supports_dimension<Kind>(Dim))
    throw std::logic_error("make_stepper: basis not available in this dimension");
  else if constexpr (!kStepperUnits[Dim - 1][I])
    throw InputError(fmt::format(
        "method.basis = \"{}\"{} in {}D is not compiled into this build of mpm: it was "
        "configured with CMake option MPM_STEPPERS_{}D leaving out \"{}\" "
        "(scripts/sanitize.sh compiles only the units its tests run); build with the default "
        "options (scripts/build.sh) to run it",
        Kind::kName, Kind::kDegree > 0 ? fmt::format(" (degree {})", Kind::kDegree) : "", Dim, Dim,
        kStepperUnitNames[I]));
  else
    return make_stepper_for<Dim, I>(in);
}

template <int Dim>
std::unique_ptr<Stepper<Dim>> make_stepper(const BasisKind& basis, const StepperInput<Dim>& in) {
  return [&]<std::size_t... I>(std::index_sequence<I...>) {
    std::unique_ptr<Stepper<Dim>> s;
    (void)((basis.index() == I ? (s = stepper_of_kind<Dim, I>(in), true) : false) || ...);
    return s;
  }
  (std::make_index_sequence<std::variant_size_v<BasisKind>>{});
}

template std::unique_ptr<Stepper<1>> make_stepper<1>(const BasisKind&, const StepperInput<1>&);
template std::unique_ptr<Stepper<2>> make_stepper<2>(const BasisKind&, const StepperInput<2>&);
template std::unique_ptr<Stepper<3>> make_stepper<3>(const BasisKind&, const StepperInput<3>&);

void report_mapping(nlohmann::ordered_json& summary, const TlsMapping& m, int) {
  const auto& t = m.totals();
  summary["tls"] = {{"element_fits", t.active},
                    {"full", t.full},
                    {"reduced", t.reduced},
                    {"with_virtual", t.with_virtual},
                    {"with_neighbours", t.with_neighbours},
                    {"min_terms", t.min_terms},
                    {"max_condition", t.max_condition}};
  // The robustness measures of the grid's cells, where switched on (element-steps).
  if (m.settings().positivity) summary["tls"]["positivity_limited"] = t.limited;
  if (m.settings().surface_volume) summary["tls"]["surface_elements"] = t.surface;
  // Particle-steps without a positive weight in the fits, whose rate was the gradient at x_p.
  if (m.settings().adjoint_strain_rate) summary["tls"]["adjoint_unweighted"] = t.unweighted;
  if (m.on_triangles()) {
    // Triangles (D 6.3): the completion resolved, the fits with dropped directions, and the
    // smallest rank (min_terms) of an element's fit.
    auto& j = summary["tls"];
    j.erase("with_virtual");
    j.erase("with_neighbours");
    j["truncated"] = t.truncated;
    j["completion"] = tls_completion_name(m.settings().completion);
  }
}

void report_mapping(nlohmann::ordered_json& summary, const MlsFamilyMapping& m, int dim) {
  const auto& t = m.totals();
  summary["mls"] = {{"degree", m.settings().degree},
                    {"dilation", m.settings().dilation},
                    {"evaluations", t.points},
                    {"empty_support", t.empty},
                    {"ill_conditioned", t.ill_conditioned},
                    {"singular", t.singular},
                    {"reduced", t.reduced},
                    {"widened", t.widened},
                    {"max_condition", t.max_condition},
                    {"worst_x", t.worst_x}};
  if (dim >= 2) summary["mls"]["worst_y"] = t.worst_y;
  if (dim == 3) summary["mls"]["worst_z"] = t.worst_z;
}

}  // namespace mpm::driver
