#pragma once
// The state of one run in three layers: RunState (grid, particles, material, grid quantities),
// BasisState (+ basis and cached stencils), Simulation (+ mapping). Stages (scheme/stages.hpp)
// operate on the lowest layer they need; schemes order the stages.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "basis/stencil.hpp"
#include "core/comm.hpp"
#include "core/parallel.hpp"
#include "grid/grid.hpp"
#include "grid/grid_state.hpp"
#include "material/materials.hpp"
#include "model/loads.hpp"
#include "particles/particles.hpp"
#include "scheme/diagnostics.hpp"
#include "scheme/dof_sharing.hpp"
#include "scheme/sort.hpp"
#include "solver/mass_matrix.hpp"

namespace mpm {

enum class MassType { Lumped, Consistent };

// The particle-to-grid sums a fused pass computes (stages::map_to_grid), as bits.
namespace grid_sum {
inline constexpr unsigned kMass = 1;      // nodal masses (and the consistent matrix)
inline constexpr unsigned kMomentum = 2;  // nodal momenta
inline constexpr unsigned kForces = 4;    // internal and body forces
// With kMomentum: first v_p += dt sum_i phi_i a_i (D eq. 2.47), then q from the new v_p (2.48).
inline constexpr unsigned kVelocityFirst = 8;
}  // namespace grid_sum

// The grid-to-particle updates a fused pass computes (stages::update_particles), as bits.
namespace particle_update {
inline constexpr unsigned kVelocity = 1;  // v_p from the grid acceleration
inline constexpr unsigned kPosition = 2;  // x_p, u_p from the grid velocity
inline constexpr unsigned kStress = 4;    // F, V, rho, sigma from the grid velocity gradient
}  // namespace particle_update

template <int Dim>
class DistributedPmg;  // scheme/distributed_pmg.hpp

// The basis- and mapping-independent state of an MPM run: what the driver (driver/) reads and
// writes between steps (outputs, checkpoints, error norms), with the grid quantities the stages
// share. Simulation adds the basis, the mapping and the cached stencils.
template <int Dim>
struct RunState {
  static constexpr int kDim = Dim;

  RunState(const Grid<Dim>& g, Particles<Dim> p, Material mat)
      : grid(g), particles(std::move(p)), material(std::move(mat)) {
    particles.state.set_names(state_names(material));
  }

  Grid<Dim> grid;
  Particles<Dim> particles;
  Material material;
  MassType mass_type = MassType::Lumped;
  double mass_tolerance = 1e-10;  // relative to the largest nodal mass
  // Largest relative mass or momentum error of one mapping before the run stops (exit code 9).
  double conservation_limit = 0.5;
  BodyForce<Dim> body_force;
  std::vector<Traction<Dim>> tractions;
  // A distributed run: the whole problem's tractions with each loaded point's particle
  // by id; `tractions` holds the points of this process's particles (localize_tractions, after
  // every migration). `face_forces`: the loaded points' nodal forces of this step, (DOF, force),
  // which stages::share_grid_sums adds where this process's sums hold the DOF and sends
  // on to the process that holds it otherwise.
  std::vector<Traction<Dim>> all_tractions;
  std::vector<std::pair<Index, Vec<Dim>>> face_forces;

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
  SortState sorting;               // re-sorting by cell between steps (scheme/sort.hpp)

  // Adds the constrained directions range(c) (c symmetric positive semi-definite) to those of
  // `dofs`: each DOF's constrained subspace is the span of all its conditions (two rollers
  // meeting at a corner at an angle fix it; a roller and a parallel one do not add up). A
  // subspace spanned by axes is kept as nodes.fixed bits, any other as a nodes.projected
  // projector. The callers then call refresh_per_component, once per condition. Per-run set-up,
  // defined in scheme/run_state.cpp and compiled once per dimension, not in every stepper unit
  // (its eigensolver was a third of a stepper unit's template instantiation).
  void constrain(const std::vector<Index>& dofs, const Mat<Dim>& c);
  void refresh_per_component();

