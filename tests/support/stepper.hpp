#pragma once
// Tests that take whole steps run the library's compiled steppers (driver/stepper.hpp): the code
// `mpm run` runs, without the test unit instantiating Simulation<Dim, Basis, Mapping> and the
// four schemes again (a scheme's step with every material law was most of a test unit's
// compile time). Tests of single stages or of a mapping's passes still build a Simulation.
#include <algorithm>
#include <exception>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <string>

#include "benchmarks/benchmarks.hpp"
#include "driver/stepper.hpp"
#include "setup/config.hpp"
#include "setup/run_settings.hpp"

namespace mpm::test {

// The BasisKind alternative whose basis template, in Dim dimensions, is Basis.
template <int Dim, class Basis, std::size_t I = 0>
constexpr BasisKind kind_of() {
  static_assert(I < std::variant_size_v<BasisKind>, "no BasisKind alternative has this basis");
  using Kind = std::variant_alternative_t<I, BasisKind>;
  if constexpr (std::is_same_v<typename Kind::template type<Dim>, Basis>)
    return BasisKind(std::in_place_index<I>);
  else
    return kind_of<Dim, Basis, I + 1>();
}

// Every basis kind available in Dim dimensions (and with Mapping), in BasisKind's order.
template <int Dim, class Mapping = DirectMapping>
std::vector<BasisKind> basis_kinds() {
  std::vector<BasisKind> kinds;
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    ((supports_dimension<std::variant_alternative_t<I, BasisKind>>(Dim) &&
              supports_mapping<std::variant_alternative_t<I, BasisKind>, Mapping>()
          ? void(kinds.emplace_back(std::in_place_index<I>))
          : void()),
     ...);
  }
  (std::make_index_sequence<std::variant_size_v<BasisKind>>{});
  return kinds;
}

// What a Simulation built by hand had: the grid, the particles and the law, with the defaults
// of RunState (lumped mass, tolerance 1e-10) unless set; no boundary conditions or loads
// unless given. The stepper re-sorts only when sort_if_due() is called.
template <int Dim>
struct StepperSpec {
  Grid<Dim> grid;
  Particles<Dim> particles;
  Material material;
  BasisKind basis = LinearKind{};
  MappingKind mapping = DirectMapping{};
  Scheme scheme = Musl{};
  MassType mass = MassType::Lumped;
  SortMode sort = SortMode::Auto;
  double mass_tolerance = 1e-10;  // method.mass_tolerance
  std::vector<FixedSide> fixed_sides = {};
  BodyForce<Dim> body_force = {};
  std::vector<Traction<Dim>> tractions = {};
};

template <int Dim>
std::unique_ptr<driver::Stepper<Dim>> compiled_stepper(StepperSpec<Dim> spec) {
  Problem<Dim> pb;
  pb.grid = spec.grid;
  pb.particles = std::move(spec.particles);
  pb.materials = std::move(spec.material);
  pb.fixed_sides = std::move(spec.fixed_sides);
  pb.body_force = std::move(spec.body_force);
  pb.tractions = std::move(spec.tractions);
  MethodSettings method;
  method.basis = spec.basis;
  method.mapping = std::move(spec.mapping);
  method.scheme = spec.scheme;
  method.mass = spec.mass;
  method.sort = spec.sort;
  method.mass_tolerance = spec.mass_tolerance;
  // As a hand-built Simulation: no reconstruction input check before the first step.
  return driver::make_stepper<Dim>(spec.basis, driver::StepperInput<Dim>{pb, method, false});
}

// Steps a problem with the linear basis, the direct mapping, lumped mass and `scheme`, with the
// library's compiled stepper (the step's count and time set after each step, as run() does);
// the particles after `steps` steps.
template <int Dim>
Particles<Dim> step_problem(Problem<Dim> pb, double dt, int steps, Scheme scheme = Musl{}) {
  MethodSettings method;
  method.basis = LinearKind{};
  method.mapping = DirectMapping{};
  method.scheme = scheme;
  auto stepper =
      driver::make_stepper<Dim>(method.basis, driver::StepperInput<Dim>{pb, method, false});
  RunState<Dim>& sim = stepper->state();
  for (int s = 0; s < steps; ++s) {
    stepper->step(dt);
    sim.step = s + 1;
    sim.time = static_cast<double>(sim.step) * dt;
  }
  return sim.particles;
}

