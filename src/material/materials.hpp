#pragma once
// Constitutive laws. Each law is a small value type with an inline per-particle update; the
// stress stage visits the material variant once and then loops over particles (no virtual
// calls in the loop). Stress is the Cauchy stress [Pa]; F the deformation gradient.
#include <cmath>
#include <concepts>
#include <string_view>
#include <variant>

#include "core/types.hpp"

namespace mpm {

struct ElasticParameters {
  double density = 1.0;         // rho0 [kg/m^3]
  double youngs_modulus = 1.0;  // E [Pa]
  double poisson_ratio = 0.0;   // nu [-]
  double lambda() const {
    return youngs_modulus * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio));
  }
  double mu() const { return youngs_modulus / (2.0 * (1.0 + poisson_ratio)); }
};

// 1D small deformation, incremental: sigma^{s+1} = sigma^s + E d_eps, d_eps = dt dv/dx
// (004 eq. 4.15).
struct Elastic1DSmall {
  static constexpr std::string_view kName = "elastic_1d_small";
  static constexpr std::string_view kDescription =
      "1D linear elastic, small deformation: sigma += E d_eps (004 eq. 4.15)";
  static constexpr bool supports_dimension(int dim) { return dim == 1; }
  ElasticParameters p;
  template <int Dim>
  void update(Mat<Dim>& sigma, const Mat<Dim>& /*F*/, const Mat<Dim>& dtL) const {
    // One-dimensional law: make_material() rejects it for Dim > 1, and the stress stage
    // instantiates no update for it there.
    if constexpr (Dim == 1) sigma(0, 0) += p.youngs_modulus * dtL(0, 0);
  }
  // Stored energy [J] of a particle: sigma^2 / (2E) per current volume.
  template <int Dim>
  double energy(const Mat<Dim>& sigma, const Mat<Dim>& /*F*/, double V, double /*V0*/) const {
    return 0.5 * sigma(0, 0) * sigma(0, 0) / p.youngs_modulus * V;
  }
  double wave_speed() const { return std::sqrt(p.youngs_modulus / p.density); }
  // A uniaxial-stress law (1D only): no stress across the bar.
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, const Mat<Dim>& /*F*/) const {
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
  ElasticParameters p;
  template <int Dim>
  void update(Mat<Dim>& sigma, const Mat<Dim>& /*F*/, const Mat<Dim>& dtL) const {
    if constexpr (Dim == 1) sigma(0, 0) += (p.youngs_modulus - sigma(0, 0)) * dtL(0, 0);
  }
  // Energy of the closed form: W(F) = E (F - 1 - ln F) per reference volume (P = sigma in 1D).
  template <int Dim>
  double energy(const Mat<Dim>& /*sigma*/, const Mat<Dim>& F, double /*V*/, double V0) const {
    const double f = F(0, 0);
    return p.youngs_modulus * (f - 1.0 - std::log(f)) * V0;
  }
  double wave_speed() const { return std::sqrt(p.youngs_modulus / p.density); }
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, const Mat<Dim>& /*F*/) const {
    return 0.0;
  }
};

// Linear elastic in F (D eq. 2.13): sigma = lambda tr(eps) I + 2 mu eps, eps = sym(F) - I.
// In 1D this is sigma = (lambda + 2 mu) (F - 1); with nu = 0 the modulus is E.
struct LinearElastic {
  static constexpr std::string_view kName = "linear_elastic";
  static constexpr std::string_view kDescription =
      "linear elastic in F, any dimension (D eq. 2.13); 1D modulus lambda+2mu";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  ElasticParameters p;
  explicit LinearElastic(const ElasticParameters& params = {})
      : p(params), lambda_(params.lambda()), mu_(params.mu()) {}
  template <int Dim>
  void update(Mat<Dim>& sigma, const Mat<Dim>& F, const Mat<Dim>& /*dtL*/) const {
    const Mat<Dim> eps = 0.5 * (F + F.transpose()) - Mat<Dim>::Identity();
    sigma = lambda_ * eps.trace() * Mat<Dim>::Identity() + 2.0 * mu_ * eps;
  }
  template <int Dim>
  double energy(const Mat<Dim>& /*sigma*/, const Mat<Dim>& F, double /*V*/, double V0) const {
    const Mat<Dim> eps = 0.5 * (F + F.transpose()) - Mat<Dim>::Identity();
    const double tr = eps.trace();
    return (0.5 * lambda_ * tr * tr + mu_ * eps.squaredNorm()) * V0;
  }
  double wave_speed() const { return std::sqrt((lambda_ + 2.0 * mu_) / p.density); }
  // Plane strain in 2D (eps_zz = 0): sigma_zz = lambda tr(eps).
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, const Mat<Dim>& F) const {
    return lambda_ * (F.trace() - Dim);
  }

 private:
  // The Lame constants of p, computed once: update() runs per particle per step, and the
  // compiler cannot hoist p.lambda() (two divisions) out of a loop that stores doubles.
  double lambda_, mu_;
};

