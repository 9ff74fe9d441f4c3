#include "material/materials.hpp"

#include <fmt/format.h>

namespace mpm {

Material make_material(std::string_view model, const ElasticParameters& p, int dim) {
  if (model == Elastic1DSmall::kName || model == Elastic1DLarge::kName) {
    if (dim != 1)
      throw InputError(fmt::format(
          "material.model = \"{}\" is a one-dimensional law; in {}D choose linear_elastic or "
          "neo_hookean",
          model, dim));
    if (model == Elastic1DSmall::kName) return Elastic1DSmall{p};
    return Elastic1DLarge{p};
  }
  if (model == LinearElastic::kName) return LinearElastic{p};
  if (model == NeoHookean::kName) return NeoHookean{p};
  throw InputError(fmt::format("unknown material.model \"{}\"", model));
}

}  // namespace mpm
