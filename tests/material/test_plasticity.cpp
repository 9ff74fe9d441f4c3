// The elasto-plastic laws (material/von_mises.hpp, drucker_prager.hpp, mohr_coulomb.hpp on
// material/hencky_plasticity.hpp) at one material point: the return lands on the yield surface to
// round-off, elastic steps are Hencky elasticity, a rigid rotation rotates the stress and changes
// nothing else, the peak strengths of triaxial and plane-strain compression equal their closed
// forms, the plastic flow dilates as the flow rule says, and the error of the integration falls
// with the strain increment at first order.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <string_view>

#include "material/materials.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

constexpr double kPi = std::numbers::pi;

ElasticParameters soil() {
  ElasticParameters p;
  p.density = 2000.0;
  p.youngs_modulus = 20e6;
  p.poisson_ratio = 0.3;
  return p;
}

VonMises von_mises(double yield_stress, double hardening = 0.0) {
  return VonMises(soil(), {yield_stress, hardening});
}
// match: 0 plane strain, 1 compression, 2 extension (kDruckerPragerMatches).
DruckerPrager drucker_prager(double c, double phi, double psi, int match, double t = -1.0) {
  return DruckerPrager(soil(), {c, phi, psi, t, static_cast<double>(match)});
}
MohrCoulomb mohr_coulomb(double c, double phi, double psi, double t = -1.0) {
  return MohrCoulomb(soil(), {c, phi, psi, t});
}

// One homogeneous material point: F, the Cauchy stress and the law's state.
template <int Dim>
struct Point {
  Mat<Dim> F = Mat<Dim>::Identity();
  Mat<Dim> sigma = Mat<Dim>::Zero();
  std::array<double, 3> state{};
  // Starts under the isotropic stress -p0 (2D: the out-of-plane stress too).
  explicit Point(double p0 = 0.0) {
    sigma = -p0 * Mat<Dim>::Identity();
    state[2] = -p0;
  }
  // One step of relative deformation f (F <- f F), as the stress stage does it.
  template <class Law>
  void step(const Law& law, const Mat<Dim>& f) {
    const Mat<Dim> dtL = f - Mat<Dim>::Identity();
    F = f * F;
    law.update(sigma, std::span<double, 3>(state), F, dtL);
  }
  // The Kirchhoff stress J sigma, with sigma_zz in 2D.
  Mat3d tau() const {
    Mat3d t = Mat3d::Zero();
    t.topLeftCorner<Dim, Dim>() = F.determinant() * sigma;
    if constexpr (Dim == 2) t(2, 2) = F.determinant() * state[2];
    return t;
  }
};

// The diagonal relative deformation of logarithmic strain increments d.
template <int Dim>
Mat<Dim> stretch(const Vec<Dim>& d) {
  return d.array().exp().matrix().asDiagonal();
}

// Compression along y by the log-strain increment dy per step for `steps` steps, the lateral
// Kirchhoff stresses held at -p0 (3D: x and z alike, the triaxial test; 2D: x, plane strain), the
// lateral strain found by Newton's method each step. Returns the axial Kirchhoff stress after each
// step and the log volume change ln J.
template <int Dim, class Law>
void compress(const Law& law, Point<Dim>& pt, double p0, double dy, int steps,
              std::vector<double>* axial, std::vector<double>* lnJ) {
  for (int s = 0; s < steps; ++s) {
    // Lateral log-strain increment e: residual r(e) = tau_xx + p0.
    const auto trial = [&](double e) {
      Point<Dim> q = pt;
      Vec<Dim> d = Vec<Dim>::Constant(e);
      d(1) = -dy;
      q.step(law, stretch<Dim>(d));
      return q;
    };
    double e = 0.0;
    for (int it = 0; it < 50; ++it) {
      const double r = trial(e).tau()(0, 0) + p0;
      if (std::abs(r) < 1e-12 * p0) break;
      const double h = 1e-9;
      const double slope = (trial(e + h).tau()(0, 0) - trial(e - h).tau()(0, 0)) / (2 * h);
      e -= r / slope;
    }
    pt = trial(e);
    if (axial) axial->push_back(pt.tau()(1, 1));
    if (lnJ) lnJ->push_back(std::log(pt.F.determinant()));
  }
}

