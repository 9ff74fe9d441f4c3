#include "parallel/distribution.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <span>
#include <stdexcept>

namespace mpm {

template <int Dim>
int SlabPartition<Dim>::owner_of_layer(Index layer) const {
  // The last cut at or below the layer.
  const auto it = std::upper_bound(cuts.begin(), cuts.end(), layer);
  return std::clamp(static_cast<int>(it - cuts.begin()) - 1, 0, ranks() - 1);
}

template <int Dim>
int SlabPartition<Dim>::owner(const Grid<Dim>& grid, const Vec<Dim>& x, int current) const {
  const Index layer = grid.last_layer(x);
  return layer < 0 ? current : owner_of_layer(layer);
}

template <int Dim>
SlabPartition<Dim> SlabPartition<Dim>::balanced(const std::vector<double>& per_layer, int ranks,
                                                const std::string& where) {
  const auto layers = static_cast<Index>(per_layer.size());
  if (layers < ranks)
    throw InputError(fmt::format(
        "{}: the grid has {} cell layer(s) along {} and this run {} processes; a process owns "
        "whole layers (a slab), so use more cells along {} or fewer processes",
        where, layers, axis_name(), ranks, axis_name()));
  double total = 0.0;
  for (double c : per_layer) total += c;
  SlabPartition p;
  p.cuts.assign(static_cast<std::size_t>(ranks) + 1, 0);
  p.cuts.back() = layers;
  // Cut r after the layer where the running count first reaches r / ranks of the particles,
  // keeping at least one layer for each rank on either side.
  double running = 0.0;
  Index layer = 0;
  for (int r = 1; r < ranks; ++r) {
    const double target = total * static_cast<double>(r) / static_cast<double>(ranks);
    while (layer < layers && running + per_layer[static_cast<std::size_t>(layer)] <= target) {
      running += per_layer[static_cast<std::size_t>(layer)];
      ++layer;
    }
    const Index lowest = p.cuts[static_cast<std::size_t>(r) - 1] + 1;
    const Index highest = layers - (ranks - r);
    const Index cut = std::clamp(layer, lowest, highest);
    p.cuts[static_cast<std::size_t>(r)] = cut;
    while (layer < cut) running += per_layer[static_cast<std::size_t>(layer++)];
  }
  return p;
}

template <int Dim>
std::vector<double> SlabPartition<Dim>::layer_counts(const Grid<Dim>& grid, const Particles<Dim>& P,
                                                     const Comm& comm, bool replicated) {
  std::vector<double> count(static_cast<std::size_t>(grid.cells[kAxis]), 0.0);
  for (const auto& x : P.x)
    if (const Index c = grid.last_layer(x); c >= 0) count[static_cast<std::size_t>(c)] += 1.0;
  if (!replicated) comm.sum(std::span<double>(count));
  return count;
}

template <int Dim>
void pack_particle(const RunState<Dim>& sim, std::size_t i, std::vector<std::byte>& out) {
  sim.particles.pack(i, out);
  const std::size_t at = out.size();
  const auto w = static_cast<std::size_t>(sim.carried_width);
  out.resize(at + sizeof(CompactIndex) + w * sizeof(double));
  std::memcpy(out.data() + at, &sim.cell[i], sizeof(CompactIndex));
  if (w > 0)
    std::memcpy(out.data() + at + sizeof(CompactIndex), sim.carried.data() + i * w,
                w * sizeof(double));
}

template <int Dim>
void unpack_particles(std::span<const std::byte> in, Particles<Dim>& P,
                      std::vector<CompactIndex>& cells, std::vector<double>& carried, int width) {
  const std::size_t kParticle = P.record_bytes();
  const auto w = static_cast<std::size_t>(width);
  const std::size_t record = kParticle + sizeof(CompactIndex) + w * sizeof(double);
  for (std::size_t at = 0; at + record <= in.size(); at += record) {
    P.unpack_append(in.subspan(at, kParticle));
    CompactIndex c;
    std::memcpy(&c, in.data() + at + kParticle, sizeof(CompactIndex));
    cells.push_back(c);
    const std::size_t k = carried.size();
    carried.resize(k + w);
    if (w > 0)
      std::memcpy(carried.data() + k, in.data() + at + kParticle + sizeof(CompactIndex),
                  w * sizeof(double));
  }
}

template <int Dim>
Index migrate(RunState<Dim>& sim, const SlabPartition<Dim>& part, const Comm& comm) {
  comm.check();
  auto& P = sim.particles;
  const int me = comm.rank();
  const auto n = static_cast<std::size_t>(P.size());
  if (sim.carried.size() != n * static_cast<std::size_t>(sim.carried_width))
    throw std::logic_error("migrate: the basis's carried state was not exported");
  std::vector<int> owner(n);
  Index leaving = 0;
  for (std::size_t i = 0; i < n; ++i) {
    owner[i] = part.owner(sim.grid, P.x[i], me);
    leaving += owner[i] != me;
  }
  std::vector<std::vector<std::byte>> send(static_cast<std::size_t>(comm.size()));
  for (std::size_t i = 0; i < n; ++i) {
    if (owner[i] == me) continue;
    pack_particle(sim, i, send[static_cast<std::size_t>(owner[i])]);
  }
  // A particle moves less than a cell per step (the time-step limit), so it goes to a
  // neighbouring slab: one message to each neighbour. After the slabs were cut anew, or should a
  // particle jump further, every rank exchanges with every other (all ranks decide alike). The
  // arrivals are in source-rank order either way, so the result is the same.
  bool far = false;
  for (std::size_t i = 0; i < n; ++i) far = far || std::abs(owner[i] - me) > 1;
  std::vector<std::vector<std::byte>> recv;
  if (comm.any(far)) {
    recv = comm.alltoall(send);
  } else {
    std::vector<int> peers;
    std::vector<std::vector<std::byte>> out;
    for (const int r : {me - 1, me + 1})
      if (r >= 0 && r < comm.size()) {
        peers.push_back(r);
        out.push_back(std::move(send[static_cast<std::size_t>(r)]));
      }
    recv = comm.exchange(peers, out, 300);
  }
  if (leaving > 0) {
    const auto w = static_cast<std::size_t>(sim.carried_width);
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (owner[i] == me) {
        for (std::size_t j = 0; j < w; ++j) sim.carried[k * w + j] = sim.carried[i * w + j];
        sim.cell[k++] = sim.cell[i];
      }
    sim.cell.resize(k);
    sim.carried.resize(k * w);
    P.keep_with_ids([&](const Particles<Dim>&, std::size_t i) { return owner[i] == me; });
  }
  for (const auto& buf : recv) unpack_particles(buf, P, sim.cell, sim.carried, sim.carried_width);
  return leaving;
}

template <int Dim>
void append_ghosts(RunState<Dim>& sim, const Comm& comm, double reach) {
  comm.check();
  remove_ghosts(sim);
  constexpr int kAxis = Dim - 1;
  auto& P = sim.particles;
  const auto n = static_cast<std::size_t>(P.size());
  const Index top = sim.grid.cells[kAxis] - 1;
  std::vector<Index> layer(n);
  Index lo = std::numeric_limits<Index>::max(), hi = -1;
  for (std::size_t i = 0; i < n; ++i) {
    // (A particle outside the grid has stopped the run at the basis evaluation before this.)
    layer[i] = std::clamp(sim.grid.cell_of(P.x[i][kAxis], kAxis), Index{0}, top);
    lo = std::min(lo, layer[i]);
    hi = std::max(hi, layer[i]);
  }
  sim.ghosts.layers = {lo, hi};
  // Each process's layers and reach in one all-gather (layer indices are exact as doubles).
  const std::array<double, 3> mine{static_cast<double>(lo), static_cast<double>(hi), reach};
  const std::vector<double> gathered = comm.allgather(std::span<const double>(mine));
  std::vector<Index> all;
  double most = 0.0;
  for (std::size_t k = 0; k < gathered.size(); k += 3) {
    all.push_back(static_cast<Index>(gathered[k]));
    all.push_back(static_cast<Index>(gathered[k + 1]));
    most = std::max(most, gathered[k + 2]);
  }
  const auto layers = static_cast<Index>(std::ceil(most));
  const int me = comm.rank();
  auto& gh = sim.ghosts;
  std::vector<int>& peers = gh.peers;
  std::vector<std::vector<std::byte>> send;
  if (lo <= hi)
    for (int r = 0; r < comm.size(); ++r) {
      const Index rlo = all[2 * static_cast<std::size_t>(r)],
                  rhi = all[2 * static_cast<std::size_t>(r) + 1];
      // The gap between the two processes' layers (1: adjacent), the same seen from either.
      if (r == me || rlo > rhi || std::max(rlo - hi, lo - rhi) > layers) continue;
      peers.push_back(r);
      auto& out = send.emplace_back();
      auto& sent = gh.sent.emplace_back();
      for (std::size_t i = 0; i < n; ++i)
        if (layer[i] >= rlo - layers && layer[i] <= rhi + layers) {
          P.pack(i, out);
          sent.push_back(static_cast<Index>(i));
        }
    }
  const auto recv = comm.exchange(peers, send, 400);
  gh.owned = static_cast<Index>(n);
  for (const auto& buf : recv) {
    const Index before = P.size();
    P.unpack_append(buf);
    gh.received.push_back(P.size() - before);
  }
}

template <int Dim>
void add_ghost_values_to_owners(const RunState<Dim>& sim, const Comm& comm,
                                std::span<double> values, std::size_t width) {
  comm.check();
  const auto& gh = sim.ghosts;
  if (gh.owned < 0 || values.size() != static_cast<std::size_t>(sim.particles.size()) * width)
    throw std::logic_error("add_ghost_values_to_owners: values of the particles with ghosts");
  std::vector<std::vector<std::byte>> send(gh.peers.size());
  auto at = static_cast<std::size_t>(gh.owned);
  for (std::size_t k = 0; k < gh.peers.size(); ++k) {
    const std::size_t count = static_cast<std::size_t>(gh.received[k]) * width;
    send[k].resize(count * sizeof(double));
    std::memcpy(send[k].data(), values.data() + at * width, count * sizeof(double));
    at += static_cast<std::size_t>(gh.received[k]);
  }
  const auto recv = comm.exchange(gh.peers, send, 500);
  // The peers' values in rank order, each peer's in the order its particles were sent.
  for (std::size_t k = 0; k < gh.peers.size(); ++k) {
    const auto& sent = gh.sent[k];
    if (recv[k].size() != sent.size() * width * sizeof(double))
      throw std::logic_error("add_ghost_values_to_owners: another count of ghosts came back");
    for (std::size_t j = 0; j < sent.size(); ++j)
      for (std::size_t c = 0; c < width; ++c) {
        double v;
        std::memcpy(&v, recv[k].data() + (j * width + c) * sizeof(double), sizeof(double));
        values[static_cast<std::size_t>(sent[j]) * width + c] += v;
      }
  }
}

template <int Dim>
void remove_ghosts(RunState<Dim>& sim) {
  auto& gh = sim.ghosts;
  gh.peers.clear();
  gh.sent.clear();
  gh.received.clear();
  if (gh.owned < 0) return;
  sim.particles.truncate(gh.owned);
  gh.owned = -1;
}

template <int Dim>
void localize_tractions(RunState<Dim>& sim) {
  const auto& P = sim.particles;
  const auto own = static_cast<std::size_t>(sim.own_particles());
  // (id, index) of this process's particles, sorted by id, for lookups.
  std::vector<std::pair<Index, Index>> at(own);
  for (std::size_t i = 0; i < own; ++i)
    at[i] = {static_cast<Index>(P.id[i]), static_cast<Index>(i)};
  std::sort(at.begin(), at.end());
  sim.tractions.clear();
  for (const auto& all : sim.all_tractions) {
    Traction<Dim> t;
    t.direction = all.direction;
    t.side = all.side;
    t.value = all.value;
    t.pressure = all.pressure;
    t.patch = all.patch;
    for (std::size_t k = 0; k < all.particles.size(); ++k) {
      const auto it = std::lower_bound(at.begin(), at.end(),
                                       std::pair<Index, Index>{all.particles[k], Index{-1}});
      if (it == at.end() || it->first != all.particles[k]) continue;
      t.particles.push_back(it->second);
      t.area.push_back(all.area[k]);
      if (k < all.offset.size()) t.offset.push_back(all.offset[k]);
      if (k < all.normal.size()) t.normal.push_back(all.normal[k]);
    }
    sim.tractions.push_back(std::move(t));
  }
}

template <int Dim>
double imbalance(const RunState<Dim>& sim, const Comm& comm, Index* most) {
  comm.check();
  const Index n = sim.particles.size();
  const Index total = comm.sum(n);
  // (A count is exact as a double up to 2^53.)
  const double largest = comm.max(static_cast<double>(n));
  if (most) *most = static_cast<Index>(largest);
  if (total == 0) return 0.0;
  return largest * static_cast<double>(comm.size()) / static_cast<double>(total) - 1.0;
}

template <int Dim>
bool rebalance_if_due(RunState<Dim>& sim, SlabPartition<Dim>& part, const Comm& comm,
                      double threshold, Index& sent, double& measured) {
  Index most = 0;
  measured = imbalance(sim, comm, &most);
  if (!(threshold > 0.0) || measured <= threshold) return false;
  const std::vector<double> per_layer =
      SlabPartition<Dim>::layer_counts(sim.grid, sim.particles, comm, /*replicated=*/false);
  SlabPartition<Dim> next =
      SlabPartition<Dim>::balanced(per_layer, comm.size(), "parallel.rebalance");
  // The most particles of one process with the new cuts, against now.
  std::vector<double> predicted(static_cast<std::size_t>(comm.size()), 0.0);
  for (std::size_t l = 0; l < per_layer.size(); ++l)
    predicted[static_cast<std::size_t>(next.owner_of_layer(static_cast<Index>(l)))] += per_layer[l];
  const double now = static_cast<double>(most);
  if (!(*std::max_element(predicted.begin(), predicted.end()) < now)) return false;
  part = std::move(next);
  sent += migrate(sim, part, comm);
  return true;
}

template struct SlabPartition<1>;
template struct SlabPartition<2>;
template struct SlabPartition<3>;
template Index migrate<1>(RunState<1>&, const SlabPartition<1>&, const Comm&);
template void pack_particle<1>(const RunState<1>&, std::size_t, std::vector<std::byte>&);
template void unpack_particles<1>(std::span<const std::byte>, Particles<1>&,
                                  std::vector<CompactIndex>&, std::vector<double>&, int);
template Index migrate<2>(RunState<2>&, const SlabPartition<2>&, const Comm&);
template void pack_particle<2>(const RunState<2>&, std::size_t, std::vector<std::byte>&);
template void unpack_particles<2>(std::span<const std::byte>, Particles<2>&,
                                  std::vector<CompactIndex>&, std::vector<double>&, int);
template Index migrate<3>(RunState<3>&, const SlabPartition<3>&, const Comm&);
template void pack_particle<3>(const RunState<3>&, std::size_t, std::vector<std::byte>&);
template void unpack_particles<3>(std::span<const std::byte>, Particles<3>&,
                                  std::vector<CompactIndex>&, std::vector<double>&, int);
template void append_ghosts<1>(RunState<1>&, const Comm&, double);
template void append_ghosts<2>(RunState<2>&, const Comm&, double);
template void append_ghosts<3>(RunState<3>&, const Comm&, double);
template void add_ghost_values_to_owners<1>(const RunState<1>&, const Comm&, std::span<double>,
                                            std::size_t);
template void add_ghost_values_to_owners<2>(const RunState<2>&, const Comm&, std::span<double>,
                                            std::size_t);
template void add_ghost_values_to_owners<3>(const RunState<3>&, const Comm&, std::span<double>,
                                            std::size_t);
template void remove_ghosts<1>(RunState<1>&);
template void remove_ghosts<2>(RunState<2>&);
template void remove_ghosts<3>(RunState<3>&);
template void localize_tractions<1>(RunState<1>&);
template void localize_tractions<2>(RunState<2>&);
template void localize_tractions<3>(RunState<3>&);
template double imbalance<1>(const RunState<1>&, const Comm&, Index*);
template double imbalance<2>(const RunState<2>&, const Comm&, Index*);
template double imbalance<3>(const RunState<3>&, const Comm&, Index*);
template bool rebalance_if_due<1>(RunState<1>&, SlabPartition<1>&, const Comm&, double, Index&,
                                  double&);
template bool rebalance_if_due<2>(RunState<2>&, SlabPartition<2>&, const Comm&, double, Index&,
                                  double&);
template bool rebalance_if_due<3>(RunState<3>&, SlabPartition<3>&, const Comm&, double, Index&,
                                  double&);

}  // namespace mpm
