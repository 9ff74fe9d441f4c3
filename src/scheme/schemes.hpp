#pragma once
// The four explicit update schemes as orders of the shared stages. Each step() reads like the
// algorithm it implements; none of them copies a loop. Adjacent particle passes that read the
// same grid state are fused (map_to_grid, update_particles: one pass over the particles and
// their stencils instead of two or three, the same bits).
#include <string_view>
#include <variant>

#include "scheme/stages.hpp"

namespace mpm {

// Update stress last, D Algorithm 1.
struct Usl {
  static constexpr std::string_view kName = "usl";
  static constexpr std::string_view kDescription =
      "update stress last: grid velocity advanced from grid acceleration (D Algorithm 1)";
  // The particle velocity after a step approximates v(t + kVelocityTime dt): Euler-Cromer's
  // velocity is the leapfrog half-step velocity when the stress is updated last (D 2.3.2).
  static constexpr double kVelocityTime = -0.5;
  template <class Sim>
  static void step(Sim& sim, double dt) {
    using namespace stages;
    evaluate_basis(sim);  // phi_i(x_p^s), grad phi_i(x_p^s)
    refresh_body_force(sim);
    // M^s (2.31), q^s (2.32), f^s (2.33) in one pass over the particles
    map_to_grid<grid_sum::kMass | grid_sum::kMomentum | grid_sum::kForces>(sim);
    // v_i^s first: the walls' friction starts from it (the two solves are otherwise independent)
    solve_velocity(sim);             // v_i^s     (2.35)
    solve_acceleration(sim, dt);     // a^s       (2.34)
    advance_grid_velocity(sim, dt);  // v_i^{s+1} (2.36)
    mapped_strain_rates(sim);        // L_p from v_i^{s+1} where the mapping defines it
    // x_p^{s+1} (2.38), v_p^{s+1} (2.39), F, V, rho, sigma from v_i^{s+1} (2.40-2.43) in one pass
    using namespace particle_update;
    update_particles<kPosition | kVelocity | kStress>(sim, dt);
  }
};

// Modified update stress last, D Algorithm 2 (004 4.2.2).
struct Musl {
  static constexpr std::string_view kName = "musl";
  static constexpr std::string_view kDescription =
      "modified USL: grid velocity remapped from updated particle velocity (D Alg. 2)";
  static constexpr double kVelocityTime = -0.5;
  template <class Sim>
  static void step(Sim& sim, double dt) {
    using namespace stages;
    evaluate_basis(sim);
    refresh_body_force(sim);
    // M^s (2.44), f^s (2.45); q^s too where the local damping or a frictional wall needs the
    // nodes' velocities
    if (sim.forces_need_momentum())
      map_to_grid<grid_sum::kMass | grid_sum::kMomentum | grid_sum::kForces>(sim);
    else
      map_to_grid<grid_sum::kMass | grid_sum::kForces>(sim);
    solve_acceleration(sim, dt);            // a^s                (2.46)
    update_velocity_map_momentum(sim, dt);  // v_p^{s+1} (2.47), q from it (2.48): one pass
    solve_velocity(sim);                    // v_i^{s+1}          (2.49)
    mapped_strain_rates(sim);               // L_p where the mapping defines it
    // x_p^{s+1} (2.50-2.51), F, V, rho, sigma (2.52-2.55) in one pass
    update_particles<particle_update::kPosition | particle_update::kStress>(sim, dt);
  }
};

// Update stress first (D 2.6.3): the stress is updated at the start of the step from the grid
// velocity of v_p^s, then forces use the new stress.
struct Usf {
  static constexpr std::string_view kName = "usf";
  static constexpr std::string_view kDescription =
      "update stress first: stress from the start-of-step grid velocity (D 2.6.3)";
  // The stress leads: sigma^{s+1} uses v^s, so v_p^s plays the role of v^{s+1/2}.
  static constexpr double kVelocityTime = +0.5;
  template <class Sim>
  static void step(Sim& sim, double dt) {
    using namespace stages;
    evaluate_basis(sim);
    refresh_body_force(sim);
    map_to_grid<grid_sum::kMass | grid_sum::kMomentum>(sim);  // M^s, q from v_p^s
    solve_velocity(sim);                                      // v_i^s
    mapped_strain_rates(sim);                                 // L_p where the mapping defines it
    update_stress(sim, dt);                                   // sigma^{s+1} from v_i^s
    map_forces(sim);  // f with the updated stress and volume
    solve_acceleration(sim, dt);
    advance_grid_velocity(sim, dt);  // v_i^{s+1} = v_i^s + dt a_i
    // v_p^{s+1} from a^s (the grid update leaves it), x_p^{s+1} from v_i^{s+1}: one pass
    update_particles<particle_update::kVelocity | particle_update::kPosition>(sim, dt);
  }
};

// Update stress averaged (D 2.6.3, after Nairn): half the stress increment from the
// start-of-step grid velocity (USF), half from the remapped end-of-step velocity (MUSL).
struct Usavg {
  static constexpr std::string_view kName = "usavg";
  static constexpr std::string_view kDescription =
      "update stress averaged: half USF, half MUSL stress increment (D 2.6.3, Nairn)";
  // Half of each: the velocity is centred on the step end.
  static constexpr double kVelocityTime = 0.0;
  template <class Sim>
  static void step(Sim& sim, double dt) {
    using namespace stages;
    evaluate_basis(sim);
    refresh_body_force(sim);
    map_to_grid<grid_sum::kMass | grid_sum::kMomentum>(sim);  // M^s, q from v_p^s
    solve_velocity(sim);                                      // v_i^s
    mapped_strain_rates(sim);                                 // L_p where the mapping defines it
    update_stress(sim, 0.5 * dt);                             // USF half
    map_forces(sim);
    solve_acceleration(sim, dt);
    update_velocity_map_momentum(sim, dt);  // v_p^{s+1}, q from v_p^{s+1}: one pass
    solve_velocity(sim);                    // v_i^{s+1}
    mapped_strain_rates(sim);               // L_p where the mapping defines it
    // x_p^{s+1} and the MUSL half of the stress increment in one pass
    update_particles<particle_update::kPosition | particle_update::kStress>(sim, dt, 0.5 * dt);
  }
};

using Scheme = std::variant<Usl, Usf, Musl, Usavg>;

}  // namespace mpm
