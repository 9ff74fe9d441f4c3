#pragma once
// The mapping concept: how particle quantities reach the grid (D 3.2, 5.3; 004 4.4). Every
// mapping maps masses, momenta and forces for a simulation type Sim, and declares its optional
// capabilities as constants that the stages and the driver branch on (never on whether a member
// happens to exist; the concept checks that a declared capability has its members):
//   kFusedScatter  map_fused<What>(sim[, dt]): several grid sums in one pass over the particles,
//                  the bits of separate passes (DirectMapping; stages::map_to_grid)
//   kRunTotals     totals() / save_totals() / load_totals(): counters over the run (TLS
//                  completions, MLS conditioning), reported in summary.json and kept in
//                  checkpoints as the bytes the mapping writes of itself
//   kGhostParticles ghost_reach(sim): the mapping reads the particles of neighbouring cells
//                  (TLS). A distributed run gives it, for each sum, copies of the other
//                  processes' particles within ghost_reach(sim) cells (along every axis) of its own
//                  (stages::GhostParticles), and the mapping integrates only the elements of
//                  RunState::own_cells(), so that each element is integrated once.
//   kStrainRates   strain_rates(sim): the mapping may define the particles' velocity
//                  gradients for the stress update (TLS's adjoint rate), which it writes to
//                  RunState::mapped_gradient (stages::mapped_strain_rates)
//   kCellQuadrature gauss_points(): the grid sums are integrals by that many Gauss points per
//                  direction of each cell (the reconstructions), not sums over the particles:
//                  face tractions are then integrated over each loaded point's patch by as
//                  many Gauss points (stages::after_forces), so that a uniform load meets a
//                  quadrature as exact as the masses' one
// Mappings hold no per-particle state, so re-sorting the particles (state/sort.hpp) needs
// nothing from them.
#include <concepts>
#include <string>
#include <string_view>

#include "state/simulation.hpp"

namespace mpm {

template <class M, class Sim>
concept MappingFor = requires(M& m, Sim& sim, int dim) {
  { M::kName } -> std::convertible_to<std::string_view>;
  { M::kFusedScatter } -> std::convertible_to<bool>;
  { M::kRunTotals } -> std::convertible_to<bool>;
  { M::kGhostParticles } -> std::convertible_to<bool>;
  { M::kStrainRates } -> std::convertible_to<bool>;
  { M::kCellQuadrature } -> std::convertible_to<bool>;
  { M::supports_dimension(dim) } -> std::convertible_to<bool>;
  m.map_mass(sim);      // nodal masses (and the consistent matrix), D eq. 2.31 / 2.44
  m.map_momentum(sim);  // nodal momenta, 2.32 / 2.48
  m.map_forces(sim);    // internal and body forces, 2.33 / 2.45
}
&&(!M::kFusedScatter ||
   requires(M & m, Sim& sim, double dt) {
     m.template map_fused<grid_sum::kMass | grid_sum::kMomentum | grid_sum::kForces>(sim);
     m.template map_fused<grid_sum::kMomentum | grid_sum::kVelocityFirst>(sim, dt);
   }) &&
    (!M::kGhostParticles ||
     requires(const M& cm, const Sim& sim) {
       { cm.ghost_reach(sim) } -> std::convertible_to<double>;
     }) &&
    (!M::kStrainRates || requires(M & m, Sim& sim) { m.strain_rates(sim); }) &&
    (!M::kCellQuadrature ||
     requires(const M& cm) {
       { cm.gauss_points() } -> std::convertible_to<int>;
     }) &&
    (!M::kRunTotals ||
     requires(M & m, const M& cm, std::string_view bytes, const std::string& what) {
       { cm.save_totals() } -> std::same_as<std::string>;
       m.load_totals(bytes, what);
     });

// The mapping type a stepper runs for a configured mapping: the mapping itself, or a class that
// runs several configured alternatives with a run-time choice (MLS and IMLS: MlsFamilyMapping,
// mapping/mls.hpp), so that the stepper units compile one Simulation for them.
template <class M>
struct stepped_mapping {
  using type = M;
};
template <class M>
using stepped_mapping_t = typename stepped_mapping<M>::type;

}  // namespace mpm
