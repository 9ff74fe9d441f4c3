#pragma once
// Elasto-plasticity at finite strain, the part the plastic laws share: Hencky (logarithmic)
// elasticity with the multiplicative split F = F_e F_p and the exponential-map return in
// principal Kirchhoff stresses (de Souza Neto, Peric and Owen 2008, "Computational Methods for
// Plasticity", 14.4 and Box 14.3). A law (von_mises.hpp, drucker_prager.hpp, mohr_coulomb.hpp)
// derives from HenckyPlastic<Law> and gives the return mapping of its yield surface in the
// principal Kirchhoff stresses, where, with constant elastic moduli in the logarithmic strains,
// it is the small-strain return; this header does the rest of a step:
//   tau_n = J_n sigma_n, eps_e,n = C^-1 : tau_n, b_e,n = exp(2 eps_e,n)  (the previous stress holds
//     the elastic strain, so an initial stress needs nothing else: the laws are incremental);
//   b_e,trial = f b_e,n f^T with f = I + dt L, the step's relative deformation (F_n+1 = f F_n);
//   eps_trial,i = ln(lambda_i) / 2 on the principal directions n_i of b_e,trial;
//   tau_trial,i = (K - 2G/3) sum_j eps_trial,j + 2G eps_trial,i;
//   tau_i = the law's return of tau_trial,i (isotropy: the directions n_i are kept);
//   sigma_n+1 = sum_i tau_i n_i n_i^T / J_n+1.
// Exactly objective: a rigid rotation f = R rotates b_e and tau and changes no principal value.
// 2D is plane strain (f_zz = 1): the stress normal to the plane is the state variable stress_zz
// (the 2D stress omits it), and z stays a principal direction exactly.
#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <string_view>

#include "material/law.hpp"

namespace mpm {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

// Principal values and directions (columns) of a symmetric 3x3 tensor whose xz and yz entries
// are zero when Dim == 2: there z is a principal direction exactly and only the in-plane block
// is decomposed, so that no round-off mixes z into the plane.
template <int Dim>
void principal(const Mat3d& A, Vec3d& values, Mat3d& directions) {
  if constexpr (Dim == 2) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(A.topLeftCorner<2, 2>());
    values << es.eigenvalues()(0), es.eigenvalues()(1), A(2, 2);
    directions.setZero();
    directions.topLeftCorner<2, 2>() = es.eigenvectors();
    directions(2, 2) = 1.0;
  } else {
    Eigen::SelfAdjointEigenSolver<Mat3d> es(A);
    values = es.eigenvalues();
    directions = es.eigenvectors();
  }
}

// Isotropic elasticity between principal logarithmic strains and principal Kirchhoff stresses
// (or between the tensors): tau = (K - 2G/3) tr(eps) I + 2G eps.
struct HenckyElasticity {
  double K = 1.0, G = 1.0;  // bulk and shear moduli [Pa]
  explicit HenckyElasticity(const ElasticParameters& p)
      : K(p.youngs_modulus / (3.0 * (1.0 - 2.0 * p.poisson_ratio))), G(p.mu()) {}
  Vec3d stress(const Vec3d& eps) const {
    return Vec3d::Constant((K - 2.0 * G / 3.0) * eps.sum()) + 2.0 * G * eps;
  }
  // eps = tau / (2G) + (1/(9K) - 1/(6G)) tr(tau) I, on principal values or on the tensor.
  Vec3d strain(const Vec3d& tau) const {
    return tau / (2.0 * G) + Vec3d::Constant(compliance_trace() * tau.sum());
  }
  Mat3d strain(const Mat3d& tau) const {
    return tau / (2.0 * G) + (compliance_trace() * tau.trace()) * Mat3d::Identity();
  }
  // The elastic stiffness on principal values, D = (K - 2G/3) 1 1^T + 2G I.
  Mat3d principal_stiffness() const {
    return Mat3d::Constant(K - 2.0 * G / 3.0) + 2.0 * G * Mat3d::Identity();
  }
  // Stored energy per unit reference volume of the elastic strain eps [J/m^3]:
  // G |dev eps|^2 + K/2 tr(eps)^2.
  double energy_density(const Mat3d& eps) const {
    const double tr = eps.trace();
    const Mat3d dev = eps - (tr / 3.0) * Mat3d::Identity();
    return G * dev.squaredNorm() + 0.5 * K * tr * tr;
  }

 private:
  double compliance_trace() const { return 1.0 / (9.0 * K) - 1.0 / (6.0 * G); }
};

// A trial stress counts as plastic when a yield function exceeds this fraction of the strength:
// a stress returned onto the surface in one step is then elastic in the next to round-off (a
// rigid rotation of it, say).
inline constexpr double kYieldTolerance = 1e-12;

// The internal variables of every plastic law, as HenckyPlastic keeps them:
//   plastic_strain: the accumulated equivalent plastic strain sum sqrt(2/3 |d eps_p|^2) [-],
//     d eps_p = C^-1 : (tau_trial - tau) per step (for von Mises the hardening variable);
//   yield_mode: the yield surfaces active in the last update: 0 elastic, 1 a smooth surface or
//     face, 2 an edge or the cone's rim, 3 or more a corner or apex, kNoReturn (-1) when the
//     return found no admissible stress [-];
//   stress_zz: the Cauchy stress normal to the plane [Pa] (2D plane strain, where the stress
//     omits it; 3D: the stress's zz, kept alike).
inline constexpr std::array<std::string_view, 3> kPlasticStateNames = {
    "plastic_strain", "yield_mode", kOutOfPlaneStressName};
