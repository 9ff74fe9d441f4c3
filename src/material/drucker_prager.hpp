#pragma once
// Drucker-Prager elasto-plasticity, perfectly plastic, at finite strain (Hencky elasticity,
// material/hencky_plasticity.hpp), the cone matched to Mohr-Coulomb, with a tension cut-off.
#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include "material/hencky_plasticity.hpp"
#include "material/law.hpp"
#include "material/soil_parameters.hpp"

namespace mpm {

// How the cone meets the Mohr-Coulomb pyramid of the same c and phi (material.dp_match).
inline constexpr std::array<std::string_view, 3> kDruckerPragerMatches = {
    "plane_strain", "compression", "extension"};

// Yield function on the Kirchhoff stress (tension positive): sqrt(J2) + eta p - xi c <= 0, p the
// mean stress; plastic potential sqrt(J2) + eta_psi p. The constants (de Souza Neto et al. 2008,
// eq. 6.121-6.123) match Mohr-Coulomb
//   plane_strain: eta = 3 tan(phi) / sqrt(9 + 12 tan^2 phi), xi = 3 / sqrt(9 + 12 tan^2 phi)
//     (the same limit loads in plane strain with associated flow);
//   compression: eta = 6 sin(phi) / (sqrt(3) (3 - sin phi)), xi = 6 cos(phi) / (sqrt(3) (3 - sin
//     phi)) (the outer cone, through the triaxial-compression corners);
//   extension: the same with 3 + sin(phi) (the inner cone, through the extension corners);
// eta_psi likewise from the dilatancy angle. The tension cut-off p <= t (associated) caps the
// cone below its apex p = xi c / eta. The return, in closed form in (p, sqrt(J2)) (Box 8.8 and
// its apex): the cone (dgamma = Phi_trial / (G + K eta eta_psi), sqrt(J2) = sqrt(J2)_trial -
// G dgamma, p = p_trial - K eta_psi dgamma), else the cap (p = t, deviator kept), else the rim
// where both meet (p = t, sqrt(J2) = xi c - eta t; at the apex the deviator vanishes).
struct DruckerPrager : HenckyPlastic<DruckerPrager> {
  static constexpr std::string_view kName = "drucker_prager";
  static constexpr std::string_view kDescription =
      "Drucker-Prager elasto-plastic (cone matched to Mohr-Coulomb, non-associated, tension "
      "cut-off), perfectly plastic, Hencky elasticity at finite strain (2D plane strain, 3D)";
  static constexpr MaterialParameter kMatch{
      .name = "dp_match",
      .unit = "",
      .default_value = 0.0,
      .choices = kDruckerPragerMatches,
      .description =
          "where the drucker_prager cone meets Mohr-Coulomb: plane_strain (same "
          "plane-strain limit loads, associated flow), compression (outer cone) or "
          "extension (inner cone)"};
  static constexpr std::array<MaterialParameter, 5> kParameters = {
      kCohesion, kFrictionAngle, kDilatancyAngle, kTensionCutoff, kMatch};
  DruckerPrager(const ElasticParameters& params, const ParametersOf<DruckerPrager>& v)
      : HenckyPlastic(params), strength(v[0], v[1], v[2], v[3]) {
    const auto match = static_cast<int>(v[4]);
    eta = cone_slope(strength.phi, match);
    eta_psi = cone_slope(strength.psi, match);
    xi = cone_intercept(strength.phi, match);
    tension = strength.tension_limit(eta > 0.0 ? xi * strength.c / eta : kInfinity);
  }
  explicit DruckerPrager(const ElasticParameters& params = {})
      : DruckerPrager(params, {1.0, 30.0, 0.0, -1.0, 0.0}) {}
  SoilStrength strength;
  double eta = 0.0, eta_psi = 0.0, xi = 1.0;  // the cone's constants [-]
  double tension = kInfinity;                 // the cap on the mean stress [Pa]

  // The larger of the cone's and the cap's yield functions [Pa] at the principal Kirchhoff
  // stresses tau.
  double yield_function(const Vec3d& tau, double /*plastic_strain*/) const {
    const double p = tau.sum() / 3.0;
    const double r = std::sqrt(0.5 * (tau - Vec3d::Constant(p)).squaredNorm());
    return std::max(r + eta * p - xi * strength.c, p - tension);
  }
  int return_map(Vec3d& tau, double /*plastic_strain*/) const {
    const double K = elastic.K, G = elastic.G;
    const double p_trial = tau.sum() / 3.0;
    const Vec3d s = tau - Vec3d::Constant(p_trial);
    const double r_trial = std::sqrt(0.5 * s.squaredNorm());  // sqrt(J2)
    const double f_trial = r_trial + eta * p_trial - xi * strength.c;
    // Round-off allowance [Pa]: the strength, or the stress where the strength is nil.
    const double tol = kYieldTolerance * std::max(xi * strength.c, std::abs(p_trial));
    if (!(f_trial > tol) && !(p_trial > tension + tol)) return 0;
    // Maps onto (p, r), keeping the deviator's direction.
    const auto set = [&](double p, double r) {
      tau = Vec3d::Constant(p) + (r_trial > 0.0 ? r / r_trial : 0.0) * s;
    };
    if (f_trial > 0.0) {  // the cone
      const double dgamma = f_trial / (G + K * eta * eta_psi);
      const double r = r_trial - G * dgamma, p = p_trial - K * eta_psi * dgamma;
      if (r >= 0.0 && p <= tension) {
        set(p, r);
        return 1;
      }
    }
    if (p_trial > tension && r_trial + eta * tension - xi * strength.c <= 0.0) {  // the cap
      set(tension, r_trial);
      return 1;
    }
    // The rim: both active, dgamma_cone = (r_trial - r) / G >= 0 and the cap's volumetric
    // multiplier (p_trial - t - K eta_psi dgamma_cone) / K >= 0.
    const double r = std::max(0.0, xi * strength.c - eta * tension);
    const double dgamma = (r_trial - r) / G;
    if (dgamma >= 0.0 && p_trial - tension - K * eta_psi * dgamma >= 0.0) {
      set(tension, r);
      return 2;
    }
    return -1;
  }

 private:
  static double cone_slope(double angle, int match) {
    const double s = std::sin(angle), t = std::tan(angle);
    if (match == 0) return 3.0 * t / std::sqrt(9.0 + 12.0 * t * t);
    return 6.0 * s / (std::sqrt(3.0) * (match == 1 ? 3.0 - s : 3.0 + s));
  }
  static double cone_intercept(double angle, int match) {
    const double c = std::cos(angle), t = std::tan(angle);
    if (match == 0) return 3.0 / std::sqrt(9.0 + 12.0 * t * t);
    return 6.0 * c /
           (std::sqrt(3.0) * (match == 1 ? 3.0 - std::sin(angle) : 3.0 + std::sin(angle)));
  }
};

}  // namespace mpm
