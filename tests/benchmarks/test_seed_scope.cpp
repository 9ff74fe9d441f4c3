// The particles a process of a distributed run sets up (issue 21, SeedScope in
// model/problem.hpp): every built-in problem, seeded with a scope that keeps one block's cells
// (slabs, and blocks of 2 x 2, 3 x 2, 2 x 2 x 2 and an automatic shape), must give exactly the
// particles of that block of the whole problem, in the whole problem's order, bit for bit in
// every field, with the same ids; the counting pass must count the whole problem's particles
// per cell layer along each axis and store none; the blocks together must hold every particle
// once; and the loaded points (tractions) must be those of the whole problem on every process,
// naming their particles by id.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include <fmt/format.h>

#include "benchmarks/benchmarks.hpp"
#include "grid/grid_state.hpp"
#include "model/problem.hpp"
#include "parallel/distribution.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// Bitwise equality of two values of a particle field (doubles, Eigen fixed-size arrays, ids).
template <class T>
bool same_bits(const T& a, const T& b) {
  return std::memcmp(static_cast<const void*>(&a), static_cast<const void*>(&b), sizeof(T)) == 0;
}

template <int Dim>
void expect_same_tractions(const std::vector<Traction<Dim>>& a, const std::vector<Traction<Dim>>& b,
                           const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t t = 0; t < a.size(); ++t) {
    EXPECT_EQ(a[t].direction, b[t].direction) << what;
    EXPECT_EQ(a[t].side, b[t].side) << what;
    EXPECT_EQ(a[t].particles, b[t].particles) << what;
    EXPECT_EQ(a[t].area, b[t].area) << what;
    ASSERT_EQ(a[t].offset.size(), b[t].offset.size()) << what;
    for (std::size_t k = 0; k < a[t].offset.size(); ++k)
      EXPECT_TRUE(same_bits(a[t].offset[k], b[t].offset[k])) << what;
    ASSERT_EQ(a[t].normal.size(), b[t].normal.size()) << what;
    for (std::size_t k = 0; k < a[t].normal.size(); ++k)
      EXPECT_TRUE(same_bits(a[t].normal[k], b[t].normal[k])) << what;
  }
}

// The whole problem against `ranks` blocks of it (parallel.blocks = `shape`), each seeded by its
// own scope.
template <int Dim>
void check_blocks(const Config& cfg, const Problem<Dim>& whole, int ranks, const std::string& shape,
                  const std::string& what) {
  const Particles<Dim>& W = whole.particles;
  ASSERT_GT(W.size(), 0) << what;
  // One process numbers its particles 0, 1, ...: a loaded point's id is its index there.
  for (std::size_t i = 0; i < W.x.size(); ++i) ASSERT_EQ(W.id[i], static_cast<Index>(i)) << what;

  std::vector<std::vector<double>> per_layer;
  SeedScope counting;
  counting.layer_counts = &per_layer;
  const AnyProblem counted = make_problem(cfg, counting);
  const auto& C = std::get<Problem<Dim>>(counted);
  EXPECT_EQ(C.particles.size(), 0) << what << ": the counting pass stores no particle";
  EXPECT_EQ(counting.seeded, W.size()) << what;
  using Part = BlockPartition<Dim>;
  const typename Part::LayerCounts counts =
      Part::layer_counts(whole.grid, W, Comm::world(), /*replicated=*/true);
  ASSERT_EQ(per_layer.size(), static_cast<std::size_t>(Dim)) << what;
  for (std::size_t d = 0; d < Dim; ++d)
    EXPECT_EQ(per_layer[d], counts[d]) << what << ", axis " << d;
  expect_same_tractions(C.tractions, whole.tractions, what + ", counting pass");

  const Part part = Part::cut(counts, ranks, BlockShapeRequest::parse(shape, "test"));
  Index held = 0;
  for (int r = 0; r < ranks; ++r) {
    SeedScope scope;
    scope.keep = [&](std::span<const Index> cell) { return part.keeps(r, cell); };
    const AnyProblem mine = make_problem(cfg, scope);
    const auto& pb = std::get<Problem<Dim>>(mine);
    const std::string where = what + ", process " + std::to_string(r);
    EXPECT_EQ(scope.seeded, W.size()) << where;
    std::vector<std::size_t> expected;
    for (std::size_t i = 0; i < W.x.size(); ++i)
      if (part.owner(whole.grid, W.x[i], 0) == r) expected.push_back(i);
    ASSERT_EQ(static_cast<std::size_t>(pb.particles.size()), expected.size()) << where;
    held += pb.particles.size();
    // Every field, bit for bit, in the whole problem's order (Particles::pack walks the one
    // field list, ids included).
    const Particles<Dim>& P = pb.particles;
    std::vector<std::byte> a, b;
    for (std::size_t k = 0; k < expected.size(); ++k) {
      a.clear();
      b.clear();
      P.pack(k, a);
      W.pack(expected[k], b);
      ASSERT_EQ(a, b) << where << ": particle " << k << " is not the whole problem's particle "
                      << expected[k];
    }
    expect_same_tractions(pb.tractions, whole.tractions, where);
  }
  EXPECT_EQ(held, W.size()) << what;
}

