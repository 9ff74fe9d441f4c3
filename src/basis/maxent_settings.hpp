#pragma once
// The settings of the local max-ent basis (basis/maxent.hpp), apart from it so that the basis
// kind (methods/kinds.hpp) can carry them without compiling the basis.

namespace mpm {

struct MaxEntSettings {
  double dmax = 2.0;         // d_max of D eq. 4.47 (method.maxent_dmax), in (1, 3]
  double tolerance = 1e-12;  // Newton stops when |sum_i phi_i (x_i - x)| / zeta is below this
  int max_iterations = 50;   // Newton iterations before the point is reported as failed
};

}  // namespace mpm
