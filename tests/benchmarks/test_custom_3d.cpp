// The custom benchmark in 3D (grid.dimension = 3):
// - cube_mms_3d written as a custom problem (rollers on the six faces, initial velocity, body
//   force and exact solution as expressions of x, y, z, t) is the built-in cube: same grid,
//   particles and conditions, body force and exact solution to round-off, and the same particle
//   state after 20 steps;
// - a problem uniform in z with rollers on the z faces (back, front) is the 2D custom problem
//   (plane strain) to round-off, with a traction and a pressure on body faces;
// - a free block under tractions on its faces, one of them a z face, gains exactly the applied
//   impulse; the stress components come in the order xx, yy, zz, yz, xz, xy;
// - examples/custom_3d.toml against its quasi-static solution;
// - input errors: wrong counts name the key and the count, 3D-only keys are refused in 1D and 2D,
//   mesh-file keys and an initial stress in 3D;
// - `mpm bench --dim 3 --problem refkernel`.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "../support/examples.hpp"
#include "../support/stepper.hpp"
#include "../support/threads.hpp"
#include "app/perf.hpp"
#include "benchmarks/benchmarks.hpp"
#include "model/problem.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// A problem set up as `mpm run` does (make_problem, run_settings, the stepper of its method).
template <int Dim>
struct Setup {
  Problem<Dim> pb;
  RunSettings settings;
  std::unique_ptr<driver::Stepper<Dim>> stepper;
};
template <int Dim>
std::unique_ptr<Setup<Dim>> set_up(const Config& cfg,
                                   const std::function<void(Problem<Dim>&)>& adjust = {}) {
  auto r = std::make_unique<Setup<Dim>>();
  r->pb = std::get<Problem<Dim>>(make_problem(cfg));
  if (adjust) adjust(r->pb);
  r->settings = run_settings(cfg, Dim);
  r->stepper = driver::make_stepper<Dim>(
      r->settings.method.basis, driver::StepperInput<Dim>{r->pb, r->settings.method, true});
  return r;
}

// On one thread: these problems are a few hundred particles, below what `mpm run` gives a second
// thread (run_threads), and OpenMP's spinning waits on a busy machine made a step of them take
// milliseconds (3 s per test under ctest -j2 against 25 ms); the thread counts are compared in
// tests/scheme/test_parallel.cpp.
template <int Dim>
void steps(driver::Stepper<Dim>& s, double dt, int n) {
  const test::Threads one(1);
  RunState<Dim>& sim = s.state();
  for (int k = 0; k < n; ++k) {
    s.step(dt);
    sim.step = k + 1;
    sim.time = static_cast<double>(sim.step) * dt;
  }
}

