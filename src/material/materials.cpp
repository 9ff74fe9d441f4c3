#include "material/materials.hpp"

#include <fmt/format.h>

#include <cstddef>
#include <variant>

namespace mpm {

namespace {
// The law named `model` as the alternative I of Material or after, if it exists in `dim`.
template <std::size_t I = 0>
Material make_law(std::string_view model, const ElasticParameters& p, int dim) {
  if constexpr (I < std::variant_size_v<Material>) {
    using Law = std::variant_alternative_t<I, Material>;
    if (model != Law::kName) return make_law<I + 1>(model, p, dim);
    if (!Law::supports_dimension(dim))
      throw InputError(fmt::format(
          "material.model = \"{}\" is a one-dimensional law; in {}D choose linear_elastic or "
          "neo_hookean",
          model, dim));
    return Law{p};
  } else {
    throw InputError(fmt::format("unknown material.model \"{}\"", model));
  }
}
}  // namespace

Material make_material(std::string_view model, const ElasticParameters& p, int dim) {
  return make_law(model, p, dim);
}

}  // namespace mpm
