// A material with internal variables through whole runs (material/tracked_elastic.hpp): its
// stress is linear_elastic's bit for bit, its state counts one update per particle and step and
// adds up the strain path in closed form, and the state follows each particle through a run
// started shuffled and re-sorted, a checkpoint and a restart (bit for bit), and the outputs.
// (Processes: scripts/mpi_check.py's case 2d_custom_plate_tracked_elastic and its restart.)
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "../support/threads.hpp"
#include "driver/run.hpp"
#include "io/checkpoint.hpp"
#include "material/materials.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

namespace fs = std::filesystem;
using test::same_bits;

class TempDir {
 public:
  explicit TempDir(const std::string& tag)
      : path_(fs::temp_directory_path() /
              fmt::format("mpm_tracked_{}_{}_{}", tag,
                          ::testing::UnitTest::GetInstance()->current_test_info()->name(),
                          static_cast<long>(::getpid()))) {
    fs::remove_all(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

TEST(TrackedElastic, StressOfLinearElasticAndStateInClosedForm) {
  ElasticParameters p;
  p.youngs_modulus = 2e7;
  p.poisson_ratio = 0.3;
  const TrackedElastic tracked(p);
  const LinearElastic plain(p);
  // Simple shear at a constant rate: dt L = [[0, g], [0, 0]], |sym(dt L)| = g / sqrt(2).
  const double g = 1e-3;
  Mat<2> dtL = Mat<2>::Zero();
  dtL(0, 1) = g;
  Mat<2> F = Mat<2>::Identity(), s1 = Mat<2>::Zero(), s2 = Mat<2>::Zero();
  std::array<double, 2> state{};
  const int n = 250;
  for (int k = 0; k < n; ++k) {
    F = (Mat<2>::Identity() + dtL) * F;
    tracked.update(s1, StateOf<TrackedElastic>(state), F, dtL);
    plain.update(s2, {}, F, dtL);
    ASSERT_TRUE(s1 == s2) << "step " << k;
  }
  EXPECT_EQ(state[0], n);
  EXPECT_NEAR(state[1], n * g / std::sqrt(2.0), 1e-14 * n * g);
  EXPECT_EQ(tracked.energy(s1, StateOf<TrackedElastic>(state), F, 1.0, 1.0),
            plain.energy(s2, {}, F, 1.0, 1.0));
  EXPECT_EQ(tracked.out_of_plane_stress(s1, StateOf<TrackedElastic>(state), F),
            plain.out_of_plane_stress(s2, {}, F));
}

// The custom plate under gravity (examples/custom_plate_2d.toml) for a few steps, with a
// checkpoint every k steps; `model` the law. 11,520 particles: a shuffled start is re-sorted
// (scheme/sort.hpp sorts a random order from 2,048 particles on).
constexpr double kDt = 1e-5;
std::vector<std::string> plate(const std::string& model, int steps, int k) {
  return {"grid.cells=16",
          "particles.per_cell=3",
          fmt::format("time.dt={}", kDt),
          "output.frames=1",
          "output.vtk=false",
          fmt::format("output.checkpoint_every={}", k),
          fmt::format("material.model=\"{}\"", model),
          "method.basis=\"bspline\"",
          fmt::format("time.end={}", steps * kDt)};
}

RunResult run_in(const Config& cfg, const fs::path& dir, std::uint64_t shuffle_seed,
                 std::shared_ptr<const io::Checkpoint> ck = nullptr, const std::string& name = "") {
  RunOptions ro;
  ro.out_dir = dir.string();
  ro.quiet = true;
  ro.shuffle_seed = shuffle_seed;
  ro.restart = std::move(ck);
  ro.restart_name = name;
  return run(cfg, ro);
}

std::string example(const std::string& name) {
  return std::string(MPM_SOURCE_DIR) + "/examples/" + name + ".toml";
}

// The checkpoint's real particle field `name`, in the stored order.
const std::vector<double>& field(const io::Checkpoint& c, const std::string& name) {
  const auto& names = io::particle_field_names();
  const auto k =
      static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  return c.particles.reals.at(k);
}

TEST(TrackedElastic, StateFollowsParticlesThroughSortingCheckpointAndRestart) {
  const int k = 6, n = 18;  // (the last checkpoint at the end: n a multiple of k)
  TempDir plain("plain"), full("full"), part("part"), cont("cont");
  constexpr std::uint64_t kSeed = 20261206;
  // linear_elastic, and tracked_elastic from shuffled particles (re-sorted after the first
  // step), the whole run and one stopped at step k and continued.
  const auto r_plain = run_in(
      Config::load(example("custom_plate_2d"), plate("linear_elastic", n, k)), plain.path(), kSeed);
  ASSERT_EQ(r_plain.exit_code, 0) << r_plain.failure;
  const auto r_full = run_in(
      Config::load(example("custom_plate_2d"), plate("tracked_elastic", n, k)), full.path(), kSeed);
  ASSERT_EQ(r_full.exit_code, 0) << r_full.failure;
  ASSERT_GE(r_full.sorts, 1);
  const auto r_part = run_in(
      Config::load(example("custom_plate_2d"), plate("tracked_elastic", k, k)), part.path(), kSeed);
  ASSERT_EQ(r_part.exit_code, 0) << r_part.failure;
  const fs::path file = part.path() / io::kCheckpointFile;
  auto ck = std::make_shared<const io::Checkpoint>(io::read_checkpoint(file));
  ASSERT_EQ(ck->step, k);
  const Config cfg =
      io::restart_config(*ck, file.string(), nullptr, {fmt::format("time.end={}", n * kDt)});
  const auto r_cont = run_in(cfg, cont.path(), 0, ck, file.string());
  ASSERT_EQ(r_cont.exit_code, 0) << r_cont.failure;

  const auto a = io::read_checkpoint(plain.path() / io::kCheckpointFile);
  const auto b = io::read_checkpoint(full.path() / io::kCheckpointFile);
  const auto c = io::read_checkpoint(cont.path() / io::kCheckpointFile);
  ASSERT_EQ(b.step, n);
  ASSERT_EQ(c.step, n);
  // The restart ends in the uninterrupted state, the material state included, bit for bit.
  EXPECT_EQ(b.particles.id, c.particles.id);
  for (const auto& name : io::particle_field_names())
    EXPECT_TRUE(same_bits(field(b, name), field(c, name))) << name;
  // The law's stress and motion are linear_elastic's (the same sorted order: same bits), and
  // linear_elastic carries no state.
  EXPECT_EQ(a.particles.id, b.particles.id);
  for (const char* name : {"x", "v", "F", "stress"})
    EXPECT_TRUE(same_bits(field(a, name), field(b, name))) << name;
  EXPECT_TRUE(field(a, "state").empty());
  // Per particle (two values each): n updates, and a strain path that grows with the depth
  // (the plate is squeezed more towards its base): the value of each id is its own.
  const auto& state = field(b, "state");
  const auto count = b.particles.id.size();
  ASSERT_EQ(state.size(), 2 * count);
  std::vector<double> path_of_id(count);
  for (std::size_t i = 0; i < count; ++i) {
    EXPECT_EQ(state[2 * i], n) << "particle " << b.particles.id[i];
    path_of_id[static_cast<std::size_t>(b.particles.id[i])] = state[2 * i + 1];
  }
  // The particle CSV frame lists the variables by name, in id order: the values of the
  // checkpoint, particle by particle.
  std::ifstream csv(full.path() / "particles_00001.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_NE(line.find(",stress_22,updates,strain_path,"), std::string::npos) << line;
  std::size_t rows = 0;
  bool varies = false;
  while (std::getline(csv, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    const auto id = static_cast<std::size_t>(std::stol(cells.at(0)));
    ASSERT_LT(id, count);
    // id, x0, x, u, v (2 each), mass, volume, density, F, stress (4 each): 20 columns first.
    EXPECT_EQ(std::stod(cells.at(20)), n);
    EXPECT_EQ(std::stod(cells.at(21)), path_of_id[id]) << "particle " << id;
    varies = varies || path_of_id[id] != path_of_id[0];
    ++rows;
  }
  EXPECT_EQ(rows, count);
  EXPECT_TRUE(varies);
}

// A checkpoint whose particles carry another number of internal variables than the law declares
// (restart_config already refuses another material.model: a foreign or crafted file).
TEST(TrackedElastic, AStateOfAnotherWidthIsRefusedOnRestart) {
  const int k = 3;
  TempDir part("part"), cont("cont");
  const auto r = run_in(Config::load(example("custom_plate_2d"), plate("tracked_elastic", k, k)),
                        part.path(), 0);
  ASSERT_EQ(r.exit_code, 0) << r.failure;
  const fs::path file = part.path() / io::kCheckpointFile;
  io::Checkpoint stored = io::read_checkpoint(file);
  const Config cfg =
      io::restart_config(stored, file.string(), nullptr, {fmt::format("time.end={}", 2 * k * kDt)});
  const auto& names = io::particle_field_names();
  const auto s =
      static_cast<std::size_t>(std::find(names.begin(), names.end(), "state") - names.begin());
  stored.particles.reals.at(s).resize(stored.particles.reals.at(s).size() / 2);
  try {
    (void)run_in(cfg, cont.path(), 0, std::make_shared<const io::Checkpoint>(stored),
                 file.string());
    FAIL() << "particles with one variable each continued with tracked_elastic's two";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("carry 1 internal variables each, the material "
                                         "declares 2"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("tracked_elastic"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
