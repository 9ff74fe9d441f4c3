// What a distributed TLS run (issue 21) relies on: the fits do not depend on the order of the
// particles in memory (ties in the neighbour completion go by particle id), and a reconstruction
// reports only the elements it was told to (set_focus), so that the processes' reports add up to
// the whole grid's. The runs on several processes are checked in Mpi.SameAnswersAsOneProcess.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "grid/grid.hpp"
#include "mapping/tls.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// Three unit cells on [0, 3]: the middle one holds two points (too few for the 3 quadratic
// terms), and its neighbours one point each, both 0.5 from it: the completion borrows one of two
// equally near points, and the fit is well posed after the first.
struct TiedLayout {
  Grid<1> grid{Vec<1>(0.0), Vec<1>(3.0), IVec<1>{3}};
  std::array<double, 4> x{0.5, 1.3, 1.7, 2.5};  // by id
  std::array<double, 4> f{1.0, 2.0, 5.0, -1.0};

  // The particles in memory in the order `order` (ids), and their values in that order.
  Particles<1> particles(const std::array<int, 4>& order, std::vector<double>& values) const {
    Particles<1> P;
    P.resize(4);
    values.clear();
    for (std::size_t k = 0; k < 4; ++k) {
      const auto id = static_cast<std::size_t>(order[k]);
      P.x[k] = Vec<1>(x[id]);
      P.id[k] = static_cast<CompactIndex>(id);
      values.push_back(f[id]);
    }
    return P;
  }
};

TlsSettings neighbour_settings() {
  TlsSettings s;
  s.terms = 3;
  s.completion = TlsCompletion::Neighbour;
  return s;
}

TEST(TlsNeighbourCompletion, TiesGoByParticleIdNotByMemoryOrder) {
  const TiedLayout L;
  std::vector<TlsCoefficients> fits;
  for (const auto& order : {std::array<int, 4>{0, 1, 2, 3}, std::array<int, 4>{3, 2, 1, 0},
                            std::array<int, 4>{3, 1, 2, 0}}) {
    std::vector<double> f;
    const Particles<1> P = L.particles(order, f);
    TlsReconstruction r(neighbour_settings());
    const TlsReport& rep = r.set_points(L.grid, P);
    ASSERT_EQ(rep.failed, 0);
    EXPECT_EQ(r.element(1).borrowed, 1);  // one of the two tied points was enough
    TlsCoefficients a;
    r.fit_plain(f, a);
    fits.push_back(a);
  }
  for (std::size_t k = 1; k < fits.size(); ++k)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(fits[k][1][j], fits[0][1][j], 1e-13) << k << " " << j;
  // The borrowed point is the lower id's (x = 0.5, f = 1): the quadratic through (0.5, 1),
  // (1.3, 2), (1.7, 5), not through (2.5, -1).
  TlsReconstruction r(neighbour_settings());
  std::vector<double> f;
  r.set_points(L.grid, L.particles({0, 1, 2, 3}, f));
  EXPECT_NEAR(r.evaluate(fits[0], 1, 0.5), 1.0, 1e-12);
  EXPECT_GT(std::abs(r.evaluate(fits[0], 1, 2.5) + 1.0), 0.1);
}

TEST(TlsReconstruction, ReportsOnlyTheElementsOfItsFocus) {
  const TiedLayout L;
  std::vector<double> f;
  const Particles<1> P = L.particles({0, 1, 2, 3}, f);
  TlsReconstruction all(neighbour_settings());
  const TlsReport whole = all.set_points(L.grid, P);
  EXPECT_EQ(whole.active, 3);
  // The processes owning cells [0, 1) and [1, 3) report parts that add up to the whole, and
  // fit every element with points all the same.
  Index active = 0, neighbours = 0;
  for (const std::array<Index, 2> focus : {std::array<Index, 2>{0, 1}, {1, 3}}) {
    TlsReconstruction part(neighbour_settings());
    CellBox<1> box = L.grid.all_cells();
    box.lo[0] = focus[0];
    box.hi[0] = focus[1];
    part.set_focus(box);
    const TlsReport& rep = part.set_points(L.grid, P);
    EXPECT_EQ(rep.active, focus[1] - focus[0]);
    active += rep.active;
    neighbours += rep.with_neighbours;
    for (Index e = 0; e < 3; ++e) EXPECT_GT(part.element(e).terms, 0);
  }
  EXPECT_EQ(active, whole.active);
  EXPECT_EQ(neighbours, whole.with_neighbours);
  // On one process the combination is the report itself.
  EXPECT_EQ(over_ranks(Comm::world(), whole).active, whole.active);
}

// Four processes on 2 x 2 blocks of a 4 x 4 grid with three points in every element: each
// reports its block's four elements alone (the linear span of a block holds two elements of the
// block beside it), and the four reports add up to the whole grid's.
TEST(TlsReconstruction, ReportsOnlyTheElementsOfABlockFocus) {
  const Grid<2> grid(Vec<2>(0.0, 0.0), Vec<2>(4.0, 4.0), IVec<2>{4, 4});
  std::vector<Vec<2>> x;
  for (Index e = 0; e < grid.num_cells(); ++e) {
    const IVec<2> c = grid.cell_coords(e);
    for (const auto& [dx, dy] : {std::array<double, 2>{0.2, 0.7}, {0.5, 0.3}, {0.8, 0.6}})
      x.emplace_back(static_cast<double>(c[0]) + dx, static_cast<double>(c[1]) + dy);
  }
  TlsSettings s;
  s.terms = 3;
  TlsReconstruction2D all(s);
  const TlsReport whole = all.set_points(grid, x);
  ASSERT_EQ(whole.active, 16);
  Index active = 0, full = 0;
  for (Index bx = 0; bx < 2; ++bx)
    for (Index by = 0; by < 2; ++by) {
      CellBox<2> box = grid.all_cells();
      box.lo = {2 * bx, 2 * by};
      box.hi = {2 * bx + 2, 2 * by + 2};
      TlsReconstruction2D part(s);
      part.set_focus(box);
      const TlsReport& rep = part.set_points(grid, x);
      EXPECT_EQ(rep.active, 4) << bx << " " << by;
      active += rep.active;
      full += rep.full;
    }
  EXPECT_EQ(active, whole.active);
  EXPECT_EQ(full, whole.full);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
