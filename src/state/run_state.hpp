#pragma once
// The basis- and mapping-independent state of an MPM run, by concern: the model as the run
// advances it (ModelState), the grid quantities and solver state of a step (SolveState), and a
// distributed run's processes, ghosts and carried state (DistributedState). RunState joins them
// with the operations that need more than one; state/simulation.hpp adds the basis and the
// mapping.
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "core/comm.hpp"
#include "core/parallel.hpp"
#include "core/stage_clock.hpp"
#include "grid/grid.hpp"
#include "grid/grid_state.hpp"
#include "material/material_set.hpp"
#include "model/loads.hpp"
#include "particles/particles.hpp"
#include "solver/mass_matrix.hpp"
#include "state/diagnostics.hpp"
#include "state/dof_sharing.hpp"
#include "state/sort.hpp"

namespace mpm {

enum class MassType { Lumped, Consistent };

template <int Dim>
class DistributedPmg;  // parallel/distributed_pmg.hpp

// The model as the run advances it: what the driver reads and writes between steps (outputs,
// checkpoints, error norms). The particles carry the materials' internal variables, named by
// the materials (MaterialState::set_names), and each its material's index.
template <int Dim>
struct ModelState {
  ModelState(const Grid<Dim>& g, Particles<Dim> p, Materials mat)
      : grid(g), particles(std::move(p)), materials(std::move(mat)) {
    particles.state.set_names(materials.state_names());
  }

  Grid<Dim> grid;
  Particles<Dim> particles;
  Materials materials;
  BodyForce<Dim> body_force;
  std::vector<Traction<Dim>> tractions;
  double time = 0.0;  // t^s [s]
  Index step = 0;     // s
  Diagnostics diag;
};

// The grid quantities and the solver state the stages share within a step, and the particle
// order's (re-sorting).
template <int Dim>
struct SolveState {
  MassType mass_type = MassType::Lumped;
  double mass_tolerance = 1e-10;  // relative to the largest nodal mass
  // Largest relative mass or momentum error of one mapping before the run stops (exit code 9).
  double conservation_limit = 0.5;
  // Cundall's local non-viscous damping alpha (method.local_damping; 0: off), applied to the
  // nodal forces by stages::solve_acceleration.
  double local_damping = 0.0;
  // The frictional walls (Problem::friction_walls): each wall's DOFs (ascending), its unit
  // normal n pointing into the wall (a grid side's: +-e_d), and Coulomb's mu; applied by
  // stages::solve_acceleration and
  // solve_velocity. `contact`: per DOF, whether the wall held it in the acceleration solve of
  // step `contact_step` (-1: none yet); read in that step only, so that a DOF's conditions do not
  // depend on which processes held it in earlier steps.
  struct Wall {
    std::vector<Index> dofs;
    Vec<Dim> normal = Vec<Dim>::Zero();
    double mu = 0.0;
    std::vector<unsigned char> contact;
    Index contact_step = -1;
  };
  std::vector<Wall> walls;
  // The forces' stage needs the nodes' velocities of the step start (q^s): for the damping's
  // signs and the walls' contact (MUSL maps q^s with the forces then).
  bool forces_need_momentum() const { return local_damping > 0.0 || !walls.empty(); }
  GridState<Dim> nodes;
  ConsistentMass consistent;
  // A distributed run's p-multigrid hierarchy (method.mass_solver = "pmg"), built with the
  // consistent matrix each step (stages::after_mass).
  std::shared_ptr<DistributedPmg<Dim>> distributed_pmg;
  // Some DOF is fixed in only some components (rollers): consistent mass then factorises once
  // per velocity component. Set by Simulation::fix_side, the only place that changes
  // nodes.fixed.
  bool consistent_per_component = false;
  // Per DOF the projector onto its admissible velocities (zero for inactive DOFs), when some
  // DOF has a nodes.projected entry: consistent mass then solves all components in one system
  // (ConsistentMass::factorize_coupled). Refreshed with the consistent matrix each step.
  std::vector<Mat<Dim>> coupled_projector;
  // Partial lumping of the consistent mass matrix (method.partial_lumping; D 7.2 proposes it for
  // the partially filled elements of PS-MPM): in each step the DOFs whose functions' integrals
  // the particles cover to less than `below` get lumped rows and columns
  // (ConsistentMass::set_lumped; marked in stages::after_mass). Set up once per run by
  // setup_partial_lumping (scheme/partial_lumping.hpp).
  struct PartialLumping {
    double below = 0.0;  // 0: off
    // The elements (the grid's cells, or a basis's triangles) and in each the DOFs whose
    // functions do not vanish there with the integrals of those functions over it: element e's
    // are dofs[k] and share[k] for k in [first[e], first[e + 1]).
    std::vector<Index> first, dofs;
    std::vector<double> share;     // int_e N_i [m^Dim]
    std::vector<double> integral;  // per DOF, int N_i over all elements [m^Dim]
    std::vector<double> volume;    // of each element [m^Dim]
    // The element holding a point (a basis's triangle); unset: the grid cell of the particle's
    // last basis evaluation (`cell`). -1: none.
    std::function<Index(const Vec<Dim>&)> element_of;
  } lumping;
  // The degree of a B-spline basis on the grid (0 for the others): method.mass_solver = "pmg"
  // builds its hierarchy over the degrees below it.
  int spline_degree = 0;
  IVec<Dim> dof_stride{};          // DOF strides of a tensor-product basis (CachedT)
  std::vector<CompactIndex> cell;  // cell of each particle at the last evaluation
  ScatterBuffers<Dim> scatter;     // per-chunk grid buffers of the parallel scatters
  SortState sorting;               // re-sorting by cell between steps (state/sort.hpp)

