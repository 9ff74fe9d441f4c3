#pragma once
// The material of a run from its [material] keys, read once here for every problem: the law
// named by material.model (material/materials.hpp) with its parameters.
#include "material/materials.hpp"
#include "setup/config.hpp"

namespace mpm {

// The law of material.model with material.density, youngs_modulus and poisson_ratio and its own
// parameters material.<name> (MaterialParameter), for a problem in `dim` dimensions. InputError
// naming material.model when the law does not exist there (the message names those that do),
// naming the parameter the law refuses, or naming a parameter given that belongs to another law.
Material material_from_config(const Config& cfg, int dim);

}  // namespace mpm
