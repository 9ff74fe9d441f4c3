#pragma once
// `mpm stiffness`: the linearised semi-discrete operator of a mapping on a frozen particle layout
// (why TLS grows at A = 0.1 while the direct mapping does not).
//
// With the particles held where they are, a grid velocity v gives each particle the velocity
// gradient L_p = sum_i v_i grad phi_i(x_p)^T, its law the stress rate dsigma_p = C_p : L_p (the
// tangent of its state, by central differences of the law's update), and the mapping the grid
// force df = f(dsigma): v'' = K v with K = M^-1 (df/dsigma) C B. A mode v ~ exp(lambda t) has
// lambda^2 = mu, an eigenvalue of K. The direct mapping's force is -B^T W sigma (W: the
// particle volumes), the adjoint of the strain rate B, so M K is symmetric negative
// semidefinite on an unstressed layout: every lambda is imaginary (neutral; D 2.3). TLS
// integrates its fitted stress against the gradients at its Gauss points, f = -B_g^T W_g R sigma
// (R: the fit), which is not the adjoint of B: a lambda with a positive real part is a mode that
// grows whatever the time step.
//
// The operator leaves out what moves with the particles (their positions, volumes and the
// gradients at them), which the pre-stress of a deformed state multiplies (the geometric
// stiffness): on a stressed state its spectrum is not the run's. `layout_only` sets every
// stress to zero and F to the identity, so that only the layout acts: the operator is then
// exact for the direct mapping's neutrality, and any growth is the mapping's.
#include <iosfwd>
#include <string>
#include <vector>

namespace mpm {

struct StiffnessOptions {
  std::string config;
  std::vector<std::string> sets;
  std::string checkpoint;  // the particles of a run's checkpoint; empty: the initial layout
  bool layout_only = false;
  double period = 0.0;  // > 0: report the energy factor exp(2 gamma period)
};

struct StiffnessRow {
  std::string force, mass;  // the mappings whose force and lumped mass make the operator
  int dofs = 0;             // active velocity components (mass > 0, not fixed)
  double growth = 0.0;      // largest Re lambda [1/s]
  double omega = 0.0;       // largest |Im lambda| [rad/s]
  double asymmetry = 0.0;   // ||S - S^T||_F / ||S||_F, S = df/dv on the active components
};

struct StiffnessReport {
  std::string basis, mapping, state;  // state: "initial layout" or the checkpoint's time
  int particles = 0;
  std::vector<StiffnessRow> rows;
};

// Throws InputError naming the key for a configuration it cannot analyse (not 2D, a basis
// other than linear or quadratic B-splines on the grid, a mapping other than direct or TLS).
StiffnessReport stiffness_spectrum(const StiffnessOptions& opt);
void print_stiffness(std::ostream& os, const StiffnessOptions& opt, const StiffnessReport& r);

}  // namespace mpm
