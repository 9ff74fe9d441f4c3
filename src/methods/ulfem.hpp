#pragma once
// One-dimensional updated-Lagrangian finite element method (ULFEM) with linear elements, lumped
// mass and Euler-Cromer time stepping (D 2.3.2). It is the reference solution of the
// large-deformation vibrating bar (D 5.4.1: "ULFEM", 120 degrees of freedom) and runs on every
// 1D benchmark. The mesh moves with the material, so there is no grid crossing and no
// particle-to-grid mapping: it integrates exactly the constitutive laws of the MPM stages
// (same F update F_new = (1 + dt L) F_old, same law.update(sigma, state, F_new, dtL) call), which
// makes MPM and ULFEM differ only by the spatial discretisation.
#include <functional>
#include <vector>

#include "model/problem.hpp"

namespace mpm {

class Ulfem1D {
 public:
  // Discretises the body [pb.body_min, pb.body_max] into `elements` linear elements with nodes
  // evenly spaced in the material coordinate X. Nodal masses are lumped (rho0 L0_e / 2 per
  // element end), v(X) = pb.initial_velocity at the nodes, sigma = pb.initial_stress at the
  // element midpoints (zero when empty). A body end is fixed (v = 0) when it lies on a grid
  // side listed in pb.fixed_sides. Throws InputError for elements < 1 or an empty body.
  Ulfem1D(const Problem<1>& pb, Index elements);

  // One Euler-Cromer step of size dt [s] from t to t + dt: a = M^-1 (f_ext(t) - f_int),
  // v += dt a, x += dt v, then F, V, rho and sigma per element. Throws RunError (exit codes
  // kNonFinite / kInvertedDeformation) when an element inverts or its stress is not finite; the
  // step counter and time then still refer to the start of the failed step. Stability is the
  // caller's responsibility: dt < critical_dt().
  void step(double dt);

  double time() const { return time_; }  // [s]
  Index steps() const { return steps_; }

  // The state as one "particle" per element at its midpoint (for outputs and error norms):
  // x0 material midpoint, x current midpoint, u = x - x0, v mean of the two nodes, mass,
  // volume (current length), volume0 (initial length), density, F, stress, body (mean of the
  // nodal body force). Refreshed by step().
  const Particles<1>& elements() const { return el_; }

  // Cauchy stress [Pa] at the material position X: linear interpolation between element
  // midpoints, constant beyond the outermost midpoints.
  double stress_at(double X) const;

  // Nodal material positions [m], current positions [m], velocities [m/s], lumped masses [kg]
  // (per unit area).
  const std::vector<double>& node_X() const { return X_; }
  const std::vector<double>& node_x() const { return x_; }
  const std::vector<double>& node_v() const { return v_; }
  const std::vector<double>& node_mass() const { return m_; }

  // Conserved quantities for diagnostics: kinetic energy sum m_i v_i^2 / 2 [J], stored energy
  // from law.energy over the elements [J], momentum sum m_i v_i [kg m/s] (all per unit area).
  double kinetic_energy() const;
  double strain_energy() const;
  double momentum() const;

  // Largest stable step estimate min_e l_e / c [s] with the current element lengths and the
  // material's small-strain wave speed (the large-deformation tangent stiffness can raise c:
  // keep a margin).
  double critical_dt() const;

  // The complete mutable state, for checkpoints (io/checkpoint.hpp): restore(save()) on a solver
  // built from the same problem continues bit for bit. The nodal material positions and masses
  // are not included: the constructor computes them from the problem.
  struct State {
    std::vector<double> x, v;       // nodal current positions [m], velocities [m/s]
    std::vector<Vec<1>> node_body;  // nodal body force per unit mass [m/s^2]
    Particles<1> elements;          // the per-element state (elements())
    double time = 0.0, time_anchor = 0.0, last_dt = 0.0;
    Index steps = 0, steps_since_anchor = 0;
  };
  State save() const;
  // Throws InputError when the sizes do not match this solver's mesh.
  void restore(const State& s);

 private:
  void refresh_body_force(double t);
  void check_elements() const;  // throws RunError

  Material material_;
  BodyForce<1> body_force_;
  std::vector<Traction<1>> tractions_;
  bool fixed_lo_ = false, fixed_hi_ = false;
  double X_lo_ = 0.0, dX_ = 0.0;  // material coordinate of node 0, element length L0 [m]

  std::vector<double> X_, x_, v_, m_;  // per node
  std::vector<double> force_;          // f_ext - f_int per node [N per unit area]
  Particles<1> nodes_;                 // node positions handed to BodyForce::fill
  Particles<1> el_;                    // per element

  double time_ = 0.0;
  Index steps_ = 0;
  // Time is anchor + n dt while dt stays the same, so that t = s dt exactly as in the MPM runner.
  double time_anchor_ = 0.0, last_dt_ = 0.0;
  Index steps_since_anchor_ = 0;
};

}  // namespace mpm
