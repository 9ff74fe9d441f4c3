#pragma once
// Work-precision studies (`mpm study --work-precision`): the runs of a refinement study over a
// method matrix, timed one at a time and alternated, so that each method's error can be set
// against what it cost: wall time, particle-steps and peak memory. Per target error, the run
// from which on each method stays below it, and the cheapest method (D 7.3 asks whether
// higher-order BSMPM with a reconstruction outperforms the simpler variants per unit of cost).
#include <optional>
#include <string>
#include <vector>

#include "app/study.hpp"

namespace mpm {

struct WorkPrecisionOptions {
  std::string error = "stress_rel_l2";  // study.csv's error column
  std::vector<double> targets;          // empty: the decades the runs' errors span (at most 4)
  int repeats = 3;                      // timed rounds; every run once per round
  int threads = 1;                      // OpenMP threads of each run
};

struct WorkPrecisionRun {
  RunResult result;                   // the first round's (its errors, particles, steps)
  std::optional<double> error_value;  // its error of WorkPrecisionOptions::error
  std::vector<double> wall_seconds;   // one per round
  double peak_memory_bytes = -1.0;    // the first round's (-1: not known on this system)
  bool reproducible = true;           // every round gave the first round's error bit for bit
  double error() const;               // NaN for a failed run or one without the error
  double wall_min() const;
  double wall_median() const;
  double particle_steps() const;
};

struct WorkPrecisionResult {
  std::vector<std::string> labels;
  std::vector<std::string> values;     // the refined key's values, coarse to fine
  std::vector<WorkPrecisionRun> runs;  // method-major, as StudyRuns
  std::vector<double> targets;
};

// Runs the study's configurations one at a time: `repeats` rounds, each over the values coarse
// to fine and, per value, every method in turn (so that a drift of the machine's speed falls on
// every method alike). The runs write no files. Throws InputError before the first run for bad
// input (a method that set-up refuses, an unknown error name, repeats or threads below 1).
WorkPrecisionResult run_work_precision(const Config& base, const StudyOptions& opt,
                                       const WorkPrecisionOptions& wp);

// Per run: method, value, cells, h, particles, steps, status, the error, wall seconds (minimum
// and median over the rounds), particle-steps, peak memory, reproducible.
std::string work_precision_csv(const StudyOptions& opt, const WorkPrecisionOptions& wp,
                               const WorkPrecisionResult& r);
// The runs, then per target error where each method reaches it (its coarsest refinement from
// which on every run's error is at or below the target), that run's cost, and the cost
// relative to the cheapest method's (minimum wall time).
std::string work_precision_table(const StudyOptions& opt, const WorkPrecisionOptions& wp,
                                 const WorkPrecisionResult& r);

// Parses "1e-2,1e-3" (--targets): positive numbers. Throws InputError.
std::vector<double> parse_targets(const std::string& text);

}  // namespace mpm
