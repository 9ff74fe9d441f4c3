#include "app/work_precision.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "core/interrupt.hpp"
#include "core/strings.hpp"
#include "io/output.hpp"

namespace mpm {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Where method m reaches `target`: its coarsest refinement from which on every run succeeded
// with an error at or below the target (a method refined until its error stays below it, so
// that a lucky coarse run on a non-monotone error does not count); -1 if none.
long reaching(const WorkPrecisionResult& r, std::size_t m, double target) {
  const std::size_t nv = r.values.size();
  long first = -1;
  for (std::size_t k = nv; k-- > 0;) {
    if (!(r.runs[m * nv + k].error() <= target)) break;
    first = static_cast<long>(k);
  }
  return first;
}

// Default targets: the decades between the smallest and the largest error of the runs, the
// smallest four (the demanding end, where the methods part).
std::vector<double> default_targets(const WorkPrecisionResult& r) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const auto& run : r.runs)
    if (run.error() > 0.0) {
      lo = std::min(lo, run.error());
      hi = std::max(hi, run.error());
    }
  std::vector<double> t;
  if (!(hi > 0.0)) return t;
  for (int k = static_cast<int>(std::ceil(std::log10(lo))); k <= std::floor(std::log10(hi)); ++k)
    t.push_back(std::pow(10.0, k));
  if (t.empty()) t.push_back(std::sqrt(lo * hi));
  if (t.size() > 4) t.resize(4);
  return t;
}
}  // namespace

double WorkPrecisionRun::error() const {
  return result.exit_code == 0 && error_value ? *error_value : kNaN;
}
double WorkPrecisionRun::wall_min() const {
  return wall_seconds.empty() ? kNaN : *std::min_element(wall_seconds.begin(), wall_seconds.end());
}
double WorkPrecisionRun::wall_median() const {
  if (wall_seconds.empty()) return kNaN;
  std::vector<double> w = wall_seconds;
  std::sort(w.begin(), w.end());
  const std::size_t n = w.size();
  return n % 2 ? w[n / 2] : 0.5 * (w[n / 2 - 1] + w[n / 2]);
}
double WorkPrecisionRun::particle_steps() const {
  return static_cast<double>(result.particles) * static_cast<double>(result.steps);
}

std::vector<double> parse_targets(const std::string& text) {
  std::vector<double> out;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const auto comma = text.find(',', pos);
    const std::string item(trim(std::string_view(text).substr(
        pos, comma == std::string::npos ? std::string::npos : comma - pos)));
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !(v > 0.0) || !std::isfinite(v))
      throw InputError(fmt::format(
          "--targets '{}': '{}' is not a positive number (e.g. --targets 1e-2,1e-3)", text, item));
    out.push_back(v);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return out;
}

WorkPrecisionResult run_work_precision(const Config& base, const StudyOptions& opt,
                                       const WorkPrecisionOptions& wp) {
  if (wp.repeats < 1)
    throw InputError(fmt::format("--repeats {}: at least one timed round", wp.repeats));
  if (wp.threads < 1)
    throw InputError(fmt::format("--threads {}: at least one OpenMP thread", wp.threads));
  (void)error_named(ErrorNorms{}, wp.error);  // the name, checked before any run
  const StudyRuns expanded = study_runs(base, opt);
  WorkPrecisionResult res;
  res.labels = expanded.labels;
  res.values = opt.values;
  res.runs.resize(expanded.configs.size());
  const std::size_t nm = res.labels.size(), nv = res.values.size();
  for (int round = 0; round < wp.repeats; ++round)
    for (std::size_t k = 0; k < nv; ++k)
      for (std::size_t m = 0; m < nm; ++m) {
        const std::size_t i = m * nv + k;
        WorkPrecisionRun& wr = res.runs[i];
        if (interrupt_signal() != 0) {
          if (round == 0) {
            wr.result.exit_code = exit_code::kInterrupted;
            wr.result.failure = "not run: the study was interrupted";
          }
          continue;
        }
        // A run that failed in the first round is not timed again (its cost reaches no target).
        if (round > 0 && wr.result.exit_code != 0) continue;
        RunOptions ro;
        ro.quiet = true;
        ro.threads = wp.threads;
        RunResult rr = run(expanded.configs[i], ro);  // InputError: set-up refused it
        wr.wall_seconds.push_back(rr.wall_seconds);
        const std::optional<double> e = error_named(rr.errors, wp.error);
        if (round == 0) {
          wr.error_value = e;
          if (rr.summary.contains("peak_memory_bytes"))
            wr.peak_memory_bytes = rr.summary["peak_memory_bytes"].get<double>();
          wr.result = std::move(rr);
        } else if (rr.exit_code != wr.result.exit_code ||
                   e.has_value() != wr.error_value.has_value() || (e && *e != *wr.error_value)) {
          wr.reproducible = false;
        }
      }
  res.targets = wp.targets.empty() ? default_targets(res) : wp.targets;
  if (!opt.out_dir.empty()) {
    std::filesystem::create_directories(opt.out_dir);
    io::write_file_atomic(std::filesystem::path(opt.out_dir) / "work_precision.csv",
                          work_precision_csv(opt, wp, res));
    io::write_file_atomic(std::filesystem::path(opt.out_dir) / "work_precision.txt",
                          work_precision_table(opt, wp, res));
  }
  return res;
}

