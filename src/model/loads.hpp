#pragma once
// The loads of a problem: body forces and face tractions (model layer; the stages of
// scheme/stages.hpp apply them).
#include <cstddef>
#include <functional>
#include <vector>

#include "core/types.hpp"
#include "particles/particles.hpp"

namespace mpm {

// Body force per unit mass b(x, t) [m/s^2]. `fill` writes b for all particles at once (one
// indirect call per step, the loop inside); skipped when the force is constant in time.
template <int Dim>
struct BodyForce {
  std::function<void(const Particles<Dim>&, double t, std::vector<Vec<Dim>>& b)> fill;
  bool time_dependent = false;
  bool position_dependent = false;
};

// A traction tau(t) on a face of the body, applied through the particles adjacent to that face
// (Steffen et al. 2008; D 4.6.2 and eq. 2.21 for the 1D traction bar): each loaded point k adds
// the point force phi_i(x_k) (tau(t) - p(t) n_k) A_k, the one-point quadrature of the boundary
// integral int phi_i tau dA over its share A_k of the face. tau and p are nominal (per unit
// reference area, dead loads): the direction of tau, the normals n_k and the areas A_k stay those
// of the undeformed body. The point follows its particle's deformation:
// x_k = x_p + F_p (X_k - X_p), with the reference offset X_k - X_p fixed at the start (a box face:
// l_p e_d outwards, l_p the reference half-width of the particle domain along the face normal
// e_d; a mesh edge: from the nearest particle of its triangle to a point on the edge). In 1D
// x_k = x_p + side V_p / 2 (V_p is the current length; A_k = 1, the force per unit
// cross-section).
template <int Dim>
struct Traction {
  int direction = 0;  // box faces and 1D: the face normal is e_d
  int side = 1;       // +1: the upper face (outward normal +e_d); -1: the lower face
  // The particle carrying each loaded point: in a Problem its id (which is its index as set
  // up on one process); in a run's RunState::tractions its index there.
  std::vector<Index> particles;
  std::vector<double> area;      // A_k [m^(Dim-1)] per loaded point (1D: 1)
  std::vector<Vec<Dim>> offset;  // X_k - X_p [m] per loaded point (unused in 1D)
  std::vector<Vec<Dim>> normal;  // n_k per loaded point; only read when `pressure` is set
  // The extent of each point's patch of the face [m], the same for every point: a box face's
  // particle spacing along each direction in the face, 0 along its normal (so A_k is the
  // product of the non-zero entries). Zero (1D, mesh edges): the point alone. Mappings that
  // integrate by Gauss points over the cells integrate the load over the patches by Gauss points
  // too (stages::after_forces).
  Vec<Dim> patch = Vec<Dim>::Zero();
  std::function<Vec<Dim>(double t)> value;   // tau(t) [Pa], evaluated once per step
  std::function<double(double t)> pressure;  // p(t) [Pa] along -n_k; empty: in `value` or none

  // Point k's force (tau - p n_k) A_k [N per unit thickness in 2D], from the step's tau =
  // value(t) and p = pressure(t) (anything without a pressure).
  Vec<Dim> point_force(std::size_t k, const Vec<Dim>& tau, double p) const {
    return (pressure ? Vec<Dim>(tau - p * normal[k]) : tau) * area[k];
  }
};

}  // namespace mpm