// examples/cube_mms_3d.toml (L = 1 m, A = 0.05 m, E = 1e7 Pa, nu = 0.3, rho0 = 1000 kg/m^3,
// quadratic B-splines, MUSL) as a custom problem. With k = 2 pi / L, w = c pi / L,
// c = sqrt(E / rho0), s = sin(w t): u_i = A sin(k X_i) s, F_ii = 1 + A k cos(k X_i) s, and
// (CubeMms3DExact::body_force) b_i = u_i (k^2 / rho0 ((lam (1 - ln J) + mu) / F_ii^2 + mu) - w^2),
// sigma_ii = lam ln J / J + mu / J (F_ii^2 - 1).
std::string cube_as_custom(int cells) {
  const double E = 1e7, nu = 0.3, rho = 1000.0;
  const double lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu = E / (2.0 * (1.0 + nu));
  const std::string s = "sin(c*pi/L*t)";
  auto u = [&](char q) { return fmt::format("A*sin(2*pi/L*{})*{}", q, s); };
  auto F = [&](char q) { return fmt::format("(1 + A*2*pi/L*cos(2*pi/L*{})*{})", q, s); };
  const std::string J = F('x') + "*" + F('y') + "*" + F('z');
  auto b = [&](char q) {
    return fmt::format("{}*((2*pi/L)^2/rho*((lam*(1 - ln({})) + mu)/{}^2 + mu) - (c*pi/L)^2)", u(q),
                       J, F(q));
  };
  auto sigma = [&](char q) {
    return fmt::format("lam*ln({0})/({0}) + mu/({0})*({1}^2 - 1)", J, F(q));
  };
  std::string t = fmt::format(
      "benchmark = \"custom\"\n[constants]\nA = 0.05\nL = 1.0\nrho = {:.17g}\nc = {:.17g}\n"
      "lam = {:.17g}\nmu = {:.17g}\n"
      "[grid]\ndimension = 3\ncells = {}\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n"
      "[body]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n[particles]\nper_cell = 2\n"
      "[time]\ndt = 1e-4\nend = 0.02\n"
      "[method]\nscheme = \"musl\"\nbasis = \"bspline\"\ndegree = 2\n"
      "[material]\nmodel = \"neo_hookean\"\ndensity = 1000.0\nyoungs_modulus = 1e7\n"
      "poisson_ratio = 0.3\n"
      "[boundary]\nleft = \"roller\"\nright = \"roller\"\nbottom = \"roller\"\ntop = \"roller\"\n"
      "back = \"roller\"\nfront = \"roller\"\n",
      rho, std::sqrt(E / rho), lam, mu, cells);
  t += fmt::format(
      "[initial]\nvelocity = [\"A*c*pi/L*sin(2*pi/L*x)\", \"A*c*pi/L*sin(2*pi/L*y)\", "
      "\"A*c*pi/L*sin(2*pi/L*z)\"]\n");
  t += fmt::format("[loading]\nbody_force = [\"{}\", \"{}\", \"{}\"]\n", b('x'), b('y'), b('z'));
  t += fmt::format("[exact]\ndisplacement = [\"{}\", \"{}\", \"{}\"]\n", u('x'), u('y'), u('z'));
  t += fmt::format(
      "velocity = [\"A*c*pi/L*sin(2*pi/L*x)*cos(c*pi/L*t)\", "
      "\"A*c*pi/L*sin(2*pi/L*y)*cos(c*pi/L*t)\", \"A*c*pi/L*sin(2*pi/L*z)*cos(c*pi/L*t)\"]\n");
  t += fmt::format("stress = [\"{}\", \"{}\", \"{}\", \"0\", \"0\", \"0\"]\n", sigma('x'),
                   sigma('y'), sigma('z'));
  return t;
}

