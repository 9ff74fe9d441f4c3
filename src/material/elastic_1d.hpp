#pragma once
// The incremental 1D elastic laws of 004 (small and large deformation).
#include <cmath>
#include <string_view>

#include "material/law.hpp"

namespace mpm {

// 1D small deformation, incremental: sigma^{s+1} = sigma^s + E d_eps, d_eps = dt dv/dx
// (004 eq. 4.15).
struct Elastic1DSmall {
  static constexpr std::string_view kName = "elastic_1d_small";
  static constexpr std::string_view kDescription =
      "1D linear elastic, small deformation: sigma += E d_eps (004 eq. 4.15)";
  static constexpr bool supports_dimension(int dim) { return dim == 1; }
  static constexpr NoState kStateNames{};
  static constexpr bool kIncremental = true;
  static constexpr NoParameters kParameters{};
  ElasticParameters p;
  template <int Dim>
  bool update(Mat<Dim>& sigma, StateOf<Elastic1DSmall> /*state*/, const Mat<Dim>& /*F*/,
              const Mat<Dim>& dtL) const {
    // One-dimensional law: make_material() rejects it for Dim > 1, and the stress stage
    // instantiates no update for it there.
    if constexpr (Dim == 1) sigma(0, 0) += p.youngs_modulus * dtL(0, 0);
    return true;
  }
  // Stored energy [J] of a particle: sigma^2 / (2E) per current volume.
  template <int Dim>
  double energy(const Mat<Dim>& sigma, ConstStateOf<Elastic1DSmall> /*state*/,
                const Mat<Dim>& /*F*/, double V, double /*V0*/) const {
    return 0.5 * sigma(0, 0) * sigma(0, 0) / p.youngs_modulus * V;
  }
  double wave_speed() const { return std::sqrt(p.youngs_modulus / p.density); }
  // A uniaxial-stress law (1D only): no stress across the bar.
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, ConstStateOf<Elastic1DSmall> /*state*/,
                             const Mat<Dim>& /*F*/) const {
    return 0.0;
  }
};

// 1D large deformation, incremental: sigma^{s+1} = sigma^s + (E - sigma^s) d_eps (004 eq. 4.16),
// whose closed form is sigma = E (1 - 1/F).
struct Elastic1DLarge {
  static constexpr std::string_view kName = "elastic_1d_large";
  static constexpr std::string_view kDescription =
      "1D elastic, large deformation: sigma += (E - sigma) d_eps (004 eq. 4.16)";
  static constexpr bool supports_dimension(int dim) { return dim == 1; }
  static constexpr NoState kStateNames{};
  static constexpr bool kIncremental = true;
  static constexpr NoParameters kParameters{};
  ElasticParameters p;
  template <int Dim>
  bool update(Mat<Dim>& sigma, StateOf<Elastic1DLarge> /*state*/, const Mat<Dim>& /*F*/,
              const Mat<Dim>& dtL) const {
    if constexpr (Dim == 1) sigma(0, 0) += (p.youngs_modulus - sigma(0, 0)) * dtL(0, 0);
    return true;
  }
  // Energy of the closed form: W(F) = E (F - 1 - ln F) per reference volume (P = sigma in 1D).
  template <int Dim>
  double energy(const Mat<Dim>& /*sigma*/, ConstStateOf<Elastic1DLarge> /*state*/,
                const Mat<Dim>& F, double /*V*/, double V0) const {
    const double f = F(0, 0);
    return p.youngs_modulus * (f - 1.0 - std::log(f)) * V0;
  }
  double wave_speed() const { return std::sqrt(p.youngs_modulus / p.density); }
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, ConstStateOf<Elastic1DLarge> /*state*/,
                             const Mat<Dim>& /*F*/) const {
    return 0.0;
  }
};

static_assert(ConstitutiveLaw<Elastic1DSmall, 1> && ConstitutiveLaw<Elastic1DLarge, 1>);

}  // namespace mpm
