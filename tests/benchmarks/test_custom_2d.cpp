// Tractions on a side in 2D and the 2D custom benchmark (issue 7):
// - a plane-strain column loaded on x = L with rollers on y = 0 and y = H is the 1D traction bar
//   (D 4.6.2, Steffen et al.): every particle row of the 2D run must match the 1D run, and both
//   the exact stress of D eq. 4.93;
// - force balance: a free block under tractions gains exactly the applied impulse;
// - examples/custom_plate_2d.toml (gravity on a plate with rollers) against its quasi-static
//   solution given as exact.* expressions;
// - input errors of the vector keys name the file, line and key.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "../support/stepper.hpp"
#include "benchmarks/benchmarks.hpp"
#include "driver/run.hpp"
#include "driver/stepper.hpp"
#include "methods/kinds.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

void expect_input_error(const std::string& toml, const std::vector<std::string>& needles);

// The traction bar of examples/traction_bar.toml on a coarser grid: rho = 100 kg/m^3,
// E = 100 Pa, nu = 0 (c = 1 m/s), L = 1 m in a 1.25 m grid of 40 cells, 2 PPC.
constexpr const char* kBar1D = R"toml(
benchmark = "traction_bar"
[grid]
cells = 40
min = 0.0
max = 1.25
[particles]
per_cell = 2
[time]
dt = 1e-3
end = 1.5
[material]
model = "neo_hookean"
density = 100.0
youngs_modulus = 100.0
poisson_ratio = 0.0
[traction]
amplitude = 1.0
)toml";

// The same bar as a 2D plane-strain column 0.125 m (4 cells) high: fixed at x = 0, rollers on
// y = 0 and y = 0.125, the traction tau = (-A sin(pi c t / L), 0) on the face x = L.
constexpr const char* kBar2D = R"toml(
benchmark = "custom"
[constants]
A = 1.0
c = 1.0
L = 1.0
[grid]
dimension = 2
cells = 40
min = [0.0, 0.0]
max = [1.25, 0.125]
[body]
min = [0.0, 0.0]
max = [1.0, 0.125]
[particles]
per_cell = 2
[time]
dt = 1e-3
end = 1.5
[material]
model = "neo_hookean"
density = 100.0
youngs_modulus = 100.0
poisson_ratio = 0.0
[boundary]
left = "fixed"
right = "free"
bottom = "roller"
top = "roller"
[traction]
right = ["-A*sin(pi*c*t/L)", "0"]
)toml";

