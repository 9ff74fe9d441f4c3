// The constitutive laws (material/) and the material state the particles carry
// (particles/material_state.hpp): every law declares distinct state names that no output column
// takes, the registry of laws answers by trait (dimensions, incremental), and a state of several
// variables per particle travels with its particle through every operation of the one field
// list: sorting, keeping, truncating, packing between processes, checkpoints and outputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "material/materials.hpp"
#include "particles/particles.hpp"
#include "state/sort.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// Two internal variables of a law that the test stands in for.
constexpr std::array<std::string_view, 2> kNames = {"alpha", "beta"};

// Particles 0..n-1 with state row (10 i, 10 i + 1) and x = i.
Particles<2> numbered(int n) {
  Particles<2> P;
  P.resize(n);
  P.state.set_names(kNames);
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    P.x[k] = Vec<2>(i, 0.0);
    P.state[k][0] = 10.0 * i;
    P.state[k][1] = 10.0 * i + 1.0;
  }
  return P;
}

// Each particle's state is still the one of its id.
void expect_rows_follow_ids(const Particles<2>& P) {
  ASSERT_EQ(P.state.size(), P.id.size());
  ASSERT_EQ(P.state.width(), 2u);
  for (std::size_t i = 0; i < P.id.size(); ++i) {
    const double id = static_cast<double>(P.id[i]);
    EXPECT_EQ(P.state[i][0], 10.0 * id) << "particle " << P.id[i];
    EXPECT_EQ(P.state[i][1], 10.0 * id + 1.0) << "particle " << P.id[i];
    EXPECT_EQ(P.x[i][0], id);
  }
}

template <class... Laws>
std::vector<std::vector<std::string_view>> state_names_of(std::variant<Laws...>*) {
  return {std::vector<std::string_view>(Laws::kStateNames.begin(), Laws::kStateNames.end())...};
}

TEST(Materials, StateNamesAreDistinctAndNoOutputColumn) {
  // The columns of a 3D CSV frame and the arrays of a VTU frame: no law may name a variable so.
  Particles<3> none;
  std::string header = io::particles_csv(none);
  header.pop_back();
  std::set<std::string> taken;
  std::stringstream in(header);
  for (std::string c; std::getline(in, c, ',');) taken.insert(c);
  for (const char* own : {"id", "x0", "u", "v", "mass", "volume", "density", "F", "stress"})
    taken.insert(own);
  for (const auto& names : state_names_of(static_cast<Material*>(nullptr))) {
    std::set<std::string> seen;
    for (const auto name : names) {
      EXPECT_FALSE(name.empty());
      EXPECT_TRUE(seen.insert(std::string(name)).second) << name << " twice";
      EXPECT_EQ(taken.count(std::string(name)), 0u) << name << " is an output column";
    }
  }
}

TEST(Materials, ListsAnswerByTrait) {
  EXPECT_EQ(laws_in(1, /*incremental_only=*/true), "elastic_1d_small or elastic_1d_large");
  EXPECT_EQ(laws_in(2, /*incremental_only=*/true), "von_mises, drucker_prager or mohr_coulomb");
  EXPECT_NE(laws_in(3).find("neo_hookean"), std::string::npos);
  EXPECT_EQ(laws_in(3).find("elastic_1d"), std::string::npos);
  EXPECT_TRUE(incremental(make_material("elastic_1d_large", {}, 1)));
  EXPECT_FALSE(incremental(make_material("neo_hookean", {}, 2)));
  EXPECT_TRUE(state_names(make_material("linear_elastic", {}, 3)).empty());
  try {
    (void)make_material("elastic_1d_small", {}, 2);
    FAIL() << "a 1D law in 2D was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("in 2D choose"), std::string::npos) << e.what();
  }
}

