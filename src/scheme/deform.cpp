// The material stage of the particle updates (stages::deform_particles): compiled once per
// dimension, so that each law's return mapping is instantiated three times in the library
// rather than once per basis, scheme and dimension in every stepper unit.
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "scheme/stages.hpp"

namespace mpm::stages {

template <int Dim>
bool deform_particles(Particles<Dim>& P, const Materials& materials, Index b, Index e,
                      const Mat<Dim>* L, double dt) {
  bool bad = false;
  // Each law is resolved once, outside its loop over the particles.
  materials.for_each_particle(
      P.material, static_cast<std::size_t>(b), static_cast<std::size_t>(e),
      [&]([[maybe_unused]] const auto& law, std::size_t, [[maybe_unused]] std::size_t offset,
          [[maybe_unused]] std::size_t i) {
        using Law = std::decay_t<decltype(law)>;
        if constexpr (!Law::supports_dimension(Dim)) {
          // make_material refuses a law outside its dimensions.
          throw std::logic_error("deform_particles: a material law outside its dimensions");
        } else {
          const Mat<Dim> dtL = dt * L[static_cast<Index>(i) - b];
          P.F[i] = (Mat<Dim>::Identity() + dtL) * P.F[i];  // D eq. 2.40
          const double J = P.F[i].determinant();
          P.volume[i] = J * P.volume0[i];  // D eq. 2.41-2.42
          const bool updated =
              law.update(P.stress[i], state_row<Law>(P.state, i, offset), P.F[i], dtL);
          bad = bad || !updated || !(J > 0.0) || !std::isfinite(P.stress[i].sum());
        }
      });
  return bad;
}

template bool deform_particles<1>(Particles<1>&, const Materials&, Index, Index, const Mat<1>*,
                                  double);
template bool deform_particles<2>(Particles<2>&, const Materials&, Index, Index, const Mat<2>*,
                                  double);
template bool deform_particles<3>(Particles<3>&, const Materials&, Index, Index, const Mat<3>*,
                                  double);

}  // namespace mpm::stages