TEST(Traction2D, PlaneStrainColumnMatchesTheTractionBarRowByRow) {
  const Config c1 = Config::parse(kBar1D, "bar1d.toml");
  const Config c2 = Config::parse(kBar2D, "bar2d.toml");
  auto p1 = std::get<Problem<1>>(make_problem(c1));
  auto p2 = std::get<Problem<2>>(make_problem(c2));
  ASSERT_EQ(p2.tractions.size(), 1u);
  const auto& tr = p2.tractions[0];
  EXPECT_EQ(tr.direction, 0);
  EXPECT_EQ(tr.side, 1);
  // The outer particle column (8 rows) carries the face: areas sum to the face height.
  EXPECT_EQ(tr.particles.size(), 8u);
  double face = 0.0;
  for (double a : tr.area) face += a;
  EXPECT_NEAR(face, 0.125, 1e-15);

  const TractionBarExact ex{1.0, 100.0, 1.0, 1.0};
  const double dt = 1e-3;
  const int steps = 1500;  // T = 1.5 s: the wave has reflected at the fixed end (c T > L)
  const auto P1 = test::step_problem<1>(std::move(p1), dt, steps);
  const auto P2 = test::step_problem<2>(std::move(p2), dt, steps);
  const std::size_t nx = P1.x.size();
  ASSERT_EQ(P2.x.size() % nx, 0u);
  const std::size_t rows = P2.x.size() / nx;
  EXPECT_EQ(rows, 8u);

  double max_ds = 0.0, max_dv = 0.0, max_du = 0.0, max_off = 0.0;
  double err1 = 0.0, err2 = 0.0;
  const double T = dt * steps;
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t i = 0; i < nx; ++i) {
      const std::size_t k = i + nx * r;  // x fastest (seed_particles)
      ASSERT_EQ(P2.x0[k][0], P1.x0[i][0]);
      max_ds = std::max(max_ds, std::abs(P2.stress[k](0, 0) - P1.stress[i](0, 0)));
      max_dv = std::max(max_dv, std::abs(P2.v[k][0] - P1.v[i][0]));
      max_du = std::max(max_du, std::abs(P2.displacement(k)[0] - P1.displacement(i)[0]));
      // Uniaxial strain: no y motion, no shear; sigma_yy = 0 with lambda = 0 (nu = 0).
      max_off = std::max({max_off, std::abs(P2.v[k][1]), std::abs(P2.displacement(k)[1]),
                          std::abs(P2.stress[k](0, 1)), std::abs(P2.stress[k](1, 1))});
      const double se = ex(Vec<1>(P1.x0[i][0]), T).stress(0, 0);
      err2 += std::pow(P2.stress[k](0, 0) - se, 2);
      if (r == 0) err1 += std::pow(P1.stress[i](0, 0) - se, 2);
    }
  err1 = std::sqrt(err1 / static_cast<double>(nx));
  err2 = std::sqrt(err2 / static_cast<double>(P2.x.size()));
  std::printf(
      "2D vs 1D: max |d sigma_xx| %.3g Pa, |d v_x| %.3g m/s, |d u_x| %.3g m, off-axis %.3g\n",
      max_ds, max_dv, max_du, max_off);
  std::printf("stress RMS error vs D eq. 4.93 at T = %.2f s: 1D %.6g Pa, 2D %.6g Pa (A = 1 Pa)\n",
              T, err1, err2);
  // Round-off only: the rows are identical and the y-weights factor out of every nodal ratio.
  EXPECT_LT(max_ds, 1e-10);
  EXPECT_LT(max_dv, 1e-10);
  EXPECT_LT(max_du, 1e-12);
  EXPECT_LT(max_off, 1e-10);
  EXPECT_NEAR(err2, err1, 1e-10);
  EXPECT_LT(err2, 0.06);  // measured 0.0509 Pa (A = 1 Pa) on h = L / 32 (P1 MPM, 2 PPC)
}

// The 1D custom benchmark with traction.right is the traction bar (a roller in 1D is "fixed").
TEST(Traction2D, OneDimensionalCustomTractionIsTheTractionBar) {
  const Config c1 = Config::parse(kBar1D, "bar1d.toml");
  const Config cc = Config::parse(R"toml(
benchmark = "custom"
[constants]
A = 1.0
c = 1.0
L = 1.0
[grid]
cells = 40
min = 0.0
max = 1.25
[body]
min = 0.0
max = 1.0
[particles]
per_cell = 2
[time]
dt = 1e-3
end = 1.5
[material]
model = "neo_hookean"
density = 100.0
youngs_modulus = 100.0
poisson_ratio = 0.0
[boundary]
left = "roller"
right = "free"
[traction]
right = "-A*sin(pi*c*t/L)"
)toml",
                                  "custom1d.toml");
  auto pc = std::get<Problem<1>>(make_problem(cc));
  ASSERT_EQ(pc.fixed_sides.size(), 1u);
  EXPECT_EQ(pc.fixed_sides[0].components, 1u);
  const auto P1 = test::step_problem<1>(std::get<Problem<1>>(make_problem(c1)), 1e-3, 1500);
  const auto PC = test::step_problem<1>(std::move(pc), 1e-3, 1500);
  ASSERT_EQ(PC.x.size(), P1.x.size());
  double max_ds = 0.0;
  for (std::size_t i = 0; i < P1.x.size(); ++i)
    max_ds = std::max(max_ds, std::abs(PC.stress[i](0, 0) - P1.stress[i](0, 0)));
  // The traction evaluated by muparser instead of C++: round-off apart.
  EXPECT_LT(max_ds, 1e-12);
}

