// The material of a run from its [material] keys (setup/material_settings.hpp): the law and its
// parameters, and a law that does not exist in the problem's dimension refused with those that do
// (named from the laws themselves, not from a hand-written list).
#include <gtest/gtest.h>

#include <cmath>
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

// A law's own parameters (material/law.hpp, MaterialParameter) are keys material.<name>, read
// for the law that has them; given for another law, missing, or refused by the law as a whole,
// they stop the set-up naming the key and where it was given.
TEST(MaterialSettings, ALawReadsItsOwnParametersAndRefusesOthers) {
  const auto with = [](const std::string& model, const std::string& extra) {
    return Config::parse(
        "benchmark = \"custom\"\n[time]\ndt = 1e-3\nend = 1e-3\n[material]\nmodel = \"" + model +
            "\"\ndensity = 2000\nyoungs_modulus = 20e6\npoisson_ratio = 0.3\n" + extra,
        "soil.toml");
  };
  const Material mc = material_from_config(
      with("mohr_coulomb", "cohesion = 5e3\nfriction_angle = 30\ndilatancy_angle = 10\n"), 2);
  ASSERT_TRUE(std::holds_alternative<MohrCoulomb>(mc));
  EXPECT_EQ(std::get<MohrCoulomb>(mc).strength.c, 5e3);
  EXPECT_NEAR(std::get<MohrCoulomb>(mc).strength.phi, 30.0 * 3.14159265358979 / 180.0, 1e-12);
  const Material dp = material_from_config(
      with("drucker_prager", "cohesion = 5e3\nfriction_angle = 30\ndp_match = \"extension\"\n"), 3);
  // The extension cone: eta = 6 sin(phi) / (sqrt(3) (3 + sin phi)).
  EXPECT_NEAR(std::get<DruckerPrager>(dp).eta, 6 * 0.5 / (std::sqrt(3.0) * 3.5), 1e-12);
  EXPECT_EQ(std::get<VonMises>(material_from_config(with("von_mises", "yield_stress = 1e5\n"), 3))
                .hardening,
            0.0);
  const auto refused = [&](const std::string& model, const std::string& extra, int dim) {
    try {
      (void)material_from_config(with(model, extra), dim);
      ADD_FAILURE() << model << " accepted " << extra;
      return std::string();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
  };
  EXPECT_EQ(refused("linear_elastic", "cohesion = 5e3\n", 2),
            "soil.toml:10:12: material.cohesion is a parameter of drucker_prager and "
            "mohr_coulomb, not of material.model = \"linear_elastic\" (which has none beyond "
            "density, youngs_modulus and poisson_ratio)");
  EXPECT_NE(refused("von_mises", "yield_stress = 1e5\nfriction_angle = 20\n", 2)
                .find("whose parameters are material.yield_stress, material.hardening"),
            std::string::npos);
  EXPECT_NE(
      refused("mohr_coulomb", "friction_angle = 30\n", 2).find("required key 'material.cohesion'"),
      std::string::npos);
  EXPECT_EQ(refused("mohr_coulomb", "cohesion = 1\nfriction_angle = 20\ndilatancy_angle = 25\n", 3),
            "soil.toml:12:19: material.dilatancy_angle = 25 exceeds material.friction_angle = 20 "
            "(choose psi <= phi; psi = phi is associated flow)");
  EXPECT_NE(refused("mohr_coulomb", "cohesion = 1\nfriction_angle = 90\n", 3).find("soil.toml:11:"),
            std::string::npos);
  EXPECT_NE(refused("von_mises", "yield_stress = 1e5\n", 1).find("does not exist in 1D"),
            std::string::npos);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
