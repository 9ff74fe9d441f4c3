#pragma once
// The typed part of an MPM run, behind one per-run interface: a Stepper owns the
// Simulation<Dim, Basis, Mapping> and takes it one step with the chosen scheme. Everything
// per step or per run around it (time loop, outputs, summary, checkpoints, error norms) is the
// driver's (driver/run_mpm.cpp), compiled once per dimension.
//
// What stays compile-time, and why: the basis and the mapping are in every per-particle loop
// (stencil size, weights, the mapping's scatters and fits), so each (dimension, basis, mapping)
// is its own Simulation type. The scheme is an order of stage calls made once per step: a
// std::visit per step costs nothing measurable (alternated runs of both dispatches), so it is a
// run-time choice inside the stepper and adds no driver instances. The steppers of one
// (dimension, basis kind) are instantiated in one generated translation unit
// (driver/stepper_kind.cpp.in, CMakeLists.txt), so a 2-core build compiles them in parallel and
// an edit to one basis rebuilds only that basis's units.
#include <cstddef>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <variant>
#include <vector>

#include "methods/kinds.hpp"
#include "model/problem.hpp"
#include "setup/run_settings.hpp"
#include "state/simulation.hpp"

namespace mpm {

namespace io {
struct Checkpoint;
}

namespace driver {

template <int Dim>
class Stepper {
 public:
  virtual ~Stepper() = default;
  // Takes the state from step s to s + 1 with the scheme (may throw RunError). The driver sets
  // the step counter and the time afterwards.
  virtual void step(double dt) = 0;
  // Re-sorts the particles by cell if due (state/sort.hpp); true when it did.
  virtual bool sort_if_due() = 0;
  // The basis- and mapping-independent state (particles, grid, time, diagnostics).
  virtual RunState<Dim>& state() = 0;
  virtual const RunState<Dim>& state() const = 0;
  // The state a checkpoint needs beyond the RunState: the mapping's run-long counters and the
  // basis's per-particle state (CPDI2 corners). load() throws InputError naming `what`.
  virtual void save(io::Checkpoint& c) const = 0;
  virtual void load(const io::Checkpoint& c, const std::string& what) = 0;
  // The mapping's report over the run (TLS completions, MLS conditioning) into summary.json.
  virtual void report(nlohmann::ordered_json& summary) const = 0;
  // Before particles travel between processes (a distributed run's migration or checkpoint):
  // the basis's per-particle state (CPDI2's corners) into state().carried, which moves with
  // them (parallel/distribution.hpp). Nothing for the other bases.
  virtual void export_carried() = 0;
  // After particles have arrived or left (a distributed run's migration,
  // parallel/distribution.hpp): sizes the per-particle caches to the particles (the next step's
  // evaluate_basis fills them) and gives the basis its carried state back.
  virtual void resize_particle_caches() = 0;
  // The positions of the basis's degrees of freedom now [m], in the order of the grid arrays
  // (RunState::nodes): the grid nodes, a B-spline's Greville abscissae, a mesh's vertices, the
  // Powell-Sabin control points; OTM's and the unified solver's moving nodes.
  virtual std::vector<Vec<Dim>> dof_positions() const = 0;
};

// What a stepper is built from: the problem (its particles are moved into the stepper) and the
// method settings (the mapping alternative holds the configured mapping). `check_input`: run
// the reconstruction's input checks on the initial particles (not on a restart).
template <int Dim>
struct StepperInput {
  Problem<Dim>& problem;
  const MethodSettings& method;
  bool check_input = true;
  // A distributed run's processes (the problem then holds this rank's particles), or null.
  const Comm* comm = nullptr;
};

// The stepper of basis kind `basis` (and the input's mapping and scheme) in Dim dimensions.
// The caller has checked that basis and mapping exist in Dim (supports_dimension).
template <int Dim>
std::unique_ptr<Stepper<Dim>> make_stepper(const BasisKind& basis, const StepperInput<Dim>& in);

// Whether this build compiled the stepper unit of basis kind `kind` (its index in BasisKind) in
// `dim` dimensions: every kind of the dimension unless CMake's MPM_STEPPERS_1D/2D/3D left it out
// (make_stepper then refuses it with an input error naming those options).
bool stepper_compiled(int dim, std::size_t kind);

// method.solver = "otm" or "unified": the stepper of methods/otm.hpp with the basis kind's
// functions on the advected nodes (OTM: linear or max-ent; unified: B-splines; run_settings has
// checked). 1D only (logic_error in 2D, which run_settings refuses).
template <int Dim>
std::unique_ptr<Stepper<Dim>> make_otm_stepper(const StepperInput<Dim>& in);

// The stepper of the I-th basis kind of BasisKind: defined in stepper_impl.hpp and instantiated
// in the generated unit of (Dim, I).
template <int Dim, std::size_t I>
std::unique_ptr<Stepper<Dim>> make_stepper_for(const StepperInput<Dim>& in);

// The mapping's report over the run into summary.json: how often the TLS completions were
// needed (D 5.2.3), where MLS moment matrices were ill-conditioned or IMLS dropped terms (001,
// 003); nothing for the other mappings. Out of line (stepper.cpp), so that the steppers' units
// do not compile the JSON library.
void report_mapping(nlohmann::ordered_json& summary, const TlsMapping& m, int dim);
void report_mapping(nlohmann::ordered_json& summary, const MlsFamilyMapping& m, int dim);
template <class Mapping>
void report_mapping(nlohmann::ordered_json&, const Mapping&, int) {}

}  // namespace driver
}  // namespace mpm
