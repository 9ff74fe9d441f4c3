// MPM runs with P1 on triangles (method.basis = "p1_triangles", basis/p1_triangle.hpp): the
// compiled stepper on the plate of examples/plate_mms_2d.toml. A linear velocity field is
// reproduced exactly through the whole step (consistent mass), momentum is conserved to
// round-off in every scheme, and the pairings that do not exist are refused with the key.
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

// The plate with `sets`, its sides free (no rollers) and, with amplitude 0, no body force.
std::unique_ptr<test::PlateRun> plate(std::vector<std::string> sets,
                                      const std::string& basis = "p1_triangles") {
  sets.push_back("method.basis=" + basis);
  return test::plate_run(std::move(sets), true);
}

// v_p = A x_p with zero stress: P1 reproduces the linear field, and with consistent mass the
// grid velocity is its exact L2 projection, v_i = A x_i, so after one USL step every particle
// has F = I + dt A and x += dt A x (to round-off), on both triangulations.
TEST(P1TrianglesRun, LinearVelocityFieldIsExactThroughTheStep) {
  Mat<2> A;
  A << 0.3, -1.1, 0.7, 0.2;
  const double dt = 1e-5;
  // The control: lumped mass averages A x_p around each node, which is not A x_i next to the
  // free edges, so the same check fails there (the test can tell).
  for (const std::string basis : {"p1_triangles", "powell_sabin"})
    for (const std::string mass : {"consistent", "lumped"})
      for (const std::string pattern : {"right", "criss_cross"}) {
        // PS: 16 particles per cell (with 9 per cell its consistent mass matrix is singular).
        auto r = plate({"grid.cells=5", "method.triangles=" + pattern, "method.mass=" + mass,
                        "method.scheme=usl",
                        basis == "powell_sabin" ? "particles.per_cell=4" : "particles.per_cell=3"},
                       basis);
        const auto [worst_f, worst_x] = test::linear_field_step(*r->stepper, A, dt);
        if (mass == "consistent") {
          EXPECT_LT(worst_f, 1e-14) << basis << " " << pattern;
          EXPECT_LT(worst_x, 1e-15) << basis << " " << pattern;
        } else {
          EXPECT_GT(worst_f, 1e-8) << basis << " " << pattern;
        }
      }
}

// A free plate with a non-uniform velocity and stress: the internal forces sum to zero
// (partition of unity), so the total momentum stays at its initial value to round-off in every
// scheme, with lumped and consistent mass.
TEST(P1TrianglesRun, FreePlateConservesMomentumInEveryScheme) {
  for (const std::string basis : {"p1_triangles", "powell_sabin"})
    for (const std::string scheme : {"usl", "usf", "musl", "usavg"})
      for (const std::string mass : {"lumped", "consistent"}) {
        auto r = plate({"grid.cells=4", "method.triangles=right", "method.mass=" + mass,
                        "method.scheme=" + scheme},
                       basis);
        auto& P = r->stepper->state().particles;
        Vec<2> m0 = Vec<2>::Zero();
        double scale = 0.0;
        for (std::size_t i = 0; i < P.x.size(); ++i) {
          P.stress[i] << 30.0 * std::cos(2.0 * P.x[i][0]), 5.0, 5.0,
              -20.0 * std::sin(3.0 * P.x[i][1]);
          P.v[i] << 0.1 * std::sin(P.x[i][1]), -0.2 * P.x[i][0];
          m0 += P.mass[i] * P.v[i];
          scale += P.mass[i] * P.v[i].norm();
        }
        for (int s = 0; s < 10; ++s) r->stepper->step(1e-5);
        Vec<2> m1 = Vec<2>::Zero();
        for (std::size_t i = 0; i < P.x.size(); ++i) m1 += P.mass[i] * P.v[i];
        EXPECT_LT((m1 - m0).norm(), 1e-13 * scale) << basis << " " << scheme << " " << mass;
      }
}

TEST(P1TrianglesRun, PairingsThatDoNotExistAreRefused) {
  auto refusal = [](const std::vector<std::string>& sets, const std::string& file, int dim) {
    try {
      run_settings(Config::load(std::string(MPM_SOURCE_DIR) + "/examples/" + file, sets), dim);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // TLS runs on triangles (tests/mapping/test_tls_triangle_mapping.cpp), MLS does not.
  const auto mls =
      refusal({"method.basis=p1_triangles", "method.mapping=mls"}, "plate_mms_2d.toml", 2);
  EXPECT_NE(mls.find("method.mapping"), std::string::npos) << mls;
  const auto one_d = refusal({"method.basis=p1_triangles"}, "vibrating_bar_small.toml", 1);
  EXPECT_NE(one_d.find("is not available in 1D"), std::string::npos) << one_d;
  const auto pattern =
      refusal({"method.basis=p1_triangles", "method.triangles=diagonal"}, "plate_mms_2d.toml", 2);
  EXPECT_NE(pattern.find("criss_cross"), std::string::npos) << pattern;
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
