#include "material/materials.hpp"

#include <fmt/format.h>

#include <cstddef>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace mpm {

namespace {
template <std::size_t... I>
std::string names_of_laws(int dim, bool incremental_only, std::index_sequence<I...>) {
  std::vector<std::string_view> names;
  ((std::variant_alternative_t<I, Material>::supports_dimension(dim) &&
            (!incremental_only || std::variant_alternative_t<I, Material>::kIncremental)
        ? names.push_back(std::variant_alternative_t<I, Material>::kName)
        : void()),
   ...);
  std::string out;
  for (std::size_t k = 0; k < names.size(); ++k)
    out += fmt::format("{}{}", k == 0 ? "" : k + 1 == names.size() ? " or " : ", ", names[k]);
  return out;
}

// The law named `model` as the alternative I of Material or after, if it exists in `dim`.
template <std::size_t I = 0>
Material make_law(std::string_view model, const ElasticParameters& p, int dim) {
  if constexpr (I < std::variant_size_v<Material>) {
    using Law = std::variant_alternative_t<I, Material>;
    if (model != Law::kName) return make_law<I + 1>(model, p, dim);
    if (!Law::supports_dimension(dim))
      throw InputError(
          fmt::format("material.model = \"{}\" does not exist in {}D; in {}D choose {}", model, dim,
                      dim, laws_in(dim)));
    return Law{p};
  } else {
    throw InputError(fmt::format("unknown material.model \"{}\"", model));
  }
}
}  // namespace

Material make_material(std::string_view model, const ElasticParameters& p, int dim) {
  return make_law(model, p, dim);
}

std::string laws_in(int dim, bool incremental_only) {
  return names_of_laws(dim, incremental_only,
                       std::make_index_sequence<std::variant_size_v<Material>>{});
}

}  // namespace mpm
