// The materials of a run (material/material_set.hpp): every pair of laws shares the particles'
// rows (a law's names in one block; laws that declare the same names share it), and each
// particle is visited once, with its own material's law and block.
#include <gtest/gtest.h>

#include <cstddef>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "material/material_set.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

template <std::size_t... I>
std::vector<Material> every_law(std::index_sequence<I...>) {
  return {Material(std::variant_alternative_t<I, Material>{})...};
}
std::vector<Material> every_law() {
  return every_law(std::make_index_sequence<std::variant_size_v<Material>>{});
}

TEST(MaterialSet, EveryPairOfLawsSharesTheRowsInBlocks) {
  for (const Material& a : every_law()) {
    for (const Material& b : every_law()) {
      SCOPED_TRACE(std::string(material_name(a)) + " and " + std::string(material_name(b)));
      Materials m(a);
      ASSERT_NO_THROW(m.add("b", b));
      const auto columns = m.state_names();
      for (std::size_t k = 0; k < 2; ++k) {
        const auto own = state_names(m[k]);
        // The law's names stand in order from its offset.
        ASSERT_LE(m.state_offset(k) + own.size(), columns.size());
        for (std::size_t c = 0; c < own.size(); ++c)
          EXPECT_EQ(columns[m.state_offset(k) + c], own[c]);
      }
      // No name twice: laws that share names share their block.
      for (std::size_t c = 0; c < columns.size(); ++c)
        for (std::size_t d = c + 1; d < columns.size(); ++d) EXPECT_NE(columns[c], columns[d]);
    }
  }
}

TEST(MaterialSet, EachParticleIsVisitedOnceWithItsLaw) {
  Materials m(LinearElastic{ElasticParameters{1000.0, 1e6, 0.3}});
  m.add("soil", MohrCoulomb{});
  m.add("tracked", TrackedElastic{});
  m.add("clay", VonMises{});
  EXPECT_EQ(m.size(), 4u);
  EXPECT_EQ(m.find("clay"), 3u);
  EXPECT_EQ(m.find("sand"), 4u);
  EXPECT_EQ(m.state_offset(1), 0u);  // the plastic block first
  EXPECT_EQ(m.state_offset(2), 3u);  // then the tracked law's
  EXPECT_EQ(m.state_offset(3), 0u);  // von Mises shares the plastic block
  EXPECT_EQ(m.law_names(), "linear_elastic, mohr_coulomb, tracked_elastic and von_mises");
  EXPECT_THROW(m.single(), std::logic_error);
  EXPECT_THROW(m.add("clay", LinearElastic{}), std::logic_error);
  const std::vector<MaterialIndex> of = {3, 0, 2, 2, 1, 0, 3};
  std::vector<int> visits(of.size(), 0);
  m.for_each_particle(of, 1, of.size(),
                      [&](const auto& law, std::size_t k, std::size_t offset, std::size_t i) {
                        EXPECT_EQ(k, of[i]);
                        EXPECT_EQ(offset, m.state_offset(k));
                        EXPECT_EQ(law.kName, material_name(m[k]));
                        ++visits[i];
                      });
  EXPECT_EQ(visits, (std::vector<int>{0, 1, 1, 1, 1, 1, 1}));
  // One material: every particle is its own, whatever the index says.
  const Materials one(NeoHookean{});
  std::vector<int> seen(of.size(), 0);
  one.for_each_particle(of, 0, of.size(),
                        [&](const auto&, std::size_t, std::size_t, std::size_t i) { ++seen[i]; });
  EXPECT_EQ(seen, std::vector<int>(of.size(), 1));
  EXPECT_EQ(&one.single(), &one[0]);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
