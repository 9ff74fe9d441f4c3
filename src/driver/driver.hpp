#pragma once
// The parts of `mpm run` that do not depend on the basis, mapping or scheme, compiled once per
// dimension (driver.cpp): the time set-up, the time loop, the output session, error norms, the
// stability check and summary.json. The steppers (driver/stepper.hpp) are the only typed part.
#include <unistd.h>

#include <csignal>

#include <fmt/format.h>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/interrupt.hpp"
#include "driver/run.hpp"
#include "io/output.hpp"
#include "methods/ulfem.hpp"
#include "model/problem.hpp"
#include "setup/run_settings.hpp"
#include "state/simulation.hpp"

namespace mpm::io {
struct Checkpoint;
}  // namespace mpm::io

namespace mpm::driver {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Terminal progress for runs longer than a second: steps, simulated time, rate, time left.
class Progress {
 public:
  Progress(bool enabled, Index total, Index particles, Index start = 0)
      : enabled_(enabled),
        total_(total),
        particles_(particles),
        start_step_(start),
        tty_(isatty(STDERR_FILENO)) {}
  void update(Index step, double t) {
    if (!enabled_) return;
    const double el = seconds_since(start_);
    if (el < 1.0 || el - last_ < (tty_ ? 0.25 : 10.0)) return;
    last_ = el;
    const double rate = static_cast<double>(step - start_step_) / el;
    const double left = rate > 0 ? static_cast<double>(total_ - step) / rate : 0.0;
    std::cerr << fmt::format("{}step {}/{}  t = {:.4g} s  {:.3g} particle-steps/s  {:.0f} s left{}",
                             tty_ ? "\r" : "", step, total_, t,
                             rate * static_cast<double>(particles_), left, tty_ ? "   " : "\n");
    shown_ = true;
  }
  void finish() {
    if (shown_ && tty_) std::cerr << "\n";
  }

 private:
  bool enabled_;
  Index total_, particles_, start_step_;
  bool tty_;
  Clock::time_point start_ = Clock::now();
  double last_ = 0.0;
  bool shown_ = false;
};

// Error norms at the particles (D eq. 4.92; 001 eq. 43 in 2D, |.| the Euclidean or Frobenius
// norm). The interior norms leave out the particles whose initial position lies in the first or
// last `boundary_cells` grid cells occupied by the body in any direction, where boundary effects of
// some bases concentrate (D Fig. 5.10): one cell for nodal bases, p cells for B-splines of degree
// p, whose asymmetric end functions phi_0 .. phi_{p-1} of the open knot vector reach p cells into
// the domain.
// comm: a distributed run's processes, each passing its particles (the sums are over all of
// them, collective), or null.
template <int Dim>
ErrorNorms error_norms(const Particles<Dim>& P, const Grid<Dim>& grid,
                       const ExactSolution<Dim>& exact, double t, double dt, double velocity_time,
                       int boundary_cells, const Comm* comm = nullptr);

inline nlohmann::ordered_json opt_json(const std::optional<double>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}

// What the time loop sees of a solver's state: the particles (MPM) or element midpoints (FEM)
// with the time and the materials, for history rows and frames.
template <int Dim>
struct StateView {
  const Particles<Dim>& particles;
  double time;
  const Materials& materials;
  // The MPM mapping's conservation errors (history.csv columns); null for other solvers.
  const Diagnostics* diag = nullptr;
};

// Everything written into the output directory during a run. In a distributed run
// (RunOptions::comm) every process takes part in each history row, frame and checkpoint (all
// collective): rank 0 writes the history, the summary and the series; each process writes its
// VTU piece, its rows of the CSV frame (one file, in id order, through MPI-IO) and its
// checkpoint piece, so that no process gathers the body. The files are those of a run on one
// process, but for the pieces.
template <int Dim>
class OutputSession {
 public:
  // config_text: Config::to_toml() of the run (config.toml).
  OutputSession(const RunOptions& opt, const RunSettings& s, const std::string& config_text,
                const Problem<Dim>& pb);
  bool enabled() const { return !dir_.empty(); }
  // The processes of a distributed run, or null.
  const Comm* comm() const { return comm_; }
  void history_row(const StateView<Dim>& s);
  // history.csv's columns, and the rows kept in memory (RunOptions::keep_history), with or
  // without an output directory: its values row after row.
  const std::vector<std::string>& history_columns() const { return history_columns_; }
  const std::vector<double>& history_values() const { return history_values_; }
  void frame(const StateView<Dim>& s);
  void summary(const nlohmann::ordered_json& j);
  // Ends the session's hold on the directory (its lock), once the summary is written: the
  // process may start another run into it (a Python session's next run).
  void close() { lock_ = io::DirectoryLock(); }

  // Checkpoints: the frames written so far, and continuing after a restart (numbering goes on;
  // particles.pvd lists the earlier frames again, history.csv keeps its rows before the
  // checkpoint and goes on).
  int frames() const { return frames_; }
  const std::vector<double>& frame_times() const { return frame_times_; }
  void resume(const io::Checkpoint& c);
  // After resume(): history.csv holds the earlier run's rows up to the checkpoint, its own row
  // included (the restart then writes no row for the step it starts from).
  bool history_continues() const { return history_continues_; }
  // Writes checkpoint.bin. A distributed run (collective): `piece` is this process's share
  // (io::encode_piece), which it writes itself; rank 0 then writes `c` as their manifest
  // (filling c.pieces).
  void checkpoint(io::Checkpoint& c, const std::string* piece = nullptr);