// A free block (no Dirichlet condition, body inside the grid) under a ramped traction on its
// right face and a constant one on its top face: the total momentum must equal the applied
// impulse sum_s tau(t_s) A dt (the internal forces sum to zero, partition of unity). The faces
// lie mid-cell: a face on a grid line that moves into the empty cell beyond puts part of its
// force on nodes without mass, which the solve leaves out (as the 1D end traction does).
TEST(Traction2D, FreeBlockGainsExactlyTheAppliedImpulse) {
  const Config c = Config::parse(R"toml(
benchmark = "custom"
[constants]
p0 = 2000.0
q0 = 500.0
T0 = 0.01
[grid]
dimension = 2
cells = 10
min = [0.0, 0.0]
max = [1.0, 1.0]
[body]
min = [0.25, 0.25]
max = [0.75, 0.65]
[particles]
per_cell = 2
[time]
dt = 1e-4
end = 0.02
[material]
model = "neo_hookean"
density = 1000.0
youngs_modulus = 1e6
poisson_ratio = 0.3
[boundary]
left = "free"
right = "free"
bottom = "free"
top = "free"
[traction]
right = ["p0*min(t/T0, 1)", "-q0"]
top = ["q0", "p0"]
)toml",
                                 "block.toml");
  auto pb = std::get<Problem<2>>(make_problem(c));
  ASSERT_EQ(pb.tractions.size(), 2u);
  const double dt = 1e-4;
  const int steps = 200;
  const auto P = test::step_problem<2>(std::move(pb), dt, steps);
  // Right face: height 0.4 m; top face: width 0.5 m (reference areas per unit thickness).
  Vec<2> impulse = Vec<2>::Zero();
  for (int s = 0; s < steps; ++s) {
    const double t = s * dt;
    impulse +=
        dt * (0.4 * Vec<2>(2000.0 * std::min(t / 0.01, 1.0), -500.0) + 0.5 * Vec<2>(500.0, 2000.0));
  }
  Vec<2> momentum = Vec<2>::Zero();
  for (std::size_t i = 0; i < P.x.size(); ++i) momentum += P.mass[i] * P.v[i];
  const double rel = (momentum - impulse).norm() / impulse.norm();
  std::printf("momentum (%.15g, %.15g) N s, impulse (%.15g, %.15g) N s, relative %.3g\n",
              momentum[0], momentum[1], impulse[0], impulse[1], rel);
  EXPECT_LT(rel, 1e-12);
}

// A normal pressure p is the traction -p n on the reference face (n its outward normal), added
// to the face's traction.* vector.
TEST(Traction2D, PressureIsMinusPTimesTheOutwardNormal) {
  const Config c = Config::parse(std::string(R"toml(benchmark = "custom"
[time]
dt = 1e-4
end = 1e-3
[material]
model = "linear_elastic"
density = 1000.0
youngs_modulus = 1e6
[grid]
dimension = 2
min = [0.0, 0.0]
max = [1.0, 1.0]
[body]
min = [0.25, 0.25]
max = [0.75, 0.75]
[pressure]
left = "100*t"
top = "7"
[traction]
top = ["3", "1"]
)toml"),
                                 "pressure.toml");
  const auto pb = std::get<Problem<2>>(make_problem(c));
  ASSERT_EQ(pb.tractions.size(), 2u);  // left, then top
  EXPECT_EQ(pb.tractions[0].direction, 0);
  EXPECT_EQ(pb.tractions[0].side, -1);
  EXPECT_EQ(pb.tractions[0].value(2.0), Vec<2>(200.0, 0.0));  // pushes along +x
  EXPECT_EQ(pb.tractions[1].direction, 1);
  EXPECT_EQ(pb.tractions[1].side, 1);
  EXPECT_EQ(pb.tractions[1].value(0.0), Vec<2>(3.0, 1.0 - 7.0));  // pushes along -y
  // 1D: only left and right exist.
  expect_input_error(
      "benchmark = \"custom\"\n[time]\ndt = 1e-4\nend = 1e-3\n[material]\ndensity = 1000.0\n"
      "youngs_modulus = 1e6\n[pressure]\ntop = \"1\"\n",
      {"case.toml:9:", "pressure.top", "grid.dimension = 2"});
}

// examples/custom_plate_2d.toml: linear elastic plate with rollers on its sides under gravity
// ramped over T = 1 s (about 9 periods of the column), compared at T with the quasi-static
// solution sigma_yy = -rho g (H - Y), sigma_xx = nu / (1 - nu) sigma_yy,
// u_y = -rho g (H Y - Y^2 / 2) / M, M = E (1 - nu) / ((1 + nu) (1 - 2 nu)) (exact.* keys).
TEST(Custom2D, GravityPlateMatchesTheQuasiStaticSolution) {
  const Config c = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/custom_plate_2d.toml",
                                {"output.frames=0", "output.csv=false", "output.vtk=false"});
  const auto r = run(c, RunOptions{});
  ASSERT_EQ(r.exit_code, 0) << r.failure;
  EXPECT_EQ(r.dim, 2);
  ASSERT_TRUE(r.errors.stress_rel_l2 && r.errors.displacement_rms);
  std::printf(
      "plate under gravity: stress rel L2 %.4g, displacement RMS %.4g m, mass %.3g, "
      "momentum %.3g\n",
      *r.errors.stress_rel_l2, *r.errors.displacement_rms, r.diag.max_rel_mass_error,
      r.diag.max_rel_momentum_error);
  // The exact top displacement is rho g H^2 / (2 M) = 3.7e-3 m.
  EXPECT_LT(*r.errors.stress_rel_l2, 0.05);
  EXPECT_LT(*r.errors.displacement_rms, 2e-4);
  EXPECT_LT(r.diag.max_rel_mass_error, 1e-12);
}

