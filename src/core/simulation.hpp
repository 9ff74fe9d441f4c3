#pragma once
// The state of one run: grid, basis, mapping, particles, material, grid quantities and the
// cached basis stencils. Stages (scheme/stages.hpp) operate on it; schemes order the stages.
#include <functional>
#include <string_view>
#include <vector>

#include "basis/stencil.hpp"
#include "grid/grid.hpp"
#include "grid/grid_state.hpp"
#include "material/materials.hpp"
#include "particles/particles.hpp"
#include "scheme/parallel.hpp"
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

// Body force per unit mass b(x, t) [m/s^2]. `fill` writes b for all particles at once (one
// indirect call per step, the loop inside); skipped when the force is constant in time.
template <int Dim>
struct BodyForce {
  std::function<void(const Particles<Dim>&, double t, std::vector<Vec<Dim>>& b)> fill;
  bool time_dependent = false;
  bool position_dependent = false;
};

// A traction on the free end of a 1D body, applied at the outer edge of the end particle's
// domain: f_i += phi_i(x_end) tau(t) (the boundary integral of D eq. 2.21; unit area).
// side = +1: the upper end x_p + V_p/2; -1: the lower end x_p - V_p/2 (1D: V_p is a length).
template <int Dim>
struct EndTraction {
  Index particle = 0;
  int side = 1;
  std::function<Vec<Dim>(double t)> value;  // traction vector tau(t) [Pa]
};

// Conservation and grid-crossing bookkeeping reported in summary.json (D 5.4).
struct Diagnostics {
  double max_rel_mass_error = 0.0;      // max over steps |sum M_ij - sum m_p| / sum m_p
  double max_rel_momentum_error = 0.0;  // max over steps |sum q_i - sum m_p v_p| / sum m_p|v_p|
  Index grid_crossings = 0;             // particle moves into another cell, summed over steps
};

template <int Dim, class Basis, class Mapping>
struct Simulation {
  static constexpr int kDim = Dim;
  using BasisT = Basis;
  using MappingT = Mapping;
  using StencilT = typename Basis::StencilT;
  // The per-particle cache: the compact 1D factors for tensor-product bases, else StencilT.
  using CachedT = typename CachedStencilOf<Basis>::type;

  Simulation(const Grid<Dim>& g, Basis b, Mapping m, Particles<Dim> p, Material mat)
      : grid(g),
        basis(std::move(b)),
        mapping(std::move(m)),
        particles(std::move(p)),
        material(std::move(mat)) {
    nodes.resize(basis.num_dofs());
    stencils.resize(static_cast<std::size_t>(particles.size()));
    if constexpr (requires { basis.dofs_per_dim(); })
      dof_stride = dof_strides<Dim>(basis.dofs_per_dim());
    cell.assign(static_cast<std::size_t>(particles.size()), -1);
  }

  Grid<Dim> grid;
  Basis basis;
  Mapping mapping;
  Particles<Dim> particles;
  Material material;
  MassType mass_type = MassType::Lumped;
  double mass_tolerance = 1e-10;  // relative to the largest nodal mass
  BodyForce<Dim> body_force;
  std::vector<EndTraction<Dim>> tractions;

  GridState<Dim> nodes;
  ConsistentMass consistent;
  bool consistent_per_component = false;  // one factorisation per velocity component
  std::vector<CachedT> stencils;          // basis at x_p^s, refreshed by evaluate_basis()
  IVec<Dim> dof_stride{};                 // DOF strides of a tensor-product basis (CachedT)
  std::vector<Index> cell;                // cell of each particle at the last evaluation
  ScatterBuffers<Dim> scatter;            // per-chunk grid buffers of the parallel scatters

  double time = 0.0;  // t^s [s]
  Index step = 0;     // s
  Diagnostics diag;

  // Prescribe zero velocity on a grid side (d: direction, side 0/1) in the components whose
  // bit is set in `components` (all by default); conditions on several sides combine.
  void fix_side(int d, int side, unsigned components = ~0u) {
    const auto mask = static_cast<std::uint8_t>(components & ((1u << Dim) - 1u));
    for (Index i : basis.boundary_dofs(d, side)) nodes.fixed[static_cast<std::size_t>(i)] |= mask;
  }
};

}  // namespace mpm
