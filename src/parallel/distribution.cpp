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

BlockShapeRequest BlockShapeRequest::parse(const std::string& text, const std::string& where) {
  BlockShapeRequest r;
  r.text = text;
  r.where = where;
  if (text == "slabs") return r;
  if (text == "auto") {
    r.kind = Kind::Auto;
    return r;
  }
  r.kind = Kind::Given;
  // "2x3", "2x2x2": whole numbers >= 1 joined by 'x'.
  std::size_t at = 0;
  bool ok = !text.empty();
  while (ok && at <= text.size()) {
    const std::size_t x = std::min(text.find('x', at), text.size());
    const std::string part = text.substr(at, x - at);
    ok = !part.empty() && part.size() <= 9 &&
         std::all_of(part.begin(), part.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (ok) {
      r.procs.push_back(std::stoll(part));
      ok = r.procs.back() >= 1;
    }
    at = x + 1;
  }
  if (!ok || r.procs.size() > 3)
    throw InputError(fmt::format(
        "{}: parallel.blocks = \"{}\" is not a decomposition; valid: \"slabs\" (cell layers along "
        "the last "
        "axis), \"auto\" (blocks shaped from the particles per layer) or the processes per "
        "axis, x first, such as \"2x2\" or \"2x2x2\"",
        where, text));
  return r;
}

namespace {

// Cuts of `layers` layers into `parts` ranges of about the same count, each at least one layer:
// cut k after the layer where the running count first reaches k / parts of the particles.
std::vector<Index> balanced_cuts(const std::vector<double>& per_layer, Index parts) {
  const auto layers = static_cast<Index>(per_layer.size());
  double total = 0.0;
  for (double c : per_layer) total += c;
  std::vector<Index> cuts(static_cast<std::size_t>(parts) + 1, 0);
  cuts.back() = layers;
  double running = 0.0;
  Index layer = 0;
  for (Index r = 1; r < parts; ++r) {
    const double target = total * static_cast<double>(r) / static_cast<double>(parts);
    while (layer < layers && running + per_layer[static_cast<std::size_t>(layer)] <= target) {
      running += per_layer[static_cast<std::size_t>(layer)];
      ++layer;
    }
    const Index lowest = cuts[static_cast<std::size_t>(r) - 1] + 1;
    const Index highest = layers - (parts - r);
    const Index cut = std::clamp(layer, lowest, highest);
    cuts[static_cast<std::size_t>(r)] = cut;
    while (layer < cut) running += per_layer[static_cast<std::size_t>(layer++)];
  }
  return cuts;
}

// The index k of the range [cuts[k], cuts[k + 1]) holding `layer`.
int range_of(const std::vector<Index>& cuts, Index layer) {
  const auto it = std::upper_bound(cuts.begin(), cuts.end(), layer);
  return std::clamp(static_cast<int>(it - cuts.begin()) - 1, 0, static_cast<int>(cuts.size()) - 2);
}

}  // namespace

template <int Dim>
int BlockPartition<Dim>::ranks() const {
  Index n = 1;
  for (int d = 0; d < Dim; ++d) n *= procs[static_cast<std::size_t>(d)];
  return static_cast<int>(n);
}

template <int Dim>
IVec<Dim> BlockPartition<Dim>::coords(int rank) const {
  IVec<Dim> c{};
  Index r = rank;
  for (std::size_t d = 0; d < Dim; ++d) {
    c[d] = r % procs[d];
    r /= procs[d];
  }
  return c;
}

template <int Dim>
int BlockPartition<Dim>::rank_at(const IVec<Dim>& c) const {
  Index r = 0;
  for (int d = Dim - 1; d >= 0; --d)
    r = r * procs[static_cast<std::size_t>(d)] + c[static_cast<std::size_t>(d)];
  return static_cast<int>(r);
}

template <int Dim>
bool BlockPartition<Dim>::slabs() const {
  for (std::size_t d = 0; d + 1 < Dim; ++d)
    if (procs[d] != 1) return false;
  return true;
}

template <int Dim>
std::array<Index, 2> BlockPartition<Dim>::span(int rank, int d) const {
  const auto k = static_cast<std::size_t>(coords(rank)[static_cast<std::size_t>(d)]);
  const auto& c = cuts[static_cast<std::size_t>(d)];
  return {c[k], c[k + 1]};
}

template <int Dim>
int BlockPartition<Dim>::owner_of_cell(const IVec<Dim>& cell) const {
  IVec<Dim> k{};
  for (std::size_t d = 0; d < Dim; ++d) k[d] = range_of(cuts[d], cell[d]);
  return rank_at(k);
}

template <int Dim>
int BlockPartition<Dim>::owner(const Grid<Dim>& grid, const Vec<Dim>& x, int current) const {
  IVec<Dim> cell{};
  for (int d = 0; d < Dim; ++d) {
    const Index c = grid.cell_of(x[d], d);
    if (c < 0 || c >= grid.cells[d]) return current;  // outside the grid (as Grid::inside)
    cell[static_cast<std::size_t>(d)] = c;
  }
  return owner_of_cell(cell);
}

template <int Dim>
std::vector<int> BlockPartition<Dim>::neighbours(int rank) const {
  const IVec<Dim> c = coords(rank);
  std::vector<int> out;
  // Every offset in {-1, 0, 1}^Dim, x fastest (the last axis slowest, as in the ranks'
  // numbering): the ranks come out ascending.
  int offsets = 1;
  for (int d = 0; d < Dim; ++d) offsets *= 3;
  for (int o = 0; o < offsets; ++o) {
    IVec<Dim> n{};
    bool inside = true;
    int rest = o;
    for (std::size_t d = 0; d < Dim; ++d, rest /= 3) {
      n[d] = c[d] + rest % 3 - 1;
      inside = inside && n[d] >= 0 && n[d] < procs[d];
    }
    if (inside && n != c) out.push_back(rank_at(n));
  }
  return out;
}

template <int Dim>
bool BlockPartition<Dim>::overlaps(int a, const BlockPartition& other, int b) const {
  for (int d = 0; d < Dim; ++d) {
    const auto [lo, hi] = span(a, d);
    const auto [olo, ohi] = other.span(b, d);
    if (!(lo < ohi && olo < hi)) return false;
  }
  return true;
}

template <int Dim>
BlockPartition<Dim> BlockPartition<Dim>::cut(const LayerCounts& per_layer, int ranks,
                                             const BlockShapeRequest& request) {
  return balanced(per_layer, choose_shape(per_layer, ranks, request), "grid.cells");
}

template <int Dim>
bool BlockPartition<Dim>::keeps(int rank, std::span<const Index> cell) const {
  if (cell.empty()) return rank == 0;
  IVec<Dim> c{};
  std::copy(cell.begin(), cell.end(), c.begin());
  return owner_of_cell(c) == rank;
}

template <int Dim>
BlockPartition<Dim> BlockPartition<Dim>::balanced(const LayerCounts& per_layer,
                                                  const IVec<Dim>& procs,
                                                  const std::string& where) {
  BlockPartition p;
  p.procs = procs;
  for (std::size_t d = 0; d < Dim; ++d) {
    const auto layers = static_cast<Index>(per_layer[d].size());
    if (layers < procs[d])
      throw InputError(fmt::format(
          "{}: the grid has {} cell layer(s) along {} and this run {} processes along it; a "
          "process owns whole layers, so use more cells along {} or fewer processes{}",
          where, layers, axis_name(static_cast<int>(d)), procs[d], axis_name(static_cast<int>(d)),
          Dim > 1 ? " (or other blocks: parallel.blocks)" : ""));
    p.cuts[d] = balanced_cuts(per_layer[d], procs[d]);
  }
  return p;
}

template <int Dim>
IVec<Dim> BlockPartition<Dim>::choose_shape(const LayerCounts& per_layer, int ranks,
                                            const BlockShapeRequest& request) {
  using Kind = BlockShapeRequest::Kind;
  IVec<Dim> shape{};
  shape.fill(1);
  if (request.kind == Kind::Slabs || Dim == 1) {
    if (request.kind == Kind::Given && request.procs != std::vector<Index>{ranks})
      throw InputError(
          fmt::format("{}: parallel.blocks = \"{}\" does not fit this 1D run on {} "
                      "processes",
                      request.where, request.text, ranks));
    shape[kAxis] = ranks;
    return shape;
  }
  if (request.kind == Kind::Given) {
    Index product = 1;
    for (Index n : request.procs) product *= n;
    if (static_cast<int>(request.procs.size()) != Dim || product != ranks)
      throw InputError(fmt::format(
          "{}: parallel.blocks = \"{}\" names {} processes along {} axes; this {}D run has {} "
          "processes: give {} "
          "counts whose product is {} (or \"auto\", or \"slabs\")",
          request.where, request.text, product, request.procs.size(), Dim, ranks, Dim, ranks));
    for (std::size_t d = 0; d < Dim; ++d) shape[d] = request.procs[d];
    return shape;
  }
  // Auto: the body's box in layers along each axis (at least one layer).
  std::array<double, Dim> extent{};
  for (std::size_t d = 0; d < Dim; ++d) {
    Index first = -1, last = -1;
    for (std::size_t l = 0; l < per_layer[d].size(); ++l)
      if (per_layer[d][l] > 0.0) {
        if (first < 0) first = static_cast<Index>(l);
        last = static_cast<Index>(l);
      }
    extent[d] = first < 0 ? 1.0 : static_cast<double>(last - first + 1);
  }
  double best = std::numeric_limits<double>::infinity();
  bool found = false;
  // Every factorisation (p_0, ..., p_{Dim-1}) of ranks, p_0 ascending, then p_1: of equal costs
  // the first met, with the most processes along the later axes, is kept.
  const auto consider = [&](const IVec<Dim>& p) {
    for (std::size_t d = 0; d < Dim; ++d)
      if (p[d] > static_cast<Index>(per_layer[d].size())) return;
    double cost = 0.0;
    for (std::size_t d = 0; d < Dim; ++d) {
      double section = 1.0;
      for (std::size_t e = 0; e < Dim; ++e)
        if (e != d) section *= extent[e];
      cost += static_cast<double>(p[d] - 1) * section;
    }
    if (cost < best) {
      best = cost;
      shape = p;
      found = true;
    }
  };
  for (Index a = 1; a <= ranks; ++a) {
    if (ranks % a != 0) continue;
    if constexpr (Dim == 2) {
      consider(IVec<Dim>{a, ranks / a});
    } else if constexpr (Dim == 3) {
      for (Index b = 1; b <= ranks / a; ++b)
        if ((ranks / a) % b == 0) consider(IVec<Dim>{a, b, ranks / a / b});
    }
  }
  if (!found)
    throw InputError(
        fmt::format("{}: parallel.blocks = \"auto\": no blocks of {} processes fit this grid (at "
                    "least one cell layer per process along "
                    "every axis); use more cells or fewer processes",
                    request.where, ranks));
  return shape;
}

template <int Dim>
typename BlockPartition<Dim>::LayerCounts BlockPartition<Dim>::layer_counts(const Grid<Dim>& grid,
                                                                            const Particles<Dim>& P,
                                                                            const Comm& comm,
                                                                            bool replicated) {
  LayerCounts count;
  std::size_t total = 0;
  for (std::size_t d = 0; d < Dim; ++d) {
    count[d].assign(static_cast<std::size_t>(grid.cells[d]), 0.0);
    total += count[d].size();
  }
  for (const auto& x : P.x) {
    if (!grid.inside(x)) continue;
    for (int d = 0; d < Dim; ++d)
      count[static_cast<std::size_t>(d)][static_cast<std::size_t>(grid.cell_of(x[d], d))] += 1.0;
  }
  if (!replicated) {
    // One sum over the processes for every axis.
    std::vector<double> all;
    all.reserve(total);
    for (const auto& c : count) all.insert(all.end(), c.begin(), c.end());
    comm.sum(std::span<double>(all));
    std::size_t at = 0;
    for (auto& c : count)
      for (double& v : c) v = all[at++];
  }
  return count;
}

template <int Dim>
std::string BlockPartition<Dim>::describe() const {
  if (slabs()) return fmt::format("slabs of whole cell layers along {}", axis_name(kAxis));
  std::string s;
  for (std::size_t d = 0; d < Dim; ++d) s += (d ? " x " : "") + std::to_string(procs[d]);
  return s + " blocks";
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
Index migrate(RunState<Dim>& sim, const BlockPartition<Dim>& part, const Comm& comm) {
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
  // neighbouring block: one message to each neighbour (2 for slabs, up to 8 in 2D and 26 in
  // 3D). After the blocks were cut anew, or should a particle jump further, every rank exchanges
  // with every other (all ranks decide alike). The arrivals are in source-rank order either way,
  // so the result is the same.
  const std::vector<int> peers = part.neighbours(me);
  std::vector<unsigned char> near(static_cast<std::size_t>(comm.size()), 0);
  near[static_cast<std::size_t>(me)] = 1;
  for (const int r : peers) near[static_cast<std::size_t>(r)] = 1;
  bool far = false;
  for (std::size_t i = 0; i < n; ++i) far = far || !near[static_cast<std::size_t>(owner[i])];
  std::vector<std::vector<std::byte>> recv;
  if (comm.any(far)) {
    recv = comm.alltoall(send);
  } else {
    std::vector<std::vector<std::byte>> out;
    out.reserve(peers.size());
    for (const int r : peers) out.push_back(std::move(send[static_cast<std::size_t>(r)]));
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
  auto& P = sim.particles;
  const auto n = static_cast<std::size_t>(P.size());
  const auto& cells = sim.grid.cells;
  // Each particle's cell coordinates, a CompactIndex each (a run's cells are numbered in one:
  // BasisState's check).
  std::vector<std::array<CompactIndex, Dim>> cell(n);
  CellBox<Dim>& box = sim.ghosts.cells;
  box.cells = cells;
  box.lo = cells;
  box.hi.fill(0);
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < Dim; ++d) {
      // (A particle outside the grid has stopped the run at the basis evaluation before this.)
      const Index c = std::clamp(sim.grid.cell_of(P.x[i][d], d), Index{0}, cells[d] - 1);
      cell[i][static_cast<std::size_t>(d)] = static_cast<CompactIndex>(c);
      box.lo[d] = std::min(box.lo[d], c);
      box.hi[d] = std::max(box.hi[d], c + 1);
    }
  // Each process's box and reach in one all-gather (cell indices are exact as doubles).
  constexpr std::size_t w = 2 * Dim + 1;
  std::array<double, w> mine{};
  for (int d = 0; d < Dim; ++d) {
    mine[2 * static_cast<std::size_t>(d)] = static_cast<double>(box.lo[d]);
    mine[2 * static_cast<std::size_t>(d) + 1] = static_cast<double>(box.hi[d]);
  }
  mine[w - 1] = reach;
  const std::vector<double> all = comm.allgather(std::span<const double>(mine));
  double most = 0.0;
  for (std::size_t k = w - 1; k < all.size(); k += w) most = std::max(most, all[k]);
  const auto layers = static_cast<Index>(std::ceil(most));
  const int me = comm.rank();
  // The processes' particles are in their own blocks at every exchange (migration follows each
  // step), so the boxes do not overlap, and a peer's widened box reaches at most `layers` cells
  // into this one: only the particles of that fringe of the box can be any peer's ghosts. One
  // pass collects them (ascending, so each peer's list keeps the particles' order); each peer's
  // pass then reads the fringe alone, not every particle.
  for (int r = 0; r < comm.size() && !box.empty(); ++r) {
    bool overlaps = r != me;
    for (int d = 0; d < Dim && overlaps; ++d) {
      const std::size_t k = w * static_cast<std::size_t>(r) + 2 * static_cast<std::size_t>(d);
      overlaps = all[k] < all[k + 1] && static_cast<Index>(all[k]) < box.hi[d] &&
                 box.lo[d] < static_cast<Index>(all[k + 1]);
    }
    if (overlaps)
      throw std::logic_error(fmt::format(
          "append_ghosts: the particles of processes {} and {} occupy overlapping boxes of "
          "cells (a particle outside its block)",
          me, r));
  }
  std::vector<std::size_t> fringe;
  if (!box.empty())
    for (std::size_t i = 0; i < n; ++i) {
      bool near = false;
      for (int d = 0; d < Dim; ++d) {
        const Index c = cell[i][static_cast<std::size_t>(d)];
        near = near || c < box.lo[d] + layers || c >= box.hi[d] - layers;
      }
      if (near) fringe.push_back(i);
    }
  auto& gh = sim.ghosts;
  std::vector<int>& peers = gh.peers;
  std::vector<std::vector<std::byte>> send;
  if (!box.empty())
    for (int r = 0; r < comm.size(); ++r) {
      // Rank r's box widened by `layers` cells in every direction: the cells whose particles
      // its fits may read. r takes part when its box is not empty and the widened box meets
      // this one's (the gap between the boxes at most `layers` along every axis, the same seen
      // from either side).
      IVec<Dim> lo{}, hi{};
      bool near = r != me;
      for (int d = 0; d < Dim && near; ++d) {
        const std::size_t k = w * static_cast<std::size_t>(r) + 2 * static_cast<std::size_t>(d);
        const auto rlo = static_cast<Index>(all[k]), rhi = static_cast<Index>(all[k + 1]);
        lo[d] = rlo - layers;
        hi[d] = rhi + layers;
        near = rlo < rhi && lo[d] < box.hi[d] && box.lo[d] < hi[d];
      }
      if (!near) continue;
      peers.push_back(r);
      auto& out = send.emplace_back();
      auto& sent = gh.sent.emplace_back();
      for (const std::size_t i : fringe) {
        bool inside = true;
        for (int d = 0; d < Dim; ++d) {
          const Index c = cell[i][static_cast<std::size_t>(d)];
          inside = inside && c >= lo[d] && c < hi[d];
        }
        if (inside) {
          P.pack(i, out);
          sent.push_back(static_cast<Index>(i));
        }
      }
    }
  const auto recv = comm.exchange(peers, send, 400);
  gh.owned = static_cast<Index>(n);
  for (const auto& buf : recv) {
    const Index before = P.size();
    P.unpack_append(buf);
    gh.received.push_back(P.size() - before);
  }
  gh.last_count = P.size() - gh.owned;
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
bool rebalance_if_due(RunState<Dim>& sim, BlockPartition<Dim>& part, const Comm& comm,
                      double threshold, Index& sent, double& measured) {
  Index most = 0;
  measured = imbalance(sim, comm, &most);
  if (!(threshold > 0.0) || measured <= threshold) return false;
  BlockPartition<Dim> next = BlockPartition<Dim>::balanced(
      BlockPartition<Dim>::layer_counts(sim.grid, sim.particles, comm, /*replicated=*/false),
      part.procs, "parallel.rebalance");
  // The most particles of one process with the new cuts (each process counts its own by their
  // new owners; the sums are whole numbers, exact), against now.
  std::vector<double> predicted(static_cast<std::size_t>(comm.size()), 0.0);
  const auto& P = sim.particles;
  for (std::size_t i = 0; i < static_cast<std::size_t>(P.size()); ++i)
    predicted[static_cast<std::size_t>(next.owner(sim.grid, P.x[i], comm.rank()))] += 1.0;
  comm.sum(std::span<double>(predicted));
  const double now = static_cast<double>(most);
  if (!(*std::max_element(predicted.begin(), predicted.end()) < now)) return false;
  part = std::move(next);
  sent += migrate(sim, part, comm);
  return true;
}

template struct BlockPartition<1>;
template struct BlockPartition<2>;
template struct BlockPartition<3>;
template Index migrate<1>(RunState<1>&, const BlockPartition<1>&, const Comm&);
template void pack_particle<1>(const RunState<1>&, std::size_t, std::vector<std::byte>&);
template void unpack_particles<1>(std::span<const std::byte>, Particles<1>&,
                                  std::vector<CompactIndex>&, std::vector<double>&, int);
template Index migrate<2>(RunState<2>&, const BlockPartition<2>&, const Comm&);
template void pack_particle<2>(const RunState<2>&, std::size_t, std::vector<std::byte>&);
template void unpack_particles<2>(std::span<const std::byte>, Particles<2>&,
                                  std::vector<CompactIndex>&, std::vector<double>&, int);
template Index migrate<3>(RunState<3>&, const BlockPartition<3>&, const Comm&);
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
template bool rebalance_if_due<1>(RunState<1>&, BlockPartition<1>&, const Comm&, double, Index&,
                                  double&);
template bool rebalance_if_due<2>(RunState<2>&, BlockPartition<2>&, const Comm&, double, Index&,
                                  double&);
template bool rebalance_if_due<3>(RunState<3>&, BlockPartition<3>&, const Comm&, double, Index&,
                                  double&);

}  // namespace mpm