  // The DOF range [lo, hi] that a reconstruction mapping's quadrature points touched in this
  // step (lo > hi: none); the exchange shares the union with the particles' range.
  std::array<Index, 2> quadrature_dofs{std::numeric_limits<Index>::max(), -1};
  // The particles' velocity gradients [1/s] from the mapping (MappingFor's kStrainRates: TLS's
  // adjoint rate), written by stages::mapped_strain_rates just before the stress update that
  // reads them, which empties it; empty: each particle's gradient from its stencil (D eq. 2.52).
  std::vector<Mat<Dim>> mapped_gradient;
  // Problem::reactions: the DOFs of each constrained boundary (reaction_names order), whose
  // reactions stages::solve_acceleration sums into diag.reactions; empty: none computed.
  std::vector<std::vector<Index>> reaction_dofs;
  // Per entry of reaction_dofs: 1 when it is a frictional wall, whose reaction has every
  // component (the contact and friction forces), 0 for the fixed components alone.
  std::vector<unsigned char> reaction_whole;
};

// A distributed run: the processes, the DOFs they share, the ghost particles lent between them,
// the basis state carried with migrating particles, and the loaded points by owner. Null `comm`
// and empty otherwise.
template <int Dim>
struct DistributedState {
  // A distributed run (core/comm.hpp): the processes, each holding the particles of
  // its block of the grid (parallel/distribution.hpp) and the grid quantities of the DOFs its
  // particles touch. Null for a run on one process. After each particle-to-grid sum the ranks
  // add their partial sums on the DOFs they share (stages::share_grid_sums), so every
  // rank's grid holds the totals on the DOFs it holds; `shared` holds each rank's DOF range
  // [lo, hi] and box of the last exchange (DofRanges::holds; for the conservation totals, which
  // count each DOF once). The DOFs of a rank's range outside its box hold its partial sums
  // alone, which are zero: no particle of it touches them.
  const Comm* comm = nullptr;
  DofRanges shared;
  // The box of DOF coordinates (per direction of the basis's layout, both ends held) that this
  // process's particle stencils touch, recorded by evaluate_basis for `stencil_box_particles`
  // particles (-1: not recorded): what the exchange of the grid sums shares with the processes
  // whose boxes meet it, so that blocks side by side exchange their faces, not whole rows.
  std::array<IVec<Dim>, 2> stencil_box{};
  Index stencil_box_particles = -1;
  // A distributed run: the whole problem's tractions with each loaded point's particle
  // by id; `tractions` holds the points of this process's particles (localize_tractions, after
  // every migration). `face_forces`: the loaded points' nodal forces of this step, (DOF, force),
  // which stages::share_grid_sums adds where this process's sums hold the DOF and sends
  // on to the process that holds it otherwise.
  std::vector<Traction<Dim>> all_tractions;
  std::vector<std::pair<Index, Vec<Dim>>> face_forces;

