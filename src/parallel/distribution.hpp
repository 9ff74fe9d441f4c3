#pragma once
// Distributed runs: the grid's cells are cut into slabs of whole cell layers along
// its last axis (x in 1D, y in 2D, z in 3D), one slab per process; a process owns the particles
// in its slab. Slabs, not a Cartesian grid of blocks or a graph partition: with the DOFs
// numbered x fastest, a slab's particles touch one contiguous DOF range, so the DOFs two
// neighbouring processes share are one contiguous segment (the layers their stencils reach
// across the cut), and the exchange after each particle-to-grid sum is one message per
// neighbour (stages::share_grid_sums); the cuts are chosen to give each process the same
// number of particles. BENCHMARKS.md ("Processes") has the communication model and where
// slabs stop scaling.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "state/simulation.hpp"

namespace mpm {

template <int Dim>
struct SlabPartition {
  static constexpr int kAxis = Dim - 1;
  // Rank r owns the cell layers [cuts[r], cuts[r + 1]) along kAxis; cuts[0] = 0 and
  // cuts[ranks] = the grid's layers.
  std::vector<Index> cuts;

  int ranks() const { return static_cast<int>(cuts.size()) - 1; }
  // The rank owning cell layer `layer` (in [0, layers)).
  int owner_of_layer(Index layer) const;
  // The rank owning a particle at x: that of its cell's layer; `current` for a point outside the
  // grid (its process then stops the run, naming it: stages::evaluate_basis).
  int owner(const Grid<Dim>& grid, const Vec<Dim>& x, int current) const;

  // Cuts that give every rank about the same number of particles, each rank at least one layer.
  // `per_layer`: the particles in each cell layer (of all ranks). InputError when the grid has
  // fewer layers than ranks (`where`: the key to change).
  static SlabPartition balanced(const std::vector<double>& per_layer, int ranks,
                                const std::string& where);
  // The particles in each cell layer along kAxis (those inside the grid: Grid::last_layer, the
  // layer that decides the owner), over all ranks (collective when comm is
  // distributed; `replicated`: every rank holds every particle, as at set-up, so no sum).
  static std::vector<double> layer_counts(const Grid<Dim>& grid, const Particles<Dim>& P,
                                          const Comm& comm, bool replicated);
  // "y" etc.: the axis of the cuts.
  static char axis_name() { return "xyz"[kAxis]; }
};

// Particle i's fields, its cell of the last evaluation (sim.cell) and its carried basis state
// (sim.carried) appended to `out` as bytes (Particles::pack, then the cell, then
// sim.carried_width doubles): what travels between processes and into checkpoints.
template <int Dim>
void pack_particle(const RunState<Dim>& sim, std::size_t i, std::vector<std::byte>& out);
// Appends the particles, cells and carried states (`width` doubles each) of a buffer of
// pack_particle records.
template <int Dim>
void unpack_particles(std::span<const std::byte> in, Particles<Dim>& P,
                      std::vector<CompactIndex>& cells, std::vector<double>& carried, int width);

// Moves every particle whose owner (part.owner) is another rank there, with its fields and its
// cell of the last evaluation (sim.cell); the particles that stay keep their order, and those
// that arrive follow in the order of their source ranks. Collective; starts with comm.check().
// Messages go to the neighbouring slabs only, unless some particle moves further.
// The caller resizes the typed per-particle caches (Stepper::resize_particle_caches). Returns
// the number of particles this rank sent.
template <int Dim>
Index migrate(RunState<Dim>& sim, const SlabPartition<Dim>& part, const Comm& comm);

// Ghost particles (RunState::ghosts) for a mapping that reads the particles of neighbouring
// cells: appends to sim.particles copies of the other processes' particles whose cell layer
// (along the last axis) lies within L layers of those this process's particles occupy, L the
// largest `reach` of any process rounded up, in rank order and, from one rank, in its particle
// order; sets sim.ghosts. Only processes whose particles lie within L of each other exchange (a
// symmetric relation, so each pair agrees). Collective; starts with comm.check().
template <int Dim>
void append_ghosts(RunState<Dim>& sim, const Comm& comm, double reach);
// Drops the ghost copies again (nothing when none are appended).
template <int Dim>
void remove_ghosts(RunState<Dim>& sim);
// While ghosts are appended: `values` holds `width` doubles per particle, own and ghosts (the
// order of sim.particles); each process sends the values at its ghosts to the processes that own
// them, which add them to those of the particles they sent, peer after peer in rank order (the
// same bits on every run). For a sum a mapping makes over its fits' points that belongs to the
// particles (TLS's adjoint strain rate). Collective; starts with comm.check().
template <int Dim>
void add_ghost_values_to_owners(const RunState<Dim>& sim, const Comm& comm,
                                std::span<double> values, std::size_t width);

// A distributed run's tractions: sim.tractions from sim.all_tractions (whose loaded points name
// their particles by id), the points of this process's particles with their indices, in the
// order of all_tractions (so each process adds its points' forces in the one process's order).
// After every change of this process's particles (set-up, migration, restart).
template <int Dim>
void localize_tractions(RunState<Dim>& sim);

// max / mean - 1 of the particles per process (0 without particles), and in `most` the most
// particles of one process. Collective (two reductions, not a gather of every count).
template <int Dim>
double imbalance(const RunState<Dim>& sim, const Comm& comm, Index* most = nullptr);

// Load balance (parallel.rebalance): when the imbalance exceeds `threshold` (> 0), cuts the
// slabs anew from the particles' current layers (SlabPartition::balanced) and migrates the
// particles, if the new cuts hold fewer particles on the most loaded process. Every process
// takes the same decision from the same gathered counts. Collective; true when it re-cut.
// `sent`: adds the particles this rank sent; `measured`: the imbalance before any re-cut.
template <int Dim>
bool rebalance_if_due(RunState<Dim>& sim, SlabPartition<Dim>& part, const Comm& comm,
                      double threshold, Index& sent, double& measured);

}  // namespace mpm