double deg(double a) {
  return a * kPi / 180.0;
}
// Mohr-Coulomb's axial stress at failure in compression under the confining stress -p0:
// -(p0 N + 2 c sqrt(N)), N = (1 + sin phi) / (1 - sin phi).
double mohr_coulomb_peak(double c, double phi_deg, double p0) {
  const double s = std::sin(deg(phi_deg)), N = (1 + s) / (1 - s);
  return -(p0 * N + 2 * c * std::sqrt(N));
}

TEST(Plasticity, TheReturnLiesOnTheYieldSurfaceToRoundOff) {
  // Trial stresses all over principal space (tension positive), at the scale of the strength.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-400e3, 100e3);
  const VonMises vm = von_mises(150e3, 2e6);
  const std::array<DruckerPrager, 4> dps = {
      drucker_prager(20e3, 30, 10, 0), drucker_prager(20e3, 30, 30, 1),
      drucker_prager(20e3, 25, 0, 2), drucker_prager(20e3, 30, 5, 0, 5e3)};
  const std::array<MohrCoulomb, 4> mcs = {mohr_coulomb(20e3, 30, 0), mohr_coulomb(20e3, 30, 30),
                                          mohr_coulomb(20e3, 0, 0),
                                          mohr_coulomb(20e3, 35, 10, 4e3)};
  int plastic = 0, corners = 0;
  // Elastic: the trial is inside and kept; plastic: it was outside and the return is on the
  // surface, the largest yield function zero to round-off of the stress scale.
  const double tol = 1e-12 * 400e3;
  const auto check = [&](const auto& law, const Vec3d& trial, const std::string& what) {
    Vec3d tau = trial;
    const int mode = law.return_map(tau, 0.0);
    ASSERT_GE(mode, 0) << what << " found no return for " << trial.transpose();
    if (mode == 0) {
      EXPECT_LE(law.yield_function(trial, 0.0), tol) << what;
      EXPECT_EQ(tau, trial) << what;
      return;
    }
    ++plastic;
    corners += mode >= 2;
    EXPECT_GT(law.yield_function(trial, 0.0), 0.0) << what;
    EXPECT_NEAR(law.yield_function(tau, 0.0), 0.0, tol) << what << " from " << trial.transpose();
  };
  for (int n = 0; n < 4000; ++n) {
    const Vec3d trial(u(rng), u(rng), u(rng));
    for (const auto& dp : dps) check(dp, trial, "drucker_prager");
    for (const auto& mc : mcs) check(mc, trial, "mohr_coulomb");
    // von Mises with hardening from eps_p = 0.01: on the surface of the hardened yield stress,
    // at eps_p + dgamma, with no volume change.
    Vec3d tau = trial;
    if (vm.return_map(tau, 0.01) > 0) {
      const double p = trial.sum() / 3;
      const double q_trial = std::sqrt(1.5 * (trial.array() - p).square().sum());
      const double dgamma = (q_trial - (150e3 + 2e6 * 0.01)) / (3 * vm.elastic.G + 2e6);
      EXPECT_NEAR(vm.yield_function(tau, 0.01 + dgamma), 0.0, tol);
      EXPECT_NEAR(tau.sum() / 3, p, tol);
    } else {
      EXPECT_LE(vm.yield_function(trial, 0.01), tol);
    }
  }
  // The sample reached faces, edges and apexes.
  EXPECT_GT(plastic, 10000);
  EXPECT_GT(corners, 1000);
}

TEST(Plasticity, ElasticStepsAreHenckyElasticity) {
  // Below yield, a stretch diag(l1, l2, l3) from rest: tau = D ln(l), sigma = tau / J.
  const Vec3d l(1.002, 0.999, 0.9995);
  const HenckyElasticity el(soil());
  const Vec3d tau = el.stress(l.array().log().matrix());
  const MohrCoulomb mc = mohr_coulomb(1e6, 30, 0);
  Point<3> pt;
  pt.step(mc, Mat3d(l.asDiagonal()));
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(pt.sigma(i, i), tau(i) / l.prod(), 1e-12 * tau.norm()) << i;
  EXPECT_EQ(pt.state[0], 0.0);
  EXPECT_EQ(pt.state[1], 0.0);
  // In two steps the same (the log strains add on fixed axes).
  Point<3> two;
  const Vec3d half = l.array().sqrt();
  two.step(mc, Mat3d(half.asDiagonal()));
  two.step(mc, Mat3d(half.asDiagonal()));
  EXPECT_LE((two.sigma - pt.sigma).norm(), 1e-10 * pt.sigma.norm());
  // 2D is the plane strain of 3D, sigma_zz in the state.
  Point<2> plane;
  plane.step(mc, Mat<2>(Vec<2>(l(0), l(1)).asDiagonal()));
  Point<3> ref;
  ref.step(mc, Mat3d(Vec3d(l(0), l(1), 1.0).asDiagonal()));
  EXPECT_LE((plane.tau() - ref.tau()).norm(), 1e-12 * ref.tau().norm());
  EXPECT_GT(std::abs(plane.state[2]), 0.0);
}

