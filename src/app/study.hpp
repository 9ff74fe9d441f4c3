#pragma once
// Convergence studies: one configuration run over a refinement series, observed orders between
// successive refinements (order = log(e_k-1 / e_k) / log(h_k-1 / h_k)).
#include <string>
#include <vector>

#include "driver/run.hpp"

namespace mpm {

// One method of a method matrix: "basis[degree]/mapping[/mass]", e.g. "bspline2/tls/consistent".
struct MethodSpec {
  std::string label;                                      // as given
  std::vector<std::pair<std::string, std::string>> keys;  // method.* settings it stands for
};

struct StudyOptions {
  std::string key;                  // the refined key, e.g. "grid.cells"
  std::vector<std::string> values;  // its values, coarse to fine
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

// Parses "linear/direct, bspline2/tls/consistent, ..." (the --methods argument) against the
// registry of bases, mappings and mass types. Throws InputError naming the bad item.
std::vector<MethodSpec> parse_methods(const std::string& text);

StudyResult run_study(const Config& base, const StudyOptions& opt);

// Observed order between two runs for one error; NaN when not defined.
double observed_order(double e_coarse, double e_fine, double h_coarse, double h_fine);

std::string study_csv(const StudyOptions& opt, const StudyResult& r);
std::string study_table(const StudyOptions& opt, const StudyResult& r);

}  // namespace mpm