  // Ghost particles: a mapping that reads the particles of neighbouring cells
  // (MappingFor's kGhostParticles: TLS) sees, during each of its particle-to-grid sums, copies of
  // the other processes' particles within a few cells of this process's own, appended
  // after them (stages::GhostParticles); `owned` is then this process's particle count (-1: no
  // ghosts appended). `cells`: the box of the cells this process's particles occupy at the last
  // exchange (inside its block, where no other process has particles: migration follows every
  // step).
  // `peers`, `sent` and `received` (per peer, in rank order): which of this process's particles
  // went to each, and how many ghosts came from each (appended in that order), for sums a
  // mapping makes at the ghosts that belong to their owners (add_ghost_values_to_owners).
  struct Ghosts {
    Index owned = -1;
    CellBox<Dim> cells;
    std::vector<int> peers;
    std::vector<std::vector<Index>> sent;
    std::vector<Index> received;
    Index last_count = 0;  // the ghosts appended at the last exchange (summary.json "mpi")
  } ghosts;
  // Per-particle state of the basis that travels with the particles between processes (CPDI2's
  // tracked corners): `carried_width` doubles per particle in particle order, filled by the
  // stepper before a migration or a distributed checkpoint (Stepper::export_carried), moved
  // and gathered with the particles (pack_particle), and taken back by the basis after
  // (Stepper::resize_particle_caches). Empty otherwise.
  int carried_width = 0;
  std::vector<double> carried;
};

// The basis- and mapping-independent state of an MPM run: what the driver (driver/) reads and
// writes between steps (outputs, checkpoints, error norms), with the grid quantities the stages
// share. BasisState (state/simulation.hpp) adds the basis and the cached stencils.
template <int Dim>
struct RunState : ModelState<Dim>, SolveState<Dim>, DistributedState<Dim> {
  static constexpr int kDim = Dim;

  RunState(const Grid<Dim>& g, Particles<Dim> p, Materials mat)
      : ModelState<Dim>(g, std::move(p), std::move(mat)) {}

  // The stages' wall times (`mpm bench --stages`, one thread only), or null: not timed.
  StageClock* clock = nullptr;

  // Adds the constrained directions range(c) (c symmetric positive semi-definite) to those of
  // `dofs`: each DOF's constrained subspace is the span of all its conditions (two rollers
  // meeting at a corner at an angle fix it; a roller and a parallel one do not add up). A
  // subspace spanned by axes is kept as nodes.fixed bits, any other as a nodes.projected
  // projector. The callers then call refresh_per_component, once per condition. Per-run set-up,
  // defined in state/run_state.cpp and compiled once per dimension, not in every stepper unit
  // (its eigensolver was a third of a stepper unit's template instantiation).
  void constrain(const std::vector<Index>& dofs, const Mat<Dim>& c);
  void refresh_per_component();

  // [first, end) of the DOFs the grid stages work on: all of them on one process; in a
  // distributed run the range this rank's particles touched at the last exchange (the other
  // DOFs hold stale values that nothing reads: ChunkDofRanges::bounded).
  std::array<Index, 2> dof_window() const {
    if (this->comm == nullptr || this->shared.lo.empty()) return {0, this->nodes.size()};
    return this->shared.window(this->comm->rank());
  }
  // A distributed run: moves the grid arrays' window (GridState::set_window, core/dof_array.hpp)
  // to hold the DOFs this process's particle stencils touch (scatter.ranges, just recorded by
  // evaluate_basis) and two layers of grid vertices' DOFs more on each side, so that a process
  // allocates its slab's share of the grid, not the whole grid. The margin holds a
  // reconstruction's quadrature points in the cells of its particles' layers (quadrature_dofs:
  // the same DOF layers, other columns) and a step's motion without a move; the window moves
  // when it no longer holds a layer either side or is wider than eight layers beyond them
  // (after a re-cut of the slabs); a process without particles holds none. A particle-to-grid
  // sum reaching past it stops the run with a logic error (scatter_fused) instead of losing a
  // contribution. Nothing on one process.
  void fit_dof_window();

  // This process's own particles: the first own_particles() of `particles` (all but ghosts).
  Index own_particles() const {
    return this->ghosts.owned >= 0 ? this->ghosts.owned : this->particles.size();
  }
  // The cells whose elements this process integrates: all of them on one process; in a
  // distributed run the box of those its particles occupy (ghosts.cells), so that each element
  // is integrated by exactly one process, on slabs and on blocks.
  CellBox<Dim> own_cells() const {
    if (this->comm == nullptr) return this->grid.all_cells();
    return this->ghosts.cells;
  }
};

}  // namespace mpm
