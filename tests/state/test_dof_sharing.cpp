// The DOFs two processes share (state/dof_sharing.hpp): with boxes of DOF coordinates, the DOFs
// both hold are the intersection of their boxes cut to their ranges, listed in DOF order and the
// same from either side; each DOF one process or more holds is owned by exactly one, the lowest
// that holds it; 2x2 blocks share a face with a neighbour and a corner across the diagonal, not
// the whole rows their ranges span. The box of a compact tensor-product stencil
// (basis/stencil.hpp) is that of its expanded DOFs. The exchange itself runs in mpi_check's
// block cases (answers of one process to 1e-12).
#include <gtest/gtest.h>

#include <array>
#include <random>
#include <vector>

#include "basis/bspline.hpp"
#include "state/dof_sharing.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// Ranks with boxes [lo, hi] (one array of per-direction values per rank) of a layout with `n`
// DOFs per direction, each rank's range from its box's first to its last DOF.
template <int Dim>
DofRanges boxes(const IVec<Dim>& n, const std::vector<std::array<IVec<Dim>, 2>>& box) {
  DofRanges sh;
  sh.axes = Dim;
  Index s = 1;
  for (int d = 0; d < Dim; ++d) {
    sh.stride[static_cast<std::size_t>(d)] = s;
    s *= n[static_cast<std::size_t>(d)];
  }
  for (const auto& [lo, hi] : box) {
    Index first = 0, last = 0;
    for (int d = 0; d < Dim; ++d) {
      const auto k = static_cast<std::size_t>(d);
      first += lo[k] * sh.stride[k];
      last += hi[k] * sh.stride[k];
      sh.box_lo.push_back(lo[k]);
      sh.box_hi.push_back(hi[k]);
    }
    sh.lo.push_back(first);
    sh.hi.push_back(last);
  }
  return sh;
}

// Every pair of ranks: for_each_shared lists, in DOF order and the same from both sides, exactly
// the DOFs both hold (a brute-force pass over all `count` DOFs); every DOF some rank holds has
// one owner, the lowest rank that holds it. Returns the shared counts per pair.
std::vector<std::vector<Index>> check_sharing(const DofRanges& sh, Index count) {
  const auto ranks = static_cast<int>(sh.lo.size());
  std::vector<std::vector<Index>> shared(static_cast<std::size_t>(ranks),
                                         std::vector<Index>(static_cast<std::size_t>(ranks), 0));
  for (int a = 0; a < ranks; ++a)
    for (int b = 0; b < ranks; ++b) {
      std::vector<Index> listed, reverse, expected;
      sh.for_each_shared(a, b, [&](Index i) { listed.push_back(i); });
      sh.for_each_shared(b, a, [&](Index i) { reverse.push_back(i); });
      for (Index i = 0; i < count; ++i)
        if (sh.holds(a, i) && sh.holds(b, i)) expected.push_back(i);
      EXPECT_EQ(listed, expected) << "ranks " << a << ", " << b;
      EXPECT_EQ(listed, reverse) << "ranks " << a << ", " << b;
      shared[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)] =
          static_cast<Index>(listed.size());
    }
  // shared_by_peer: the peers that share any DOF, ascending, each with for_each_shared's list;
  // union_of: the DOFs a rank holds that some other rank holds too, once each, ascending.
  for (int a = 0; a < ranks; ++a) {
    const auto by_peer = sh.shared_by_peer(a);
    std::vector<int> peers;
    for (const auto& [b, dofs] : by_peer) {
      peers.push_back(b);
      EXPECT_EQ(static_cast<Index>(dofs.size()),
                shared[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)]);
    }
    std::vector<int> expected_peers;
    std::vector<Index> expected_union;
    for (int b = 0; b < ranks; ++b)
      if (b != a && shared[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)] > 0)
        expected_peers.push_back(b);
    for (Index i = 0; i < count; ++i) {
      bool other = false;
      for (int b = 0; b < ranks; ++b) other = other || (b != a && sh.holds(b, i));
      if (sh.holds(a, i) && other) expected_union.push_back(i);
    }
    EXPECT_EQ(peers, expected_peers) << "rank " << a;
    EXPECT_EQ(DofRanges::union_of(by_peer), expected_union) << "rank " << a;
  }
  for (Index i = 0; i < count; ++i) {
    int owners = 0, lowest = -1;
    for (int r = ranks - 1; r >= 0; --r)
      if (sh.holds(r, i)) lowest = r;
    for (int r = 0; r < ranks; ++r) owners += sh.owns(r, i) ? 1 : 0;
    EXPECT_EQ(owners, lowest >= 0 ? 1 : 0) << "DOF " << i;
    if (lowest >= 0) {
      EXPECT_TRUE(sh.owns(lowest, i)) << "DOF " << i;
    }
  }
  return shared;
}

