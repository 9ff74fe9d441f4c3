#pragma once
// Convergence studies: one configuration run over a refinement series, observed orders between
// successive refinements (order = log(e_k-1 / e_k) / log(h_k-1 / h_k)).
#include <string>
#include <vector>

#include "core/run.hpp"

namespace mpm {

struct StudyOptions {
  std::string key;                  // the refined key, e.g. "grid.cells"
  std::vector<std::string> values;  // its values, coarse to fine
  std::string out_dir;              // study.csv here, each run in out_dir/<key>_<value>
  int jobs = 0;                     // parallel runs; 0: one per hardware thread
  bool quiet = false;
};

struct StudyResult {
  std::vector<RunResult> runs;  // in the order of `values`
};

// Parses "key=v1,v2,..." (the --refine argument). Throws InputError.
StudyOptions parse_refine(const std::string& text);

StudyResult run_study(const Config& base, const StudyOptions& opt);

// Observed order between two runs for one error; NaN when not defined.
double observed_order(double e_coarse, double e_fine, double h_coarse, double h_fine);

std::string study_csv(const StudyOptions& opt, const StudyResult& r);
std::string study_table(const StudyOptions& opt, const StudyResult& r);

}  // namespace mpm
