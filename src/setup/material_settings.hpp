#pragma once
// The material of a run from its [material] keys, read once here for every problem: the law
// named by material.model (material/materials.hpp) with its parameters.
#include <cstddef>
#include <string>

#include "material/material_set.hpp"
#include "material/materials.hpp"
#include "setup/config.hpp"

namespace mpm {

// The law of material.model with material.density, youngs_modulus and poisson_ratio and its own
// parameters material.<name> (MaterialParameter), for a problem in `dim` dimensions. InputError
// naming material.model when the law does not exist there (the message names those that do),
// naming the parameter the law refuses, or naming a parameter given that belongs to another law.
// `table`: the material's table, "material" or a named one "material.NAME" (its keys
// TABLE.density, ...).
Material material_from_config(const Config& cfg, int dim, const std::string& table = "material");

// Every material of the configuration: [material] (index 0, named "material"), then each
// [material.NAME] in alphabetical order (Config::instances), each as material_from_config.
Materials materials_from_config(const Config& cfg, int dim);
// The index in `materials` of the material named by the value of the String key `key`
// ("material" or a NAME of [material.NAME]); InputError naming the key and the materials there
// are otherwise. `value` (not empty): the name as found inside the key's value (a list).
std::size_t material_index(const Config& cfg, const Materials& materials, const std::string& key,
                           const std::string& value = "");

}  // namespace mpm