// Rotation by angle a about the axis (x, y, z) (Rodrigues).
Mat3d rotation(double a, Vec3d axis) {
  axis.normalize();
  return Eigen::AngleAxisd(a, axis).toRotationMatrix();
}

TEST(Plasticity, ARigidRotationRotatesTheStressAndChangesNothingElse) {
  const auto check = [](const auto& law, const std::string& what) {
    // Plastic loading first: shear and some compression.
    Point<3> pt(50e3);
    Mat3d f = Mat3d::Identity();
    f(1, 1) = 0.999;
    f(0, 1) = 0.01;
    for (int s = 0; s < 20; ++s) pt.step(law, f);
    ASSERT_GT(pt.state[0], 0.0) << what << " did not yield";
    const Point<3> before = pt;
    const Mat3d R = rotation(0.7, Vec3d(1.0, -2.0, 0.5));
    pt.step(law, R);
    EXPECT_LE((pt.sigma - R * before.sigma * R.transpose()).norm(), 1e-12 * before.sigma.norm())
        << what;
    EXPECT_EQ(pt.state[0], before.state[0]) << what;
    EXPECT_EQ(pt.state[1], 0.0) << what << ": a rotation is elastic";
    // 2D: a rotation in the plane.
    Point<2> q(50e3);
    Mat<2> g = Mat<2>::Identity();
    g(1, 1) = 0.999;
    g(0, 1) = 0.01;
    for (int s = 0; s < 20; ++s) q.step(law, g);
    const Point<2> q0 = q;
    const Mat<2> R2 = rotation(-1.1, Vec3d::UnitZ()).topLeftCorner<2, 2>();
    q.step(law, R2);
    EXPECT_LE((q.sigma - R2 * q0.sigma * R2.transpose()).norm(), 1e-12 * q0.sigma.norm()) << what;
    EXPECT_NEAR(q.state[2], q0.state[2], 1e-12 * std::abs(q0.state[2])) << what;
    EXPECT_EQ(q.state[0], q0.state[0]) << what;
  };
  check(von_mises(60e3), "von_mises");
  check(drucker_prager(10e3, 30, 10, 1), "drucker_prager");
  check(mohr_coulomb(10e3, 30, 10), "mohr_coulomb");
}

TEST(Plasticity, TriaxialCompressionReachesTheClosedFormStrength) {
  // 3D, lateral stresses -p0, axial compression to 4 % in 200 steps: the axial Kirchhoff
  // stress ends on the closed form (perfect plasticity: a plateau).
  const double c = 10e3, p0 = 100e3;
  const auto peak = [&](const auto& law) {
    Point<3> pt(p0);
    std::vector<double> axial;
    compress<3>(law, pt, p0, 2e-4, 200, &axial, nullptr);
    EXPECT_NEAR(axial[180], axial.back(), 1e-9 * p0) << "no plateau";
    return axial.back();
  };
  for (const double psi : {0.0, 15.0, 30.0}) {
    // Triaxial compression is Mohr-Coulomb's edge (the two lateral stresses equal), where the
    // outer Drucker-Prager cone touches it.
    const double exact = mohr_coulomb_peak(c, 30.0, p0);
    EXPECT_NEAR(peak(mohr_coulomb(c, 30, psi)), exact, 1e-9 * p0) << "psi " << psi;
    EXPECT_NEAR(peak(drucker_prager(c, 30, psi, 1)), exact, 1e-9 * p0) << "psi " << psi;
  }
  // Tresca (phi = 0): sigma_1 - sigma_3 = 2c; von Mises: q = sigma_y.
  EXPECT_NEAR(peak(mohr_coulomb(c, 0, 0)), -p0 - 2 * c, 1e-9 * p0);
  EXPECT_NEAR(peak(von_mises(3 * c)), -p0 - 3 * c, 1e-9 * p0);
  // Triaxial extension (the axis stretched, lateral held): the inner cone through the
  // extension corners; Mohr-Coulomb (sigma_1 = axial): (2 c cos phi - p0 (1 - sin phi)) /
  // (1 + sin phi).
  const double s = std::sin(deg(30.0));
  const double extension = (2 * c * std::cos(deg(30.0)) - p0 * (1 - s)) / (1 + s);
  for (const auto& law : {mohr_coulomb(c, 30, 10)}) {
    Point<3> pt(p0);
    std::vector<double> axial;
    compress<3>(law, pt, p0, -2e-4, 200, &axial, nullptr);
    EXPECT_NEAR(axial.back(), extension, 1e-9 * p0);
  }
  Point<3> pt(p0);
  std::vector<double> axial;
  compress<3>(drucker_prager(c, 30, 10, 2), pt, p0, -2e-4, 200, &axial, nullptr);
  EXPECT_NEAR(axial.back(), extension, 1e-9 * p0);
}