void check_config(const std::string& example, const std::vector<std::string>& sets, int ranks,
                  const std::string& shape = "slabs") {
  const Config cfg = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/" + example, sets);
  const AnyProblem whole = make_problem(cfg);
  std::string what = example + " (" + shape + ")";
  for (const auto& s : sets) what += " " + s;
  std::visit([&](const auto& pb) { check_blocks(cfg, pb, ranks, shape, what); }, whole);
}

TEST(SeedScope, EveryProcessSetsUpExactlyItsBlockOfTheWholeProblem1D) {
  check_config("vibrating_bar_crossing.toml", {"grid.cells=40"}, 3);
  check_config("traction_bar.toml", {"grid.cells=20"}, 4);  // a loaded end
  check_config("custom_bar.toml", {}, 2);
  check_config("column_compaction.toml", {"grid.cells=10"}, 3);
  check_config("mms_1d.toml", {"grid.cells=16"}, 2);
}

TEST(SeedScope, EveryProcessSetsUpExactlyItsBlockOfTheWholeProblem2D) {
  check_config("plate_mms_2d.toml", {"grid.cells=8"}, 3);
  check_config("plate_mms_2d.toml", {"grid.cells=8"}, 4, "2x2");
  check_config("vortex_2d.toml", {"grid.cells=16"}, 6, "auto");
  check_config("custom_plate_2d.toml", {}, 6, "3x2");
  check_config("vortex_2d.toml", {"grid.cells=16"}, 4);  // rings (not in layer order)
  check_config("vortex_2d.toml", {"grid.cells=16", "vortex.seeding=\"cells\""}, 3);
  check_config("plate_triangles_2d.toml", {"particles.per_triangle=6"}, 3);
  check_config("custom_plate_2d.toml", {}, 4);           // tractions on the body's faces
  check_config("incline_pressure_2d.toml", {}, 3);       // a mesh file, a loaded boundary
  check_config("plate_ps_unstructured_2d.toml", {}, 2);  // triangles of a mesh file
}

TEST(SeedScope, EveryProcessSetsUpExactlyItsBlockOfTheWholeProblem3D) {
  check_config("cube_mms_3d.toml", {"grid.cells=4"}, 3);
  check_config("cube_mms_3d.toml", {"grid.cells=4"}, 8, "2x2x2");
  check_config("custom_3d.toml", {}, 3);
}

// The grid memory check (benchmarks/problem.cpp) of a distributed run counts this machine's
// processes' windows of the grid arrays (their share of them) and each process's whole
// velocity-condition bits: a grid whose arrays need about four times this machine's memory is
// refused on one process and for 1024 processes all on this machine, and accepted for a process
// of 1024 spread over as many machines. (The body is a speck, so the particles are few.)
TEST(SeedScope, TheGridMemoryCheckCountsThisMachinesShareOfTheGrid) {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) GTEST_SKIP() << "this machine's memory is not known";
  const double memory = static_cast<double>(pages) * static_cast<double>(page);
  const double per_node = static_cast<double>(GridState<2>::bytes_per_dof() + 1);
  const auto cells = static_cast<Index>(std::sqrt(4.0 * memory / per_node));
  const Config cfg = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/custom_plate_2d.toml",
                                  {fmt::format("grid.cells={}", cells), "body.max=[1e-7, 1e-7]"});
  const auto refused = [&](const SeedScope& scope) {
    try {
      (void)make_problem(cfg, scope);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(refused({}).find("GB of memory: use fewer cells"), std::string::npos);
  SeedScope spread;
  spread.machine_share = 1.0 / 1024;
  EXPECT_EQ(refused(spread), "");
  SeedScope here;
  here.machine_processes = 1024;
  const std::string msg = refused(here);
  EXPECT_NE(msg.find("for the 1024 process(es) of the run on this machine"), std::string::npos)
      << msg;
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
