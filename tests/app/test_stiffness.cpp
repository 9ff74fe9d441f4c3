// `mpm stiffness` (app/stiffness.hpp): the linearised grid operator of a mapping on a frozen
// layout. The direct mapping's force is the adjoint of the strain rate, so on any unstressed
// layout its operator is symmetric and neutral; TLS with quadratic B-splines integrates its
// fitted stress against the gradients at its Gauss points, which is not, and on the stretched
// layout of the plate (a quarter period of 001's motion at A = 0.1) has a growing mode (issue 22
// item 3, docs/verification.md); TLS with the bilinear functions, each component of whose
// gradient lies in the span of the linear fit in a cell, is symmetric again while every element
// fits a linear stress from its own particles; with the strain rate its force's adjoint
// (method.tls_strain_rate = "adjoint") B2-TLS is symmetric and neutral there too.
#include "app/stiffness.hpp"

#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <string>

#include "core/types.hpp"
#include "driver/run.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

const std::string kPlate = std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml";

// The plate on 4 x 4 cells at t = 0.005 s, a quarter period: every particle at its farthest
// from where it started (001's motion, A = 0.1 m), as the direct mapping ran it.
std::string stretched_layout() {
  const auto dir =
      std::filesystem::temp_directory_path() / ("mpm_stiffness_" + std::to_string(::getpid()));
  RunOptions ro;
  ro.out_dir = dir.string();
  ro.quiet = true;
  ro.overwrite = true;
  const auto r = run(Config::load(kPlate, {"grid.cells=4", "time.end=0.005", "output.frames=1",
                                           "output.vtk=false", "output.checkpoint_every=500"}),
                     ro);
  EXPECT_EQ(r.exit_code, 0) << r.failure;
  return (dir / "checkpoint.bin").string();
}

const StiffnessRow& row(const StiffnessReport& r, const std::string& force,
                        const std::string& mass) {
  for (const auto& x : r.rows)
    if (x.force == force && x.mass == mass) return x;
  throw std::logic_error("no row " + force + "/" + mass);
}

// On the initial layout (3 x 3 particles in every cell) B2-TLS is neutral as the direct mapping
// is: the growth below is the stretched layout's.
TEST(Stiffness, DirectAndQuadraticTlsAreNeutralOnTheInitialLayout) {
  StiffnessOptions o;
  o.config = kPlate;
  o.sets = {"grid.cells=4", "method.mapping=tls"};
  const StiffnessReport r = stiffness_spectrum(o);
  ASSERT_EQ(r.rows.size(), 4u);
  EXPECT_EQ(r.state, "the initial layout");
  for (const auto& x : r.rows) {
    SCOPED_TRACE(x.force + "/" + x.mass);
    EXPECT_EQ(x.dofs, 48);
    EXPECT_GT(x.omega, 500.0);
    EXPECT_LT(x.growth, 1e-9 * x.omega);
  }
  EXPECT_LT(row(r, "direct", "direct").asymmetry, 1e-7);
}

TEST(Stiffness, QuadraticTlsGrowsOnAStretchedLayoutWhereDirectAndP1AreNeutral) {
  StiffnessOptions o;
  o.config = kPlate;
  o.checkpoint = stretched_layout();
  o.layout_only = true;
  o.sets = {"grid.cells=4", "method.mapping=tls"};
  const StiffnessReport b2 = stiffness_spectrum(o);
  ASSERT_EQ(b2.rows.size(), 4u);
  EXPECT_EQ(b2.particles, 144);
  for (const auto& r : b2.rows) {
    SCOPED_TRACE(r.force + "/" + r.mass);
    EXPECT_EQ(r.dofs, 48);      // 6 x 6 DOFs, 2 components, less the rollers' normal components
    EXPECT_GT(r.omega, 500.0);  // about 2 pi c / h = 2.5e3 at most
    if (r.force == "direct") {
      // -B^T W C B: symmetric, every lambda imaginary (round-off of the differences aside).
      EXPECT_LT(r.asymmetry, 1e-7);
      EXPECT_LT(r.growth, 1e-9 * r.omega);
    }
  }
  // TLS's force against the particles' strain rate: 19 % asymmetric here, and with its own
  // lumped mass a mode growing at 4.7 1/s (measured; the 16-cell layout of the run's own
  // state gives 46 1/s, docs/verification.md).
  EXPECT_GT(row(b2, "tls", "tls").asymmetry, 0.05);
  EXPECT_GT(row(b2, "tls", "tls").growth, 1e-3 * row(b2, "tls", "tls").omega);
  // The same B2-TLS with the strain rate its force's adjoint (method.tls_strain_rate =
  // "adjoint"): -G^T diag(omega C) G, symmetric and neutral with either lumped mass.
  o.sets.push_back("method.tls_strain_rate=adjoint");
  const StiffnessReport adj = stiffness_spectrum(o);
  for (const auto& r : adj.rows) {
    SCOPED_TRACE("adjoint " + r.force + "/" + r.mass);
    EXPECT_LT(r.asymmetry, 1e-7);
    EXPECT_LT(r.growth, 1e-9 * r.omega);
  }
  o.sets.pop_back();
  // P1: grad phi_i = (c_i . psi) in each cell, so the force matrix is -c_i^T G c_j C (G: the
  // Gram matrix of the Taylor basis), symmetric (docs/verification.md).
  o.sets.push_back("method.basis=linear");
  const StiffnessReport p1 = stiffness_spectrum(o);
  for (const auto& r : p1.rows) {
    SCOPED_TRACE(r.force + "/" + r.mass);
    EXPECT_LT(r.asymmetry, 1e-7);
    EXPECT_LT(r.growth, 1e-9 * r.omega);
  }
  std::filesystem::remove_all(std::filesystem::path(o.checkpoint).parent_path());
}

TEST(Stiffness, RefusesWhatItCannotAnalyse) {
  StiffnessOptions o;
  o.config = kPlate;
  o.sets = {"method.basis=cpdi"};
  EXPECT_THROW(stiffness_spectrum(o), InputError);
  o.sets = {"method.mapping=mls"};
  EXPECT_THROW(stiffness_spectrum(o), InputError);
  o.sets = {"method.degree=3"};
  EXPECT_THROW(stiffness_spectrum(o), InputError);
  o.config = std::string(MPM_SOURCE_DIR) + "/examples/vibrating_bar_small.toml";
  o.sets = {};
  try {
    stiffness_spectrum(o);
    ADD_FAILURE() << "a 1D problem was analysed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2D problems"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
