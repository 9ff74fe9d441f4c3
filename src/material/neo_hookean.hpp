#pragma once
// Compressible neo-Hookean, any dimension (D eq. 2.14).
#include <cmath>
#include <string_view>

#include "material/law.hpp"

namespace mpm {

// sigma = lambda ln(J)/J I + mu/J (F F^T - I).
struct NeoHookean {
  static constexpr std::string_view kName = "neo_hookean";
  static constexpr std::string_view kDescription =
      "compressible neo-Hookean, any dimension (D eq. 2.14)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr NoState kStateNames{};
  static constexpr bool kIncremental = false;
  static constexpr NoParameters kParameters{};
  ElasticParameters p;
  explicit NeoHookean(const ElasticParameters& params = {})
      : p(params), lambda_(params.lambda()), mu_(params.mu()) {}
  template <int Dim>
  bool update(Mat<Dim>& sigma, StateOf<NeoHookean> /*state*/, const Mat<Dim>& F,
              const Mat<Dim>& /*dtL*/) const {
    const double J = F.determinant();
    sigma = (lambda_ * std::log(J) / J) * Mat<Dim>::Identity() +
            (mu_ / J) * (F * F.transpose() - Mat<Dim>::Identity());
    return true;
  }
  // W = mu/2 (tr(F^T F) - d) - mu ln J + lambda/2 (ln J)^2 per reference volume.
  template <int Dim>
  double energy(const Mat<Dim>& /*sigma*/, ConstStateOf<NeoHookean> /*state*/, const Mat<Dim>& F,
                double /*V*/, double V0) const {
    const double lnJ = std::log(F.determinant());
    return (0.5 * mu_ * ((F.transpose() * F).trace() - Dim) - mu_ * lnJ +
            0.5 * lambda_ * lnJ * lnJ) *
           V0;
  }
  double wave_speed() const { return std::sqrt((lambda_ + 2.0 * mu_) / p.density); }
  // Plane strain in 2D (F_zz = 1, so b_zz = 1): sigma_zz = lambda ln(J) / J.
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, ConstStateOf<NeoHookean> /*state*/,
                             const Mat<Dim>& F) const {
    const double J = F.determinant();
    return lambda_ * std::log(J) / J;
  }

 private:
  double lambda_, mu_;  // of p, computed once (see LinearElastic)
};

static_assert(ConstitutiveLaw<NeoHookean, 1> && ConstitutiveLaw<NeoHookean, 2> &&
              ConstitutiveLaw<NeoHookean, 3>);

}  // namespace mpm
