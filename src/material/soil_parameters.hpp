#pragma once
// The strength parameters the frictional laws (drucker_prager, mohr_coulomb) share: one
// declaration each, so that material.cohesion means one thing whichever law reads it. Angles are
// given in degrees.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <fmt/format.h>

#include "material/law.hpp"

namespace mpm {

inline constexpr MaterialParameter kCohesion{
    .name = "cohesion",
    .unit = "Pa",
    .min = 0.0,
    .description = "cohesion c of drucker_prager and mohr_coulomb"};
inline constexpr MaterialParameter kFrictionAngle{
    .name = "friction_angle",
    .unit = "deg",
    .min = 0.0,
    .max = 90.0,
    .max_exclusive = true,
    .description = "angle of internal friction phi of drucker_prager and mohr_coulomb"};
inline constexpr MaterialParameter kDilatancyAngle{
    .name = "dilatancy_angle",
    .unit = "deg",
    .default_value = 0.0,
    .min = 0.0,
    .max = 90.0,
    .max_exclusive = true,
    .description =
        "dilatancy angle psi of the plastic potential of drucker_prager and "
        "mohr_coulomb, at most the friction angle (psi = phi: associated flow)"};
inline constexpr MaterialParameter kTensionCutoff{
    .name = "tension_cutoff",
    .unit = "Pa",
    .default_value = -1.0,
    .min = -1.0,
    .description =
        "tensile strength t of drucker_prager (on the mean stress) and mohr_coulomb "
        "(on the largest principal stress), associated flow; -1 (the default): none "
        "below the apex c cot(phi), which is then the limit"};

// Cohesion, friction and dilatancy angle [rad] and tension cut-off of a frictional law, checked
// as a whole.
struct SoilStrength {
  double c = 0.0, phi = 0.0, psi = 0.0, t = kInfinity;
  // tension < 0: no cut-off below the apex.
  SoilStrength(double cohesion, double friction_deg, double dilatancy_deg, double tension)
      : c(cohesion),
        phi(friction_deg * std::numbers::pi / 180.0),
        psi(dilatancy_deg * std::numbers::pi / 180.0),
        t(tension < 0.0 ? kInfinity : tension) {
    if (dilatancy_deg > friction_deg)
      throw InvalidParameter(kDilatancyAngle.name,
                             fmt::format("material.dilatancy_angle = {} exceeds "
                                         "material.friction_angle = {} (choose psi <= phi; "
                                         "psi = phi is associated flow)",
                                         dilatancy_deg, friction_deg));
    if (c == 0.0 && friction_deg == 0.0)
      throw InvalidParameter(kCohesion.name,
                             "material.cohesion = 0 with material.friction_angle = 0: the material "
                             "has no strength");
  }
  // The apex of the Mohr-Coulomb pyramid, c cot(phi) [Pa] (infinite without friction).
  double apex() const { return phi > 0.0 ? c / std::tan(phi) : kInfinity; }
  // The tensile limit on the mean stress (Drucker-Prager) or the largest principal stress
  // (Mohr-Coulomb): the cut-off, or the apex where that is lower.
  double tension_limit(double apex_pressure) const { return std::min(t, apex_pressure); }
};

}  // namespace mpm