// The 2D custom problem built from the example: grid, particles, conditions.
TEST(Custom2D, ExampleBuildsTheDeclaredProblem) {
  const Config c = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/custom_plate_2d.toml");
  const auto pb = std::get<Problem<2>>(make_problem(c));
  EXPECT_EQ(pb.grid.cells[0], 4);
  EXPECT_EQ(pb.grid.cells[1], 22);  // grid.cells_y = 0: cells closest to square
  EXPECT_EQ(pb.particles.size(), 4 * 2 * 20 * 2);
  ASSERT_EQ(pb.fixed_sides.size(), 3u);  // two rollers, the fixed bottom; top free
  EXPECT_EQ(pb.fixed_sides[0].components, 1u);
  EXPECT_EQ(pb.fixed_sides[1].components, 1u);
  EXPECT_EQ(pb.fixed_sides[2].direction, 1);
  EXPECT_EQ(pb.fixed_sides[2].side, 0);
  EXPECT_TRUE(pb.body_force.time_dependent);
  EXPECT_FALSE(pb.body_force.position_dependent);
  ASSERT_TRUE(pb.exact);
  const auto e = pb.exact(Vec<2>(0.1, 0.0), 1.0);
  EXPECT_NEAR(e.stress(1, 1), -1000.0 * 10.0 * 1.0, 1e-9);
  EXPECT_NEAR(e.stress(0, 0), -1e4 * 0.3 / 0.7, 1e-9);
}

void expect_input_error(const std::string& toml, const std::vector<std::string>& needles) {
  try {
    const Config c = Config::parse(toml, "case.toml");
    (void)make_problem(c);
    ADD_FAILURE() << "no InputError for\n" << toml;
  } catch (const InputError& e) {
    for (const auto& n : needles)
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
  }
}

constexpr const char* kBase2D = R"toml(benchmark = "custom"
[time]
dt = 1e-4
end = 1e-3
[material]
model = "linear_elastic"
density = 1000.0
youngs_modulus = 1e6
[grid]
dimension = 2
min = [0.0, 0.0]
max = [1.0, 1.0]
[body]
min = [0.2, 0.2]
max = [0.8, 0.8]
)toml";

// A non-finite initial field (issue 16, 12: "1/0" stopped the run at its first step as a
// non-finite stress) is refused at set-up, naming the key and the first bad point.
TEST(Custom2D, NonFiniteInitialFieldsNameTheKeyAndPoint) {
  expect_input_error(kBase2D + std::string("[initial]\nvelocity = [\"0\", \"sqrt(x-0.5)\"]\n"),
                     {"case.toml:17:", "initial.velocity is not finite at (x, y) = (0.2"});
  expect_input_error(
      "benchmark = \"custom\"\n[time]\ndt = 1e-4\nend = 1e-3\n[material]\ndensity = 1000.0\n"
      "youngs_modulus = 1e6\n[initial]\nvelocity = \"1/0\"\n",
      {"case.toml:9:", "initial.velocity = \"1/0\" is not finite at x = ", "(particle 0)"});
  expect_input_error(
      "benchmark = \"custom\"\n[time]\ndt = 1e-4\nend = 1e-3\n[material]\ndensity = 1000.0\n"
      "youngs_modulus = 1e6\nmodel = \"elastic_1d_small\"\n[initial]\nstress = \"sqrt(x-0.5)\"\n",
      {"case.toml:10:", "initial.stress = \"sqrt(x-0.5)\" is not finite at x = "});
}

