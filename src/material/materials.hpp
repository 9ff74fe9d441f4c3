#pragma once
// The constitutive laws a run can choose (material.model). Each law is a small value type with
// an inline per-particle update in its own header (the ConstitutiveLaw concept, material/law.hpp,
// says what it declares); the stress stage visits the material variant once and then loops over
// particles (no virtual calls in the loop). Stress is the Cauchy stress [Pa]; F the deformation
// gradient. A new law: its header, and its type in the list below.
#include <cmath>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <variant>
#include <vector>

#include "material/drucker_prager.hpp"
#include "material/elastic_1d.hpp"
#include "material/law.hpp"
#include "material/linear_elastic.hpp"
#include "material/mohr_coulomb.hpp"
#include "material/neo_hookean.hpp"
#include "material/tracked_elastic.hpp"
#include "material/von_mises.hpp"

namespace mpm {

using Material = std::variant<Elastic1DSmall, Elastic1DLarge, LinearElastic, NeoHookean,
                              TrackedElastic, VonMises, DruckerPrager, MohrCoulomb>;

// Every law of the list satisfies the concept in each dimension it supports (a law that does
// not declare what is asked of it does not compile).
template <class Law>
constexpr bool law_is_complete() {
  return (!Law::supports_dimension(1) || ConstitutiveLaw<Law, 1>)&&(
      !Law::supports_dimension(2) || ConstitutiveLaw<Law, 2>)&&(!Law::supports_dimension(3) ||
                                                                ConstitutiveLaw<Law, 3>);
}
template <class... Laws>
constexpr bool laws_are_complete(std::variant<Laws...>*) {
  return (law_is_complete<Laws>() && ...);
}
static_assert(laws_are_complete(static_cast<Material*>(nullptr)));

// The value of a law's parameter (MaterialParameter; a choice as its index), from configuration.
using ParameterSource = std::function<double(const MaterialParameter&)>;
// Build the material named by `model` (a law's kName; registry::kMaterials lists them), its
// parameters beyond the elastic ones from `parameters` (without a source: their defaults).
// Throws InputError when the law does not exist in dimension `dim`, naming those that do, and
// InvalidParameter when the law refuses its parameters.
Material make_material(std::string_view model, const ElasticParameters& p, int dim,
                       const ParameterSource& parameters = {});
// The parameters of the law named `model` (empty for an unknown name).
std::span<const MaterialParameter> parameters_of(std::string_view model);
// Every parameter of every law, each once (laws share one declaration; a name declared twice
// differently is a logic_error).
std::vector<MaterialParameter> all_material_parameters();
// The names of the laws that declare the parameter `name`, as "a and b".
std::string laws_with_parameter(std::string_view name);
// The names of the laws that exist in `dim` (those with kIncremental alone when
// `incremental_only`), as "a, b or c"; empty when there is none.
std::string laws_in(int dim, bool incremental_only = false);

inline double wave_speed(const Material& m) {
  return std::visit([](const auto& law) { return law.wave_speed(); }, m);
}
inline std::string_view material_name(const Material& m) {
  return std::visit([](const auto& law) { return law.kName; }, m);
}
// The names of the material's internal variables per particle (Particles::state's columns).
inline std::span<const std::string_view> state_names(const Material& m) {
  return std::visit(
      [](const auto& law) { return std::span<const std::string_view>(law.kStateNames); }, m);
}
// A particle whose last stress update failed (the law's update returned false: the plastic
// laws' return mapping found no admissible stress, and left the trial stress): the law's
// residual there, the yield function at that stress [Pa]; nullopt for a particle whose update
// succeeded, and for every particle of a law that cannot fail.
template <int Dim>
std::optional<double> failed_update(const Material& m, const Mat<Dim>& sigma,
                                    std::span<const double> state, const Mat<Dim>& F) {
  return std::visit(
      [&](const auto& law) -> std::optional<double> {
        using Law = std::decay_t<decltype(law)>;
        constexpr std::size_t n = std::tuple_size_v<decltype(Law::kStateNames)>;
        if constexpr (requires {
                        law.failed_return(sigma, std::span<const double, n>(state.data(), n), F);
                      }) {
          const double r = law.failed_return(sigma, std::span<const double, n>(state.data(), n), F);
          if (!std::isnan(r)) return r;
        }
        return std::nullopt;
      },
      m);
}
// Whether the law advances the stress from the previous one (an initial stress is meaningful).
inline bool incremental(const Material& m) {
  return std::visit([](const auto& law) { return law.kIncremental; }, m);
}

}  // namespace mpm
