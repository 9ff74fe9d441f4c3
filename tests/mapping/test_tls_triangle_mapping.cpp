// The TLS mapping on triangles (mapping/tls_triangle_mapping.cpp; D 6.1.2, 6.3): through the
// compiled steppers of P1 and Powell-Sabin splines on the plate of examples/plate_mms_2d.toml.
// Mass and momentum are conserved to round-off in every scheme (D Table 6.1), a linear velocity
// field goes through a step exactly with consistent mass, D 6.3.1's rank loss with 12 particles
// per triangle stops the baseline and not the default, and the settings that do not apply to
// triangles (or to rectangles) are refused with the key.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "../support/stepper.hpp"
#include "benchmarks/benchmarks.hpp"
#include "driver/stepper.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"
#include "setup/run_settings.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// The plate with TLS and `sets`; `free_sides`: no rollers and (amplitude 0) no body force.
std::unique_ptr<test::PlateRun> plate(std::vector<std::string> sets, bool free_sides = true) {
  sets.insert(sets.begin(), "method.mapping=tls");
  return test::plate_run(std::move(sets), free_sides);
}

// D eq. 5.19-5.21 on triangles: the conservative density and momentum fits integrate exactly
// (the collapsed 2 x 2 Gauss rule is exact for the quadratic Taylor basis), so in every step the
// grid holds the particles' mass and momentum to round-off, in every scheme (D Table 6.1), and
// the internal forces at the Gauss points sum to zero (partition of unity). The particles'
// momentum itself drifts (2e-9 relative over 10 steps): the grid-to-particle update weighs
// a_i = f_i / m_i with the particles' phi_i(x_p) m_p, whose sum over p is not the reconstructed
// m_i, as with TLS on rectangles; D's conservation is that of the mapping.
TEST(TlsOnTriangles, ConservesMassAndMomentumInEveryScheme) {
  for (const std::string basis : {"p1_triangles", "powell_sabin"})
    for (const std::string pattern : {"right", "criss_cross"})
      for (const std::string scheme : {"usl", "usf", "musl", "usavg"})
        for (const std::string mass : {"lumped", "consistent"}) {
          SCOPED_TRACE(basis + " " + pattern + " " + scheme + " " + mass);
          auto r = plate({"method.basis=" + basis, "grid.cells=3", "particles.per_triangle=12",
                          "method.triangles=" + pattern, "method.mass=" + mass,
                          "method.scheme=" + scheme});
          auto& S = r->stepper->state();
          auto& P = S.particles;
          for (std::size_t i = 0; i < P.x.size(); ++i) {
            P.stress[i] << 3e4 * std::cos(2.0 * P.x[i][0]), 5e3, 5e3,
                -2e4 * std::sin(3.0 * P.x[i][1]);
            P.v[i] << 0.1 * std::sin(P.x[i][1]), -0.2 * P.x[i][0];
          }
          try {
            for (int s = 0; s < 4; ++s) r->stepper->step(1e-5);
          } catch (const RunError& e) {
            ADD_FAILURE() << e.what();
            continue;
          }
          EXPECT_GT(S.diag.max_rel_mass_error, 0.0);  // measured (0 would mean not checked)
          EXPECT_LT(S.diag.max_rel_mass_error, 1e-14);
          EXPECT_LT(S.diag.max_rel_momentum_error, 1e-14);
        }
}

// v_p = A x_p, zero stress, uniform density: (rho v)^ = rho A x is in the Taylor space and its
// integral over each triangle is the particles' momentum (their centroid is the triangle's), so
// the fit is exact; with consistent mass the grid velocity solves M v = q with M and q from the
// same Gauss points, which reproduces any field of the basis's space: v_i = A x_i (P1; for PS
// the linear field's spline coefficients), and after one USL step F = I + dt A everywhere.
TEST(TlsOnTriangles, LinearVelocityFieldIsExactThroughTheStep) {
  Mat<2> A;
  A << 0.3, -1.1, 0.7, 0.2;
  const double dt = 1e-5;
  for (const std::string basis : {"p1_triangles", "powell_sabin"})
    for (const std::string pattern : {"right", "criss_cross"}) {
      SCOPED_TRACE(basis + " " + pattern);
      auto r =
          plate({"method.basis=" + basis, "grid.cells=4", "particles.per_triangle=12",
                 "method.triangles=" + pattern, "method.mass=consistent", "method.scheme=usl"});
      const auto [worst_f, worst_x] = test::linear_field_step(*r->stepper, A, dt);
      EXPECT_LT(worst_f, 1e-13);
      EXPECT_LT(worst_x, 1e-15);
    }
}