// The problem and method of a configuration stepped as `mpm run` steps them (time.dt, the
// step's time and count set as the driver sets them), without output: for tests that look at
// the state between steps. The problem is built here; the stepper holds its particles.
template <int Dim>
struct ConfiguredRun {
  explicit ConfiguredRun(const Config& cfg)
      : problem(std::get<Problem<Dim>>(make_problem(cfg))),
        method(run_settings(cfg, Dim).method),
        dt(cfg.get_real("time.dt")),
        stepper(driver::make_stepper<Dim>(method.basis,
                                          driver::StepperInput<Dim>{problem, method, false})) {}
  RunState<Dim>& state() { return stepper->state(); }
  // `steps` more steps.
  void advance(int steps) {
    RunState<Dim>& sim = state();
    for (int s = 0; s < steps; ++s) {
      sim.time = static_cast<double>(sim.step) * dt;
      stepper->step(dt);
      ++sim.step;
      sim.time = static_cast<double>(sim.step) * dt;
    }
  }
  Problem<Dim> problem;
  MethodSettings method;
  double dt;
  std::unique_ptr<driver::Stepper<Dim>> stepper;
};

// The mapping's run report (summary.json's "tls" or "mls" object; empty for the others).
template <int Dim>
nlohmann::ordered_json mapping_report(const driver::Stepper<Dim>& s) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  s.report(j);
  return j;
}

// A linear velocity field v = A x with zero stress through one step of `stepper` (dt): the
// largest distances of the particles' F from I + dt A and of their positions from
// x0 + dt A x0. A mapping and mass matrix that reproduce linear fields give round-off.
struct LinearFieldErrors {
  double f = 0.0, x = 0.0;
};
template <int Dim>
LinearFieldErrors linear_field_step(driver::Stepper<Dim>& stepper, const Mat<Dim>& A, double dt) {
  auto& P = stepper.state().particles;
  const std::vector<Vec<Dim>> x0(P.x.begin(), P.x.end());
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    P.v[i] = A * P.x[i];
    P.stress[i].setZero();
  }
  stepper.step(dt);
  const Mat<Dim> F = Mat<Dim>::Identity() + dt * A;
  LinearFieldErrors e;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    e.f = std::max(e.f, (P.F[i] - F).norm());
    e.x = std::max(e.x, (P.x[i] - (x0[i] + dt * A * x0[i])).norm());
  }
  return e;
}

// The 2D plate of examples/plate_mms_2d.toml with `sets`, set up as `mpm run` does
// (make_problem, run_settings, the reconstruction input check before the first step).
// `free_sides`: no rollers, and with mms.amplitude = 0 no body force.
struct PlateRun {
  Problem<2> pb;
  RunSettings settings;
  std::unique_ptr<driver::Stepper<2>> stepper;
};
// Any 2D configuration set up the same way; `adjust` may change the problem first.
inline std::unique_ptr<PlateRun> run_2d(const Config& cfg,
                                        const std::function<void(Problem<2>&)>& adjust = {}) {
  auto r = std::make_unique<PlateRun>();
  r->pb = std::get<Problem<2>>(make_problem(cfg));
  if (adjust) adjust(r->pb);
  r->settings = run_settings(cfg, 2);
  r->stepper = driver::make_stepper<2>(r->settings.method.basis,
                                       driver::StepperInput<2>{r->pb, r->settings.method, true});
  return r;
}
inline std::unique_ptr<PlateRun> plate_run(std::vector<std::string> sets, bool free_sides) {
  if (free_sides) sets.push_back("mms.amplitude=0");
  const Config cfg =
      Config::load(std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml", sets);
  return run_2d(cfg, [free_sides](Problem<2>& pb) {
    if (free_sides) pb.fixed_sides.clear();
  });
}

// The message of the exception `f` throws; empty when it throws none.
inline std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace mpm::test
