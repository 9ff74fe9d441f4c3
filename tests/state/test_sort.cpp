// Re-sorting the particles by cell (state/sort.hpp): a run started from shuffled particles and
// re-sorted gives the seeded run's results per particle id to round-off; sorting puts the
// particles in cell order and shrinks the chunks' DOF spans; 1 and 2 threads stay bitwise
// identical; a restart across a sort stays bitwise identical; method.sort is validated.
#include <gtest/gtest.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <numeric>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "../support/stepper.hpp"
#include "../support/threads.hpp"
#include "basis/bases.hpp"
#include "core/parallel.hpp"
#include "driver/run.hpp"
#include "io/checkpoint.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"
#include "scheme/schemes.hpp"
#include "setup/config.hpp"
#include "state/sort.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

using test::same_bits;
using test::Threads;

namespace fs = std::filesystem;

class TempDir {
 public:
  explicit TempDir(const std::string& tag)
      : path_(fs::temp_directory_path() /
              fmt::format("mpm_sort_{}_{}_{}", tag,
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

std::string example(const std::string& name) {
  return std::string(MPM_SOURCE_DIR) + "/examples/" + name + ".toml";
}

constexpr std::uint64_t kSeed = 20261122;

RunResult run_case(const std::string& name, std::vector<std::string> sets, const fs::path& dir,
                   std::uint64_t shuffle_seed) {
  sets.insert(sets.end(), {"output.frames=1", "output.vtk=false"});
  RunOptions ro;
  ro.out_dir = dir.string();
  ro.quiet = true;
  ro.shuffle_seed = shuffle_seed;
  return run(Config::load(example(name), sets), ro);
}

// A particle CSV: the field of each column (its name without a component suffix: x_1 -> x,
// F_12 -> F) and the rows as numbers.
struct Csv {
  std::vector<std::string> field;
  std::vector<std::vector<double>> rows;
};
Csv read_csv(const fs::path& file) {
  std::ifstream in(file);
  Csv csv;
  std::string line, cell;
  std::getline(in, line);
  std::stringstream header(line);
  while (std::getline(header, cell, ',')) {
    const auto us = cell.rfind('_');
    const bool component = us != std::string::npos && us + 1 < cell.size() &&
                           std::all_of(cell.begin() + static_cast<std::ptrdiff_t>(us) + 1,
                                       cell.end(), [](char c) { return c >= '0' && c <= '9'; });
    csv.field.push_back(component ? cell.substr(0, us) : cell);
  }
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    while (std::getline(ss, cell, ',')) row.push_back(std::stod(cell));
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

// The largest difference between two frames relative to the largest magnitude of its field over
// all particles and components (a component that vanishes exactly, like F_12 of an
// axis-aligned vibration, holds only round-off noise of the field's size). Both frames must list
// the particles in id order (column id = row).
double max_relative_difference(const fs::path& a, const fs::path& b) {
  const Csv ca = read_csv(a), cb = read_csv(b);
  const auto &ra = ca.rows, &rb = cb.rows;
  EXPECT_EQ(ca.field, cb.field);
  EXPECT_EQ(ra.size(), rb.size());
  EXPECT_FALSE(ra.empty());
  if (ra.size() != rb.size() || ra.empty() || ca.field != cb.field) return 1.0;
  std::map<std::string, double> scale, diff;
  for (std::size_t i = 0; i < ra.size(); ++i) {
    EXPECT_EQ(ra[i][0], static_cast<double>(i));
    EXPECT_EQ(rb[i][0], static_cast<double>(i));
    for (std::size_t j = 1; j < ra[i].size(); ++j) {
      const std::string& f = ca.field[j];
      scale[f] = std::max(scale[f], std::abs(ra[i][j]));
      diff[f] = std::max(diff[f], std::abs(ra[i][j] - rb[i][j]));
    }
  }
  double worst = 0.0;
  for (const auto& [f, s] : scale)
    if (s > 0.0) worst = std::max(worst, diff[f] / s);
  return worst;
}

// Relative tolerance per field (max_relative_difference) of a shuffled and re-sorted run against
// the seeded one. Sorting regroups the particle sums of every node (9-27 terms per particle, the
// chunk partial sums), a relative change of a few 1e-16 per sum, and the first step of the
// shuffled run sums in random order; the elastic problems here do not amplify that over their
// 10-100 steps (measured: 7e-16 to 1.2e-13, the largest for the quasi-static custom plate), so
// 1e-12 leaves a margin of 8 or more, while a particle that ends up with another's state or a
// traction applied to the wrong particle changes a field by O(1).
constexpr double kRoundOff = 1e-12;

void expect_shuffled_matches_seeded(const std::string& name, const std::vector<std::string>& sets) {
  SCOPED_TRACE(name);
  TempDir seeded("seeded"), shuffled("shuffled");
  const RunResult a = run_case(name, sets, seeded.path(), 0);
  const RunResult b = run_case(name, sets, shuffled.path(), kSeed);
  ASSERT_EQ(a.exit_code, 0) << a.failure;
  ASSERT_EQ(b.exit_code, 0) << b.failure;
  ASSERT_GT(a.particles, 4 * ParticleChunks::kMinSize);  // enough chunks for random order to show
  EXPECT_EQ(a.sorts, 0);                                 // seeded order needs no sort
  EXPECT_GE(b.sorts, 1);  // shuffled order is sorted after the first step
  // The last frame (output.frames = 1: frames 0 and 1).
  const double d = max_relative_difference(seeded.path() / "particles_00001.csv",
                                           shuffled.path() / "particles_00001.csv");
  std::cout << "[ info ] " << name << ": max relative difference " << d << ", " << b.sorts
            << " sort(s)\n";
  EXPECT_LE(d, kRoundOff);
  EXPECT_GT(d, 0.0);  // the sums were really regrouped (else the test would prove nothing)
  EXPECT_EQ(a.diag.grid_crossings, b.diag.grid_crossings);
}

TEST(Sort, CellOrderIsStableWithCursorsOverTheOccupiedCellsOnly) {
  // A body in cells 5..9 of a 100,000-cell grid: the counting sort's cursors span those cells
  // (6 entries), and the order is the stable sort by cell.
  const std::vector<CompactIndex> cell{9, 5, 7, 5, 9, 6, 7, 5};
  SortState st;
  cell_order(cell, 100000, st);
  EXPECT_EQ(st.cursor.size(), 6u);
  std::vector<CompactIndex> expect(cell.size());
  std::iota(expect.begin(), expect.end(), CompactIndex{0});
  std::stable_sort(expect.begin(), expect.end(),
                   [&](CompactIndex a, CompactIndex b) { return cell[a] < cell[b]; });
  EXPECT_EQ(st.perm.order, expect);
  cell_order({}, 100000, st);  // no particles: nothing to order
  EXPECT_TRUE(st.perm.order.empty());
  EXPECT_EQ(st.cursor.size(), 1u);
}

TEST(Sort, ShuffledBar1DQuadraticBSplineMatchesSeeded) {
  expect_shuffled_matches_seeded(
      "vibrating_bar_small",
      {"grid.cells=200", "particles.per_cell=16", "method.basis=\"bspline\"", "method.degree=2"});
}

TEST(Sort, ShuffledPlate2DQuadraticBSplineMatchesSeeded) {
  expect_shuffled_matches_seeded("plate_mms_2d",
                                 {"grid.cells=24", "particles.per_cell=3", "time.end=1e-4",
                                  "method.basis=\"bspline\"", "method.degree=2"});
}

// CPDI2: the tracked corners are per-particle basis state and must move with their particles.
TEST(Sort, ShuffledPlate2DCpdi2MatchesSeeded) {
  expect_shuffled_matches_seeded("plate_mms_2d", {"grid.cells=24", "particles.per_cell=3",
                                                  "time.end=1e-4", "method.basis=\"cpdi2\""});
}

// Tractions: the loaded particles are a list of indices that the sort must remap.
TEST(Sort, ShuffledTractionBar1DCpdiMatchesSeeded) {
  expect_shuffled_matches_seeded(
      "traction_bar", {"particles.per_cell=48", "time.end=0.01", "method.basis=\"cpdi\""});
}
TEST(Sort, ShuffledCustomPlate2DWithTractionMatchesSeeded) {
  expect_shuffled_matches_seeded("custom_plate_2d",
                                 {"grid.cells=16", "time.dt=1e-4", "time.end=2e-3",
                                  "traction.top=[\"1e3*t\", \"-1e3\"]", "method.scheme=\"usl\""});
}

// Direct use of the stages: a plate of 3 x 3 particles per cell on 20 x 20 cells.
using PlateSim = Simulation<2, BSplineBasis<2, 2>, DirectMapping>;

const Grid<2> kPlateGrid(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{20, 20});

// The plate's particles with a sine velocity field, in seeded or shuffled order.
Particles<2> plate_particles(bool shuffled) {
  auto P = seed_particles<2>(kPlateGrid, Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), 3, 1000.0);
  for (std::size_t i = 0; i < P.v.size(); ++i) {
    using std::numbers::pi;
    P.v[i] = Vec<2>(0.5 * std::sin(2 * pi * P.x[i][0]), -0.3 * std::sin(2 * pi * P.x[i][1]));
  }
  std::vector<Traction<2>> none;
  if (shuffled) shuffle_particles(P, none, kSeed);
  return P;
}

std::unique_ptr<PlateSim> make_plate(bool shuffled) {
  const Grid<2>& g = kPlateGrid;
  const auto P = plate_particles(shuffled);
  ElasticParameters ep{1000.0, 1e7, 0.3};
  auto sim =
      std::make_unique<PlateSim>(g, BSplineBasis<2, 2>(g), DirectMapping{}, P, NeoHookean{ep});
  sim->fix_side(0, 0);
  sim->fix_side(0, 1);
  return sim;
}

TEST(Sort, SortPutsParticlesInCellOrderAndShrinksSpans) {
  auto sim = make_plate(true);
  stages::evaluate_basis(*sim);
  const ChunkSpans before = chunk_spans(sim->scatter.ranges);
  ASSERT_GT(ParticleChunks::count(sim->particles.size()), 4);
  // Random order: every chunk spans nearly the whole grid.
  EXPECT_GT(before.total, 4 * before.uni);
  EXPECT_TRUE(sort_due(sim->scatter.ranges, sim->sorting));
  const auto old = sim->particles;
  ASSERT_TRUE(sort_particles(*sim));
  EXPECT_TRUE(std::is_sorted(sim->cell.begin(), sim->cell.end()));
  // A permutation: each id keeps its exact state, and ids are unique.
  std::vector<Index> seen(sim->particles.id.size(), 0);
  for (std::size_t i = 0; i < sim->particles.id.size(); ++i) {
    const Index id = sim->particles.id[i];
    ++seen[static_cast<std::size_t>(id)];
    const auto j =
        static_cast<std::size_t>(std::find(old.id.begin(), old.id.end(), id) - old.id.begin());
    ASSERT_EQ(std::memcmp(sim->particles.x[i].data(), old.x[j].data(), sizeof(Vec<2>)), 0);
    ASSERT_EQ(std::memcmp(sim->particles.v[i].data(), old.v[j].data(), sizeof(Vec<2>)), 0);
    ASSERT_EQ(sim->particles.mass[i], old.mass[j]);
    ASSERT_EQ(sim->cell[i], sim->grid.cell_index(sim->particles.x[i]));
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](Index s) { return s == 1; }));
  // Stable: equal cells keep the old relative order.
  for (std::size_t i = 1; i < sim->cell.size(); ++i)
    if (sim->cell[i] == sim->cell[i - 1]) {
      const auto a = std::find(old.id.begin(), old.id.end(), sim->particles.id[i - 1]);
      const auto b = std::find(old.id.begin(), old.id.end(), sim->particles.id[i]);
      ASSERT_LT(a, b);
    }
  stages::evaluate_basis(*sim);
  const ChunkSpans after = chunk_spans(sim->scatter.ranges);
  EXPECT_EQ(after.uni, before.uni);
  EXPECT_LT(4 * after.total, before.total);
  std::cout << "[ info ] chunk spans: " << before.total << " -> " << after.total << " DOFs (union "
            << after.uni << ")\n";
  // Sorted now: the next measurement is the reference, and nothing is due.
  EXPECT_FALSE(sort_due(sim->scatter.ranges, sim->sorting));
  EXPECT_EQ(sim->sorting.reference, after.total);
  EXPECT_FALSE(sort_particles(*sim));  // already in cell order: nothing moves
}

// The first measurement of particles in seeded order does not sort; the reference then follows.
TEST(Sort, SeededOrderIsNotSortedAndTriggerFollowsTheReference) {
  auto sim = make_plate(false);
  stages::evaluate_basis(*sim);
  EXPECT_FALSE(sort_due(sim->scatter.ranges, sim->sorting));
  const Index ref = sim->sorting.reference;
  EXPECT_EQ(ref, chunk_spans(sim->scatter.ranges).total);
  ChunkDofRanges r = sim->scatter.ranges;
  // Widen one chunk until the total passes kResortFactor x the reference.
  r.lo[0] = 0;
  r.hi[0] = std::max(r.hi[0], static_cast<Index>(SortState::kResortFactor * ref));
  EXPECT_TRUE(sort_due(r, sim->sorting));
  SortState never;
  never.mode = SortMode::Never;
  EXPECT_FALSE(sort_due(r, never));
}

// The plate of make_plate, shuffled, ten MUSL steps with the library's compiled stepper,
// re-sorted as the driver does when due.
std::unique_ptr<driver::Stepper<2>> step_plate(int threads) {
  const Threads t(threads);
  auto stepper =
      test::compiled_stepper<2>({.grid = kPlateGrid,
                                 .particles = plate_particles(true),
                                 .material = NeoHookean{ElasticParameters{1000.0, 1e7, 0.3}},
                                 .basis = BSplineKind<2>{},
                                 .fixed_sides = {FixedSide{0, 0}, FixedSide{0, 1}}});
  for (int s = 0; s < 10; ++s) {
    stepper->step(1e-4);
    stepper->sort_if_due();
  }
  return stepper;
}

TEST(Sort, SameBitsForOneAndTwoThreads) {
  const auto sa = step_plate(1);
  const auto sb = step_plate(2);
  const RunState<2>* a = &sa->state();
  const RunState<2>* b = &sb->state();
  EXPECT_EQ(a->sorting.sorts, 1);
  EXPECT_EQ(b->sorting.sorts, 1);
  EXPECT_TRUE(same_bits(a->particles.id, b->particles.id));
  EXPECT_TRUE(same_bits(a->particles.x, b->particles.x));
  EXPECT_TRUE(same_bits(a->particles.v, b->particles.v));
  EXPECT_TRUE(same_bits(a->particles.F, b->particles.F));
  EXPECT_TRUE(same_bits(a->particles.stress, b->particles.stress));
  EXPECT_TRUE(same_bits(a->nodes.momentum, b->nodes.momentum));

  // Through `run`, with the summary's error norms (sums over all particles).
  const std::vector<std::string> sets = {"grid.cells=24", "particles.per_cell=3", "time.end=1e-4",
                                         "method.basis=\"bspline\"", "method.degree=2"};
  RunResult r[2];
  for (int k = 0; k < 2; ++k) {
    const Threads t(k + 1);
    RunOptions ro;
    ro.quiet = true;
    ro.shuffle_seed = kSeed;
    r[k] = run(Config::load(example("plate_mms_2d"), sets), ro);
    ASSERT_EQ(r[k].exit_code, 0) << r[k].failure;
  }
  EXPECT_GE(r[0].sorts, 1);
  EXPECT_EQ(r[0].sorts, r[1].sorts);
  EXPECT_EQ(r[0].summary["errors"], r[1].summary["errors"]);
  EXPECT_EQ(r[0].diag.max_rel_momentum_error, r[1].diag.max_rel_momentum_error);
}

// A shuffled run is sorted after its first step; a restart from the checkpoint of step k must
// restore the sorted order (ids) and the trigger state and end in the uninterrupted state. The
// custom plate carries a traction on its top face, whose particles the restart must find by id
// in the checkpoint's order.
TEST(Sort, RestartAfterSortIsBitwise) {
  for (const auto& [name, basis, extra] :
       {std::tuple{"plate_mms_2d", "bspline", std::vector<std::string>{}},
        std::tuple{"plate_mms_2d", "cpdi2", std::vector<std::string>{}},
        std::tuple{"custom_plate_2d", "linear",
                   std::vector<std::string>{"time.dt=1e-5", "traction.top=[\"2e4\", \"-1e5\"]"}}}) {
    SCOPED_TRACE(std::string(name) + " " + basis);
    TempDir full("full"), part("part"), cont("cont");
    const int k = 5, n = 15;
    const double dt = 1e-5;
    std::vector<std::string> base = {
        "grid.cells=16",    "particles.per_cell=3", fmt::format("method.basis=\"{}\"", basis),
        "output.csv=false", "output.vtk=false",     fmt::format("output.checkpoint_every={}", k)};
    base.insert(base.end(), extra.begin(), extra.end());
    auto with_end = [&](int steps) {
      auto s = base;
      s.push_back(fmt::format("time.end={}", steps * dt));
      return s;
    };
    auto run_in = [&](const Config& cfg, const fs::path& dir,
                      std::shared_ptr<const io::Checkpoint> ck, const std::string& name) {
      RunOptions ro;
      ro.out_dir = dir.string();
      ro.quiet = true;
      ro.shuffle_seed = kSeed;  // ignored on restart
      ro.restart = std::move(ck);
      ro.restart_name = name;
      return run(cfg, ro);
    };
    const auto r_full = run_in(Config::load(example(name), with_end(n)), full.path(), nullptr, "");
    ASSERT_EQ(r_full.exit_code, 0) << r_full.failure;
    ASSERT_GE(r_full.sorts, 1);
    const auto r_part = run_in(Config::load(example(name), with_end(k)), part.path(), nullptr, "");
    ASSERT_EQ(r_part.exit_code, 0) << r_part.failure;
    const fs::path file = part.path() / io::kCheckpointFile;
    auto ck = std::make_shared<const io::Checkpoint>(io::read_checkpoint(file));
    ASSERT_GE(ck->sorts, 1);
    // The stored order is the sorted one, not the id order.
    ASSERT_FALSE(std::is_sorted(ck->particles.id.begin(), ck->particles.id.end()));
    const Config cfg =
        io::restart_config(*ck, file.string(), nullptr, {fmt::format("time.end={}", n * dt)});
    const auto r_cont = run_in(cfg, cont.path(), ck, file.string());
    ASSERT_EQ(r_cont.exit_code, 0) << r_cont.failure;
    const auto a = io::read_checkpoint(full.path() / io::kCheckpointFile);
    const auto b = io::read_checkpoint(cont.path() / io::kCheckpointFile);
    ASSERT_EQ(a.step, n);
    ASSERT_EQ(b.step, n);
    EXPECT_EQ(a.particles.id, b.particles.id);
    // Every real field (x, x0, u, v, ..., stress, body), bit for bit.
    ASSERT_EQ(a.particles.reals.size(), b.particles.reals.size());
    for (std::size_t k = 0; k < a.particles.reals.size(); ++k)
      EXPECT_TRUE(same_bits(a.particles.reals[k], b.particles.reals[k]))
          << io::particle_field_names()[k];
    EXPECT_TRUE(same_bits(a.basis_state, b.basis_state));
    EXPECT_EQ(a.cells, b.cells);
    EXPECT_EQ(a.sort_reference, b.sort_reference);
    EXPECT_EQ(a.sorts, b.sorts);
    EXPECT_EQ(r_full.summary["errors"].dump(), r_cont.summary["errors"].dump());
  }
}

TEST(Sort, BadSortModeIsRefusedWithTheChoices) {
  const std::string rest =
      "[time]\ndt = 1e-7\nend = 1e-6\n[material]\ndensity = 1.0\nyoungs_modulus = 1.0\n";
  try {
    (void)Config::parse("benchmark = \"vibrating_bar\"\n[method]\nsort = \"sometimes\"\n" + rest,
                        "test.toml");
    FAIL() << "method.sort = \"sometimes\" was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("test.toml:3:8: key 'method.sort' = \"sometimes\" is not valid"),
              std::string::npos)
        << msg;
    EXPECT_NE(msg.find("choose one of: auto, never"), std::string::npos) << msg;
  }
  EXPECT_NO_THROW((void)Config::parse(
      "benchmark = \"vibrating_bar\"\n[method]\nsort = \"never\"\n" + rest, "t"));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
