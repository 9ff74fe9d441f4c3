#pragma once
// The settings of the DDMPM basis (basis/ddmpm.hpp), apart from it so that the basis kind
// (methods/kinds.hpp) can carry them without compiling the basis.

namespace mpm {

// How DDMPM's integrals over the material domain (node volumes V_j and int phi_j grad phi_i) are
// evaluated (method.ddmpm_integrals); D 2.6.4 does not say.
enum class DdmpmIntegrals {
  particles,   // sum_p V_p (...)(x_p): the particles as quadrature points
  quadrature,  // exactly, by Gauss-Legendre points over the grid cells that hold particles
};

// The weight alpha that blends P1's gradient with the smoothed one (method.ddmpm_weight); D gives
// it in 1D only, alpha = 2 xi (1 - xi).
enum class DdmpmWeight {
  per_direction,  // component d of the gradient blended by alpha_d = 2 xi_d (1 - xi_d)
  product,        // every component by alpha = prod_d 2 xi_d (1 - xi_d)
};

struct DdmpmSettings {
  DdmpmIntegrals integrals = DdmpmIntegrals::particles;
  DdmpmWeight weight = DdmpmWeight::per_direction;
};

}  // namespace mpm