  // A distributed run (core/comm.hpp): the processes, each holding the particles of
  // its slab of the grid (scheme/distribution.hpp) and the grid quantities of the DOFs its
  // particles touch. Null for a run on one process. After each particle-to-grid sum the ranks
  // add their partial sums on the DOFs they share (stages::share_grid_sums), so every
  // rank's grid holds the totals on its DOFs; `shared` holds each rank's DOF range [lo, hi] of
  // the last exchange (for the conservation totals, which count each DOF once).
  const Comm* comm = nullptr;
  DofRanges shared;
  // [first, end) of the DOFs the grid stages work on: all of them on one process; in a
  // distributed run the range this rank's particles touched at the last exchange (the other
  // DOFs hold stale values that nothing reads: ChunkDofRanges::bounded).
  std::array<Index, 2> dof_window() const {
    if (comm == nullptr || shared.lo.empty()) return {0, nodes.size()};
    return shared.window(comm->rank());
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

  // Ghost particles: a mapping that reads the particles of neighbouring cells
  // (MappingFor's kGhostParticles: TLS) sees, during each of its particle-to-grid sums, copies of
  // the other processes' particles within a few cell layers of this process's own, appended
  // after them (stages::GhostParticles); `owned` is then this process's particle count (-1: no
  // ghosts appended). `layers`: the cell layers [lo, hi] along the last axis that this process's
  // particles occupy at the last exchange (no other process has particles there).
  // `peers`, `sent` and `received` (per peer, in rank order): which of this process's particles
  // went to each, and how many ghosts came from each (appended in that order), for sums a
  // mapping makes at the ghosts that belong to their owners (add_ghost_values_to_owners).
  struct Ghosts {
    Index owned = -1;
    std::array<Index, 2> layers{0, -1};
    std::vector<int> peers;
    std::vector<std::vector<Index>> sent;
    std::vector<Index> received;
  } ghosts;
  // Per-particle state of the basis that travels with the particles between processes (CPDI2's
  // tracked corners): `carried_width` doubles per particle in particle order, filled by the
  // stepper before a migration or a distributed checkpoint (Stepper::export_carried), moved
  // and gathered with the particles (pack_particle), and taken back by the basis after
  // (Stepper::resize_particle_caches). Empty otherwise.
  int carried_width = 0;
  std::vector<double> carried;
  // This process's own particles: the first own_particles() of `particles` (all but ghosts).
  Index own_particles() const { return ghosts.owned >= 0 ? ghosts.owned : particles.size(); }
  // The DOF range [lo, hi] that a reconstruction mapping's quadrature points touched in this
  // step (lo > hi: none); the exchange shares the union with the particles' range.
  std::array<Index, 2> quadrature_dofs{std::numeric_limits<Index>::max(), -1};
  // [first, end) of the cells whose elements this process integrates: all of them on one
  // process; in a distributed run those of the layers its particles occupy (ghosts.layers), so
  // that each element is integrated by exactly one process.
  std::array<Index, 2> own_cells() const {
    if (comm == nullptr) return {0, grid.num_cells()};
    const Index per_layer = grid.num_cells() / grid.cells[Dim - 1];
    const auto& l = ghosts.layers;
    if (l[0] > l[1]) return {0, 0};
    return {l[0] * per_layer, (l[1] + 1) * per_layer};
  }

  // The particles' velocity gradients [1/s] from the mapping (MappingFor's kStrainRates: TLS's
  // adjoint rate), written by stages::mapped_strain_rates just before the stress update that
  // reads them, which empties it; empty: each particle's gradient from its stencil (D eq. 2.52).
  std::vector<Mat<Dim>> mapped_gradient;

  double time = 0.0;  // t^s [s]
  Index step = 0;     // s
  Diagnostics diag;
};

// RunState with the basis and the cached basis stencils: everything the mapping-independent
// per-particle stages read (basis evaluation, grid-to-particle updates, tractions, sorting).
// Those stages take a BasisState, so each is compiled once per (dimension, basis), not once
// per mapping as well.
template <int Dim, class Basis>
struct BasisState : RunState<Dim> {
  using BasisT = Basis;
  using StencilT = typename Basis::StencilT;
  // The per-particle cache: the compact 1D factors for tensor-product bases, else StencilT.
  using CachedT = typename CachedStencilOf<Basis>::type;