inline constexpr double kNoReturn = -1.0;

// The Hencky kinematics of a plastic law Law, which declares its name, description and
// parameters and the return in principal Kirchhoff stresses:
//   int return_map(Vec3d& tau, double plastic_strain) const;
//   double yield_function(const Vec3d& tau, double plastic_strain) const;  [Pa]
// tau: the trial principal stresses in, the returned ones out; the result is the number of
// active yield surfaces (0: the trial is elastic), or -1 when no return exists. Then update()
// leaves the trial stress, sets yield_mode to kNoReturn and returns false, and the stage stops the
// run (exit_code::kReturnMapping) naming the particle, its trial stress and failed_return().
template <class Law>
struct HenckyPlastic {
  static constexpr auto kStateNames = kPlasticStateNames;
  static constexpr bool kIncremental = true;
  // Plane strain and 3D (1D, uniaxial strain, would need the lateral stress as state).
  static constexpr bool supports_dimension(int dim) { return dim == 2 || dim == 3; }
  ElasticParameters p;
  HenckyElasticity elastic;
  explicit HenckyPlastic(const ElasticParameters& params) : p(params), elastic(params) {}

  template <int Dim>
  bool update(Mat<Dim>& sigma, std::span<double, 3> state, const Mat<Dim>& F,
              const Mat<Dim>& dtL) const {
    const double J = F.determinant();
    // The stage stops the run at det F <= 0 (inverted deformation), naming the particle.
    if (!(J > 0.0)) return true;
    Mat3d f = Mat3d::Identity();
    f.topLeftCorner<Dim, Dim>() += dtL;
    const Mat3d tau_n = kirchhoff(sigma, std::span<const double, 3>(state), J / f.determinant());
    // b_e,n = exp(2 C^-1 : tau_n) on the principal directions of tau_n (I when stress-free).
    Vec3d values;
    Mat3d Q;
    Mat3d be = Mat3d::Identity();
    if (!tau_n.isZero(0.0)) {
      principal<Dim>(tau_n, values, Q);
      const Vec3d eps = elastic.strain(values);
      be = Q * (2.0 * eps).array().exp().matrix().asDiagonal() * Q.transpose();
    }
    be = f * be * f.transpose();
    principal<Dim>(be, values, Q);
    const Vec3d tau_trial = elastic.stress(0.5 * values.array().log().matrix());
    Vec3d tau = tau_trial;
    const int mode = static_cast<const Law&>(*this).return_map(tau, state[0]);
    if (mode < 0) tau = tau_trial;
    if (mode > 0) state[0] += std::sqrt(2.0 / 3.0) * elastic.strain(Vec3d(tau_trial - tau)).norm();
    state[1] = mode < 0 ? kNoReturn : mode;
    const Mat3d tau_new = Q * tau.asDiagonal() * Q.transpose();
    sigma = tau_new.topLeftCorner<Dim, Dim>() / J;
    state[2] = tau_new(2, 2) / J;
    return mode >= 0;
  }

  // The yield function [Pa] at the stress a failed update left (the trial stress), for a particle
  // whose yield_mode is kNoReturn; NaN for any other.
  template <int Dim>
  double failed_return(const Mat<Dim>& sigma, std::span<const double, 3> state,
                       const Mat<Dim>& F) const {
    if (state[1] != kNoReturn) return std::numeric_limits<double>::quiet_NaN();
    Vec3d values;
    Mat3d Q;
    principal<Dim>(kirchhoff(sigma, state, F.determinant()), values, Q);
    return static_cast<const Law&>(*this).yield_function(values, state[0]);
  }

  // The elastic energy of the particle [J]: the Hencky energy of eps_e = C^-1 : (J sigma) per
  // reference volume.
  template <int Dim>
  double energy(const Mat<Dim>& sigma, std::span<const double, 3> state, const Mat<Dim>& F,
                double /*V*/, double V0) const {
    return elastic.energy_density(elastic.strain(kirchhoff(sigma, state, F.determinant()))) * V0;
  }
  // The elastic P-wave speed sqrt((K + 4G/3) / rho0) [m/s] (plastic flow only slows waves).
  double wave_speed() const { return std::sqrt((elastic.K + 4.0 * elastic.G / 3.0) / p.density); }
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& /*sigma*/, std::span<const double, 3> state,
                             const Mat<Dim>& /*F*/) const {
    return state[2];
  }

 private:
  // The Kirchhoff stress J sigma as a 3x3 tensor (2D: the plane-strain stress_zz completes it).
  template <int Dim>
  static Mat3d kirchhoff(const Mat<Dim>& sigma, std::span<const double, 3> state, double J) {
    Mat3d tau = Mat3d::Zero();
    tau.topLeftCorner<Dim, Dim>() = J * sigma;
    if constexpr (Dim == 2) tau(2, 2) = J * state[2];
    return tau;
  }
};

}  // namespace mpm
