// Distributed runs, the parts that do not need several processes: the blocks' cuts balance the
// particles along each axis and give every process a layer, the process grid is the one asked
// for (slabs, given, or shaped for the least halo), a particle's owner follows its cell, a
// block's neighbours are those around it,
// particles travel between processes as bytes that restore every field, the traction lists
// follow their particles by id, a process's grid arrays hold the window of its particles' DOFs,
// and the collective operations are plain copies on one process. The runs on several processes are
// checked in Mpi.SameAnswersAsOneProcess (scripts/mpi_check.py, under mpirun).
#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "parallel/distribution.hpp"
#include "state/simulation.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// Slabs: the process grid (1, ..., 1, N).
template <int Dim>
BlockPartition<Dim> slabs(const std::vector<double>& last, int ranks) {
  typename BlockPartition<Dim>::LayerCounts counts;
  for (std::size_t d = 0; d + 1 < Dim; ++d) counts[d].assign(4, 1.0);
  counts[Dim - 1] = last;
  return BlockPartition<Dim>::balanced(
      counts, BlockPartition<Dim>::choose_shape(counts, ranks, BlockShapeRequest{}), "grid.cells");
}

TEST(BlockPartition, SlabCutsBalanceTheParticles) {
  // 10 layers: the body fills layers 2-7 with 100 particles each.
  std::vector<double> per_layer(10, 0.0);
  for (int l = 2; l < 8; ++l) per_layer[static_cast<std::size_t>(l)] = 100.0;
  const auto p = slabs<2>(per_layer, 3);
  EXPECT_TRUE(p.slabs());
  EXPECT_EQ(p.procs, (IVec<2>{1, 3}));
  EXPECT_EQ(p.cuts[0], (std::vector<Index>{0, 4}));
  ASSERT_EQ(p.cuts[1].size(), 4u);
  EXPECT_EQ(p.cuts[1].front(), 0);
  EXPECT_EQ(p.cuts[1].back(), 10);
  std::vector<double> per_rank(3, 0.0);
  for (Index l = 0; l < 10; ++l)
    per_rank[static_cast<std::size_t>(p.owner_of_cell(IVec<2>{0, l}))] +=
        per_layer[static_cast<std::size_t>(l)];
  for (double c : per_rank) EXPECT_EQ(c, 200.0);
}

TEST(BlockPartition, EveryProcessGetsALayer) {
  // All particles in one layer: the other processes still own one layer each.
  std::vector<double> per_layer(4, 0.0);
  per_layer[3] = 50.0;
  const auto p = slabs<1>(per_layer, 4);
  EXPECT_EQ(p.cuts[0], (std::vector<Index>{0, 1, 2, 3, 4}));
  EXPECT_THROW(slabs<1>(per_layer, 5), InputError);
}

TEST(BlockPartition, OwnerFollowsTheCell) {
  const Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{4, 4});
  BlockPartition<2> p;
  p.procs = {1, 3};
  p.cuts = {std::vector<Index>{0, 4}, std::vector<Index>{0, 1, 3, 4}};
  EXPECT_EQ(p.owner(g, Vec<2>(0.9, 0.1), 2), 0);
  EXPECT_EQ(p.owner(g, Vec<2>(0.1, 0.3), 0), 1);
  EXPECT_EQ(p.owner(g, Vec<2>(0.1, 0.74), 0), 1);
  EXPECT_EQ(p.owner(g, Vec<2>(0.1, 1.0), 0), 2);  // the upper side belongs to the last cell
  EXPECT_EQ(p.owner(g, Vec<2>(0.1, 1.5), 1), 1);  // outside: stays where it is
  // 2 x 2 blocks: rank = x + 2 y.
  p.procs = {2, 2};
  p.cuts = {std::vector<Index>{0, 1, 4}, std::vector<Index>{0, 3, 4}};
  EXPECT_EQ(p.owner(g, Vec<2>(0.1, 0.1), 3), 0);
  EXPECT_EQ(p.owner(g, Vec<2>(0.3, 0.1), 3), 1);
  EXPECT_EQ(p.owner(g, Vec<2>(0.1, 0.9), 3), 2);
  EXPECT_EQ(p.owner(g, Vec<2>(1.0, 1.0), 0), 3);
  EXPECT_EQ(p.coords(3), (IVec<2>{1, 1}));
  EXPECT_EQ(p.rank_at(IVec<2>{0, 1}), 2);
  EXPECT_EQ(p.span(1, 0), (std::array<Index, 2>{1, 4}));
  EXPECT_EQ(p.span(1, 1), (std::array<Index, 2>{0, 3}));
  EXPECT_FALSE(p.slabs());
  EXPECT_EQ(p.describe(), "2 x 2 blocks");
}

