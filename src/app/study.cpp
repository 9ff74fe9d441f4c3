#include "app/study.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <limits>
#include <mutex>
#include <thread>

#include <omp.h>

#include "core/interrupt.hpp"
#include "core/strings.hpp"
#include "io/output.hpp"
#include "setup/config.hpp"
#include "setup/registry.hpp"

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
    // Each value is one run into one directory: a value twice would be two runs into one.
    if (std::find(o.values.begin(), o.values.end(), item) != o.values.end())
      throw InputError(
          fmt::format("--refine '{}' gives the value {} twice; give each once", text, item));
    o.values.push_back(item);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return o;
}

StudyOptions parse_refine(const std::vector<std::string>& texts) {
  if (texts.empty()) throw InputError("--refine KEY=V1,V2,... is required");
  StudyOptions o = parse_refine(texts.front());
  for (std::size_t i = 1; i < texts.size(); ++i) {
    StudyOptions more = parse_refine(texts[i]);
    if (more.values.size() != o.values.size())
      throw InputError(fmt::format(
          "--refine '{}' gives {} value(s) and --refine '{}' {}: keys refined together need one "
          "value per run",
          texts.front(), o.values.size(), texts[i], more.values.size()));
    if (more.key == o.key || std::any_of(o.lockstep.begin(), o.lockstep.end(),
                                         [&](const auto& l) { return l.first == more.key; }))
      throw InputError(fmt::format("--refine names {} twice", more.key));
    o.lockstep.emplace_back(more.key, std::move(more.values));
  }
  return o;
}

std::vector<MethodSpec> parse_methods(const std::string& text) {
  auto names = [](const auto& entries) {
    std::string out;
    for (const auto& e : entries) out += fmt::format("{}{}", out.empty() ? "" : ", ", e.name);
    return out;
  };
  auto known = [](const auto& entries, const std::string& name) {
    for (const auto& e : entries)
      if (e.name == name) return true;
    return false;
  };
  std::vector<MethodSpec> out;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const auto comma = text.find(',', pos);
    std::string item(trim(std::string_view(text).substr(
        pos, comma == std::string::npos ? std::string::npos : comma - pos)));
    if (item.empty()) throw InputError(fmt::format("--methods '{}' has an empty item", text));
    MethodSpec m;
    m.label = item;
    // An optional solver first: "otm:linear/direct/consistent".
    if (const auto colon = item.find(':'); colon != std::string::npos) {
      const std::string solver = item.substr(0, colon);
      if (!known(registry::kSolvers, solver))
        throw InputError(fmt::format("--methods item '{}': solver '{}' is not one of: {}", item,
                                     solver, names(registry::kSolvers)));
      m.keys.emplace_back("method.solver", solver);
      item.erase(0, colon + 1);
    }
    std::vector<std::string> parts;
    for (std::size_t p = 0;;) {
      const auto slash = item.find('/', p);
      parts.push_back(item.substr(p, slash == std::string::npos ? std::string::npos : slash - p));
      if (slash == std::string::npos) break;
      p = slash + 1;
    }
    if (parts.size() < 2 || parts.size() > 3)
      throw InputError(
          fmt::format("--methods item '{}' must be [solver:]basis[degree]/mapping[/mass], e.g. "
                      "bspline2/tls/consistent or otm:maxent/direct/consistent",
                      m.label));
    // A basis name as it is (cpdi2), else a name and its degree (bspline2): only the B-splines
    // take a degree, so "cpdi2" is never CPDI of degree 2.
    std::string basis = parts[0];
    std::string degree;
    if (!known(registry::kBases, basis)) {
      while (!basis.empty() && std::isdigit(static_cast<unsigned char>(basis.back()))) {
        degree.insert(degree.begin(), basis.back());
        basis.pop_back();
      }
      if (!known(registry::kBases, basis))
        throw InputError(fmt::format("--methods item '{}': basis '{}' is not one of: {}", m.label,
                                     parts[0], names(registry::kBases)));
      if (basis != BSplineKind<1>::kName)
        throw InputError(fmt::format(
            "--methods item '{}': only {} takes a degree (e.g. {}2); '{}' is not one of: {}",
            m.label, BSplineKind<1>::kName, BSplineKind<1>::kName, parts[0],
            names(registry::kBases)));
    }
    if (!known(registry::kMappings, parts[1]))
      throw InputError(fmt::format("--methods item '{}': mapping '{}' is not one of: {}", m.label,
                                   parts[1], names(registry::kMappings)));
    m.keys.emplace_back("method.basis", basis);
    if (!degree.empty()) m.keys.emplace_back("method.degree", degree);
    m.keys.emplace_back("method.mapping", parts[1]);
    if (parts.size() == 3) {
      if (!known(registry::kMassTypes, parts[2]))
        throw InputError(fmt::format("--methods item '{}': mass '{}' is not one of: {}", m.label,
                                     parts[2], names(registry::kMassTypes)));
      m.keys.emplace_back("method.mass", parts[2]);
    }
    out.push_back(std::move(m));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return out;
}

