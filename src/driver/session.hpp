#pragma once
// One run under the caller's control: set up, taken step by step or to a step, its particles
// and grid looked at between steps, a prescribed velocity changed, a checkpoint written, then
// finished. run() (driver/run.hpp) is a session taken to its end at once, so a session taken
// to its end writes what `mpm run` writes, byte for byte. The Python module (src/python) drives
// it.
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "core/types.hpp"
#include "driver/run.hpp"
#include "material/materials.hpp"
#include "model/problem.hpp"
#include "particles/particles.hpp"
#include "setup/run_settings.hpp"
#include "state/run_state.hpp"

namespace mpm {

class Config;

// A run's particles, of its dimension.
using ParticlesRef = std::variant<const Particles<1>*, const Particles<2>*, const Particles<3>*>;
// A run's grid state (RunState: the grid, the nodal arrays of the last step, the prescribed
// velocities), of its dimension; null for the updated-Lagrangian FEM, which has no grid.
using RunStateRef = std::variant<RunState<1>*, RunState<2>*, RunState<3>*>;

namespace driver {

// The solver's part of a session: an MPM, OTM or unified run of one dimension, or the
// updated-Lagrangian FEM. One object per run (the per-step work is behind its stepper).
class SolverRun {
 public:
  virtual ~SolverRun() = default;
  // Takes steps until step `to` (at most the last), a failure or a signal; returns running().
  virtual bool advance_to(Index to) = 0;
  virtual bool running() const = 0;
  virtual Index step() const = 0;
  virtual double time() const = 0;
  // Ends the run before its last step (TimeLoop::stop).
  virtual void stop(const std::string& why) = 0;
  // A checkpoint of the state now into the output directory (checkpoint.bin).
  virtual void checkpoint() = 0;
  // The error norms, summary.json; the result. Once.
  virtual RunResult finish() = 0;
  // The result so far (the failure, when the run has stopped).
  virtual const RunResult& result() const = 0;
  virtual ParticlesRef particles() const = 0;
  virtual const Materials& materials() const = 0;
  // Null pointer for the FEM.
  virtual RunStateRef run_state() = 0;
  // The positions of the grid arrays' DOFs, flat (dim values each); empty for the FEM.
  virtual std::vector<double> dof_positions() const = 0;
  // history.csv's columns and the rows kept in memory (RunOptions::keep_history).
  virtual const std::vector<std::string>& history_columns() const = 0;
  virtual const std::vector<double>& history_values() const = 0;
};

class Session {
 public:
  // Sets the run up (input errors throw InputError; nothing is stepped) and writes the initial
  // outputs when opt.out_dir is set.
  Session(const Config& cfg, const RunOptions& opt);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  int dim() const { return dim_; }
  const RunSettings& settings() const { return settings_; }
  // The run's configuration as stored (config.toml).
  const std::string& config_text() const { return config_text_; }
  // The step of time.end (time.end / time.dt), the step and time the state is at.
  Index steps() const { return settings_.time.steps; }
  Index step() const { return solver_->step(); }
  double time() const { return solver_->time(); }
  // Can take another step: not at the last step, not failed, not stopped, not finished.
  bool running() const { return !finished_ && solver_->running(); }
  // Takes steps until step `to` (at most the last) under the run's thread count; false when the
  // run can take no more (its end, a failure: result().failure).
  bool advance_to(Index to);
  // Ends the run before its last step: the state written as an interrupted run's, exit code
  // kInterrupted with `why`. Nothing when the run is not running.
  void stop(const std::string& why);
  // checkpoint.bin of the state now; needs an output directory (InputError otherwise).
  void checkpoint();
  // The error norms and summary.json; a run not at its last step is first stopped ("finished
  // by the caller after step k of n"), so its summary says "interrupted", never "ok". Once.
  RunResult finish();
  bool finished() const { return finished_; }
  const RunResult& result() const { return solver_->result(); }
  SolverRun& solver() { return *solver_; }
  const SolverRun& solver() const { return *solver_; }
  int threads() const { return threads_; }

 private:
  RunOptions opt_;
  AnyProblem problem_;
  RunSettings settings_;
  std::string config_text_;
  int dim_ = 1;
  int threads_ = 1;
  bool finished_ = false;
  std::unique_ptr<SolverRun> solver_;
};

}  // namespace driver
}  // namespace mpm
