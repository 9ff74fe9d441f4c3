#pragma once
// The state of one run in three layers: RunState (state/run_state.hpp: the model, the grid and
// solver state, the distribution), BasisState (+ basis and cached stencils), Simulation
// (+ mapping). Stages (scheme/stages.hpp)
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
#include "model/problem.hpp"
#include "particles/particles.hpp"
#include "state/run_state.hpp"

namespace mpm {

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
  BasisState(const Grid<Dim>& g, Basis b, Particles<Dim> p, Materials mat, bool whole_grid = true)
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
  // Prescribes the velocity of `pv` on the DOFs whose positions lie in its box (to 1e-9 of the
  // largest cell size) in its components; returns those DOFs (none: the box holds no DOF).
  std::vector<Index> prescribe_box(const PrescribedVelocity& pv) {
    const double tol = 1e-9 * this->grid.h.maxCoeff();
    std::vector<Index> dofs;
    for (Index i = 0; i < basis.num_dofs(); ++i) {
      const Vec<Dim> x = basis.dof_position(i);
      bool in = true;
      for (int d = 0; d < Dim; ++d) {
        const auto k = static_cast<std::size_t>(d);
        in = in && x[d] >= pv.min[k] - tol && x[d] <= pv.max[k] + tol;
      }
      if (in) dofs.push_back(i);
    }
    if (dofs.empty()) return dofs;
    fix_dofs(dofs, pv.components);
    Vec<Dim> v;
    for (int d = 0; d < Dim; ++d) v[d] = pv.velocity[static_cast<std::size_t>(d)];
    auto& pr = this->nodes.prescribed;
    for (Index i : dofs) pr.emplace_back(i, v);
    std::sort(pr.begin(), pr.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    return dofs;
  }
  // The DOFs of a grid side (d, side) or of a named boundary of the basis's mesh.
  std::vector<Index> side_dofs(const FixedSide& f) const {
    if (f.boundary.empty()) return basis.boundary_dofs(f.direction, f.side);
    if constexpr (Basis::kTriangleMesh)
      return basis.boundary_dofs(f.boundary);
    else
      throw std::logic_error("side_dofs: named boundaries belong to bases on triangles");
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

  Simulation(const Grid<Dim>& g, Basis b, Mapping m, Particles<Dim> p, Materials mat,
             bool whole_grid = true)
      : BasisState<Dim, Basis>(g, std::move(b), std::move(p), std::move(mat), whole_grid),
        mapping(std::move(m)) {}

  Mapping mapping;
};

}  // namespace mpm
