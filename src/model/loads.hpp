#pragma once
// The loads of a problem: body forces and face tractions (model layer; the stages of
// scheme/stages.hpp apply them).
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
// (Steffen et al. 2008; D 4.6.2 and eq. 2.21 for the 1D traction bar): each loaded particle adds
// the point force phi_i(x_f) tau(t) A_p at the centre x_f of the outer face of its domain, the
// one-point quadrature of the boundary integral int phi_i tau dA over its share A_p of the face.
// tau is a nominal traction (force per unit reference area, a dead load): its direction and the
// areas A_p stay those of the undeformed body. The face centre follows the deformation:
// x_f = x_p + side F_p (l_p e_d) with l_p the reference half-width of the particle domain along
// the face normal e_d; in 1D x_f = x_p + side V_p / 2 (V_p is the current length; A_p = 1, the
// force per unit cross-section).
template <int Dim>
struct Traction {
  int direction = 0;               // d: the face normal is e_d
  int side = 1;                    // +1: the upper face (outward normal +e_d); -1: the lower face
  std::vector<Index> particles;    // the particles whose domains touch the face
  std::vector<double> area;        // A_p [m^(Dim-1)] per loaded particle (1D: 1)
  std::vector<double> half_width;  // l_p [m] per loaded particle (unused in 1D)
  std::function<Vec<Dim>(double t)> value;  // tau(t) [Pa], evaluated once per step
};

}  // namespace mpm