double observed_order(double e_coarse, double e_fine, double h_coarse, double h_fine) {
  if (!(e_coarse > 0.0) || !(e_fine > 0.0) || h_coarse == h_fine)
    return std::numeric_limits<double>::quiet_NaN();
  return std::log(e_coarse / e_fine) / std::log(h_coarse / h_fine);
}

std::optional<double> error_named(const ErrorNorms& e, std::string_view name) {
  for (const auto& c : kColumns)
    if (name == c.name) return e.*(c.member);
  std::string names;
  for (const auto& c : kColumns) names += fmt::format("{}{}", names.empty() ? "" : ", ", c.name);
  throw InputError(fmt::format("error '{}' is not one of: {}", name, names));
}

StudyRuns study_runs(const Config& base, const StudyOptions& opt) {
  // The configuration's own method when no matrix is given, labelled by its keys.
  std::vector<MethodSpec> methods = opt.methods;
  if (methods.empty()) {
    std::string label = base.get_string("method.basis");
    if (label == "bspline") label += std::to_string(base.get_int("method.degree"));
    label += "/" + base.get_string("method.mapping") + "/" + base.get_string("method.mass");
    methods.push_back({label, {}});
  }
  StudyRuns r;
  for (const auto& m : methods) {
    r.labels.push_back(m.label);
    for (const auto& v : opt.values) {
      Config c = base;
      for (const auto& [key, value] : m.keys)
        c.set(key, value, fmt::format("--methods {}", m.label));
      c.set(opt.key, v, fmt::format("--refine {}={}", opt.key, v));
      const std::size_t k = r.configs.size() % opt.values.size();
      for (const auto& [key, values] : opt.lockstep)
        c.set(key, values[k], fmt::format("--refine {}={}", key, values[k]));
      r.configs.push_back(std::move(c));
      std::string method_dir = m.label;
      std::replace(method_dir.begin(), method_dir.end(), '/', '_');
      std::replace(method_dir.begin(), method_dir.end(), ':', '_');
      r.dirs.push_back((std::filesystem::path(opt.out_dir) /
                        (opt.methods.empty() ? "" : method_dir) / fmt::format("{}_{}", opt.key, v))
                           .string());
    }
  }
  return r;
}