// An exact solution that is not finite (issue 16, 9: exact.displacement = "0/0" gave null
// errors and status ok) fails the run with exit code 3, naming the norms; a finite one is ok.
TEST(Custom2D, NonFiniteExactSolutionFailsTheRun) {
  const std::string bar = std::string(MPM_SOURCE_DIR) + "/examples/custom_bar.toml";
  RunOptions ro;
  ro.quiet = true;
  const RunResult bad = run(Config::load(bar, {"time.end=1e-4", "exact.displacement=0/0"}), ro);
  EXPECT_EQ(bad.exit_code, exit_code::kNonFinite);
  EXPECT_NE(bad.failure.find("the error norms displacement_rms are not finite"), std::string::npos)
      << bad.failure;
  EXPECT_EQ(bad.summary["status"], "failed");
  EXPECT_EQ(bad.summary["exit_code"], exit_code::kNonFinite);
  const RunResult good = run(Config::load(bar, {"time.end=1e-4", "exact.displacement=0"}), ro);
  EXPECT_EQ(good.exit_code, exit_code::kOk) << good.failure;
  EXPECT_EQ(good.summary["status"], "ok");
}

TEST(Custom2D, VectorKeyErrorsNameFileLineAndKey) {
  const std::string base = kBase2D;
  // Wrong length for the dimension (line 17: the key's line).
  expect_input_error(base + "[loading]\nbody_force = [\"0\", \"-9.81\", \"1\"]\n",
                     {"case.toml:17:", "loading.body_force", "needs 2 expressions", "got 3"});
  // A bad expression in one component.
  expect_input_error(base + "[initial]\nvelocity = [\"0.1*sin(pi*x)\", \"cos((\"]\n",
                     {"case.toml:17:", "initial.velocity", "value 2 of 2", "invalid expression"});
  // A single value in 2D (other than "0") is not broadcast.
  expect_input_error(base + "[loading]\nbody_force = \"-9.81\"\n",
                     {"case.toml:17:", "loading.body_force", "needs 2 expressions", "got 1"});
  // A traction is uniform over its face: a function of t only.
  expect_input_error(kBase2D + std::string("[particles]\nper_cell = 2\n") + "[constants]\nH = 1\n" +
                         "[traction]\ntop = [\"0\", \"-x\"]\n",
                     {"case.toml:21:", "traction.top", "t only"});
  // An array in 1D.
  expect_input_error(
      "benchmark = \"custom\"\n[time]\ndt = 1e-4\nend = 1e-3\n[material]\ndensity = 1000.0\n"
      "youngs_modulus = 1e6\n[loading]\nbody_force = [\"0\", \"1\"]\n",
      {"case.toml:9:", "loading.body_force", "1D"});
  // Wrong element type inside a real array.
  expect_input_error(base + "[exact]\ndisplacement = [\"x\", true]\n",
                     {"case.toml:17:", "exact.displacement", "value 2 of 2"});
  // A 2D-only key in 1D.
  expect_input_error(
      "benchmark = \"custom\"\n[time]\ndt = 1e-4\nend = 1e-3\n[material]\ndensity = 1000.0\n"
      "youngs_modulus = 1e6\n[traction]\ntop = [\"1\"]\n",
      {"case.toml:9:", "traction.top", "grid.dimension = 2"});
}

TEST(Custom2D, ScalarKeysStillReadAsBefore) {
  // 1D files are unchanged: grid.min as a number, expressions as strings.
  const Config c = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/custom_bar.toml");
  EXPECT_EQ(c.get_real("grid.max"), 1.25);
  EXPECT_EQ(c.get_reals("grid.max"), std::vector<double>{1.25});
  EXPECT_EQ(c.get_string("initial.velocity"), "v0*sin(pi*x/(2*L))");
  const std::string text = c.to_toml();
  EXPECT_NE(text.find("max = 1.25"), std::string::npos) << text;
  EXPECT_NE(text.find("velocity = \"v0*sin(pi*x/(2*L))\""), std::string::npos) << text;
  // Arrays round-trip through the written configuration.
  const Config d =
      Config::parse(std::string(kBase2D) + "[loading]\nbody_force = [\"0\", -9.81]\n", "arr.toml");
  EXPECT_EQ(d.get_expressions("loading.body_force"), (std::vector<std::string>{"0", "-9.81"}));
  const Config e = Config::parse(d.to_toml(), "again.toml");
  EXPECT_EQ(e.get_expressions("loading.body_force"), d.get_expressions("loading.body_force"));
  EXPECT_EQ(e.get_reals("grid.max"), (std::vector<double>{1.0, 1.0}));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