TEST(MaterialState, FreshParticlesStartAtZeroAndGrowWithTheBody) {
  Particles<2> P;
  P.resize(3);
  P.state.set_names(kNames);
  ASSERT_EQ(P.state.values().size(), 6u);
  EXPECT_TRUE(std::all_of(P.state.values().begin(), P.state.values().end(),
                          [](double v) { return v == 0.0; }));
  P.append(Vec<2>(1.0, 2.0), 0.5, 1.0, 3);
  ASSERT_EQ(P.state.size(), 4u);
  EXPECT_EQ(P.state[3][1], 0.0);
  // Naming again with the same width keeps the values (a RunState built from set-up particles).
  P.state[2][0] = 7.0;
  P.state.set_names(kNames);
  EXPECT_EQ(P.state[2][0], 7.0);
  EXPECT_EQ(P.record_bytes(), Particles<2>::bytes_per_particle(0) + 2 * sizeof(double));
}

TEST(MaterialState, FollowsItsParticleThroughTheFieldList) {
  // Sorting (a permutation).
  Particles<2> P = numbered(7);
  Permutation perm;
  perm.order = {6, 2, 0, 5, 1, 3, 4};
  P.for_each_field([&](auto& field) { perm.apply(field); });
  expect_rows_follow_ids(P);
  EXPECT_EQ(P.id[0], 6);
  // Back in id order.
  expect_rows_follow_ids(particles_in_id_order(P));
  EXPECT_TRUE(particles_in_id_order(P).in_id_order());
  // Keeping some (a process's own particles), then dropping the last (ghosts).
  P.keep_with_ids([](const Particles<2>& Q, std::size_t i) { return Q.id[i] % 2 == 0; });
  ASSERT_EQ(P.size(), 4);
  expect_rows_follow_ids(P);
  P.truncate(3);
  expect_rows_follow_ids(P);
  // Room for migrations keeps the values.
  P.keep_room(5);
  EXPECT_GE(P.state.capacity(), 8u);
  expect_rows_follow_ids(P);
  // Between processes: packed rows appended to particles of the same state.
  std::vector<std::byte> buf;
  P.pack(2, buf);
  P.pack(0, buf);
  EXPECT_EQ(buf.size(), 2 * P.record_bytes());
  Particles<2> Q = P.empty_like();
  EXPECT_EQ(Q.unpack_append(buf), buf.size());
  ASSERT_EQ(Q.size(), 2);
  EXPECT_EQ(Q.id[0], P.id[2]);
  expect_rows_follow_ids(Q);
}

TEST(MaterialState, CheckpointsCarryItAndTheMaterialNamesIt) {
  const Particles<2> P = numbered(5);
  const auto a = io::pack_particles(P);
  const auto names = io::particle_field_names();
  const auto k =
      static_cast<std::size_t>(std::find(names.begin(), names.end(), "state") - names.begin());
  ASSERT_LT(k, names.size());
  EXPECT_EQ(a.reals[k], P.state.values());
  Particles<2> R = io::unpack_particles<2>(a, "test");
  R.state.set_names(kNames);
  expect_rows_follow_ids(R);
  // A material of another width refuses the stored rows.
  Particles<2> S = io::unpack_particles<2>(a, "test");
  constexpr std::array<std::string_view, 3> three = {"a", "b", "c"};
  EXPECT_THROW(S.state.set_names(three), std::invalid_argument);
  // Values that are no whole rows are refused as they are read.
  auto bad = a;
  bad.reals[k].pop_back();
  EXPECT_THROW((void)io::unpack_particles<2>(bad, "test"), InputError);
}

TEST(MaterialState, OutputsNameEachVariable) {
  const Particles<2> P = numbered(3);
  const std::string csv = io::particles_csv(P);
  const std::string head = csv.substr(0, csv.find('\n'));
  EXPECT_NE(head.find(",stress_22,alpha,beta"), std::string::npos) << head;
  EXPECT_NE(csv.find(",10,11\n"), std::string::npos) << csv;  // particle 1's row ends so
  const std::string vtu = io::particles_vtu(P, 0.0);
  EXPECT_NE(vtu.find("Name=\"alpha\""), std::string::npos);
  EXPECT_NE(vtu.find("Name=\"beta\""), std::string::npos);
  // An extra field may not take a variable's name.
  std::vector<double> values(3, 0.0);
  EXPECT_THROW((void)io::particles_csv(P, {{"beta", &values}}), std::invalid_argument);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
