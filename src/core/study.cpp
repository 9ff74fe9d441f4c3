#include "core/study.hpp"

#include <fmt/format.h>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <thread>

#include "io/config.hpp"
#include "io/output.hpp"

namespace mpm {
namespace {

struct ErrorColumn {
  const char* name;
  std::optional<double> ErrorNorms::*member;
  const char* label;  // heading in the terminal table; nullptr: study.csv only
};

constexpr ErrorColumn kColumns[] = {
    {"displacement_rms", &ErrorNorms::displacement_rms, "u_rms"},
    {"velocity_rms", &ErrorNorms::velocity_rms, nullptr},
    {"velocity_rms_midstep", &ErrorNorms::velocity_rms_midstep, "v_rms_mid"},
    {"velocity_rms_scheme_time", &ErrorNorms::velocity_rms_scheme_time, "v_rms_scheme"},
    {"stress_rms", &ErrorNorms::stress_rms, "stress_rms"},
    {"stress_rel_l2", &ErrorNorms::stress_rel_l2, "stress_rel_l2"},
    {"displacement_rms_interior", &ErrorNorms::displacement_rms_interior, nullptr},
    {"velocity_rms_scheme_time_interior", &ErrorNorms::velocity_rms_scheme_time_interior, nullptr},
    {"stress_rms_interior", &ErrorNorms::stress_rms_interior, nullptr},
};

std::string fmt_opt(const std::optional<double>& v) {
  return v ? fmt::format("{:.4e}", *v) : std::string("-");
}

}  // namespace

StudyOptions parse_refine(const std::string& text) {
  StudyOptions o;
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw InputError(fmt::format(
        "--refine '{}' must look like KEY=V1,V2,... (for example grid.cells=5,10,20,40)", text));
  o.key = text.substr(0, eq);
  std::string rest = text.substr(eq + 1);
  std::size_t pos = 0;
  while (pos <= rest.size()) {
    const auto comma = rest.find(',', pos);
    const auto item =
        rest.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    if (item.empty()) throw InputError(fmt::format("--refine '{}' has an empty value", text));
    o.values.push_back(item);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return o;
}

double observed_order(double e_coarse, double e_fine, double h_coarse, double h_fine) {
  if (!(e_coarse > 0.0) || !(e_fine > 0.0) || h_coarse == h_fine)
    return std::numeric_limits<double>::quiet_NaN();
  return std::log(e_coarse / e_fine) / std::log(h_coarse / h_fine);
}

StudyResult run_study(const Config& base, const StudyOptions& opt) {
  // Validate every configuration before running any (bad input fails fast).
  std::vector<Config> configs;
  for (const auto& v : opt.values) {
    Config c = base;
    c.set(opt.key, v, fmt::format("--refine {}={}", opt.key, v));
    configs.push_back(std::move(c));
  }
  if (!opt.out_dir.empty()) std::filesystem::create_directories(opt.out_dir);

  StudyResult res;
  res.runs.resize(configs.size());
  std::vector<std::string> input_errors(configs.size());
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const unsigned jobs = std::min<unsigned>(opt.jobs > 0 ? static_cast<unsigned>(opt.jobs) : hw,
                                           static_cast<unsigned>(configs.size()));
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t k = next++; k < configs.size(); k = next++) {
      RunOptions ro;
      ro.quiet = true;
      if (!opt.out_dir.empty())
        ro.out_dir =
            (std::filesystem::path(opt.out_dir) / fmt::format("{}_{}", opt.key, opt.values[k]))
                .string();
      try {
        res.runs[k] = run(configs[k], ro);
      } catch (const InputError& e) {
        input_errors[k] = e.what();
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < jobs; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  for (const auto& e : input_errors)
    if (!e.empty()) throw InputError(e);
  if (!opt.out_dir.empty()) {
    io::write_file_atomic(std::filesystem::path(opt.out_dir) / "study.csv", study_csv(opt, res));
    io::write_file_atomic(std::filesystem::path(opt.out_dir) / "study.txt", study_table(opt, res));
  }
  return res;
}

std::string study_csv(const StudyOptions& opt, const StudyResult& r) {
  std::string s = fmt::format("{},cells,h,particles,steps,status", opt.key);
  for (const auto& c : kColumns) s += fmt::format(",{}", c.name);
  s += ",max_rel_mass_error,max_rel_momentum_error,grid_crossings,wall_seconds,"
       "ns_per_particle_step\n";
  for (std::size_t k = 0; k < r.runs.size(); ++k) {
    const auto& run = r.runs[k];
    s += fmt::format("{},{},{:.17g},{},{},{}", opt.values[k], run.cells, run.h, run.particles,
                     run.steps, run.exit_code == 0 ? "ok" : "failed");
    for (const auto& c : kColumns) {
      const auto& v = run.errors.*(c.member);
      s += v ? fmt::format(",{:.17g}", *v) : std::string(",");
    }
    s += fmt::format(",{:.17g},{:.17g},{},{:.6g},{:.6g}\n", run.diag.max_rel_mass_error,
                     run.diag.max_rel_momentum_error, run.diag.grid_crossings, run.wall_seconds,
                     run.ns_per_particle_step);
  }
  return s;
}

std::string study_table(const StudyOptions& opt, const StudyResult& r) {
  std::string s = fmt::format("{:>12} {:>11} {:>9}", opt.key, "h", "particles");
  for (const auto& c : kColumns)
    if (c.label) s += fmt::format(" {:>13} {:>5}", c.label, "order");
  s += "\n";
  for (std::size_t k = 0; k < r.runs.size(); ++k) {
    const auto& run = r.runs[k];
    s += fmt::format("{:>12} {:>11.4e} {:>9}", opt.values[k], run.h, run.particles);
    for (const auto& c : kColumns) {
      if (!c.label) continue;
      const auto& v = run.errors.*(c.member);
      std::string order;
      if (k > 0 && v && (r.runs[k - 1].errors.*(c.member))) {
        const double o =
            observed_order(*(r.runs[k - 1].errors.*(c.member)), *v, r.runs[k - 1].h, run.h);
        if (std::isfinite(o)) order = fmt::format("{:.2f}", o);
      }
      s += fmt::format(" {:>13} {:>5}", fmt_opt(v), order);
    }
    if (run.exit_code != 0) s += fmt::format("  FAILED: {}", run.failure);
    s += "\n";
  }
  return s;
}

}  // namespace mpm
