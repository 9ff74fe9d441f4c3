#include "setup/material_settings.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string>

namespace mpm {

Material material_from_config(const Config& cfg, int dim) {
  ElasticParameters p;
  p.density = cfg.get_real("material.density");
  p.youngs_modulus = cfg.get_real("material.youngs_modulus");
  p.poisson_ratio = cfg.get_real("material.poisson_ratio");
  const std::string model = cfg.get_string("material.model");
  // A parameter given for another law than the chosen one is a mistake to report, not to ignore.
  const auto own = parameters_of(model);
  for (const MaterialParameter& m : all_material_parameters()) {
    const std::string key = fmt::format("material.{}", m.name);
    const bool mine = std::any_of(own.begin(), own.end(),
                                  [&](const MaterialParameter& o) { return o.name == m.name; });
    if (!mine && !cfg.at_default(key)) {
      std::string those;
      for (const MaterialParameter& o : own)
        those += fmt::format("{}material.{}", those.empty() ? "" : ", ", o.name);
      throw InputError(fmt::format(
          "{}: {} is a parameter of {}, not of material.model = \"{}\" ({})", cfg.where(key), key,
          laws_with_parameter(m.name), model,
          those.empty() ? "which has none beyond density, youngs_modulus and poisson_ratio"
                        : "whose parameters are " + those));
    }
  }
  const auto source = [&](const MaterialParameter& m) -> double {
    const std::string key = fmt::format("material.{}", m.name);
    if (m.choices.empty()) return cfg.get_real(key);
    const std::string value = cfg.get_string(key);  // the schema holds it to the choices
    return static_cast<double>(std::find(m.choices.begin(), m.choices.end(), value) -
                               m.choices.begin());
  };
  for (const MaterialParameter& m : own) (void)source(m);  // a missing required key: its message
  try {
    return make_material(model, p, dim, source);
  } catch (const InvalidParameter& e) {
    throw InputError(
        fmt::format("{}: {}", cfg.where(fmt::format("material.{}", e.parameter())), e.what()));
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", cfg.where("material.model"), e.what()));
  }
}

}  // namespace mpm
