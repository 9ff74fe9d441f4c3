// Dimension is a template parameter: the same stages run a 2D problem. A body in uniform
// translation must move rigidly: velocity unchanged, x = x0 + v t, no strain, no stress
// (the P1 basis reproduces constants, so L = sum v grad phi_i = 0).
#include <gtest/gtest.h>

#include "../support/stepper.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

void rigid_translation_2d(const Scheme& scheme) {
  Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{8, 8});
  auto P = seed_particles<2>(g, Vec<2>(0.3, 0.3), Vec<2>(0.6, 0.7), 2, 1000.0);
  const Vec<2> vel(0.3, -0.2);
  for (auto& v : P.v) v = vel;
  ElasticParameters ep{1000.0, 1e6, 0.3};
  auto stepper = test::compiled_stepper<2>(
      {.grid = g, .particles = P, .material = NeoHookean{ep}, .scheme = scheme});
  const RunState<2>& sim = stepper->state();
  const double dt = 1e-3;
  const int steps = 200;  // travels 0.06 and 0.04: crosses cells
  for (int s = 0; s < steps; ++s) stepper->step(dt);
  for (Index p = 0; p < sim.particles.size(); ++p) {
    const auto i = static_cast<std::size_t>(p);
    EXPECT_LT((sim.particles.v[i] - vel).norm(), 1e-13);
    EXPECT_LT((sim.particles.x[i] - (P.x[i] + vel * dt * steps)).norm(), 1e-12);
    EXPECT_LT(sim.particles.stress[i].norm(), 1e-6);  // Pa, with E = 1e6 Pa
    EXPECT_LT((sim.particles.F[i] - Mat<2>::Identity()).norm(), 1e-12);
  }
  EXPECT_GT(sim.diag.grid_crossings, 0);
}

TEST(GenericDimension, RigidTranslation2DMusl) {
  rigid_translation_2d(Musl{});
}
TEST(GenericDimension, RigidTranslation2DUsl) {
  rigid_translation_2d(Usl{});
}
TEST(GenericDimension, RigidTranslation2DUsf) {
  rigid_translation_2d(Usf{});
}
TEST(GenericDimension, RigidTranslation2DUsavg) {
  rigid_translation_2d(Usavg{});
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// A 2D body that leaves the grid stops the run with the whole box in the message (not only the
// extent along x) and the particles by id with both coordinates.
TEST(GenericDimension, LeavingTheGridIn2DNamesTheBox) {
  Grid<2> g(Vec<2>(0.0, -1.0), Vec<2>(1.0, 1.0), IVec<2>{4, 8});
  auto P = seed_particles<2>(g, Vec<2>(0.25, 0.5), Vec<2>(0.5, 0.75), 2, 1000.0);
  for (auto& v : P.v) v = Vec<2>(0.0, 30.0);  // up through y = 1 within a few steps
  ElasticParameters ep{1000.0, 1e6, 0.3};
  auto stepper = test::compiled_stepper<2>({.grid = g, .particles = P, .material = NeoHookean{ep}});
  try {
    for (int s = 0; s < 100; ++s) stepper->step(1e-3);
    FAIL() << "the body did not leave the grid";
  } catch (const RunError& e) {
    const std::string m = e.what();
    EXPECT_EQ(e.exit_code(), exit_code::kLeftGrid);
    EXPECT_NE(m.find("left the grid [0, 1] x [-1, 1]"), std::string::npos) << m;
    EXPECT_NE(m.find("at x = (0."), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