TEST(Custom3D, CubeMmsWrittenAsExpressionsIsTheBuiltInCube) {
  const Config builtin = test::example_config("cube_mms_3d", {"grid.cells=4"});
  const Config custom = Config::parse(cube_as_custom(4), "cube_custom.toml");
  const auto pc = std::get<Problem<3>>(make_problem(builtin));
  const auto pu = std::get<Problem<3>>(make_problem(custom));

  // Grid, particles (same seeding order), conditions.
  EXPECT_EQ(pu.grid.cells, pc.grid.cells);
  EXPECT_EQ(pu.grid.origin, pc.grid.origin);
  EXPECT_EQ(pu.grid.h, pc.grid.h);
  ASSERT_EQ(pu.particles.size(), 4 * 4 * 4 * 8);
  ASSERT_EQ(pu.particles.size(), pc.particles.size());
  double dv0 = 0.0, vmax = 0.0;
  for (std::size_t i = 0; i < pc.particles.x.size(); ++i) {
    ASSERT_EQ(pu.particles.x0[i], pc.particles.x0[i]);
    ASSERT_EQ(pu.particles.volume[i], pc.particles.volume[i]);
    ASSERT_EQ(pu.particles.mass[i], pc.particles.mass[i]);
    dv0 = std::max(dv0, (pu.particles.v[i] - pc.particles.v[i]).norm());
    vmax = std::max(vmax, pc.particles.v[i].norm());
  }
  EXPECT_GT(vmax, 10.0);  // A w = 0.05 * 100 pi m/s at most per component
  EXPECT_LT(dv0, 1e-14 * vmax);
  ASSERT_EQ(pu.fixed_sides.size(), 6u);
  for (std::size_t k = 0; k < 6; ++k) {
    EXPECT_EQ(pu.fixed_sides[k].direction, pc.fixed_sides[k].direction);
    EXPECT_EQ(pu.fixed_sides[k].side, pc.fixed_sides[k].side);
    EXPECT_EQ(pu.fixed_sides[k].components, pc.fixed_sides[k].components);
  }
  EXPECT_TRUE(pu.tractions.empty());

  // The body force expressions at the particles' reference positions (where the built-in
  // evaluates it; the custom problem evaluates it at the current position) and the exact
  // solution, at times over the period T = 0.02 s.
  std::vector<Vec<3>> bc(pc.particles.x.size()), bu(bc.size());
  double db = 0.0, bmax = 0.0, du = 0.0, dv = 0.0, ds = 0.0, smax = 0.0;
  for (double t : {0.0013, 0.0061, 0.0117, 0.0183}) {
    pc.body_force.fill(pc.particles, t, bc);
    pu.body_force.fill(pu.particles, t, bu);
    for (std::size_t i = 0; i < bc.size(); ++i) {
      db = std::max(db, (bu[i] - bc[i]).norm());
      bmax = std::max(bmax, bc[i].norm());
      const Vec<3>& X = pc.particles.x0[i];
      const auto ec = pc.exact(X, t), eu = pu.exact(X, t);
      du = std::max(du, (eu.u - ec.u).norm());
      dv = std::max(dv, (eu.v - ec.v).norm());
      ds = std::max(ds, (eu.stress - ec.stress).norm());
      smax = std::max(smax, ec.stress.norm());
    }
  }
  std::printf(
      "expressions vs built-in: |db| %.3g of %.3g m/s^2, |du| %.3g m, |dv| %.3g m/s, "
      "|dsigma| %.3g of %.3g Pa\n",
      db, bmax, du, dv, ds, smax);
  EXPECT_GT(bmax, 1e4);
  EXPECT_LT(db, 1e-12 * bmax);
  EXPECT_LT(du, 1e-15);
  EXPECT_LT(dv, 1e-13);
  EXPECT_LT(ds, 1e-12 * smax);

  // 20 steps of both. The built-in takes the custom problem's body force (expressions at the
  // current position; the difference from b(X, t) is not round-off but A-sized), so that
  // everything else (seeding, initial velocity, rollers, law, method) is compared.
  const BodyForce<3> force = pu.body_force;
  auto rc = set_up<3>(builtin, [&](Problem<3>& pb) { pb.body_force = force; });
  auto ru = set_up<3>(custom);
  steps(*rc->stepper, 1e-4, 20);
  steps(*ru->stepper, 1e-4, 20);
  const auto& Pc = rc->stepper->state().particles;
  const auto& Pu = ru->stepper->state().particles;
  double dx = 0.0, dvel = 0.0, dsig = 0.0, dF = 0.0, umax = 0.0, sig = 0.0;
  for (std::size_t i = 0; i < Pc.x.size(); ++i) {
    dx = std::max(dx, (Pu.x[i] - Pc.x[i]).norm());
    dvel = std::max(dvel, (Pu.v[i] - Pc.v[i]).norm());
    dsig = std::max(dsig, (Pu.stress[i] - Pc.stress[i]).norm());
    dF = std::max(dF, (Pu.F[i] - Pc.F[i]).norm());
    umax = std::max(umax, Pc.displacement(i).norm());
    sig = std::max(sig, Pc.stress[i].norm());
  }
  std::printf(
      "after 20 steps: |dx| %.3g m (u up to %.3g m), |dv| %.3g m/s, |dF| %.3g, "
      "|dsigma| %.3g of %.3g Pa\n",
      dx, umax, dvel, dF, dsig, sig);
  EXPECT_GT(umax, 1e-3);
  EXPECT_LT(dx, 1e-15);
  EXPECT_LT(dvel, 1e-12 * vmax);
  EXPECT_LT(dF, 1e-13);
  EXPECT_LT(dsig, 1e-12 * sig);
}

