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
  void frame(const StateView<Dim>& s);
  void summary(const nlohmann::ordered_json& j);

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

// The time loop shared by every solver: `advance(s)` takes step s to s + 1 (timed; may throw
// RunError), `after()` runs untimed companions (the FEM reference), `view()` exposes the state.
// Writes history rows and frames, shows progress, and on a RunError keeps the failing state as
// the last frame and records the failure in `res`. `start`: the step the state is at (non-zero
// after a restart: no initial frame then). `save(step)` writes a checkpoint every
// output.checkpoint_every steps.
template <int Dim, class Advance, class After, class View, class Save>
void drive(const RunSettings& settings, const RunOptions& opt, OutputSession<Dim>& out, Index start,
           Advance&& advance, After&& after, View&& view, Save&& save, RunResult& res) {
  const TimeSettings& ts = settings.time;
  const int frames = settings.output.frames;
  const Index history_every = settings.output.history_every;
  const Index checkpoint_every = settings.output.checkpoint_every;
  if (start > ts.steps)
    throw InputError(
        fmt::format("{}: the checkpoint is at step {}, beyond time.end = {} ({} steps of time.dt)",
                    ts.where_end, start, ts.end, ts.steps));
  Index next_frame = 1;
  auto frame_step = [&](Index k) {
    return frames > 0 ? (k * ts.steps + frames - 1) / frames : ts.steps;
  };
  while (next_frame <= frames && start >= frame_step(next_frame)) ++next_frame;
  Progress progress(!opt.quiet, ts.steps, res.particles, start);
  double step_seconds = 0.0;
  Index step = start;
  try {
    if (start == 0 || !out.history_continues()) out.history_row(view());
    if (start == 0) out.frame(view());
    while (step < ts.steps) {
      const auto t0 = Clock::now();
      advance(step);
      const double seconds = seconds_since(t0);
      step_seconds += seconds;
      if (step == start) res.first_step_seconds = seconds;
      ++step;
      after();
      const bool last = step == ts.steps;
      const bool row = step % history_every == 0 || last;
      const bool frame = last || (frames > 0 && step >= frame_step(next_frame));
      const bool checkpoint = checkpoint_every > 0 && step % checkpoint_every == 0;
      if (row) out.history_row(view());
      if (frame) {
        while (next_frame <= frames && step >= frame_step(next_frame)) ++next_frame;
        out.frame(view());
      }
      if (checkpoint) save(step);
      progress.update(step, view().time);
      int sig = interrupt_signal();
      if (const Comm* comm = out.comm()) {
        // Every rank ends after the same step: a signal that reached any of them ends them all,
        // each recording the signal it was (the highest number if several came).
        comm->check();
        sig = static_cast<int>(comm->max(static_cast<double>(sig)));
      }
      if (sig != 0 && !last) {
        // A signal (core/interrupt.hpp): the state after this step, complete, ends the run: its
        // history row, a frame and, when checkpoints are on, a checkpoint to restart from,
        // each unless this step has written it already.
        res.exit_code = exit_code::kInterrupted;
        res.failure = fmt::format("interrupted by {} after step {} of {} (t = {:.6g} s)",
                                  signal_name(sig), step, ts.steps, view().time);
        if (!row) out.history_row(view());
        if (!frame) out.frame(view());
        if (checkpoint_every > 0 && !checkpoint) save(step);
        break;
      }
    }
  } catch (const RunError& e) {
    res.exit_code = e.exit_code();
    res.failure = e.what();
    // A distributed run: a failure met on this rank is told to the others, which wait for it at
    // their next collective operation (Comm::check); every rank reports the lowest failing one.
    if (const Comm* comm = out.comm(); comm && !dynamic_cast<const RemoteRunError*>(&e)) {
      const Comm::Failure mine{comm->rank(), e.exit_code(), e.what()};
      const Comm::Failure first = *comm->agree(&mine);
      res.exit_code = first.exit_code;
      res.failure = fmt::format("rank {} of {}: {}", first.rank, comm->size(), first.message);
    }
    try {
      out.history_row(view());
      out.frame(view());  // the state the failure was detected in, for diagnosis
    } catch (const RunError&) {
      // An output failing again (a full disk): the failure above is what the summary reports.
    }
  }
  progress.finish();
  res.steps = step;
  const Index taken = step - start;
  res.ns_per_particle_step =
      taken > 0
          ? 1e9 * step_seconds / (static_cast<double>(taken) * static_cast<double>(res.particles))
          : 0.0;
}

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
