#include "material/materials.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace mpm {

namespace {
// "a, b or c" (last_separator " or ") of `names`.
std::string join_names(const std::vector<std::string_view>& names, std::string_view last) {
  std::string out;
  for (std::size_t k = 0; k < names.size(); ++k)
    out += fmt::format("{}{}", k == 0 ? "" : k + 1 == names.size() ? last : ", ", names[k]);
  return out;
}

template <std::size_t... I>
std::string names_of_laws(int dim, bool incremental_only, std::index_sequence<I...>) {
  std::vector<std::string_view> names;
  ((std::variant_alternative_t<I, Material>::supports_dimension(dim) &&
            (!incremental_only || std::variant_alternative_t<I, Material>::kIncremental)
        ? names.push_back(std::variant_alternative_t<I, Material>::kName)
        : void()),
   ...);
  return join_names(names, " or ");
}

template <std::size_t... I>
std::vector<std::string_view> names_of_all_laws(std::index_sequence<I...>) {
  return {std::variant_alternative_t<I, Material>::kName...};
}
std::vector<std::string_view> names_of_all_laws() {
  return names_of_all_laws(std::make_index_sequence<std::variant_size_v<Material>>{});
}

// The law named `model` as the alternative I of Material or after, if it exists in `dim`.
template <std::size_t I = 0>
Material make_law(std::string_view model, const ElasticParameters& p, int dim,
                  const ParameterSource& source) {
  if constexpr (I < std::variant_size_v<Material>) {
    using Law = std::variant_alternative_t<I, Material>;
    if (model != Law::kName) return make_law<I + 1>(model, p, dim, source);
    if (!Law::supports_dimension(dim))
      throw InputError(
          fmt::format("material.model = \"{}\" does not exist in {}D; in {}D choose {}", model, dim,
                      dim, laws_in(dim)));
    if constexpr (Law::kParameters.empty()) {
      return Law{p};
    } else {
      ParametersOf<Law> values{};
      for (std::size_t k = 0; k < values.size(); ++k)
        values[k] = source ? source(Law::kParameters[k]) : Law::kParameters[k].default_value;
      return Law{p, values};
    }
  } else {
    throw InputError(fmt::format("unknown material.model \"{}\"", model));
  }
}

template <std::size_t... I>
std::span<const MaterialParameter> parameters_of_law(std::string_view model,
                                                     std::index_sequence<I...>) {
  std::span<const MaterialParameter> out;
  ((model == std::variant_alternative_t<I, Material>::kName
        ? void(out = std::variant_alternative_t<I, Material>::kParameters)
        : void()),
   ...);
  return out;
}

// Whether two declarations of a parameter say the same (shared ones are one object; this
// catches two laws that declare one name differently).
bool same_parameter(const MaterialParameter& a, const MaterialParameter& b) {
  const auto same_number = [](double x, double y) {
    return x == y || (std::isnan(x) && std::isnan(y));
  };
  return a.name == b.name && a.unit == b.unit && same_number(a.default_value, b.default_value) &&
         a.min == b.min && a.max == b.max && a.min_exclusive == b.min_exclusive &&
         a.max_exclusive == b.max_exclusive &&
         std::equal(a.choices.begin(), a.choices.end(), b.choices.begin(), b.choices.end()) &&
         a.description == b.description;
}
}  // namespace

Material make_material(std::string_view model, const ElasticParameters& p, int dim,
                       const ParameterSource& parameters) {
  return make_law(model, p, dim, parameters);
}

std::span<const MaterialParameter> parameters_of(std::string_view model) {
  return parameters_of_law(model, std::make_index_sequence<std::variant_size_v<Material>>{});
}

std::vector<MaterialParameter> all_material_parameters() {
  std::vector<MaterialParameter> out;
  for (const auto& entry : names_of_all_laws()) {
    for (const MaterialParameter& m : parameters_of(entry)) {
      const auto it = std::find_if(out.begin(), out.end(),
                                   [&](const MaterialParameter& o) { return o.name == m.name; });
      if (it == out.end())
        out.push_back(m);
      else if (!same_parameter(*it, m))
        throw std::logic_error(fmt::format(
            "material parameter \"{}\" is declared twice with different meanings", m.name));
    }
  }
  return out;
}

std::string laws_with_parameter(std::string_view name) {
  std::vector<std::string_view> laws;
  for (const auto& law : names_of_all_laws())
    for (const MaterialParameter& m : parameters_of(law))
      if (m.name == name) laws.push_back(law);
  return join_names(laws, " and ");
}

std::string laws_in(int dim, bool incremental_only) {
  return names_of_laws(dim, incremental_only,
                       std::make_index_sequence<std::variant_size_v<Material>>{});
}

}  // namespace mpm
