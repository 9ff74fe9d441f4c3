#pragma once
// Convergence studies: one configuration run over a refinement series, observed orders between
// successive refinements (order = log(e_k-1 / e_k) / log(h_k-1 / h_k)).
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "driver/run.hpp"
#include "setup/config.hpp"

namespace mpm {

// One method of a method matrix: "basis[degree]/mapping[/mass]", e.g. "bspline2/tls/consistent".
struct MethodSpec {
  std::string label;                                      // as given
  std::vector<std::pair<std::string, std::string>> keys;  // method.* settings it stands for
};

struct StudyOptions {
  std::string key;                  // the refined key, e.g. "grid.cells"
  std::vector<std::string> values;  // its values, coarse to fine
  // Keys refined in lockstep with `key`, one value per value of it (e.g. time.dt with the cells,
  // so that the step follows the cell size): further --refine arguments.
  std::vector<std::pair<std::string, std::vector<std::string>>> lockstep;
  std::vector<MethodSpec> methods;  // empty: the configuration's own method
  std::string out_dir;              // study.csv here, each run in out_dir/<method>/<key>_<value>
  int jobs = 0;                     // parallel runs; 0: one per hardware thread
  bool overwrite = false;           // replace earlier runs' files (RunOptions::overwrite)
  bool quiet = false;
};

struct StudyResult {
  std::vector<std::string> labels;  // one per method
  std::vector<RunResult> runs;      // method-major: runs[m * values.size() + k]
};

// Parses "key=v1,v2,..." (the --refine argument). Throws InputError.
StudyOptions parse_refine(const std::string& text);
// Parses several --refine arguments: the first is the study's key, the others are refined in
// lockstep with it and must give as many values. Throws InputError.
StudyOptions parse_refine(const std::vector<std::string>& texts);

// Parses "linear/direct, bspline2/tls/consistent, ..." (the --methods argument) against the
// registry of bases, mappings and mass types. Throws InputError naming the bad item.
std::vector<MethodSpec> parse_methods(const std::string& text);

// The study's configurations, method-major (method m, value k at m * values + k), each with
// its output directory; the methods' labels.
struct StudyRuns {
  std::vector<std::string> labels;
  std::vector<Config> configs;
  std::vector<std::string> dirs;
};
StudyRuns study_runs(const Config& base, const StudyOptions& opt);

StudyResult run_study(const Config& base, const StudyOptions& opt);

// The error of study.csv's column `name` (stress_rel_l2, displacement_rms, ...); InputError
// naming the columns for another name.
std::optional<double> error_named(const ErrorNorms& e, std::string_view name);

// The error columns of study.csv, in their order (the names error_named() reads).
std::vector<std::string_view> study_error_columns();

// Observed order between two runs for one error; NaN when not defined.
double observed_order(double e_coarse, double e_fine, double h_coarse, double h_fine);

std::string study_csv(const StudyOptions& opt, const StudyResult& r);
std::string study_table(const StudyOptions& opt, const StudyResult& r);

}  // namespace mpm
