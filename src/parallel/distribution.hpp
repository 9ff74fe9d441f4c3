#pragma once
// Distributed runs: the grid's cells are cut into blocks, one per process, by a Cartesian grid
// of processes: procs[d] processes along axis d, the cuts along each axis chosen to give each
// process about the same number of particles (from the particles per cell layer along that axis),
// and a process owns the particles in its block. Slabs of whole cell layers along the last axis
// (x in 1D, y in 2D, z in 3D) are the shape (1, ..., 1, N): with the DOFs numbered x fastest, a
// slab's particles touch one contiguous DOF range, so the DOFs two neighbouring slabs share are
// one contiguous segment (stages::share_grid_sums). Blocks (parallel.blocks) let a run use more
// processes than the grid has layers along one axis, and a block's halo is its faces, not a
// whole cross-section; particles move to the up to 3^Dim - 1 neighbouring blocks. BENCHMARKS.md
// ("Processes") has the communication model.
#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/comm.hpp"
#include "state/simulation.hpp"

namespace mpm {

// parallel.blocks: "slabs" (processes along the last axis only), "auto" (the shape chosen from
// the particles per cell layer along each axis: BlockPartition::choose_shape) or processes per
// axis, x first ("2x2", "2x2x2"), whose product is the number of processes.
struct BlockShapeRequest {
  enum class Kind { Slabs, Auto, Given } kind = Kind::Slabs;
  std::vector<Index> procs;                       // Given: per axis
  std::string text = "slabs", where = "default";  // the value and Config::where of the key
  // InputError at `where` when `text` is none of those.
  static BlockShapeRequest parse(const std::string& text, const std::string& where);
};

template <int Dim>
struct BlockPartition {
  static constexpr int kAxis = Dim - 1;                      // the slabs' axis
  using LayerCounts = std::array<std::vector<double>, Dim>;  // particles per cell layer, per axis

  // Processes along each axis (their product: the processes of the run); rank r sits at
  // coords(r), x fastest: r = c_0 + procs_0 (c_1 + procs_1 c_2).
  IVec<Dim> procs{};
  // Along axis d, process coordinate k owns the cell layers [cuts[d][k], cuts[d][k + 1]);
  // cuts[d][0] = 0 and cuts[d][procs[d]] = the grid's layers along d.
  std::array<std::vector<Index>, Dim> cuts;

  int ranks() const;
  IVec<Dim> coords(int rank) const;
  int rank_at(const IVec<Dim>& c) const;
  // Whether the shape is slabs (1, ..., 1, N).
  bool slabs() const;
  // The layers [first, end) of rank's block along axis d.
  std::array<Index, 2> span(int rank, int d) const;
  // The rank owning the cell with coordinates `cell` (each in [0, cells[d])).
  int owner_of_cell(const IVec<Dim>& cell) const;
  // The rank owning a particle at x: that of its cell; `current` for a point outside the grid
  // (its process then stops the run, naming it: stages::evaluate_basis).
  int owner(const Grid<Dim>& grid, const Vec<Dim>& x, int current) const;
  // The ranks whose blocks touch rank's (coordinates at most one apart along every axis),
  // ascending, rank itself left out: where a particle that moved less than a cell can go.
  std::vector<int> neighbours(int rank) const;
  // Whether rank a's block of this partition and rank b's of `other` share a cell.
  bool overlaps(int a, const BlockPartition& other, int b) const;

  // The cuts along every axis that give every process coordinate about the same number of
  // particles, each at least one layer, for the process grid `procs`. InputError when an axis
  // has fewer layers than processes along it (`where`: the key to change).
  static BlockPartition balanced(const LayerCounts& per_layer, const IVec<Dim>& procs,
                                 const std::string& where);
  // The process grid of `request` for `ranks` processes: slabs; the given shape (InputError
  // naming the request's key when its product is not `ranks` or it has another number of axes);
  // or, for "auto", the shape of the smallest halo: among the factorisations of `ranks` into Dim
  // factors, each at most the layers along its axis, the one whose cuts cross the least area of
  // the body's box (the span of the occupied layers along each axis), sum over d of
  // (procs_d - 1) x the box's cross-section normal to d; ties go to more processes along the
  // later axes (slabs where they cost no more).
  static IVec<Dim> choose_shape(const LayerCounts& per_layer, int ranks,
                                const BlockShapeRequest& request);
  // The partition of `request` for `ranks` processes: choose_shape's process grid, balanced.
  // Every process computes the same one from the same counts (the errors name the key to
  // change: the request's, or grid.cells when an axis has too few layers).
  static BlockPartition cut(const LayerCounts& per_layer, int ranks,
                            const BlockShapeRequest& request);
  // Whether `rank` stores, at set-up, a particle in the cell with coordinates `cell`
  // (SeedScope::keep): the owner of the cell; a particle outside the grid (empty `cell`) goes to
  // rank 0 (whose run then stops, naming it).
  bool keeps(int rank, std::span<const Index> cell) const;
  // The particles in each cell layer along each axis (those inside the grid), over all ranks
  // (collective when comm is distributed; `replicated`: every rank holds every particle, as at
  // set-up, so no sum).
  static LayerCounts layer_counts(const Grid<Dim>& grid, const Particles<Dim>& P, const Comm& comm,
                                  bool replicated);
  // "slabs along y", "2 x 2 blocks".
  std::string describe() const;
};

// "x", "y", "z".
inline char axis_name(int d) {
  return "xyz"[d];
}

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
// Messages go to the neighbouring blocks only, unless some particle moves further.
// The caller resizes the typed per-particle caches (Stepper::resize_particle_caches). Returns
// the number of particles this rank sent.
template <int Dim>
Index migrate(RunState<Dim>& sim, const BlockPartition<Dim>& part, const Comm& comm);

// Ghost particles (RunState::ghosts) for a mapping that reads the particles of neighbouring
// cells: appends to sim.particles copies of the other processes' particles whose cell lies
// within L cells, along every axis, of the box of cells this process's particles occupy
// (ghosts.cells, RunState::own_cells), L the largest `reach` of any process rounded up, in rank
// order and, from one rank, in its particle order; sets sim.ghosts. Only processes whose boxes
// lie within L of each other exchange (a symmetric relation, so each pair agrees): two slabs
// and, with blocks, the up to 3^Dim - 1 blocks around one. Collective; starts with comm.check().
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

// Load balance (parallel.rebalance): when the imbalance exceeds `threshold` (> 0), moves the
// blocks' boundaries (the same process grid, cuts anew from the particles' current layers along
// each axis: BlockPartition::balanced) and migrates the particles, if the new cuts hold fewer
// particles on the most loaded process (counted over the processes). Every process takes the
// same decision from the same summed counts. Collective; true when it re-cut.
// `sent`: adds the particles this rank sent; `measured`: the imbalance before any re-cut.
template <int Dim>
bool rebalance_if_due(RunState<Dim>& sim, BlockPartition<Dim>& part, const Comm& comm,
                      double threshold, Index& sent, double& measured);

}  // namespace mpm
