#pragma once
// Re-sorting the particles by cell. The parallel scatters (core/parallel.hpp) give
// each fixed chunk of consecutive particles a grid slice covering the DOF range its stencils
// touch. Particles seeded cell by cell make those ranges narrow bands (about 1.4 grids in all at
// 1e6 particles in 2D); particles in random order, or mixed by a long flow, make every range
// the whole grid: 64 grids of zeroing and adding per scatter and gathers from all over the
// grid. A stable counting sort by cell index restores the bands.
//
// When (sort_due): the measure is the total length T of the chunks' DOF ranges, which
// evaluate_basis records every step anyway (ChunkDofRanges), against U, the length of their
// union. The first measurement of a run sorts when T > kFirstSortSpan U (random order:
// T ~ chunks x U; seeded or sorted order: T / U about 1-2);
// otherwise it, or the first measurement after a sort, becomes the reference T_ref, and the
// particles are sorted again when T > kResortFactor T_ref. The decision depends only on the
// particle state, never on the thread count, so runs stay bitwise identical for any thread
// count; the trigger state is checkpointed (restarts stay bitwise identical too).
//
// What is permuted (apply_particle_order), all with one Permutation: every Particles field
// (ids included, Particles::for_each_field), the cell of each particle, per-particle basis
// state (CPDI2's tracked corners: Basis::permute), per-particle mapping state (Mapping::permute,
// none so far), and the particle indices of the traction lists (remapped, the lists keep their
// order). The cached stencils and chunk ranges are not permuted: the sort runs between steps
// and every scheme's first stage, evaluate_basis, rewrites them all before they are read.
// Sorting changes the order of the particle sums, so results change by round-off only.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <new>
#include <numeric>
#include <random>
#include <type_traits>
#include <vector>

#include "core/parallel.hpp"
#include "core/types.hpp"
#include "particles/permutation.hpp"

namespace mpm {

enum class SortMode { Auto, Never };

// The re-sorting state of a run (Simulation::sorting).
struct SortState {
  // The first measurement of a run sorts when the chunks' ranges total more than this many
  // times their union: sorted or seeded particles measure about 1-2 (the 20 x 20-cell plate of
  // test_sort.cpp, 3600 particles in 8 chunks: 1.65 sorted, 8.0 shuffled; about 1.4 grids at 1e6
  // particles in 2D), random order about the chunk count (up
  // to 64). Below 4 chunks (2048 particles) random order is never sorted at the start: it costs
  // at most 4 slices of small grids.
  static constexpr double kFirstSortSpan = 4.0;
  // Later measurements sort when the total exceeds this factor times the reference (the first
  // measurement after the last sort). Measured (2D
  // quadratic B-spline MUSL, 1e6 particles, alternated): one sort costs about one step (140-330 ns
  // per particle), random order (about 62 grids of extra span) about 210-420 ns per particle-step
  // more than sorted order. Interpolated linearly, spans at twice the sorted ones (1.4 extra
  // grids) cost about 5-10 ns per particle-step, so a sort then pays back within some 30-60
  // steps, while a smaller factor would sort more often for less.
  static constexpr double kResortFactor = 2.0;

  SortMode mode = SortMode::Auto;
  // Trigger state (checkpointed): the reference total span T_ref [DOFs], -1 when the next
  // measurement sets it; the number of sorts so far.
  Index reference = -1;
  Index sorts = 0;

