#pragma once
// Grid functions shared between the processes of a distributed run: each process
// holds the functions its particles touch, a range [lo, hi] of the grid's numbering, and adds
// its partial particle-to-grid sums to those of the processes whose ranges overlap it. Used for
// the grid sums (stages::share_grid_sums) and for the matrix-free operators of the
// distributed mass solvers (CG, p-multigrid: parallel/distributed_pmg.hpp), whose levels have
// their own numbering and ranges.
#include <algorithm>
#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "core/comm.hpp"

namespace mpm {

struct DofRanges {
  std::vector<Index> lo, hi;  // per rank; lo > hi: the rank touches none

  // [first, end) of `rank`'s range (empty when it touches none).
  std::array<Index, 2> window(int rank) const {
    const auto r = static_cast<std::size_t>(rank);
    return lo[r] <= hi[r] ? std::array<Index, 2>{lo[r], hi[r] + 1} : std::array<Index, 2>{0, 0};
  }
  // Whether `rank` counts function i in sums over functions (each counted once over the
  // ranks): the lowest rank whose range holds it.
  bool owns(int rank, Index i) const {
    for (std::size_t r = 0; r < static_cast<std::size_t>(rank); ++r)
      if (lo[r] <= i && i <= hi[r]) return false;
    return true;
  }
  // Every rank's range from its own (collective): `mine` = {lo, hi}.
  static DofRanges gather(const Comm& comm, std::array<Index, 2> mine) {
    const std::vector<Index> all = comm.allgather(std::span<const Index>(mine));
    DofRanges out;
    const auto n = static_cast<std::size_t>(comm.size());
    out.lo.resize(n);
    out.hi.resize(n);
    for (std::size_t r = 0; r < n; ++r) {
      out.lo[r] = all[2 * r];
      out.hi[r] = all[2 * r + 1];
    }
    return out;
  }
};

// Each rank's values on its range of `sh` summed with those of the ranks whose ranges overlap
// it: values(i, f) calls f(double&) on each of the `width` values of function i. Every rank that
// holds a function adds the same partial sums in the same (rank) order: the same bits
// everywhere. tag: the exchange's MPI tag.
template <class Values>
void sum_over_sharing_ranks(const Comm& comm, const DofRanges& sh, std::size_t width, int tag,
                            Values&& values) {
  const int me = comm.rank();
  const Index lo = sh.lo[static_cast<std::size_t>(me)], hi = sh.hi[static_cast<std::size_t>(me)];
  // The values of functions [a, b] as doubles, `width` per function.
  const auto pack = [&](Index a, Index b) {
    std::vector<std::byte> out(static_cast<std::size_t>(b - a + 1) * width * sizeof(double));
    auto* v = reinterpret_cast<double*>(out.data());
    for (Index i = a; i <= b; ++i) values(i, [&](double& x) { *v++ = x; });
    return out;
  };
  const auto overlap = [&](int r) {
    return std::array<Index, 2>{std::max(lo, sh.lo[static_cast<std::size_t>(r)]),
                                std::min(hi, sh.hi[static_cast<std::size_t>(r)])};
  };
  std::vector<int> peers;
  std::vector<std::vector<std::byte>> send;
  for (int r = 0; r < comm.size(); ++r) {
    const auto [a, b] = overlap(r);
    if (r == me || a > b) continue;
    peers.push_back(r);
    send.push_back(pack(a, b));
  }
  const auto recv = comm.exchange(peers, send, tag);
  if (lo > hi || peers.empty()) return;
  // Only the functions some other rank holds take the sum in rank order: the union of the
  // overlaps, as sorted disjoint intervals (with slabs, one at each end of the range). A function
  // no other rank holds keeps its value, which is its sum (packing, zeroing and adding the whole
  // range would copy it per exchange, and 0 + x would turn a -0 into +0).
  std::vector<std::array<Index, 2>> both;
  for (int r : peers) both.push_back(overlap(r));
  std::sort(both.begin(), both.end());
  std::size_t m = 0;
  for (std::size_t k = 1; k < both.size(); ++k) {
    if (both[k][0] <= both[m][1] + 1)
      both[m][1] = std::max(both[m][1], both[k][1]);
    else
      both[++m] = both[k];
  }
  both.resize(m + 1);
  std::vector<std::vector<std::byte>> own;
  for (const auto& [a, b] : both) {
    own.push_back(pack(a, b));
    for (Index i = a; i <= b; ++i) values(i, [](double& x) { x = 0.0; });
  }
  std::size_t next = 0;
  for (int r = 0; r < comm.size(); ++r) {
    if (r == me) {
      for (std::size_t k = 0; k < both.size(); ++k) {
        const auto* v = reinterpret_cast<const double*>(own[k].data());
        for (Index i = both[k][0]; i <= both[k][1]; ++i) values(i, [&](double& x) { x += *v++; });
      }
      continue;
    }
    if (next >= peers.size() || peers[next] != r) continue;
    const auto [a, b] = overlap(r);
    const auto* v = reinterpret_cast<const double*>(recv[next++].data());
    for (Index i = a; i <= b; ++i) values(i, [&](double& x) { x += *v++; });
  }
}

}  // namespace mpm
