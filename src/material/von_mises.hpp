#pragma once
// von Mises (J2) plasticity with linear isotropic hardening at finite strain (Hencky elasticity,
// material/hencky_plasticity.hpp): undrained clay (Tresca-like, phi = 0) and metals.
#include <array>
#include <cmath>
#include <string_view>

#include "material/hencky_plasticity.hpp"
#include "material/law.hpp"

namespace mpm {

// Yield function on the Kirchhoff stress: q - sigma_y(eps_p) <= 0, q = sqrt(3/2 s:s), s the
// deviator, sigma_y = yield_stress + hardening eps_p (eps_p: plastic_strain). The return is radial
// in the deviatoric plane, in closed form (de Souza Neto et al. 2008, Box 7.4, linear hardening):
// dgamma = (q_trial - sigma_y,n) / (3G + H), s = (1 - 3G dgamma / q_trial) s_trial, and
// plastic_strain grows by dgamma. Undrained clay of strength c_u: yield_stress = sqrt(3) c_u
// gives the Tresca strength c_u in plane strain (the flow has no out-of-plane component, so
// s_zz = 0 and q = sqrt(3)/2 (sigma_1 - sigma_3)).
struct VonMises : HenckyPlastic<VonMises> {
  static constexpr std::string_view kName = "von_mises";
  static constexpr std::string_view kDescription =
      "von Mises (J2) elasto-plastic with linear isotropic hardening, Hencky elasticity at "
      "finite strain (2D plane strain, 3D)";
  static constexpr MaterialParameter kYieldStress{
      .name = "yield_stress",
      .unit = "Pa",
      .min = 0.0,
      .min_exclusive = true,
      .description =
          "initial uniaxial yield stress sigma_y0 of von_mises (undrained clay of "
          "strength c_u: sqrt(3) c_u)"};
  static constexpr MaterialParameter kHardening{
      .name = "hardening",
      .unit = "Pa",
      .default_value = 0.0,
      .min = 0.0,
      .description =
          "linear isotropic hardening modulus H of von_mises: sigma_y = sigma_y0 + H "
          "plastic_strain"};
  static constexpr std::array<MaterialParameter, 2> kParameters = {kYieldStress, kHardening};
  VonMises(const ElasticParameters& params, const ParametersOf<VonMises>& values)
      : HenckyPlastic(params), yield_stress(values[0]), hardening(values[1]) {}
  explicit VonMises(const ElasticParameters& params = {}) : VonMises(params, {1.0, 0.0}) {}
  double yield_stress, hardening;  // sigma_y0, H [Pa]

  // The yield function q - sigma_y(eps_p) [Pa] at the principal Kirchhoff stresses tau.
  double yield_function(const Vec3d& tau, double plastic_strain) const {
    const Vec3d s = tau - Vec3d::Constant(tau.sum() / 3.0);
    return std::sqrt(1.5 * s.squaredNorm()) - (yield_stress + hardening * plastic_strain);
  }
  int return_map(Vec3d& tau, double plastic_strain) const {
    const double p = tau.sum() / 3.0;
    const Vec3d s = tau - Vec3d::Constant(p);
    const double q = std::sqrt(1.5 * s.squaredNorm());
    const double yield = yield_stress + hardening * plastic_strain;
    const double f = q - yield;
    if (!(f > kYieldTolerance * yield)) return 0;
    const double dgamma = f / (3.0 * elastic.G + hardening);
    tau = Vec3d::Constant(p) + (1.0 - 3.0 * elastic.G * dgamma / q) * s;
    return 1;
  }
};

}  // namespace mpm