// A 2D custom problem (a block on a roller at x = 0 and a fixed base, gravity, a traction on its
// right face, a pressure on its top, an initial velocity) and the same problem extruded over nz
// cells in z with rollers on the z faces: every z layer of 3D particles is the 2D particle set
// (x fastest, then y, then z), and with v_z = 0, b_z = 0 the nodal sums of each z level are the
// 2D sums times one factor for mass, momentum, forces and the face loads alike (each face
// particle's share of the face is its y spacing times its z spacing). So after 60 steps the 3D
// run is the 2D run to round-off: P1 on one cell in z (both z levels on rollers) and quadratic
// B-splines on two (free interior levels).
std::string block(int dim, int nz) {
  const bool d3 = dim == 3;
  const std::string z = d3 ? ", \"0\"" : "";
  return fmt::format(
      "benchmark = \"custom\"\n[constants]\np0 = 2e4\nq0 = 5e3\nT0 = 3e-3\n"
      "[grid]\ndimension = {0}\ncells = 10\n{1}min = [0, 0{2}]\nmax = [1, 1{3}]\n"
      "[body]\nmin = [0, 0{2}]\nmax = [0.55, 0.65{3}]\n[particles]\nper_cell = 2\n"
      "[time]\ndt = 1e-4\nend = 6e-3\n"
      "[material]\nmodel = \"neo_hookean\"\ndensity = 1000.0\nyoungs_modulus = 1e6\n"
      "poisson_ratio = 0.3\n"
      "[initial]\nvelocity = [\"0.5*sin(pi*x)*y\", \"-0.3*x*y\"{4}]\n"
      "[loading]\nbody_force = [\"0\", \"-9.81*(1 + x)\"{4}]\n"
      "[boundary]\nleft = \"roller\"\nright = \"free\"\nbottom = \"fixed\"\ntop = \"free\"\n{5}"
      "[traction]\nright = [\"-p0*min(t/T0, 1)\", \"q0\"{4}]\n"
      "[pressure]\ntop = \"q0*min(t/T0, 1)\"\n",
      dim, d3 ? fmt::format("cells_z = {}\n", nz) : "", d3 ? ", 0" : "",
      d3 ? fmt::format(", {}", 0.1 * nz) : "", z,
      d3 ? "back = \"roller\"\nfront = \"roller\"\n" : "");
}

