#include "setup/material_settings.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

namespace mpm {

Material material_from_config(const Config& cfg, int dim, const std::string& table) {
  ElasticParameters p;
  p.density = cfg.get_real(table + ".density");
  p.youngs_modulus = cfg.get_real(table + ".youngs_modulus");
  p.poisson_ratio = cfg.get_real(table + ".poisson_ratio");
  const std::string model = cfg.get_string(table + ".model");
  // A parameter given for another law than the chosen one is a mistake to report, not to ignore.
  const auto own = parameters_of(model);
  for (const MaterialParameter& m : all_material_parameters()) {
    const std::string key = fmt::format("{}.{}", table, m.name);
    const bool mine = std::any_of(own.begin(), own.end(),
                                  [&](const MaterialParameter& o) { return o.name == m.name; });
    if (!mine && !cfg.at_default(key)) {
      std::string those;
      for (const MaterialParameter& o : own)
        those += fmt::format("{}{}.{}", those.empty() ? "" : ", ", table, o.name);
      throw InputError(fmt::format(
          "{}: {} is a parameter of {}, not of {}.model = \"{}\" ({})", cfg.where(key), key,
          laws_with_parameter(m.name), table, model,
          those.empty() ? "which has none beyond density, youngs_modulus and poisson_ratio"
                        : "whose parameters are " + those));
    }
  }
  const auto source = [&](const MaterialParameter& m) -> double {
    const std::string key = fmt::format("{}.{}", table, m.name);
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
        fmt::format("{}: {}", cfg.where(fmt::format("{}.{}", table, e.parameter())), e.what()));
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", cfg.where(table + ".model"), e.what()));
  }
}

Materials materials_from_config(const Config& cfg, int dim) {
  Materials out(material_from_config(cfg, dim));
  const std::vector<std::string> named = cfg.instances("material");
  if (named.size() + 1 > Materials::kMaxMaterials)
    throw InputError(fmt::format("{}: {} materials; a run holds at most {}",
                                 cfg.instance_where("material", named.back()), named.size() + 1,
                                 Materials::kMaxMaterials));
  for (const std::string& name : named)
    out.add(name, material_from_config(cfg, dim, "material." + name));
  return out;
}

std::size_t material_index(const Config& cfg, const Materials& materials, const std::string& key,
                           const std::string& value) {
  const std::string name = value.empty() ? cfg.get_string(key) : value;
  const std::size_t k = materials.find(name);
  if (k < materials.size()) return k;
  std::string known;
  for (std::size_t j = 0; j < materials.size(); ++j)
    known += fmt::format("{}\"{}\"", j == 0 ? "" : ", ", materials.name(j));
  throw InputError(fmt::format(
      "{}: {} names the material \"{}\", which is not given; the materials are {} (\"material\" "
      "is the [material] table, the others [material.NAME] tables)",
      cfg.where(key), key, name, known));
}

}  // namespace mpm