// D 6.3.1: with 12 particles per triangle on the 1058-triangle plate (A = 0.05 m) the
// least-squares matrices lose rank as particles move between triangles and D's runs stop. The
// baseline (method.tls_completion = "none") stops within the first steps with exit code 6,
// naming the triangle; the default (reduce, limit 10 in the orthonormal basis) keeps every
// field finite and conservative through the steps where the unlimited fits (limit 1e8) made the
// stress non-finite (steps 32-46, docs/verification.md).
TEST(TlsOnTriangles, RankLossOfD631StopsTheBaselineNotTheDefault) {
  const std::vector<std::string> d631{"method.basis=p1_triangles", "grid.cells=23",
                                      "particles.per_triangle=12", "mms.amplitude=0.05"};
  {
    auto sets = d631;
    sets.push_back("method.tls_completion=none");
    auto r = plate(sets, false);
    int code = 0;
    std::string what;
    int steps = 0;
    try {
      for (; steps < 20; ++steps) r->stepper->step(1.25e-4);
    } catch (const RunError& e) {
      code = e.exit_code();
      what = e.what();
    }
    EXPECT_EQ(code, exit_code::kReconstruction);
    EXPECT_LT(steps, 20);
    EXPECT_NE(what.find("TLS cannot fit triangle"), std::string::npos) << what;
    EXPECT_NE(what.find("min_norm or graded"), std::string::npos) << what;
  }
  auto r = plate(d631, false);
  auto& S = r->stepper->state();
  for (int s = 0; s < 60; ++s) {
    r->stepper->step(1.25e-4);
    S.time += 1.25e-4;  // the body force depends on t (the driver advances it)
    ++S.step;
  }
  for (const auto& sigma : S.particles.stress) ASSERT_TRUE(sigma.allFinite());
  EXPECT_LT(S.diag.max_rel_mass_error, 1e-13);
  EXPECT_LT(S.diag.max_rel_momentum_error, 1e-13);
}

std::string refusal(const std::vector<std::string>& sets, const std::string& example) {
  try {
    run_settings(Config::load(std::string(MPM_SOURCE_DIR) + "/examples/" + example, sets), 2);
  } catch (const InputError& e) {
    return e.what();
  }
  return {};
}

TEST(TlsOnTriangles, SettingsThatDoNotApplyAreRefused) {
  const std::vector<std::string> tri{"method.basis=p1_triangles", "method.mapping=tls"};
  auto with = [](std::vector<std::string> a, const std::string& b) {
    a.push_back(b);
    return a;
  };
  const auto virt = refusal(with(tri, "method.tls_completion=virtual"), "plate_mms_2d.toml");
  EXPECT_NE(virt.find("method.tls_completion"), std::string::npos) << virt;
  EXPECT_NE(virt.find("min_norm, graded"), std::string::npos) << virt;
  const auto graded =
      refusal({"method.mapping=tls", "method.tls_completion=graded"}, "plate_mms_2d.toml");
  EXPECT_NE(graded.find("works on triangles"), std::string::npos) << graded;
  const auto limit = refusal(with(tri, "method.tls_max_condition=1e4"), "plate_mms_2d.toml");
  EXPECT_NE(limit.find("method.tls_triangle_max_condition"), std::string::npos) << limit;
  const auto limit2 =
      refusal({"method.mapping=tls", "method.tls_triangle_max_condition=20"}, "plate_mms_2d.toml");
  EXPECT_NE(limit2.find("applies to triangles"), std::string::npos) << limit2;
  const auto gauss = refusal(with(tri, "method.gauss_points=1"), "plate_mms_2d.toml");
  EXPECT_NE(gauss.find("method.gauss_points = 1"), std::string::npos) << gauss;
  const auto mls =
      refusal({"method.basis=powell_sabin", "method.mapping=mls"}, "plate_mms_2d.toml");
  EXPECT_NE(mls.find("method.mapping"), std::string::npos) << mls;
  // The default completion in 2D is reduce, on triangles and on the grid's cells (with the
  // cells' positivity and surface stress), virtual in 1D (D 5.2.3).
  const auto t = run_settings(
      Config::load(std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml", tri), 2);
  EXPECT_EQ(std::get<TlsMapping>(t.method.mapping).settings().completion, TlsCompletion::Reduce);
  EXPECT_EQ(std::get<TlsMapping>(t.method.mapping).settings().max_condition, 10.0);
  const auto q =
      run_settings(Config::load(std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml",
                                {"method.mapping=tls"}),
                   2);
  const auto& qs = std::get<TlsMapping>(q.method.mapping).settings();
  EXPECT_EQ(qs.completion, TlsCompletion::Reduce);
  EXPECT_EQ(qs.max_condition, 10.0);
  EXPECT_TRUE(qs.positivity && qs.surface_volume);
  EXPECT_FALSE(std::get<TlsMapping>(t.method.mapping).settings().positivity);
  const auto one = run_settings(
      Config::load(std::string(MPM_SOURCE_DIR) + "/examples/mms_1d.toml", {"method.mapping=tls"}),
      1);
  const auto& os = std::get<TlsMapping>(one.method.mapping).settings();
  EXPECT_EQ(os.completion, TlsCompletion::Virtual);
  EXPECT_EQ(os.max_condition, 1e8);
  EXPECT_FALSE(os.positivity || os.surface_volume);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