 private:
  std::filesystem::path dir_;
  const Comm* comm_ = nullptr;
  bool writer_ = true;      // this process writes the files (rank 0)
  io::DirectoryLock lock_;  // one run at a time in dir_
  ExactSolution<Dim> exact_;
  bool csv_ = true, vtk_ = true, vtk_binary_ = true;
  std::string history_header_;
  io::AppendFile history_;            // history.csv
  bool mapping_errors_ = false;       // history.csv has mass_error, momentum_error
  std::size_t reaction_columns_ = 0;  // history.csv's reaction_* columns (output.reactions)
  bool history_continues_ = false;
  bool keep_history_ = false;
  std::vector<std::string> history_columns_;
  std::vector<double> history_values_;
  io::PvdSeries pvd_;
  // A distributed run's CSV frame: every process writes rows of it into the one file, in
  // rounds over the ids (collective; driver.cpp).
  void write_distributed_csv(const std::filesystem::path& path, const Particles<Dim>& P,
                             const Materials& materials, double time);
  Index root_pid_ = -1;     // rank 0's process id (the frame's temporary name), once known
  Index history_rows_ = 0;  // rows of history.csv below its header
  // Runs a write that some processes make and others do not (rank 0's history row, series,
  // summary and manifest; each process's own piece) and agrees its failure at once: every
  // process then throws the same RemoteRunError (the lowest failing rank's exit code and
  // message), so that none goes on to a collective call the failed one never makes. One
  // process: the write alone.
  template <class Write>
  void agreed(Write&& write) const;
  int frames_ = 0;
  std::vector<double> frame_times_;
};

// Stops before the first step when time.dt exceeds the limit factor h / (c sqrt(dim)), unless
// time.allow_unstable; `what` names the basis and bound in the message.
// c is the largest wave speed of the materials.
void check_stability(const TimeSettings& time, double h, const Materials& materials, double factor,
                     int dim, std::string_view what);

// The time loop shared by every solver, resumable: the caller takes it to a step, looks at the
// state, and goes on (driver/session.hpp; run() takes it to the end at once). Its hooks:
// `advance(s)` takes step s to s + 1 (timed; may throw RunError), `after()` runs untimed
// companions (the FEM reference), `view()` exposes the state, `save(step)` writes a checkpoint
// (every output.checkpoint_every steps). It writes history rows and frames, shows progress, and
// on a RunError keeps the failing state as the last frame and records the failure in `res`.
// `start`: the step the state is at (non-zero after a restart: no initial frame then).
template <int Dim>
class TimeLoop {
 public:
  struct Hooks {
    std::function<void(Index)> advance;
    std::function<void()> after;
    std::function<StateView<Dim>()> view;
    std::function<void(Index)> save;
  };
  // Writes the initial history row and frame.
  TimeLoop(const RunSettings& settings, const RunOptions& opt, OutputSession<Dim>& out, Index start,
           Hooks hooks, RunResult& res);
  // Takes steps until step `to` (at most the last), a failure or a signal; returns running().
  bool advance_to(Index to);
  // Not at the last step, not failed, not interrupted.
  bool running() const { return !stopped_ && step_ < settings_.time.steps; }
  Index step() const { return step_; }
  Index start() const { return start_; }
  // Ends a run before its last step, at the caller's request: as a signal does (the state after
  // the step is complete: its history row, a frame and, with checkpoints on, a checkpoint, each
  // unless this step has written it), with exit code kInterrupted and `why` as the failure.
  void stop(const std::string& why);
  // The step counts and timing into `res` (steps, ns_per_particle_step); the progress line ends.
  void finish();
  // A checkpoint of the state now (the caller's; needs an output directory and
  // output.checkpoint_every or not).
  void checkpoint() { hooks_.save(step_); }

 private:
  Index frame_step(Index k) const;
  void fail(const RunError& e);
  // A row, frame and checkpoint of the step just taken, unless written (the end of a stop).
  void write_final_state();
  const RunSettings& settings_;
  OutputSession<Dim>& out_;
  Hooks hooks_;
  RunResult& res_;
  Progress progress_;
  Index start_ = 0, step_ = 0, next_frame_ = 1;
  double step_seconds_ = 0.0;
  bool stopped_ = false;
  // What the last step wrote (the end of a stop writes what is missing).
  bool wrote_row_ = true, wrote_frame_ = true, wrote_checkpoint_ = true;
};

// A run whose error norms against the exact solution are not finite (the exact solution is
// not finite at some particle, e.g. exact.displacement = "0/0") has no result to report: its
// status becomes failed with exit_code::kNonFinite, naming the norms.
void check_error_norms(RunResult& res);

// The fields of summary.json common to every solver; `method` describes the solver.
nlohmann::ordered_json make_summary(const RunResult& res, const RunSettings& settings,
                                    const Materials& materials, double t_end,
                                    nlohmann::ordered_json method, double velocity_time);

// Stress errors of the particles against the FEM reference at their material positions
// (D 5.4.1: the large-deformation bar is compared with ULFEM, 120 DOFs).
void reference_errors(const Particles<1>& P, const Ulfem1D& ref, ErrorNorms& e);

}  // namespace mpm::driver
