#pragma once
// The optimal transportation meshfree method (OTM, D 4.2, Algorithm 3) in 1D and 2D: nodes that
// move with the material, material points that are the quadrature points, the basis evaluated every
// step on the advected nodes (P1 or local max-ent, D 4.3), and per step
//   M_ij = sum_p phi_i m_p phi_j,  q_i = sum_p phi_i m_p (x_p^s - x_p^{s-1}) / dt,
//   f_i = sum_p (-grad phi_i sigma_p + phi_i rho_p b_p) V_p                  (D eq. 4.28-4.30)
//   x_i^{s+1} = x_i^s + dt M^-1 (q + dt f)                                   (4.31, constant dt)
//   x_p^{s+1} = sum_i phi_i(x_p^s) x_i^{s+1},  F_p and V_p by grad phi^{s->s+1}  (4.32-4.35).
// D prints eq. 4.30 with +grad phi sigma; the internal force is -int grad phi sigma dV (D eq.
// 2.33), which the test OTM-P1 = USL-MPM-P1 on the first step (D 4.4) confirms.
//
// The particles' velocity v_p holds (x_p^{s+1} - x_p^s) / dt, a velocity at t^{s+1/2}: the
// momentum of the next step (4.29), with x_p^{-1} = x_p^0 - dt v_p^0 for the first (D 4.4).
// The nodes are the grid's nodes from the body's first to its last at the start (the body's ends
// must be grid nodes; OTM has no empty elements); a grid side's Dirichlet condition fixes the
// body's end node where the body touches that side; a traction acts on the body's end node
// (unified: its end control point), where the basis interpolates, and in 2D through the
// functions of the isoparametric map at the face points' material positions. The nodal sums, the
// conservation checks and the mass solves are the MPM stages' (RunState's nodes hold the
// advected nodes' sums), lumped or consistent mass by method.mass (D: consistent).
//
// The unified approach (D 4.5, Algorithm 4) is the same nodal update with B-splines of degree p
// on advected degrees of freedom and USL's particle velocity, v_p += dt sum phi_i a_i (4.88):
// the degrees of freedom are the control points c_i of the map x(X) = sum_i B_i(X) c_i from the
// material coordinate X (the initial grid, its open uniform knot vector), which start at the
// Greville abscissae (x(X) = X) and move by c_i += dt v_i (4.85-4.86). A material point keeps X,
// x_p = x(X_p) (4.87 by induction), phi_i(x_p) = B_i(X_p) and grad phi_i = B_i'(X_p) / x'(X_p).
// With p = 1 this is P1 on the advected nodes, OTM-P1's basis. D does not say how the basis
// follows the advected degrees of freedom; this isoparametric reading is ours.
//
// Powell-Sabin splines in the unified approach (D 7.3: "an alternative to partial lumping"): the
// same map with the quadratic PS splines N_ij of the body's triangulation (2D): the control
// points start at the PS-triangle vertices Q_ij, so x(X) = sum N_ij(X) Q_ij = X (PS splines
// reproduce quadratics), and move with the material. The material points keep X, so the
// functions and the mass matrix are those of the initial, full triangles for the whole run: no
// element is ever partially filled, which is what makes consistent PS mass fail in PS-MPM.
#include <memory>
#include <string>
#include <vector>

#include "basis/maxent_settings.hpp"
#include "grid/triangle_mesh.hpp"
#include "methods/otm_settings.hpp"
#include "model/problem.hpp"
#include "state/simulation.hpp"

namespace mpm {

template <int Dim>
class PowellSabinGridBasis;  // basis/powell_sabin.hpp

// OTM (1D and 2D: P1, max-ent) and the unified approach (1D and 2D, tensor-product B-splines;
// 2D, Powell-Sabin splines).
template <int Dim>
class Otm {
 public:
  // Takes the problem's particles. InputError when the body's ends are not grid nodes, or for
  // tractions on OTM-maxent in 2D.
  Otm(Problem<Dim>& pb, const OtmSettings& s);

  // One step of D Algorithm 3 or 4 (the driver sets the step counter and time afterwards).
  // RunError: a particle outside the nodes' span (exit code 4), inverted elements or det <= 0
  // (5), a max-ent point that does not converge (10), non-finite values (3), conservation (9).
  void step(double dt);

  RunState<Dim>& state() { return st_; }
  const RunState<Dim>& state() const { return st_; }
  // The advected node coordinates [m] (unified: the control points), Dim per node, for
  // checkpoints; set_nodes throws InputError naming `what` when the count differs or OTM's nodes
  // are not increasing.
  const std::vector<double>& nodes() const { return x_; }
  void set_nodes(const std::vector<double>& x, const std::string& what);
  const OtmSettings& settings() const { return s_; }
  // Unified PS: the splines of the material triangles; null otherwise.
  const PowellSabinGridBasis<2>* powell_sabin() const { return ps_.get(); }

 private:
  void evaluate_basis();
  // The max-ent functions of the advected nodes at x (element e holds x; 1D): appends to the
  // particle's stencil; false when Newton did not converge.
  bool maxent_at(double x, Index e, Index p);
  // OTM-maxent in 2D: the rows of every particle (nodes found through bins).
  void maxent_rows();
  void add_tractions();
  // Unified: B_i(X_p) and (dx/dX)^-T grad_X B_i(X_p) of every particle.
  template <int P>
  void bspline_rows();
  // Unified with Powell-Sabin splines: the same on the material triangles (2D).
  void powell_sabin_rows();
  // grad_x phi_i = (dx/dX)^-T grad_X N_i at material point p from its stencil's functions of X;
  // RunError when the map is inverted there.
  template <class Stencil>
  void append_isoparametric_row(Index p, const Stencil& s);

  RunState<Dim> st_;
  Grid<Dim> body_;  // the body's part of the initial grid: the initial nodes (unified: the knots)
  OtmSettings s_;
  bool iso_ = false;  // the isoparametric map (unified: B-splines of degree degree_ or PS; OTM-P1)
  int degree_ = 1;
  std::vector<double> x_;       // advected node coordinates [m], Dim per node
  std::vector<Index> element_;  // OTM: element of each particle (x_e <= x_p <= x_{e+1});
                                // unified PS: its material triangle (X_p never changes)
  std::shared_ptr<const PowellSabinGridBasis<2>> ps_;  // unified PS: the splines of X
  std::vector<double> support_;  // OTM max-ent: the support radius d_i of each node this step
  // Per-particle stencils of variable size (max-ent), compressed rows: nodes, values, gradients
  // (Dim per entry).
  std::vector<Index> row_, node_;
  std::vector<double> w_, g_;
};

}  // namespace mpm