// Compressible neo-Hookean (D eq. 2.14): sigma = lambda ln(J)/J I + mu/J (F F^T - I).
struct NeoHookean {
  static constexpr std::string_view kName = "neo_hookean";
  static constexpr std::string_view kDescription =
      "compressible neo-Hookean, any dimension (D eq. 2.14)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  ElasticParameters p;
  explicit NeoHookean(const ElasticParameters& params = {})
      : p(params), lambda_(params.lambda()), mu_(params.mu()) {}
  template <int Dim>
  void update(Mat<Dim>& sigma, const Mat<Dim>& F, const Mat<Dim>& /*dtL*/) const {
    const double J = F.determinant();
    sigma = (lambda_ * std::log(J) / J) * Mat<Dim>::Identity() +
            (mu_ / J) * (F * F.transpose() - Mat<Dim>::Identity());
  }
  // W = mu/2 (tr(F^T F) - d) - mu ln J + lambda/2 (ln J)^2 per reference volume.
  template <int Dim>
  double energy(const Mat<Dim>& /*sigma*/, const Mat<Dim>& F, double /*V*/, double V0) const {
    const double lnJ = std::log(F.determinant());
    return (0.5 * mu_ * ((F.transpose() * F).trace() - Dim) - mu_ * lnJ +
            0.5 * lambda_ * lnJ * lnJ) *
           V0;
  }
  double wave_speed() const { return std::sqrt((lambda_ + 2.0 * mu_) / p.density); }
  // Plane strain in 2D (F_zz = 1, so b_zz = 1): sigma_zz = lambda ln(J) / J.
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, const Mat<Dim>& F) const {
    const double J = F.determinant();
    return lambda_ * std::log(J) / J;
  }

 private:
  double lambda_, mu_;  // of p, computed once (see LinearElastic)
};

// The constitutive-law concept: the per-particle stress update over a step (dtL = dt L, the
// velocity gradient times the increment; F already updated), the strain energy of a particle
// (history.csv), the wave speed of the stability limit, and the dimensions it exists in
// (make_material refuses the others; the stages compile no update for them), and the stress
// normal to the plane of a 2D run, which the 2D state omits (plane strain: outputs).
template <class Law, int Dim>
concept ConstitutiveLaw = requires(const Law& law, Mat<Dim>& sigma, const Mat<Dim>& F,
                                   const Mat<Dim>& dtL, double V, double V0, int dim) {
  { Law::kName } -> std::convertible_to<std::string_view>;
  { Law::kDescription } -> std::convertible_to<std::string_view>;
  { Law::supports_dimension(dim) } -> std::convertible_to<bool>;
  law.update(sigma, F, dtL);
  { law.energy(sigma, F, V, V0) } -> std::convertible_to<double>;
  { law.wave_speed() } -> std::convertible_to<double>;
  { law.out_of_plane_stress(sigma, F) } -> std::convertible_to<double>;
};
static_assert(ConstitutiveLaw<Elastic1DSmall, 1> && ConstitutiveLaw<Elastic1DLarge, 1>);
static_assert(ConstitutiveLaw<LinearElastic, 1> && ConstitutiveLaw<LinearElastic, 2>);
static_assert(ConstitutiveLaw<NeoHookean, 1> && ConstitutiveLaw<NeoHookean, 2>);
static_assert(ConstitutiveLaw<LinearElastic, 3> && ConstitutiveLaw<NeoHookean, 3>);

using Material = std::variant<Elastic1DSmall, Elastic1DLarge, LinearElastic, NeoHookean>;

// Build the material named by `model` (a law's kName; registry::kMaterials lists them). Throws
// InputError when the law does not exist in dimension `dim`, naming those that do.
Material make_material(std::string_view model, const ElasticParameters& p, int dim);

inline double wave_speed(const Material& m) {
  return std::visit([](const auto& law) { return law.wave_speed(); }, m);
}
inline std::string_view material_name(const Material& m) {
  return std::visit([](const auto& law) { return law.kName; }, m);
}

}  // namespace mpm
