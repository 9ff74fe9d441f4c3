#pragma once
// Grid functions shared between the processes of a distributed run: each process
// holds the functions its particles touch, a range [lo, hi] of the grid's numbering and, for a
// tensor-product layout, a box of DOF coordinates (so that blocks side by side share their
// faces, not the whole rows a range spans), and adds its partial particle-to-grid sums to those
// of the processes that hold the same functions. Used for
// the grid sums (stages::share_grid_sums) and for the matrix-free operators of the
// distributed mass solvers (CG, p-multigrid: parallel/distributed_pmg.hpp), whose levels have
// their own numbering and ranges.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstring>
#include <span>
#include <utility>
#include <vector>

#include "core/comm.hpp"

namespace mpm {

struct DofRanges {
  std::vector<Index> lo, hi;  // per rank; lo > hi: the rank touches none
  // A tensor-product layout (axes > 0): each rank holds the DOFs of its range that lie in its
  // box of DOF coordinates too, box_lo/box_hi[axes r + d] along direction d (x first), the
  // coordinates of DOF i those of the layout with strides `stride` (x fastest). axes = 0: the
  // ranges alone (the triangle layouts, the levels of the distributed p-multigrid).
  int axes = 0;
  std::array<Index, 3> stride{};
  std::vector<Index> box_lo, box_hi;