TEST(DofSharing, BlocksShareFacesAndCornersNotRows2D) {
  // 12 x 9 DOFs; 2 x 2 blocks whose boxes overlap by two DOFs along each direction.
  const IVec<2> n{12, 9};
  const DofRanges sh = boxes<2>(
      n, {{{{0, 0}, {6, 5}}}, {{{5, 0}, {11, 5}}}, {{{0, 4}, {6, 8}}}, {{{5, 4}, {11, 8}}}});
  const auto shared = check_sharing(sh, n[0] * n[1]);
  EXPECT_EQ(shared[0][0], 7 * 6);
  EXPECT_EQ(shared[0][1], 2 * 6);  // a face
  EXPECT_EQ(shared[0][2], 7 * 2);
  EXPECT_EQ(shared[0][3], 2 * 2);  // a corner
  EXPECT_EQ(shared[1][2], 2 * 2);
  // By ranges alone, ranks 0 and 1 would share every DOF from the first of rank 1 (5, 0) to the
  // last of rank 0 (6, 5): 62 DOFs over six rows.
  EXPECT_EQ(sh.hi[0] - sh.lo[1] + 1, 62);
}

TEST(DofSharing, RangesCutTheBoxes) {
  // A range narrower than its box (a rank whose stencils start and end mid-row): only the DOFs
  // in both count.
  const IVec<2> n{10, 6};
  DofRanges sh = boxes<2>(n, {{{{0, 0}, {5, 5}}}, {{{4, 0}, {9, 5}}}, {{{2, 2}, {7, 4}}}});
  sh.lo[1] = 4 + 2 * 10 + 3;  // (7, 2)
  sh.hi[2] = 3 + 4 * 10;      // (3, 4)
  const auto shared = check_sharing(sh, n[0] * n[1]);
  EXPECT_LT(shared[0][1], 2 * 6);
  EXPECT_GT(shared[0][1], 0);
}

TEST(DofSharing, BlocksShareFacesEdgesAndCorners3D) {
  const IVec<3> n{5, 4, 6};
  std::vector<std::array<IVec<3>, 2>> box;
  for (Index k = 0; k < 2; ++k)
    for (Index j = 0; j < 2; ++j)
      for (Index i = 0; i < 2; ++i)
        box.push_back({{{i * 2, j * 2, k * 3}, {i * 2 + 2, j * 2 + 1, k * 3 + 2}}});
  box[5][0][2] = 2;  // one block reaching one layer further down: it meets more
  const DofRanges sh = boxes<3>(n, box);
  const auto shared = check_sharing(sh, n[0] * n[1] * n[2]);
  EXPECT_EQ(shared[0][1], 1 * 2 * 3);  // a face normal to x
  EXPECT_EQ(shared[0][2], 0);          // blocks side by side along y that do not overlap
  EXPECT_EQ(shared[0][4], 0);
  EXPECT_EQ(shared[0][5], 1 * 2 * 1);
}

TEST(DofSharing, RangesAloneWithoutALayout) {
  DofRanges sh;
  sh.lo = {0, 40, 90, 10};
  sh.hi = {49, 99, 89, 20};  // rank 2 holds none
  const auto shared = check_sharing(sh, 100);
  EXPECT_EQ(shared[0][1], 10);
  EXPECT_EQ(shared[0][3], 11);
  EXPECT_EQ(shared[2][0], 0);
  EXPECT_EQ(shared[1][3], 0);
}

// The box of the compact stencil that evaluate_basis caches is that of the full stencil's DOFs.
template <int Dim, int Degree>
void expect_compact_box_is_the_full_one(const Grid<Dim>& g) {
  const BSplineBasis<Dim, Degree> basis(g);
  const IVec<Dim> stride = dof_strides<Dim>(basis.dofs_per_dim());
  std::mt19937 rng(7);
  for (int k = 0; k < 50; ++k) {
    Particles<Dim> P;
    P.resize(1);
    for (int d = 0; d < Dim; ++d)
      P.x[0][d] = std::uniform_real_distribution<double>(g.origin[d], g.upper()[d])(rng);
    typename BSplineBasis<Dim, Degree>::StencilT full;
    typename BSplineBasis<Dim, Degree>::CachedStencilT compact;
    basis.evaluate(P, 0, full);
    basis.evaluate(P, 0, compact);
    IVec<Dim> lo, hi, flo, fhi;
    lo.fill(1 << 30);
    hi.fill(-1);
    flo = lo;
    fhi = hi;
    extend_dof_box(compact, stride, lo, hi);
    extend_dof_box(full, stride, flo, fhi);
    EXPECT_EQ(lo, flo);
    EXPECT_EQ(hi, fhi);
    for (int d = 0; d < Dim; ++d) EXPECT_EQ(hi[d] - lo[d], Degree);
  }
}

TEST(DofSharing, CompactStencilBoxIsTheFullStencils) {
  expect_compact_box_is_the_full_one<2, 2>(Grid<2>(Vec<2>(-0.3, 0.2), Vec<2>(1.7, 1.4), {7, 5}));
  expect_compact_box_is_the_full_one<3, 3>(
      Grid<3>(Vec<3>(-0.3, 0.2, 1.0), Vec<3>(1.7, 1.4, 2.5), {7, 5, 4}));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
