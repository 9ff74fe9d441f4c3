#pragma once
// Mohr-Coulomb elasto-plasticity, perfectly plastic, non-associated, with a tension cut-off, at
// finite strain (Hencky elasticity, material/hencky_plasticity.hpp). Faces, edges and the apex
// are handled exactly: the return is the multi-surface one (Koiter's rule) over the planes of
// the yield surface in principal stress space.
#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include <Eigen/Dense>

#include "material/hencky_plasticity.hpp"
#include "material/law.hpp"
#include "material/soil_parameters.hpp"

namespace mpm {

// Yield planes on the principal Kirchhoff stresses tau_1..3 (tension positive, unsorted):
//   Mohr-Coulomb, for each ordered pair i != j (6 planes; de Souza Neto et al. 2008, eq. 6.118):
//     f_ij = (tau_i - tau_j) + (tau_i + tau_j) sin(phi) - 2 c cos(phi) <= 0,
//     flow b_ij = (1 + sin psi) e_i - (1 - sin psi) e_j (the potential with psi for phi);
//   tension cut-off, for each i (3 planes, where the limit is finite): f_i = tau_i - t <= 0,
//     flow e_i (associated), t = min(tension_cutoff, c cot phi).
// The returned stress tau = tau_trial - sum_k dgamma_k D b_k over an active set A, with
// f_k(tau) = 0 on A (a linear system in dgamma: the planes are flat and the law perfectly
// plastic), dgamma_k >= 0 and every f <= 0 (Koiter; Simo and Hughes 1998, 2.3.2). The sets are
// tried with one plane (a face), then two (an edge), then three (a corner, the apex); the first
// that satisfies the conditions is the return. With associated flow this is the closest point in
// the energy norm, which is unique. The tension planes give the apex a volumetric flow, so that
// a return exists for every trial stress even with psi = 0.
struct MohrCoulomb : HenckyPlastic<MohrCoulomb> {
  static constexpr std::string_view kName = "mohr_coulomb";
  static constexpr std::string_view kDescription =
      "Mohr-Coulomb elasto-plastic (non-associated, corners and apex exact, tension cut-off), "
      "perfectly plastic, Hencky elasticity at finite strain (2D plane strain, 3D)";
  static constexpr std::array<MaterialParameter, 4> kParameters = {kCohesion, kFrictionAngle,
                                                                   kDilatancyAngle, kTensionCutoff};
  MohrCoulomb(const ElasticParameters& params, const ParametersOf<MohrCoulomb>& v)
      : HenckyPlastic(params), strength(v[0], v[1], v[2], v[3]) {
    const double sf = std::sin(strength.phi), sp = std::sin(strength.psi);
    const Mat3d D = elastic.principal_stiffness();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        if (i == j) continue;
        Plane& k = planes_[planes_count_++];
        k.normal = (1.0 + sf) * Vec3d::Unit(i) - (1.0 - sf) * Vec3d::Unit(j);
        k.flow = D * ((1.0 + sp) * Vec3d::Unit(i) - (1.0 - sp) * Vec3d::Unit(j));
        k.limit = 2.0 * strength.c * std::cos(strength.phi);
      }
    const double t = strength.tension_limit(strength.apex());
    if (std::isfinite(t))
      for (int i = 0; i < 3; ++i) {
        Plane& k = planes_[planes_count_++];
        k.normal = Vec3d::Unit(i);
        k.flow = D * Vec3d::Unit(i);
        k.limit = t;
      }
  }
  explicit MohrCoulomb(const ElasticParameters& params = {})
      : MohrCoulomb(params, {1.0, 30.0, 0.0, -1.0}) {}
  SoilStrength strength;

  // The largest of the planes' yield functions [Pa] at the principal Kirchhoff stresses tau.
  double yield_function(const Vec3d& tau, double /*plastic_strain*/) const {
    double f = -kInfinity;
    for (int k = 0; k < planes_count_; ++k)
      f = std::max(f, planes_[k].normal.dot(tau) - planes_[k].limit);
    return f;
  }
  int return_map(Vec3d& tau, double /*plastic_strain*/) const {
    const int n = planes_count_;
    std::array<double, kMaxPlanes> f{};
    // Round-off allowance of the conditions [Pa]: of the strength and the stress.
    double scale = tau.cwiseAbs().maxCoeff();
    for (int k = 0; k < n; ++k) scale = std::max(scale, std::abs(planes_[k].limit));
    const double tol = kYieldTolerance * scale;
    bool plastic = false;
    for (int k = 0; k < n; ++k) {
      f[k] = planes_[k].normal.dot(tau) - planes_[k].limit;
      plastic |= f[k] > tol;
    }
    if (!plastic) return 0;
    const Vec3d trial = tau;
    // Active set {a[0], .., a[m-1]}: solve sum_l (n_k . D b_l) dgamma_l = f_k, check, accept.
    const auto try_set = [&](const int* a, int m) {
      Mat3d A = elastic.G * Mat3d::Identity();  // the unused rows: of the scale of the others
      Vec3d rhs = Vec3d::Zero();
      for (int r = 0; r < m; ++r) {
        rhs(r) = f[a[r]];
        for (int c = 0; c < m; ++c) A(r, c) = planes_[a[r]].normal.dot(planes_[a[c]].flow);
      }
      const Eigen::FullPivLU<Mat3d> lu(A);
      if (!lu.isInvertible()) return false;  // dependent planes (e.g. parallel: phi = 0)
      const Vec3d dgamma = lu.solve(rhs);
      Vec3d out = trial;
      for (int r = 0; r < m; ++r) {
        if (dgamma(r) * A(r, r) < -tol) return false;
        out -= dgamma(r) * planes_[a[r]].flow;
      }
      for (int k = 0; k < n; ++k)
        if (planes_[k].normal.dot(out) - planes_[k].limit > tol) return false;
      tau = out;
      return true;
    };
    for (int i = 0; i < n; ++i)
      if (f[i] > 0.0 && try_set(std::array{i}.data(), 1)) return 1;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        if (try_set(std::array{i, j}.data(), 2)) return 2;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        for (int k = j + 1; k < n; ++k)
          if (try_set(std::array{i, j, k}.data(), 3)) return 3;
    return -1;
  }

 private:
  static constexpr int kMaxPlanes = 9;
  struct Plane {
    Vec3d normal = Vec3d::Zero();  // n_k: f_k = n_k . tau - limit
    Vec3d flow = Vec3d::Zero();    // D b_k: the stress change per unit multiplier
    double limit = 0.0;            // [Pa]
  };
  std::array<Plane, kMaxPlanes> planes_{};
  int planes_count_ = 0;
};

}  // namespace mpm