TEST(Custom3D, UniformInZWithRollersIsThe2DProblem) {
  struct Case {
    const char* basis;
    int nz;
  };
  for (const Case& c : {Case{"linear", 1}, Case{"bspline", 2}}) {
    SCOPED_TRACE(c.basis);
    const std::string method = fmt::format("[method]\nbasis = \"{}\"\n", c.basis);
    auto r2 = set_up<2>(Config::parse(block(2, 0) + method, "block2d.toml"));
    auto r3 = set_up<3>(Config::parse(block(3, c.nz) + method, "block3d.toml"));
    ASSERT_EQ(r3->pb.grid.cells, (IVec<3>{10, 10, c.nz}));
    ASSERT_EQ(r2->pb.tractions.size(), 2u);
    ASSERT_EQ(r3->pb.tractions.size(), 2u);
    ASSERT_EQ(r3->pb.fixed_sides.size(), 4u);  // left, bottom, back, front
    const auto& P2 = r2->stepper->state().particles;
    const auto& P3 = r3->stepper->state().particles;
    const std::size_t n2 = P2.x.size();
    ASSERT_EQ(n2, 11u * 13u);  // 2 per cell width 0.1 m: 0.55 / 0.05 by 0.65 / 0.05
    ASSERT_EQ(P3.x.size(), n2 * 2 * static_cast<std::size_t>(c.nz));
    for (std::size_t i = 0; i < P3.x.size(); ++i) ASSERT_EQ(P3.x0[i].head<2>(), P2.x0[i % n2]);

    steps(*r2->stepper, 1e-4, 60);
    steps(*r3->stepper, 1e-4, 60);
    double vmax = 0.0, smax = 0.0, umax = 0.0, dx = 0.0, dv = 0.0, vz = 0.0, ds = 0.0, dF = 0.0;
    for (std::size_t q = 0; q < n2; ++q) {
      vmax = std::max(vmax, P2.v[q].norm());
      smax = std::max(smax, P2.stress[q].norm());
      umax = std::max(umax, P2.displacement(q).norm());
    }
    for (std::size_t i = 0; i < P3.x.size(); ++i) {
      const std::size_t q = i % n2;
      dx = std::max(dx, (P3.x[i].head<2>() - P2.x[q]).norm());
      dv = std::max(dv, (P3.v[i].head<2>() - P2.v[q]).norm());
      vz = std::max(vz, std::abs(P3.v[i][2]));
      ds = std::max(ds, (P3.stress[i].topLeftCorner<2, 2>() - P2.stress[q]).norm());
      dF = std::max(dF, std::abs(P3.F[i](2, 2) - 1.0) + P3.F[i].col(2).head<2>().norm() +
                            P3.F[i].row(2).head<2>().norm());
    }
    std::printf(
        "%s: |dx| %.3g m (u up to %.3g m), |dv| %.3g of %.3g m/s, v_z %.3g, |dsigma| "
        "%.3g of %.3g Pa, F out of plane %.3g\n",
        c.basis, dx, umax, dv, vmax, vz, ds, smax, dF);
    EXPECT_GT(umax, 1e-3);  // m: the block deforms
    EXPECT_LT(dx, 1e-14);
    EXPECT_LT(dv, 1e-12 * vmax);
    EXPECT_LT(vz, 1e-12 * vmax);
    EXPECT_LT(ds, 1e-11 * smax);
    EXPECT_LT(dF, 1e-13);
  }
}

// A free block (all six sides free, faces mid-cell) under a ramped traction on its right face,
// a constant one on its top face and a pressure on its front face (z = body.max): the total
// momentum gains exactly the applied impulse sum_s tau(t_s) A dt, the reference face areas
// 0.4 x 0.3 (right), 0.5 x 0.3 (top) and 0.5 x 0.4 (front).
TEST(Custom3D, FreeBlockGainsExactlyTheAppliedImpulse) {
  const Config c = Config::parse(R"toml(
benchmark = "custom"
[constants]
p0 = 2000.0
q0 = 500.0
T0 = 0.01
[grid]
dimension = 3
cells = 10
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[body]
min = [0.25, 0.25, 0.35]
max = [0.75, 0.65, 0.65]
[particles]
per_cell = 2
[time]
dt = 1e-4
end = 0.01
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
back = "free"
front = "free"
[traction]
right = ["p0*min(t/T0, 1)", "-q0", "q0"]
top = ["q0", "p0", "0"]
[pressure]
front = "3*q0*min(t/T0, 1)"
)toml",
                                 "block3d.toml");
  auto r = set_up<3>(c);
  ASSERT_EQ(r->pb.tractions.size(), 3u);  // right, top, front (x, y, z order)
  EXPECT_EQ(r->pb.tractions[2].direction, 2);
  EXPECT_EQ(r->pb.tractions[2].side, 1);
  EXPECT_EQ(r->pb.tractions[2].value(0.02), Vec<3>(0.0, 0.0, -1500.0));  // -p n, n = +e_z
  double front = 0.0;
  for (double a : r->pb.tractions[2].area) front += a;
  EXPECT_NEAR(front, 0.5 * 0.4, 1e-15);
  // 50 steps, halfway up the ramp (100 took 17 s under the sanitizers; the impulse is exact at
  // every step, ramped or not).
  const double dt = 1e-4;
  const int n = 50;
  steps(*r->stepper, dt, n);
  Vec<3> impulse = Vec<3>::Zero();
  for (int s = 0; s < n; ++s) {
    const double ramp = std::min(s * dt / 0.01, 1.0);
    impulse += dt * (0.4 * 0.3 * Vec<3>(2000.0 * ramp, -500.0, 500.0) +
                     0.5 * 0.3 * Vec<3>(500.0, 2000.0, 0.0) +
                     0.5 * 0.4 * Vec<3>(0.0, 0.0, -1500.0 * ramp));
  }
  const auto& P = r->stepper->state().particles;
  Vec<3> momentum = Vec<3>::Zero();
  for (std::size_t i = 0; i < P.x.size(); ++i) momentum += P.mass[i] * P.v[i];
  const double rel = (momentum - impulse).norm() / impulse.norm();
  std::printf(
      "momentum (%.15g, %.15g, %.15g) N s, impulse (%.15g, %.15g, %.15g) N s, "
      "relative %.3g\n",
      momentum[0], momentum[1], momentum[2], impulse[0], impulse[1], impulse[2], rel);
  EXPECT_LT(rel, 1e-12);
}

