#include "setup/material_settings.hpp"

#include <fmt/format.h>

namespace mpm {

Material material_from_config(const Config& cfg, int dim) {
  ElasticParameters p;
  p.density = cfg.get_real("material.density");
  p.youngs_modulus = cfg.get_real("material.youngs_modulus");
  p.poisson_ratio = cfg.get_real("material.poisson_ratio");
  try {
    return make_material(cfg.get_string("material.model"), p, dim);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", cfg.where("material.model"), e.what()));
  }
}

}  // namespace mpm
