#pragma once
// Linear elastic in F, any dimension (D eq. 2.13).
#include <cmath>
#include <string_view>

#include "material/law.hpp"

namespace mpm {

// sigma = lambda tr(eps) I + 2 mu eps, eps = sym(F) - I. In 1D this is sigma = (lambda + 2 mu)
// (F - 1); with nu = 0 the modulus is E.
struct LinearElastic {
  static constexpr std::string_view kName = "linear_elastic";
  static constexpr std::string_view kDescription =
      "linear elastic in F, any dimension (D eq. 2.13); 1D modulus lambda+2mu";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr NoState kStateNames{};
  static constexpr bool kIncremental = false;
  static constexpr NoParameters kParameters{};
  ElasticParameters p;
  explicit LinearElastic(const ElasticParameters& params = {})
      : p(params), lambda_(params.lambda()), mu_(params.mu()) {}
  template <int Dim>
  bool update(Mat<Dim>& sigma, StateOf<LinearElastic> /*state*/, const Mat<Dim>& F,
              const Mat<Dim>& /*dtL*/) const {
    sigma = stress(F);
    return true;
  }
  template <int Dim>
  Mat<Dim> stress(const Mat<Dim>& F) const {
    const Mat<Dim> eps = 0.5 * (F + F.transpose()) - Mat<Dim>::Identity();
    return lambda_ * eps.trace() * Mat<Dim>::Identity() + 2.0 * mu_ * eps;
  }
  template <int Dim>
  double energy(const Mat<Dim>& /*sigma*/, ConstStateOf<LinearElastic> /*state*/, const Mat<Dim>& F,
                double /*V*/, double V0) const {
    const Mat<Dim> eps = 0.5 * (F + F.transpose()) - Mat<Dim>::Identity();
    const double tr = eps.trace();
    return (0.5 * lambda_ * tr * tr + mu_ * eps.squaredNorm()) * V0;
  }
  double wave_speed() const { return std::sqrt((lambda_ + 2.0 * mu_) / p.density); }
  // Plane strain in 2D (eps_zz = 0): sigma_zz = lambda tr(eps).
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, ConstStateOf<LinearElastic> /*state*/,
                             const Mat<Dim>& F) const {
    return lambda_ * (F.trace() - Dim);
  }

 private:
  // The Lame constants of p, computed once: update() runs per particle per step, and the
  // compiler cannot hoist p.lambda() (two divisions) out of a loop that stores doubles.
  double lambda_, mu_;
};

static_assert(ConstitutiveLaw<LinearElastic, 1> && ConstitutiveLaw<LinearElastic, 2> &&
              ConstitutiveLaw<LinearElastic, 3>);

}  // namespace mpm