StudyResult run_study(const Config& base, const StudyOptions& opt) {
  // Validate every configuration before running any (bad input fails fast).
  StudyRuns expanded = study_runs(base, opt);
  const std::vector<Config>& configs = expanded.configs;
  const std::vector<std::string>& dirs = expanded.dirs;
  StudyResult res;
  res.labels = expanded.labels;
  if (!opt.out_dir.empty()) {
    std::filesystem::create_directories(opt.out_dir);
    // --overwrite: the earlier study's table goes before the first run, so that a study that
    // stops (a refused run, an interrupt) never leaves an old study.csv beside new runs.
    if (opt.overwrite)
      for (const char* name : {"study.csv", "study.txt"}) {
        std::error_code ec;
        std::filesystem::remove(std::filesystem::path(opt.out_dir) / name, ec);
        if (ec)
          throw InputError(fmt::format("--overwrite: cannot remove '{}': {}",
                                       (std::filesystem::path(opt.out_dir) / name).string(),
                                       ec.message()));
      }
  }

  res.runs.resize(configs.size());
  std::vector<std::string> input_errors(configs.size());
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const unsigned jobs = std::min<unsigned>(opt.jobs > 0 ? static_cast<unsigned>(opt.jobs) : hw,
                                           static_cast<unsigned>(configs.size()));
  std::atomic<std::size_t> next{0};
  // Any other exception of a run (out of memory, an I/O error) stops the study: the workers take
  // no further run, and the first one is rethrown here after every thread has joined (an
  // exception leaving a std::thread would terminate the process with no message).
  std::vector<std::exception_ptr> failures(configs.size());
  auto worker = [&] {
    // Runs in parallel share the cores with the OpenMP loops inside each run: split them
    // (results do not depend on the thread count). Per thread; the main thread's is restored.
    const int omp_threads = omp_get_max_threads();
    if (jobs > 1) omp_set_num_threads(std::max(1, omp_threads / static_cast<int>(jobs)));
    for (std::size_t k = next++; k < configs.size(); k = next++) {
      if (interrupt_signal() != 0) {
        // After SIGINT/SIGTERM/SIGHUP the runs under way end early; no new one starts.
        res.runs[k].exit_code = exit_code::kInterrupted;
        res.runs[k].failure = "not run: the study was interrupted";
        continue;
      }
      RunOptions ro;
      ro.quiet = true;
      // This worker's share of the cores, capped by the run's size (unless OMP_NUM_THREADS
      // was set: then the share of that).
      ro.threads = std::getenv("OMP_NUM_THREADS") ? -1 : 0;
      if (!opt.out_dir.empty()) ro.out_dir = dirs[k];
      ro.overwrite = opt.overwrite;
      try {
        res.runs[k] = run(configs[k], ro);
      } catch (const InputError& e) {
        input_errors[k] = e.what();
      } catch (...) {
        failures[k] = std::current_exception();
        next = configs.size();
      }
    }
    omp_set_num_threads(omp_threads);
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < jobs; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  for (const auto& e : input_errors)
    if (!e.empty()) throw InputError(e);
  for (const auto& f : failures)
    if (f) std::rethrow_exception(f);
  if (!opt.out_dir.empty()) {
    io::write_file_atomic(std::filesystem::path(opt.out_dir) / "study.csv", study_csv(opt, res));
    io::write_file_atomic(std::filesystem::path(opt.out_dir) / "study.txt", study_table(opt, res));
  }
  return res;
}

std::vector<std::string_view> study_error_columns() {
  std::vector<std::string_view> names;
  for (const auto& c : kColumns) names.push_back(c.name);
  return names;
}

std::string study_csv(const StudyOptions& opt, const StudyResult& r) {
  std::string s = fmt::format("method,{},cells,h,particles,steps,status", opt.key);
  for (const auto& c : kColumns) s += fmt::format(",{}", c.name);
  s += ",max_rel_mass_error,max_rel_momentum_error,grid_crossings,wall_seconds,"
       "ns_per_particle_step\n";
  for (std::size_t k = 0; k < r.runs.size(); ++k) {
    const auto& run = r.runs[k];
    const std::size_t nv = opt.values.size();
    s += fmt::format("{},{},{},{:.17g},{},{},{}", r.labels[k / nv], opt.values[k % nv], run.cells,
                     run.h, run.particles, run.steps,
                     run.exit_code == 0                         ? "ok"
                     : run.exit_code == exit_code::kInterrupted ? "interrupted"
                                                                : "failed");
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
  std::string head = fmt::format("{:>12} {:>11} {:>9}", opt.key, "h", "particles");
  for (const auto& c : kColumns)
    if (c.label) head += fmt::format(" {:>13} {:>5}", c.label, "order");
  std::string s;
  const std::size_t nv = opt.values.size();
  for (std::size_t m = 0; m < r.labels.size(); ++m) {
    s += fmt::format("{}{}\n{}\n", m > 0 ? "\n" : "", r.labels[m], head);
    for (std::size_t k = 0; k < nv; ++k) {
      const auto& run = r.runs[m * nv + k];
      s += fmt::format("{:>12} {:>11.4e} {:>9}", opt.values[k], run.h, run.particles);
      for (const auto& c : kColumns) {
        if (!c.label) continue;
        const auto& v = run.errors.*(c.member);
        std::string order;
        if (k > 0) {
          const auto& prev = r.runs[m * nv + k - 1];
          if (v && prev.errors.*(c.member)) {
            const double o = observed_order(*(prev.errors.*(c.member)), *v, prev.h, run.h);
            if (std::isfinite(o)) order = fmt::format("{:.2f}", o);
          }
        }
        s += fmt::format(" {:>13} {:>5}", fmt_opt(v), order);
      }
      if (run.exit_code != 0) s += fmt::format("  FAILED: {}", run.failure);
      s += "\n";
    }
  }
  return s;
}

}  // namespace mpm