// initial.stress and exact.stress list [xx, yy, zz, yz, xz, xy]; the expressions get x, y, z, t.
TEST(Custom3D, ComponentsAndCoordinatesInTheirOrder) {
  const Config c = Config::parse(R"toml(
benchmark = "custom"
[grid]
dimension = 3
cells = 2
min = [0, 0, 0]
max = [1, 1, 1]
[body]
min = [0, 0, 0]
max = [1, 1, 1]
[time]
dt = 1e-4
end = 1e-3
[material]
model = "linear_elastic"
density = 1000.0
youngs_modulus = 1e6
[initial]
velocity = ["x", "2*y", "3*z"]
[exact]
displacement = ["x + t", "y", "z"]
stress = ["1", "2", "3", "4", "5", "6*z + t"]
)toml",
                                 "order.toml");
  const auto pb = std::get<Problem<3>>(make_problem(c));
  EXPECT_EQ(pb.grid.cells, (IVec<3>{2, 2, 2}));    // cells_y, cells_z = 0: cubic cells
  EXPECT_EQ(pb.particles.size(), 2 * 2 * 2 * 64);  // per_cell 4 per direction (default)
  EXPECT_EQ(pb.fixed_sides.size(), 6u);            // boundary.* default "fixed"
  const Vec<3> X(0.1, 0.2, 0.7);
  EXPECT_EQ(pb.initial_velocity(X), Vec<3>(0.1, 2 * 0.2, 3 * 0.7));
  const auto e = pb.exact(X, 0.5);
  EXPECT_EQ(e.u, Vec<3>(0.1 + 0.5, 0.2, 0.7));
  const double xy = 6 * 0.7 + 0.5;
  Mat<3> s;
  s << 1.0, xy, 5.0, xy, 2.0, 4.0, 5.0, 4.0, 3.0;
  EXPECT_EQ(e.stress, s);
  EXPECT_EQ(e.v, Vec<3>::Zero());  // exact.velocity left "0"
  for (std::size_t i = 0; i < pb.particles.x.size(); ++i)
    ASSERT_EQ(pb.particles.v[i], pb.initial_velocity(pb.particles.x0[i]));
}