  Permutation perm;
  std::vector<Index> cursor;  // counting-sort cursors, one per cell the particles span (+1)
};

// The total length of the chunks' DOF ranges and the length of their union [DOFs].
struct ChunkSpans {
  Index total = 0, uni = 0;
};
inline ChunkSpans chunk_spans(const ChunkDofRanges& r) {
  ChunkSpans s;
  if (r.particles < 0) return s;
  Index lo = 0, hi = -1;
  const int k = ParticleChunks::count(r.particles);
  for (int c = 0; c < k; ++c) {
    const auto cc = static_cast<std::size_t>(c);
    if (r.hi[cc] < r.lo[cc]) continue;
    s.total += r.hi[cc] - r.lo[cc] + 1;
    lo = hi < 0 ? r.lo[cc] : std::min(lo, r.lo[cc]);
    hi = std::max(hi, r.hi[cc]);
  }
  s.uni = hi < 0 ? 0 : hi - lo + 1;
  return s;
}

// Whether the particles should be sorted now, from the chunk ranges of the latest
// evaluate_basis (file comment); updates the reference.
inline bool sort_due(const ChunkDofRanges& r, SortState& st) {
  if (st.mode == SortMode::Never) return false;
  const ChunkSpans s = chunk_spans(r);
  if (s.uni <= 0) return false;  // nothing recorded (no step yet)
  if (st.reference < 0) {
    if (st.sorts == 0 &&
        static_cast<double>(s.total) > SortState::kFirstSortSpan * static_cast<double>(s.uni))
      return true;
    st.reference = s.total;
    return false;
  }
  return static_cast<double>(s.total) >
         SortState::kResortFactor * static_cast<double>(st.reference);
}

// perm.order = the particles in cell order, stable (equal cells keep their relative order): a
// counting sort over cell[p] in [0, cells), its cursors over the cells from the lowest to the
// highest the particles occupy (not the whole grid: 8 bytes a cell, on every process of a
// distributed run). Serial: streaming passes over the particles and those cells.
inline void cell_order(const std::vector<CompactIndex>& cell, Index cells, SortState& st) {
  Index lo = cells, hi = -1;
  for (const CompactIndex c : cell) {
    lo = std::min<Index>(lo, c);
    hi = std::max<Index>(hi, c);
  }
  auto& cur = st.cursor;
  cur.assign(static_cast<std::size_t>(hi >= lo ? hi - lo + 1 : 0) + 1, 0);
  for (const CompactIndex c : cell) ++cur[static_cast<std::size_t>(c - lo) + 1];
  for (std::size_t c = 1; c < cur.size(); ++c) cur[c] += cur[c - 1];
  st.perm.order.resize(cell.size());
  for (std::size_t p = 0; p < cell.size(); ++p)
    st.perm.order[static_cast<std::size_t>(cur[static_cast<std::size_t>(cell[p] - lo)]++)] =
        static_cast<CompactIndex>(p);
}

// Applies st.perm to everything indexed by particle in sim (file comment).
template <class Sim>
void apply_particle_order(Sim& sim, Permutation& perm) {
  sim.particles.for_each_field([&](auto& field) { perm.apply(field); });
  perm.apply(sim.cell);
  // Mappings hold no per-particle state (mapping/mapping.hpp).
  if constexpr (Sim::BasisT::kTrackedCorners) sim.basis.permute(perm);
  perm.set_inverse();
  for (auto& tr : sim.tractions)
    for (auto& p : tr.particles) p = perm.inverse[static_cast<std::size_t>(p)];
  // Stale until the next evaluate_basis, the first stage of every scheme.
  sim.scatter.ranges.particles = -1;
}

// Sorts the particles by their cell at the latest basis evaluation (sim.cell). Returns false
// (and changes nothing) when they are in cell order already.
template <class Sim>
bool sort_particles(Sim& sim) {
  auto& st = sim.sorting;
  for (const Index c : sim.cell)
    if (c < 0) return false;  // not evaluated yet
  cell_order(sim.cell, sim.grid.num_cells(), st);
  ++st.sorts;
  st.reference = -1;  // the next measurement is the sorted one
  if (st.perm.identity()) return false;
  apply_particle_order(sim, st.perm);
  return true;
}

// Between time steps: sorts the particles when their order has degraded (sort_due).
template <class Sim>
void sort_particles_if_due(Sim& sim) {
  if (sort_due(sim.scatter.ranges, sim.sorting)) sort_particles(sim);
}

// Puts the particles into a random order (seeded std::mt19937_64, std::shuffle), remapping the
// traction lists: tests and `mpm bench --shuffle` start from it to exercise and measure the
// re-sorting. Ids travel with their particles.
template <class ParticlesT, class Tractions>
void shuffle_particles(ParticlesT& P, Tractions& tractions, std::uint64_t seed) {
  Permutation perm;
  perm.order.resize(static_cast<std::size_t>(P.size()));
  std::iota(perm.order.begin(), perm.order.end(), CompactIndex{0});
  std::mt19937_64 gen(seed);
  std::shuffle(perm.order.begin(), perm.order.end(), gen);
  P.for_each_field([&](auto& field) { perm.apply(field); });
  perm.set_inverse();
  for (auto& tr : tractions)
    for (auto& p : tr.particles) p = perm.inverse[static_cast<std::size_t>(p)];
}

// A copy of the particles in id order (outputs: a run's frames do not depend on when it was
// sorted). Ids must be a permutation of 0 .. n-1, which creation and sorting keep.
template <class ParticlesT>
ParticlesT particles_in_id_order(const ParticlesT& P) {
  ParticlesT out = P;
  Permutation perm;
  perm.order.resize(P.id.size());
  for (std::size_t i = 0; i < P.id.size(); ++i)
    perm.order[static_cast<std::size_t>(P.id[i])] = static_cast<CompactIndex>(i);
  out.for_each_field([&](auto& field) { perm.apply(field); });
  return out;
}

}  // namespace mpm