  // [first, end) of `rank`'s range (empty when it touches none).
  std::array<Index, 2> window(int rank) const {
    const auto r = static_cast<std::size_t>(rank);
    return lo[r] <= hi[r] ? std::array<Index, 2>{lo[r], hi[r] + 1} : std::array<Index, 2>{0, 0};
  }
  // The coordinates of DOF i along each of the `axes` directions.
  std::array<Index, 3> coords(Index i) const {
    std::array<Index, 3> c{};
    for (int d = axes - 1; d > 0; --d) {
      c[static_cast<std::size_t>(d)] = i / stride[static_cast<std::size_t>(d)];
      i -= c[static_cast<std::size_t>(d)] * stride[static_cast<std::size_t>(d)];
    }
    c[0] = i;
    return c;
  }
  // Whether `rank` holds DOF i (c: coords(i), or anything when axes = 0).
  bool holds(int rank, Index i, const std::array<Index, 3>& c) const {
    const auto r = static_cast<std::size_t>(rank);
    if (i < lo[r] || i > hi[r]) return false;
    for (int d = 0; d < axes; ++d) {
      const auto k = r * static_cast<std::size_t>(axes) + static_cast<std::size_t>(d);
      if (c[static_cast<std::size_t>(d)] < box_lo[k] || c[static_cast<std::size_t>(d)] > box_hi[k])
        return false;
    }
    return true;
  }
  bool holds(int rank, Index i) const { return holds(rank, i, coords(i)); }
  // Whether `rank` counts function i in sums over functions (each counted once over the
  // ranks): the lowest rank that holds it.
  bool owns(int rank, Index i) const {
    const auto c = coords(i);
    if (!holds(rank, i, c)) return false;
    for (int r = 0; r < rank; ++r)
      if (holds(r, i, c)) return false;
    return true;
  }
  // f(i) for every DOF that ranks a and b both hold, ascending.
  template <class F>
  void for_each_shared(int a, int b, F&& f) const {
    const auto ra = static_cast<std::size_t>(a), rb = static_cast<std::size_t>(b);
    const Index first = std::max(lo[ra], lo[rb]), last = std::min(hi[ra], hi[rb]);
    if (first > last) return;
    if (axes == 0) {
      for (Index i = first; i <= last; ++i) f(i);
      return;
    }
    std::array<Index, 3> from{}, to{};  // the boxes' intersection
    for (int d = 0; d < axes; ++d) {
      const auto ka = ra * static_cast<std::size_t>(axes) + static_cast<std::size_t>(d);
      const auto kb = rb * static_cast<std::size_t>(axes) + static_cast<std::size_t>(d);
      from[static_cast<std::size_t>(d)] = std::max(box_lo[ka], box_lo[kb]);
      to[static_cast<std::size_t>(d)] = std::min(box_hi[ka], box_hi[kb]);
      if (from[static_cast<std::size_t>(d)] > to[static_cast<std::size_t>(d)]) return;
    }
    // Rows along x, in DOF order, each cut to [first, last].
    for (Index z = from[2]; z <= (axes > 2 ? to[2] : 0); ++z)
      for (Index y = from[1]; y <= (axes > 1 ? to[1] : 0); ++y) {
        const Index row = y * stride[1] + z * stride[2];
        const Index i0 = std::max(first, row + from[0]), i1 = std::min(last, row + to[0]);
        for (Index i = i0; i <= i1; ++i) f(i);
      }
  }
  // The DOFs `rank` shares with each other rank that shares any: (peer, its DOFs ascending),
  // peers ascending.
  std::vector<std::pair<int, std::vector<Index>>> shared_by_peer(int rank) const {
    std::vector<std::pair<int, std::vector<Index>>> out;
    for (int r = 0; r < static_cast<int>(lo.size()); ++r) {
      if (r == rank) continue;
      std::vector<Index> dofs;
      for_each_shared(rank, r, [&](Index i) { dofs.push_back(i); });
      if (!dofs.empty()) out.emplace_back(r, std::move(dofs));
    }
    return out;
  }
  // Every DOF of `by_peer` (shared_by_peer) once, ascending: with slabs a segment at each end of
  // a range; with blocks a box's faces, edges and corners.
  static std::vector<Index> union_of(
      const std::vector<std::pair<int, std::vector<Index>>>& by_peer) {
    std::vector<Index> all;
    for (const auto& [r, dofs] : by_peer) all.insert(all.end(), dofs.begin(), dofs.end());
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    return all;
  }
  // Every rank's range from its own (collective): `mine` = {lo, hi}.
  static DofRanges gather(const Comm& comm, std::array<Index, 2> mine) {
    return gather(comm, mine, {}, {}, {});
  }
  // Every rank's range and box from its own (collective): a layout with strides `strides`
  // (one per direction, x fastest, at most three), this rank's box [box_lo, box_hi].
  static DofRanges gather(const Comm& comm, std::array<Index, 2> mine,
                          std::span<const Index> strides, std::span<const Index> mine_lo,
                          std::span<const Index> mine_hi) {
    DofRanges out;
    out.axes = static_cast<int>(strides.size());
    std::copy(strides.begin(), strides.end(), out.stride.begin());
    std::vector<Index> send(mine.begin(), mine.end());
    send.insert(send.end(), mine_lo.begin(), mine_lo.end());
    send.insert(send.end(), mine_hi.begin(), mine_hi.end());
    const std::vector<Index> all = comm.allgather(std::span<const Index>(send));
    const auto n = static_cast<std::size_t>(comm.size()), w = send.size();
    const auto axes = static_cast<std::size_t>(out.axes);
    out.lo.resize(n);
    out.hi.resize(n);
    out.box_lo.resize(n * axes);
    out.box_hi.resize(n * axes);
    for (std::size_t r = 0; r < n; ++r) {
      out.lo[r] = all[w * r];
      out.hi[r] = all[w * r + 1];
      for (std::size_t d = 0; d < axes; ++d) {
        out.box_lo[r * axes + d] = all[w * r + 2 + d];
        out.box_hi[r * axes + d] = all[w * r + 2 + axes + d];
      }
    }
    return out;
  }
};

// Each rank's values on the functions it holds in `sh` summed with those of the other ranks
// that hold them: values(i, f) calls f(double&) on each of the `width` values of function i. Every
// rank that holds a function adds the same partial sums in the same (rank) order: the same bits
// everywhere. tag: the exchange's MPI tag.
template <class Values>
void sum_over_sharing_ranks(const Comm& comm, const DofRanges& sh, std::size_t width, int tag,
                            Values&& values) {
  // The functions this rank and each peer both hold, in DOF order (the same order on both
  // sides); their values travel as doubles, `width` per function.
  const auto by_peer = sh.shared_by_peer(comm.rank());
  std::vector<int> peers;
  std::vector<std::vector<std::byte>> send;
  for (const auto& [r, dofs] : by_peer) {
    peers.push_back(r);
    auto& out = send.emplace_back(dofs.size() * width * sizeof(double));
    std::byte* v = out.data();
    for (const Index i : dofs)
      values(i, [&](double& x) {
        std::memcpy(v, &x, sizeof(double));
        v += sizeof(double);
      });
  }
  const auto recv = comm.exchange(peers, send, tag);
  if (peers.empty()) return;
  // Only the functions some other rank holds take the sum in rank order: the union of what this
  // rank shares with each peer. A function no other rank holds keeps its value, which is its sum
  // (packing, zeroing and adding the whole range would copy it per exchange, and 0 + x would
  // turn a -0 into +0).
  const std::vector<Index> both = DofRanges::union_of(by_peer);
  std::vector<double> own;
  own.reserve(both.size() * width);
  for (const Index i : both)
    values(i, [&](double& x) {
      own.push_back(x);
      x = 0.0;
    });
  const int me = comm.rank();
  bool own_added = false;
  const auto add_own = [&] {
    const double* v = own.data();
    for (const Index i : both) values(i, [&](double& x) { x += *v++; });
    own_added = true;
  };
  for (std::size_t k = 0; k < by_peer.size(); ++k) {
    if (!own_added && by_peer[k].first > me) add_own();
    const std::byte* v = recv[k].data();
    for (const Index i : by_peer[k].second)
      values(i, [&](double& x) {
        double y;
        std::memcpy(&y, v, sizeof(double));
        v += sizeof(double);
        x += y;
      });
  }
  if (!own_added) add_own();
}

}  // namespace mpm