  // whole_grid = false (a process of a distributed run): the grid arrays start with an empty
  // window, placed by the first evaluate_basis (RunState::fit_dof_window), so that no process
  // allocates them for the whole grid.
  BasisState(const Grid<Dim>& g, Basis b, Particles<Dim> p, Material mat, bool whole_grid = true)
      : RunState<Dim>(g, std::move(p), std::move(mat)), basis(std::move(b)) {
    auto& particles = this->particles;
    this->nodes.resize(basis.num_dofs(), whole_grid);
    // Room for an eighth more particles (Particles::keep_room: particles arriving from other
    // processes; the capacity beyond them is never written and takes no resident memory).
    const auto n = static_cast<std::size_t>(particles.size());
    stencils.reserve(n + n / 8);
    stencils.resize(n);
    this->dof_stride = dof_strides<Dim>(basis.dofs_per_dim());
    this->cell.reserve(n + n / 8);
    this->cell.assign(n, -1);
    // Particle ids and cells are stored as CompactIndex (core/types.hpp).
    constexpr Index kMax = std::numeric_limits<CompactIndex>::max();
    if (particles.size() > kMax || this->grid.num_cells() > kMax)
      throw InputError("a run holds at most " + std::to_string(kMax) + " particles and cells; " +
                       "this one has " + std::to_string(particles.size()) + " particles and " +
                       std::to_string(this->grid.num_cells()) + " cells");
  }

  Basis basis;
  std::vector<CachedT> stencils;  // basis at x_p^s, refreshed by evaluate_basis()

  // Prescribe zero velocity on a grid side (d: direction, side 0/1) in the components whose
  // bit is set in `components` (all by default); conditions on several sides combine.
  void fix_side(int d, int side, unsigned components = ~0u) {
    fix_dofs(basis.boundary_dofs(d, side), components);
  }
  // The same on a named boundary of the basis's triangle mesh (FixedSide::boundary).
  void fix_boundary(std::string_view name, unsigned components = ~0u) {
    if constexpr (Basis::kTriangleMesh)
      fix_dofs(basis.boundary_dofs(name), components);
    else
      throw std::logic_error("fix_boundary: named boundaries belong to bases on triangles");
  }
  // A roller on an inclined named boundary: v_i . n = 0 on its DOFs (n: unit normal). Since
  // v . n = sum_i phi_i (v_i . n) on the boundary, this holds along the whole boundary for the
  // DOFs whose functions do not vanish there (what boundary_dofs lists).
  void fix_boundary_normal(std::string_view name, const Vec<Dim>& n) {
    if constexpr (Basis::kTriangleMesh)
      this->constrain(basis.boundary_dofs(name), n * n.transpose());
    else
      throw std::logic_error("fix_boundary_normal: named boundaries belong to bases on triangles");
    this->refresh_per_component();
  }
  // A roller on a bent named boundary of a P1 mesh (DOF i is vertex i): v_i . n = 0 for each
  // (vertex, unit normal) of FixedSide::vertex_normals.
  void fix_vertex_normals(const std::vector<std::pair<Index, std::array<double, 3>>>& normals) {
    if constexpr (Basis::kTriangleMesh) {
      if (basis.num_dofs() != basis.mesh().num_vertices())
        throw std::logic_error("fix_vertex_normals: the basis's DOFs are not the mesh vertices");
      for (const auto& [v, a] : normals) {
        Vec<Dim> n;
        for (int d = 0; d < Dim; ++d) n[d] = a[static_cast<std::size_t>(d)];
        this->constrain({v}, n * n.transpose());
      }
    } else {
      throw std::logic_error("fix_vertex_normals: named boundaries belong to bases on triangles");
    }
    this->refresh_per_component();
  }

 private:
  void fix_dofs(const std::vector<Index>& dofs, unsigned components) {
    Mat<Dim> c = Mat<Dim>::Zero();
    for (int d = 0; d < Dim; ++d)
      if (components & (1u << d)) c(d, d) = 1.0;
    this->constrain(dofs, c);
    this->refresh_per_component();
  }
};

// The whole state of a run: BasisState with the mapping.
template <int Dim, class Basis, class Mapping>
struct Simulation : BasisState<Dim, Basis> {
  using MappingT = Mapping;

  Simulation(const Grid<Dim>& g, Basis b, Mapping m, Particles<Dim> p, Material mat,
             bool whole_grid = true)
      : BasisState<Dim, Basis>(g, std::move(b), std::move(p), std::move(mat), whole_grid),
        mapping(std::move(m)) {}

  Mapping mapping;
};

}  // namespace mpm