TEST(Plasticity, PlaneStrainCompressionReachesTheClosedFormStrength) {
  // 2D plane strain, lateral stress -p0, axial compression: Mohr-Coulomb's peak for any
  // dilatancy (sigma_zz stays intermediate); the plane-strain Drucker-Prager cone has the same
  // peak with associated flow; von Mises (= Tresca with c = sigma_y / sqrt(3)) sigma_1 - sigma_3
  // = 2 sigma_y / sqrt(3).
  const double c = 10e3, p0 = 100e3;
  const auto peak = [&](const auto& law, int steps = 250) {
    Point<2> pt(p0);
    std::vector<double> axial;
    compress<2>(law, pt, p0, 2e-4, steps, &axial, nullptr);
    EXPECT_NEAR(axial[static_cast<std::size_t>(steps - 20)], axial.back(), 1e-9 * p0)
        << "no plateau";
    return axial.back();
  };
  const double exact = mohr_coulomb_peak(c, 30.0, p0);
  for (const double psi : {0.0, 10.0, 30.0})
    EXPECT_NEAR(peak(mohr_coulomb(c, 30, psi)), exact, 1e-9 * p0) << "psi " << psi;
  // The cone's out-of-plane stress settles more slowly (10 % axial strain).
  EXPECT_NEAR(peak(drucker_prager(c, 30, 30, 0), 500), exact, 1e-9 * p0);
  EXPECT_NEAR(peak(von_mises(std::sqrt(3.0) * c)), -p0 - 2 * c, 1e-9 * p0);
}

TEST(Plasticity, PlasticFlowDilatesAsTheFlowRuleSays) {
  // At the plateau every strain increment is plastic: the volume change per axial shortening is
  // that of the plastic potential. Mohr-Coulomb (faces and the triaxial edge alike):
  // d ln J / -d eps_axial = 2 sin psi / (1 - sin psi). Drucker-Prager in triaxial compression:
  // eta_psi / (1 / sqrt(3) - eta_psi / 3).
  const double c = 10e3, p0 = 100e3, dy = 2e-4;
  const auto rate = [&](const auto& law, auto dim) {
    constexpr int Dim = decltype(dim)::value;
    Point<Dim> pt(p0);
    std::vector<double> lnJ;
    compress<Dim>(law, pt, p0, dy, 250, nullptr, &lnJ);
    return (lnJ[249] - lnJ[248]) / dy;
  };
  for (const double psi : {0.0, 10.0, 25.0}) {
    const double s = std::sin(deg(psi));
    const double mc = 2 * s / (1 - s);
    EXPECT_NEAR(rate(mohr_coulomb(c, 30, psi), std::integral_constant<int, 3>{}), mc, 1e-8);
    EXPECT_NEAR(rate(mohr_coulomb(c, 30, psi), std::integral_constant<int, 2>{}), mc, 1e-8);
    const DruckerPrager dp = drucker_prager(c, 30, psi, 1);
    EXPECT_NEAR(rate(dp, std::integral_constant<int, 3>{}),
                dp.eta_psi / (1 / std::sqrt(3.0) - dp.eta_psi / 3), 1e-8);
  }
  // J2 flow is isochoric.
  EXPECT_NEAR(rate(von_mises(20e3), std::integral_constant<int, 3>{}), 0.0, 1e-10);
}