// examples/custom_3d.toml: a column with rollers on its four sides and a fixed base, under
// gravity and a pressure on its top face ramped over T = 1 s, against its quasi-static solution
// (exact.* keys) at T.
TEST(Custom3D, ExampleColumnMatchesTheQuasiStaticSolution) {
  const RunResult r = test::run_example_ok("custom_3d", {"output.csv=false", "output.vtk=false"});
  EXPECT_EQ(r.dim, 3);
  EXPECT_EQ(r.particles, 2 * 2 * 10 * 8);
  ASSERT_TRUE(r.errors.stress_rel_l2 && r.errors.displacement_rms);
  std::printf("column: stress rel L2 %.4g, displacement RMS %.4g m, mass %.3g, momentum %.3g\n",
              *r.errors.stress_rel_l2, *r.errors.displacement_rms, r.diag.max_rel_mass_error,
              r.diag.max_rel_momentum_error);
  // The exact top displacement is (rho g H^2 / 2 + p H) / M = 7.4e-3 m.
  EXPECT_LT(*r.errors.stress_rel_l2, 0.05);
  EXPECT_LT(*r.errors.displacement_rms, 2e-4);
  EXPECT_LT(r.diag.max_rel_mass_error, 1e-12);
}

void expect_input_error(const std::string& toml, const std::vector<std::string>& needles) {
  const std::string m = test::message_of([&] {
    const Config c = Config::parse(toml, "case.toml");
    (void)make_problem(c);
  });
  EXPECT_FALSE(m.empty()) << "no error for\n" << toml;
  for (const auto& n : needles) EXPECT_NE(m.find(n), std::string::npos) << m;
}

// Lines 1-16; a key added after it is on line 17.
constexpr const char* kBase3D = R"toml(benchmark = "custom"
[time]
dt = 1e-4
end = 1e-3
[material]
model = "linear_elastic"
density = 1000.0
youngs_modulus = 1e6
[grid]
dimension = 3
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
cells = 4
[body]
min = [0.2, 0.2, 0.2]
max = [0.8, 0.8, 0.8]
)toml";

TEST(Custom3D, InputErrorsNameTheKeyAndTheCount) {
  const std::string base = kBase3D;
  expect_input_error(base + "[loading]\nbody_force = [\"0\", \"-9.81\"]\n",
                     {"case.toml:18:", "loading.body_force", "needs 3 expressions (x, y, z)",
                      "grid.dimension = 3", "got 2"});
  expect_input_error(
      base + "[initial]\nstress = [\"1\", \"2\", \"3\"]\n",
      {"case.toml:18:", "initial.stress", "needs 6 expressions (xx, yy, zz, yz, xz, xy)", "got 3"});
  expect_input_error(base + "[exact]\nvelocity = [\"1\", \"2\", \"3\", \"4\"]\n",
                     {"case.toml:18:", "exact.velocity", "needs 3 expressions", "got 4"});
  expect_input_error(base + "[traction]\nfront = [\"1\", \"2\"]\n",
                     {"case.toml:18:", "traction.front", "needs 3 expressions", "got 2"});
  expect_input_error(base + "[traction]\nback = [\"0\", \"0\", \"z\"]\n",
                     {"case.toml:18:", "traction.back", "t only"});
  // grid.min is on line 11.
  std::string two = base;
  two.replace(two.find("min = [0.0, 0.0, 0.0]"), 21, "min = [0.0, 0.0]");
  expect_input_error(two, {"case.toml:11:", "grid.min",
                           "needs 3 values (one per direction, x, "
                           "y, z)",
                           "got 2"});
  // Extents in z.
  std::string flat = base;
  flat.replace(flat.find("max = [0.8, 0.8, 0.8]"), 21, "max = [0.8, 0.8, 0.1]");
  expect_input_error(flat, {"case.toml:16:", "body.max = 0.1 must exceed body.min = 0.2 in z"});
  // No 3D law is incremental: an initial stress is refused.
  expect_input_error(base + "[initial]\nstress = [\"0\", \"0\", \"0\", \"1e3\", \"0\", \"0\"]\n",
                     {"case.toml:18:", "initial.stress", "needs an incremental law (von_mises"});
  // Mesh-file keys are 2D.
  expect_input_error(base + "[boundary]\nroller = \"wall\"\n",
                     {"case.toml:18:", "boundary.roller", "2D mesh file",
                      "boundary.left, right, "
                      "bottom, top, back, "
                      "front"});
  expect_input_error(base + "[pressure]\nloaded = \"1\"\n",
                     {"case.toml:18:", "pressure.loaded", "traction.left ... front"});
}

