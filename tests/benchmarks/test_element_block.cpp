// examples/element_block_2d.toml: the plane-strain compression test of a homogeneous soil block
// under a confining pressure, run through the whole code (a platen of prescribed velocity, its
// reaction, a pressure on a body face, the initial stress, local damping) with each plastic
// law against its closed-form strength: the block's stress stays uniform, reaches the law's
// plane-strain failure state, and the platen's reaction is the stress it carries.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "../support/stepper.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

struct BlockResult {
  // The platen's force [N/m] (the block is 1 m wide) in steady plastic flow: its mean over the
  // last third of the push, sampled every 0.01 s.
  double plateau = 0.0;
  // Per particle at the end: the in-plane principal Kirchhoff stresses, compression positive
  // [Pa] (s1 >= s3), and the out-of-plane one.
  std::vector<double> s1, s3, szz;
};

// The example with its [material] parameters beyond the elastic ones replaced by `parameters`
// (empty: kept) and the overrides `sets`.
BlockResult compress(const std::string& parameters, const std::vector<std::string>& sets) {
  const std::string path = std::string(MPM_SOURCE_DIR) + "/examples/element_block_2d.toml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  const std::string own = "cohesion = 10.0e3\nfriction_angle = 30.0\n";
  EXPECT_NE(toml.find(own), std::string::npos);
  if (!parameters.empty()) toml.replace(toml.find(own), own.size(), parameters);
  const Config cfg = Config::parse(toml, path, sets);
  test::ConfiguredRun<2> run(cfg);
  // left, bottom (the rollers), then the platen.
  EXPECT_EQ(reaction_names(run.problem),
            (std::vector<std::string>{"left", "bottom", "prescribed"}));
  BlockResult r;
  int samples = 0;
  for (int k = 0; k < 300; ++k) {
    run.advance(10);
    if (k < 200) continue;
    r.plateau += -run.state().diag.reactions[5];
    ++samples;
  }
  r.plateau /= samples;
  const auto& P = run.state().particles;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    // The laws' yield surfaces bound the Kirchhoff stress tau = J sigma
    // (material/hencky_plasticity.hpp).
    const double J = P.F[i].determinant();
    const Mat<2> t = J * P.stress[i];
    const double m = -0.5 * (t(0, 0) + t(1, 1));
    const double d = std::hypot(0.5 * (t(0, 0) - t(1, 1)), t(0, 1));
    r.s1.push_back(m + d);
    r.s3.push_back(m - d);
    r.szz.push_back(-J * P.state[i][2]);
  }
  return r;
}

// sigma_1 at failure, compression positive, from sigma_3 (Mohr-Coulomb in plane strain with
// sigma_zz intermediate).
double mohr_coulomb_sigma1(double sigma3, double c, double phi_deg) {
  const double s = std::sin(phi_deg * std::numbers::pi / 180.0);
  const double N = (1 + s) / (1 - s);
  return N * sigma3 + 2 * c * std::sqrt(N);
}

// Unconfined (no pressure, no initial stress) each law fails at its closed-form plane-strain
// strength in each particle's principal Kirchhoff stresses: Mohr-Coulomb on its face
// (sigma_1 = N sigma_3 + 2 c sqrt(N), to round-off, sigma_zz intermediate); Drucker-Prager
// matched in plane strain with associated flow at the same strength in steady plastic flow;
// von Mises at sigma_1 - sigma_3 = 2 sigma_y / sqrt(3) in steady flow (both to 1e-4). The
// platen's force is sigma_1 at sigma_3 = 0, 2 c sqrt(N), to 2 %: the particles' stresses differ
// by that much, since the compressed block no longer fills its top row of cells and the
// velocities mapped to a partly filled cell's nodes are not linear in the position.
TEST(ElementBlock, UnconfinedEachLawFailsAtItsPlaneStrainStrength) {
  const std::vector<std::string> unconfined = {
      "pressure.right=0", R"(initial.stress=["0", "0", "0"])", "initial.stress_zz=0"};
  const double c = 10e3, sy = 60e3;
  auto with = [&](std::vector<std::string> more) {
    more.insert(more.begin(), unconfined.begin(), unconfined.end());
    return more;
  };
  {
    const BlockResult r = compress("", unconfined);
    for (std::size_t i = 0; i < r.s1.size(); ++i) {
      EXPECT_NEAR(r.s1[i], mohr_coulomb_sigma1(r.s3[i], c, 30.0), 1e-9 * r.s1[i]) << i;
      EXPECT_GT(r.szz[i], r.s3[i]) << i;  // intermediate
      EXPECT_LT(r.szz[i], r.s1[i]) << i;
    }
    std::printf("element block, unconfined mohr_coulomb: platen %.6g N/m against %.6g\n", r.plateau,
                mohr_coulomb_sigma1(0.0, c, 30.0));
    EXPECT_NEAR(r.plateau, mohr_coulomb_sigma1(0.0, c, 30.0), 0.02 * r.plateau);
  }
  {
    const BlockResult r =
        compress("", with({"material.model=drucker_prager", "material.dilatancy_angle=30"}));
    double worst = 0.0;
    for (std::size_t i = 0; i < r.s1.size(); ++i)
      worst = std::max(worst, std::abs(r.s1[i] / mohr_coulomb_sigma1(r.s3[i], c, 30.0) - 1));
    std::printf(
        "element block, unconfined drucker_prager: sigma_1 within %.3g of the closed "
        "form\n",
        worst);
    EXPECT_LT(worst, 1e-4);
  }
  {
    const BlockResult r =
        compress(fmt::format("yield_stress = {}\n", sy), with({"material.model=von_mises"}));
    double worst = 0.0;
    for (std::size_t i = 0; i < r.s1.size(); ++i)
      worst = std::max(worst, std::abs((r.s1[i] - r.s3[i]) / (2 * sy / std::sqrt(3.0)) - 1));
    std::printf(
        "element block, unconfined von_mises: sigma_1 - sigma_3 within %.3g of the "
        "closed form\n",
        worst);
    EXPECT_LT(worst, 1e-4);
  }
}

// The example, confined by p0 = 50 kPa on its free side: the platen's force is the
// Mohr-Coulomb strength at p0, to the change of the block's shape (the pressure is per reference
// area) and the share of the pressure that the loaded face, moved into the next cell, gives to
// nodes without mass.
TEST(ElementBlock, ConfinedMohrCoulombFailsAtItsStrength) {
  const double p0 = 50e3, c = 10e3;
  const BlockResult r = compress("", {});
  std::printf("element block, mohr_coulomb at p0 = 50 kPa: platen %.6g N/m against %.6g\n",
              r.plateau, mohr_coulomb_sigma1(p0, c, 30.0));
  EXPECT_NEAR(r.plateau, mohr_coulomb_sigma1(p0, c, 30.0), 0.02 * r.plateau);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
