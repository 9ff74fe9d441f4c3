// The material of a run from its [material] keys (setup/material_settings.hpp): the law and its
// parameters, and a law that does not exist in the problem's dimension refused with those that do
// (named from the laws themselves, not from a hand-written list).
#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "setup/config.hpp"
#include "setup/material_settings.hpp"
#include "setup/registry.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

Config material(const std::string& model) {
  return Config::parse(
      "benchmark = \"custom\"\n[grid]\ncells = 4\n[time]\ndt = 1e-3\nend = 1e-3\n"
      "[material]\nmodel = \"" +
          model + "\"\ndensity = 1200\nyoungs_modulus = 3e6\npoisson_ratio = 0.25\n",
      "material.toml");
}

TEST(MaterialSettings, TheLawAndItsParametersFromTheKeys) {
  const Material m = material_from_config(material("neo_hookean"), 2);
  ASSERT_TRUE(std::holds_alternative<NeoHookean>(m));
  EXPECT_EQ(std::get<NeoHookean>(m).p.density, 1200.0);
  EXPECT_EQ(std::get<NeoHookean>(m).p.youngs_modulus, 3e6);
  EXPECT_EQ(std::get<NeoHookean>(m).p.poisson_ratio, 0.25);
  // Every law is a choice of material.model, with its own description.
  EXPECT_EQ(std::size(registry::kMaterials), std::variant_size_v<Material>);
  EXPECT_EQ(registry::kMaterials[3].name, NeoHookean::kName);
  EXPECT_EQ(registry::kMaterials[3].description, NeoHookean::kDescription);
}

TEST(MaterialSettings, ALawOfAnotherDimensionIsRefusedWithThoseThatExist) {
  try {
    material_from_config(material("elastic_1d_small"), 3);
    ADD_FAILURE() << "a 1D law was accepted in 3D";
  } catch (const InputError& e) {
    // The choices are the laws that declare 3D (laws_in), whichever they are.
    EXPECT_EQ(std::string(e.what()),
              "material.toml:8:9: material.model = \"elastic_1d_small\" does not exist in 3D; "
              "in 3D choose " +
                  laws_in(3));
    EXPECT_EQ(laws_in(3).find("elastic_1d"), std::string::npos);
    EXPECT_NE(laws_in(3).find("linear_elastic, neo_hookean"), std::string::npos);
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