TEST(Plasticity, TheIntegrationErrorFallsAtFirstOrderWithTheStrainIncrement) {
  // Simple shear to gamma = 0.2 after compression, the principal axes turning: the stress after
  // N equal increments against N = 12800; the error falls about in proportion to 1/N.
  const auto final_stress = [](const auto& law, int n) {
    Point<3> pt(80e3);
    Mat3d f = Mat3d::Identity();
    f(0, 1) = 0.2 / n;
    f(1, 1) = std::exp(-0.02 / n);
    for (int s = 0; s < n; ++s) pt.step(law, f);
    return pt.sigma;
  };
  const auto check = [&](const auto& law, const std::string& what) {
    const Mat3d ref = final_stress(law, 12800);
    double previous = 0.0;
    for (const int n : {25, 50, 100, 200}) {
      const double e = (final_stress(law, n) - ref).norm() / ref.norm();
      if (previous > 0.0) {
        const double order = std::log2(previous / e);
        EXPECT_GT(order, 0.8) << what << " N = " << n;
        EXPECT_LT(order, 1.5) << what << " N = " << n;
      }
      previous = e;
    }
  };
  check(von_mises(60e3, 1e6), "von_mises");
  check(drucker_prager(10e3, 30, 10, 1), "drucker_prager");
  check(mohr_coulomb(10e3, 30, 10), "mohr_coulomb");
}

// A law whose return never finds a stress beyond its von Mises surface q = 100 kPa: what
// HenckyPlastic does with a return mapping that fails.
struct NoReturn : HenckyPlastic<NoReturn> {
  static constexpr std::string_view kName = "no_return";
  static constexpr std::string_view kDescription = "a return mapping that always fails";
  static constexpr NoParameters kParameters{};
  explicit NoReturn(const ElasticParameters& params) : HenckyPlastic(params) {}
  double yield_function(const Vec3d& tau, double /*plastic_strain*/) const {
    const Vec3d s = tau - Vec3d::Constant(tau.sum() / 3.0);
    return std::sqrt(1.5 * s.squaredNorm()) - 100e3;
  }
  int return_map(const Vec3d& tau, double plastic_strain) const {
    return yield_function(tau, plastic_strain) > 0.0 ? -1 : 0;
  }
};

TEST(Plasticity, AFailedReturnKeepsTheTrialStressAndSaysSo) {
  // Simple shear in steps of 0.1 %: elastic (Hencky, as von Mises far below yield) until the
  // trial stress leaves the surface; that update returns false, leaves the trial stress, marks
  // yield_mode kNoReturn and keeps the plastic strain, and failed_return is the yield function
  // there. A law that returns reports nothing.
  const NoReturn law(soil());
  const VonMises elastic = von_mises(1e12);
  Point<2> a(50e3), b(50e3);
  Mat<2> f = Mat<2>::Identity();
  f(0, 1) = 1e-3;
  int steps = 0;
  bool updated = true;
  for (; updated && steps < 100; ++steps) {
    const Mat<2> dtL = f - Mat<2>::Identity();
    a.F = f * a.F;
    b.F = f * b.F;
    updated = law.update(a.sigma, std::span<double, 3>(a.state), a.F, dtL);
    ASSERT_TRUE(elastic.update(b.sigma, std::span<double, 3>(b.state), b.F, dtL));
    EXPECT_EQ(a.sigma, b.sigma) << "step " << steps;
    EXPECT_EQ(a.state[2], b.state[2]) << "step " << steps;
    const double residual = law.failed_return(a.sigma, std::span<const double, 3>(a.state), a.F);
    if (updated) {
      EXPECT_EQ(a.state[1], 0.0);
      EXPECT_TRUE(std::isnan(residual));
    } else {
      EXPECT_EQ(a.state[1], kNoReturn);
      EXPECT_EQ(a.state[0], 0.0);
      const Mat3d tau = a.tau();
      const double q = std::sqrt(1.5 * (tau - tau.trace() / 3 * Mat3d::Identity()).squaredNorm());
      EXPECT_NEAR(residual, q - 100e3, 1e-9 * q);
      EXPECT_GT(residual, 0.0);
    }
  }
  EXPECT_FALSE(updated);
  EXPECT_EQ(steps, 8);  // q = sqrt(3) G gamma: 100 kPa at gamma = 0.75 %
  // A real law's plastic step, and an elastic law: nothing to report.
  Point<2> c(50e3);
  const MohrCoulomb mc = mohr_coulomb(20e3, 30, 0);
  for (int s = 0; s < 30; ++s) c.step(mc, f);
  EXPECT_GE(c.state[1], 1.0);
  EXPECT_FALSE(failed_update<2>(Material(mc), c.sigma, c.state, c.F).has_value());
  EXPECT_FALSE(
      failed_update<2>(Material(LinearElastic(soil())), c.sigma, std::span<const double>(), c.F)
          .has_value());
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