TEST(Custom3D, ThreeDimensionalKeysAreRefusedIn1DAnd2D) {
  const std::string two = R"toml(benchmark = "custom"
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
)toml";
  expect_input_error(two + "cells_z = 4\n",
                     {"case.toml:13:", "grid.cells_z", "3D custom problem only",
                      "grid.dimension = 3", "this one is 2D"});
  expect_input_error(two + "[boundary]\nfront = \"free\"\n",
                     {"case.toml:14:", "boundary.front", "3D custom problem only"});
  expect_input_error(two + "[boundary]\nback = \"roller\"\n",
                     {"case.toml:14:", "boundary.back", "3D custom problem only"});
  expect_input_error(two + "[traction]\nback = [\"1\", \"0\"]\n",
                     {"case.toml:14:", "traction.back", "3D custom problem only"});
  expect_input_error(two + "[pressure]\nfront = \"1\"\n",
                     {"case.toml:14:", "pressure.front", "3D custom problem only"});
  const std::string one =
      "benchmark = \"custom\"\n[time]\ndt = 1e-4\nend = 1e-3\n[material]\ndensity = 1000.0\n"
      "youngs_modulus = 1e6\n";
  expect_input_error(one + "[grid]\ncells_z = 2\n",
                     {"case.toml:9:", "grid.cells_z", "3D custom problem only", "this one is 1D"});
  expect_input_error(one + "[pressure]\nback = \"1\"\n",
                     {"case.toml:9:", "pressure.back", "3D custom problem only"});
  expect_input_error(one + "[grid]\ncells_y = 2\n",
                     {"case.toml:9:", "grid.cells_y", "a 2D or 3D custom problem only",
                      "grid.dimension = 2 or 3"});
  // The defaults pass (as in a restarted run's stored configuration, which holds every key).
  EXPECT_NO_THROW((void)make_problem(
      Config::parse(two + "cells_z = 0\n[body]\nmin = [0.2, 0.2]\nmax = [0.8, "
                          "0.8]\n[boundary]\nback = \"fixed\"\nfront = \"fixed\"\n[traction]\n"
                          "back = \"0\"\n[pressure]\nfront = \"0\"\n",
                    "defaults.toml")));
}

// `mpm bench --dim 3 --problem refkernel`: n^3 cells of the unit cube in a grid padded by two
// cells per side (n + 4 per direction), 2 x 2 x 2 particles per cell, free sides, no body force;
// the cube stays the default problem.
TEST(Custom3D, BenchRunsTheRefkernelProblem) {
  BenchOptions opt;
  opt.dim = 3;
  opt.particles = 4000;
  opt.steps = 2;
  opt.repeats = 1;
  opt.basis = "bspline";
  opt.degree = 2;
  opt.threads = 1;
  EXPECT_EQ(opt.problem, "plate");
  const BenchResult cube = bench_3d(opt);
  opt.problem = "refkernel";
  const BenchResult r = bench_3d(opt);
  EXPECT_EQ(r.cells, 8);  // round(cbrt(4000) / 2)
  EXPECT_EQ(r.particles, 8 * 8 * 8 * 8);
  EXPECT_EQ(r.steps, 2);
  EXPECT_GT(r.best_ns_per_particle_step, 0.0);
  // The padded grid's share: (8 + 4 + 2)^3 quadratic B-spline DOFs against the cube's
  // (8 + 2)^3, over the same particles.
  EXPECT_EQ(cube.particles, r.particles);
  EXPECT_GT(r.bytes_per_particle, cube.bytes_per_particle);
  EXPECT_GT(r.sort_bytes_per_particle, cube.sort_bytes_per_particle);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