TEST(BlockPartition, NeighboursAreTheBlocksAroundOne) {
  BlockPartition<3> p;
  p.procs = {3, 3, 3};
  for (auto& c : p.cuts) c = {0, 2, 4, 6};
  // The centre block touches all 26 others; a corner 7; a slab its two neighbours.
  std::vector<int> all;
  for (int r = 0; r < 27; ++r)
    if (r != 13) all.push_back(r);
  EXPECT_EQ(p.neighbours(13), all);
  EXPECT_EQ(p.neighbours(0), (std::vector<int>{1, 3, 4, 9, 10, 12, 13}));
  BlockPartition<2> s;
  s.procs = {1, 4};
  EXPECT_EQ(s.neighbours(0), (std::vector<int>{1}));
  EXPECT_EQ(s.neighbours(2), (std::vector<int>{1, 3}));
  // Blocks of two partitions overlap where they share a cell along every axis.
  BlockPartition<2> a, b;
  a.procs = {2, 1};
  a.cuts = {std::vector<Index>{0, 2, 4}, std::vector<Index>{0, 4}};
  b.procs = {1, 2};
  b.cuts = {std::vector<Index>{0, 4}, std::vector<Index>{0, 1, 4}};
  EXPECT_TRUE(a.overlaps(0, b, 0));
  EXPECT_TRUE(a.overlaps(1, b, 1));
  a.cuts[1] = {0, 1};  // (only the spans matter)
  EXPECT_FALSE(a.overlaps(0, b, 1));
}