std::string work_precision_csv(const StudyOptions& opt, const WorkPrecisionOptions& wp,
                               const WorkPrecisionResult& r) {
  std::string s = fmt::format(
      "method,{},cells,h,particles,steps,status,{},wall_seconds_min,wall_seconds_median,"
      "particle_steps,peak_memory_bytes,threads,rounds,reproducible\n",
      opt.key, wp.error);
  const std::size_t nv = r.values.size();
  for (std::size_t i = 0; i < r.runs.size(); ++i) {
    const auto& w = r.runs[i];
    const RunResult& run = w.result;
    s += fmt::format("{},{},{},{:.17g},{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{},{},{}\n",
                     r.labels[i / nv], r.values[i % nv], run.cells, run.h, run.particles, run.steps,
                     run.exit_code == 0                         ? "ok"
                     : run.exit_code == exit_code::kInterrupted ? "interrupted"
                                                                : "failed",
                     std::isfinite(w.error()) ? fmt::format("{:.17g}", w.error()) : std::string(),
                     w.wall_min(), w.wall_median(), w.particle_steps(), w.peak_memory_bytes,
                     wp.threads, w.wall_seconds.size(), w.reproducible ? "yes" : "no");
  }
  return s;
}

std::string work_precision_table(const StudyOptions& opt, const WorkPrecisionOptions& wp,
                                 const WorkPrecisionResult& r) {
  const std::size_t nm = r.labels.size(), nv = r.values.size();
  std::string s = fmt::format(
      "work-precision: error {}, {} OpenMP thread(s), wall time the minimum of {} alternated "
      "round(s)\n",
      wp.error, wp.threads, wp.repeats);
  for (std::size_t m = 0; m < nm; ++m) {
    s += fmt::format("\n{}\n{:>12} {:>11} {:>9} {:>13} {:>10} {:>10} {:>13} {:>10}\n", r.labels[m],
                     opt.key, "h", "particles", wp.error, "wall_min", "wall_med", "particle-steps",
                     "memory_MB");
    for (std::size_t k = 0; k < nv; ++k) {
      const auto& w = r.runs[m * nv + k];
      s += fmt::format("{:>12} {:>11.4e} {:>9} {:>13} {:>10.4g} {:>10.4g} {:>13.4g} {:>10.4g}",
                       r.values[k], w.result.h, w.result.particles,
                       std::isfinite(w.error()) ? fmt::format("{:.4e}", w.error()) : "-",
                       w.wall_min(), w.wall_median(), w.particle_steps(),
                       w.peak_memory_bytes / 1048576.0);
      if (w.result.exit_code != 0) s += fmt::format("  FAILED: {}", w.result.failure);
      if (!w.reproducible) s += "  (the error differed between rounds)";
      s += "\n";
    }
  }
  for (double target : r.targets) {
    s += fmt::format("\ntarget {} <= {:.3g}:\n", wp.error, target);
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t m = 0; m < nm; ++m)
      if (const long k = reaching(r, m, target); k >= 0)
        best = std::min(best, r.runs[m * nv + static_cast<std::size_t>(k)].wall_min());
    for (std::size_t m = 0; m < nm; ++m) {
      const long k = reaching(r, m, target);
      if (k < 0) {
        s += fmt::format("  {:<36} not reached\n", r.labels[m]);
        continue;
      }
      const auto& w = r.runs[m * nv + static_cast<std::size_t>(k)];
      s += fmt::format(
          "  {:<36} {}={:<6} {:.4g} s ({:.3g} particle-steps)  {}\n", r.labels[m], opt.key,
          r.values[static_cast<std::size_t>(k)], w.wall_min(), w.particle_steps(),
          w.wall_min() == best ? std::string("cheapest")
                               : fmt::format("{:.3g}x the cheapest", w.wall_min() / best));
    }
  }
  return s;
}

}  // namespace mpm