TEST(BlockPartition, TheShapeIsAsked) {
  typename BlockPartition<2>::LayerCounts c2;
  c2[0].assign(8, 1.0);
  c2[1].assign(8, 1.0);
  const auto shape = [&](const std::string& text, int ranks) {
    return BlockPartition<2>::choose_shape(c2, ranks, BlockShapeRequest::parse(text, "f.toml:3:1"));
  };
  EXPECT_EQ(shape("slabs", 4), (IVec<2>{1, 4}));
  EXPECT_EQ(shape("2x3", 6), (IVec<2>{2, 3}));
  // Auto: the least cut area through the body's box. A square: 2 x 2 for 4 (cuts of 8 + 8
  // layers against 24 for slabs), 2 x 3 or 3 x 2 for 6 (more processes along the later axis).
  EXPECT_EQ(shape("auto", 4), (IVec<2>{2, 2}));
  EXPECT_EQ(shape("auto", 6), (IVec<2>{2, 3}));
  EXPECT_EQ(shape("auto", 7), (IVec<2>{1, 7}));  // a prime: slabs
  // A wide, low body (8 layers along x, 2 along y): cut along x.
  c2[1] = {1, 1, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(shape("auto", 4), (IVec<2>{4, 1}));
  // At most the layers along an axis.
  EXPECT_EQ(shape("auto", 16), (IVec<2>{8, 2}));
  // Refused, naming the line and the valid forms.
  const auto message = [&](const std::string& text, int ranks) {
    try {
      (void)shape(text, ranks);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message("2x2", 6).find("f.toml:3:1: parallel.blocks = \"2x2\" names 4 processes"),
            std::string::npos);
  EXPECT_NE(message("2x2x1", 4).find("along 3 axes"), std::string::npos);
  EXPECT_NE(message("two", 4).find("valid: \"slabs\""), std::string::npos);
  EXPECT_NE(message("0x4", 4).find("is not a decomposition"), std::string::npos);
  EXPECT_NE(message("2x", 4).find("is not a decomposition"), std::string::npos);
  EXPECT_NE(message("auto", 128).find("no blocks of 128 processes"), std::string::npos);
}

TEST(BlockPartition, BlockCutsBalanceEachAxis) {
  // A 2D body of 6 x 4 cells with 2 particles each, in a grid of 8 x 8; 2 x 2 blocks: each
  // process holds 12 cells of the body.
  typename BlockPartition<2>::LayerCounts c;
  c[0].assign(8, 0.0);
  c[1].assign(8, 0.0);
  for (int x = 1; x < 7; ++x) c[0][static_cast<std::size_t>(x)] = 8.0;
  for (int y = 0; y < 4; ++y) c[1][static_cast<std::size_t>(y)] = 12.0;
  const auto p = BlockPartition<2>::balanced(c, IVec<2>{2, 2}, "grid.cells");
  EXPECT_EQ(p.cuts[0], (std::vector<Index>{0, 4, 8}));
  EXPECT_EQ(p.cuts[1], (std::vector<Index>{0, 2, 8}));
  // Too few layers along an axis: refused with the axis named.
  c[0].resize(1);
  try {
    (void)BlockPartition<2>::balanced(c, IVec<2>{2, 2}, "grid.cells");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1 cell layer(s) along x"), std::string::npos) << e.what();
  }
}

TEST(Particles, PackedParticlesRestoreEveryField) {
  Particles<3> a;
  a.resize(3);
  for (std::size_t i = 0; i < 3; ++i) {
    const double s = static_cast<double>(i) + 0.25;
    a.x[i] = Vec<3>(s, 2 * s, 3 * s);
    a.x0[i] = Vec<3>(-s, 0.5, 1.0);
    a.v[i] = Vec<3>(s * s, 0.0, -1.0);
    a.mass[i] = 1.5 * s;
    a.volume[i] = 0.1 * s;
    a.volume0[i] = 0.2 * s;
    a.F[i] = Mat<3>::Identity() * (1.0 + s);
    a.stress[i] = Mat<3>::Constant(s);
    a.body[i] = Vec<3>(0.0, -9.81, s);
  }
  std::vector<std::byte> buf;
  a.pack(2, buf);
  a.pack(0, buf);
  EXPECT_EQ(buf.size(), 2 * Particles<3>::bytes_per_particle(0));
  Particles<3> b;
  EXPECT_EQ(b.unpack_append(buf), buf.size());
  ASSERT_EQ(b.size(), 2);
  for (std::size_t k = 0; k < 2; ++k) {
    const std::size_t i = k == 0 ? 2 : 0;
    EXPECT_EQ(b.id[k], a.id[i]);
    EXPECT_EQ(b.x[k], a.x[i]);
    EXPECT_EQ(b.x0[k], a.x0[i]);
    EXPECT_EQ(b.v[k], a.v[i]);
    EXPECT_EQ(b.mass[k], a.mass[i]);
    EXPECT_EQ(b.volume[k], a.volume[i]);
    EXPECT_EQ(b.volume0[k], a.volume0[i]);
    EXPECT_EQ(b.F[k], a.F[i]);
    EXPECT_EQ(b.stress[k], a.stress[i]);
    EXPECT_EQ(b.body[k], a.body[i]);
  }
  // keep_with_ids keeps the ids of the whole body.
  a.keep_with_ids([](const Particles<3>&, std::size_t i) { return i != 1; });
  EXPECT_EQ(a.id, (std::vector<CompactIndex>{0, 2}));
}

TEST(Comm, OneProcessIsAPlainCopy) {
  const Comm& c = Comm::world();  // the test binary never starts MPI
  EXPECT_EQ(c.size(), 1);
  EXPECT_FALSE(c.distributed());
  EXPECT_EQ(c.sum(2.5), 2.5);
  EXPECT_EQ(c.max(-1.0), -1.0);
  const Index v[2] = {3, 4};
  EXPECT_EQ(c.allgather(std::span<const Index>(v)), (std::vector<Index>{3, 4}));
  EXPECT_FALSE(c.agree(nullptr).has_value());
  const Comm::Failure f{0, 4, "left the grid"};
  ASSERT_TRUE(c.agree(&f).has_value());
  EXPECT_EQ(c.agree(&f)->exit_code, 4);
  EXPECT_NO_THROW(c.check());
  EXPECT_TRUE(c.any(true));
}

// RunState::fit_dof_window (a distributed run's grid arrays: GridState's window) on a 10 x 40
// grid of linear functions (11 x 41 DOFs numbered x fastest, 11 per layer): the window holds the
// DOFs the particles' stencils touched and two layers either side, stays while it holds a layer
// either side and is not eight layers wider, keeps the values of the DOFs both windows hold, and
// is empty on a process without particles. On one process (no comm) it stays every DOF.
TEST(GridWindow, FollowsTheDofsOfTheParticles) {
  Particles<2> P;
  P.resize(1);
  RunState<2> sim(Grid<2>(Vec<2>(0.0, 0.0), Vec<2>(1.0, 4.0), IVec<2>{10, 40}), std::move(P),
                  NeoHookean{});
  sim.nodes.resize(11 * 41);
  auto& r = sim.scatter.ranges;
  const auto touch = [&](Index lo, Index hi) {
    r.particles = 1;
    r.lo[0] = lo;
    r.hi[0] = hi;
    sim.fit_dof_window();
  };
  using W = std::array<Index, 2>;
  touch(113, 225);  // no comm: one process, every DOF
  EXPECT_EQ(sim.nodes.window(), (W{0, 451}));
  sim.comm = &Comm::world();
  touch(113, 225);
  EXPECT_EQ(sim.nodes.window(), (W{113 - 22, 226 + 22}));
  sim.nodes.mass[200] = 7.0;
  sim.nodes.velocity[120] = Vec<2>(1.0, 2.0);
  touch(120, 230);  // within the margins: the same window and values
  EXPECT_EQ(sim.nodes.window(), (W{91, 248}));
  touch(125, 240);  // past the upper margin: moved, the values of both windows kept
  EXPECT_EQ(sim.nodes.window(), (W{125 - 22, 241 + 22}));
  EXPECT_EQ(sim.nodes.mass[200], 7.0);
  EXPECT_EQ(sim.nodes.velocity[120], Vec<2>(1.0, 2.0));
  EXPECT_EQ(sim.nodes.mass.size(), sim.nodes.velocity.size());
  touch(180, 190);  // much narrower (a re-cut of the slabs): shrunk
  EXPECT_EQ(sim.nodes.window(), (W{180 - 22, 191 + 22}));
  EXPECT_EQ(sim.nodes.mass[200], 7.0);
  touch(0, 20);  // at the grid's side: clipped
  EXPECT_EQ(sim.nodes.window(), (W{0, 21 + 22}));
  r.lo[0] = std::numeric_limits<Index>::max();  // no particle
  r.hi[0] = -1;
  sim.fit_dof_window();
  EXPECT_EQ(sim.nodes.window(), (W{0, 0}));
  EXPECT_EQ(sim.nodes.size(), 451);  // the basis's DOFs, whatever the window
}

TEST(Tractions, LoadedPointsFollowTheirParticlesById) {
  // Six particles with ids 0 .. 5 at set-up; this process holds ids 4, 1, 3 (in that order,
  // as after migrations). Two tractions name their points' particles by id.
  Particles<2> P;
  P.resize(3);
  P.id = {4, 1, 3};
  RunState<2> sim(Grid<2>(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{2, 2}), std::move(P),
                  NeoHookean{});
  Traction<2> a;
  a.direction = 0;
  a.side = 1;
  a.particles = {0, 1, 3, 5};
  a.area = {0.5, 1.5, 2.5, 3.5};
  a.offset = {Vec<2>(0, 0), Vec<2>(1, 0), Vec<2>(3, 0), Vec<2>(5, 0)};
  a.value = [](double t) { return Vec<2>(t, 0.0); };
  Traction<2> b;
  b.direction = 1;
  b.side = -1;
  b.particles = {2, 4};
  b.area = {7.0, 8.0};
  b.offset = {Vec<2>(0, 2), Vec<2>(0, 4)};
  sim.all_tractions = {a, b};
  localize_tractions(sim);
  ASSERT_EQ(sim.tractions.size(), 2u);
  // a: ids 1 and 3 are here, at indices 1 and 2, in a's order with their own data.
  EXPECT_EQ(sim.tractions[0].particles, (std::vector<Index>{1, 2}));
  EXPECT_EQ(sim.tractions[0].area, (std::vector<double>{1.5, 2.5}));
  EXPECT_EQ(sim.tractions[0].offset[1], Vec<2>(3, 0));
  EXPECT_EQ(sim.tractions[0].side, 1);
  EXPECT_EQ(sim.tractions[0].value(2.0), Vec<2>(2.0, 0.0));
  // b: id 4 only, at index 0.
  EXPECT_EQ(sim.tractions[1].particles, (std::vector<Index>{0}));
  EXPECT_EQ(sim.tractions[1].area, (std::vector<double>{8.0}));
  EXPECT_EQ(sim.tractions[1].direction, 1);
  // After a migration the lists follow: id 5 arrives, id 1 leaves.
  sim.particles.id = {4, 3, 5};
  localize_tractions(sim);
  EXPECT_EQ(sim.tractions[0].particles, (std::vector<Index>{1, 2}));
  EXPECT_EQ(sim.tractions[0].area, (std::vector<double>{2.5, 3.5}));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
