// mpm: the mpmlab command line. Subcommands: run, study, bench, reconstruct, massmatrix, mesh,
// stiffness, verify, keys, list.
#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <new>
#include <optional>

#include "app/massmatrix.hpp"
#include "app/mesh_info.hpp"
#include "app/perf.hpp"
#include "app/reconstruct.hpp"
#include "app/stiffness.hpp"
#include "app/study.hpp"
#include "app/work_precision.hpp"
#include "core/comm.hpp"
#include "core/interrupt.hpp"
#include "core/memory.hpp"
#include "driver/run.hpp"
#include "io/checkpoint.hpp"
#include "mpm/version.hpp"
#include "setup/config.hpp"
#include "setup/gmsh_mesh.hpp"
#include "setup/registry.hpp"

namespace {

std::string default_out(const std::string& prefix, const std::string& config) {
  return (std::filesystem::path(prefix) / std::filesystem::path(config).stem()).string();
}

void print_list() {
  auto section = [](const char* title, const auto& entries) {
    std::cout << title << ":\n";
    for (const auto& e : entries) std::cout << fmt::format("  {:<22} {}\n", e.name, e.description);
    std::cout << "\n";
  };
  section("benchmarks (benchmark)", mpm::registry::kBenchmarks);
  section("bases (method.basis)", mpm::registry::kBases);
  section("mappings (method.mapping)", mpm::registry::kMappings);
  section("schemes (method.scheme)", mpm::registry::kSchemes);
  section("mass matrices (method.mass)", mpm::registry::kMassTypes);
  section("materials (material.model)", mpm::registry::kMaterials);
}

// --threads N, else OMP_NUM_THREADS as set, else OpenMP's count capped by the problem size.
int run_threads_option(int threads) {
  if (threads > 0) return threads;
  return std::getenv("OMP_NUM_THREADS") ? -1 : 0;
}

int cmd_run(const std::string& config, const std::vector<std::string>& sets, std::string out,
            bool quiet, const std::string& restart, bool overwrite, int threads) {
  mpm::RunOptions ro;
  ro.quiet = quiet;
  ro.overwrite = overwrite;
  ro.threads = run_threads_option(threads);
  std::optional<mpm::Config> cfg;
  if (!config.empty()) cfg = mpm::Config::load(config, sets);
  if (restart.empty()) {
    if (!cfg) throw mpm::InputError("mpm run needs a CONFIG file (or --restart FILE)");
  } else {
    // Continue from a checkpoint: its stored configuration, which CONFIG (if given) must match
    // except for output.*, parallel.* and time.end; outputs go next to the checkpoint by default.
    ro.restart = std::make_shared<const mpm::io::Checkpoint>(mpm::io::read_checkpoint(restart));
    ro.restart_name = restart;
    cfg = mpm::io::restart_config(*ro.restart, restart, cfg ? &*cfg : nullptr, sets);
    if (out.empty()) out = std::filesystem::path(restart).parent_path().string();
    if (out.empty()) out = ".";
  }
  if (out.empty()) out = default_out("runs", config);
  ro.out_dir = out;
  // Under mpirun: the processes share the run (driver/run_mpm.cpp); rank 0 reports.
  const mpm::Comm& comm = mpm::Comm::world();
  if (comm.distributed()) ro.comm = &comm;
  ro.quiet = quiet || !comm.root();
  const auto r = mpm::run(*cfg, ro);
  if (!comm.root()) return r.exit_code;
  if (!quiet) {
    std::cout << fmt::format(
        "{}: {} particles, {} cells, {} steps in {:.3f} s ({:.1f} ns per "
        "particle-step)\n",
        r.benchmark, r.particles, r.cells, r.steps, r.wall_seconds, r.ns_per_particle_step);
    // Every error norm of summary.json that was computed, in its order.
    bool any = false;
    for (const auto& [name, value] : r.summary["errors"].items())
      if (value.is_number()) {
        std::cout << fmt::format("  {:<34} {:.6e}\n", name, value.get<double>());
        any = true;
      }
    // A run that stopped before time.end has no final errors (summary.json: null).
    if (!any && r.exit_code != 0)
      std::cout << "  errors: none (the run did not reach time.end)\n";
    else if (!any)
      std::cout << "  errors: none (this benchmark has no exact or reference solution)\n";
    std::cout << fmt::format("  conservation: mass {:.3e}, momentum {:.3e}; grid crossings {}\n",
                             r.diag.max_rel_mass_error, r.diag.max_rel_momentum_error,
                             r.diag.grid_crossings);
    std::cout << fmt::format("  outputs in {}/\n", out);
  }
  if (r.exit_code == mpm::exit_code::kInterrupted)
    std::cerr << "mpm: run " << r.failure << "; its outputs so far are in " << out << "/\n";
  else if (r.exit_code != 0)
    std::cerr << "mpm: run failed: " << r.failure << "\n";
  return r.exit_code;
}

// Single-quoted for /bin/sh.
std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs a plotting script of scripts/ on a CSV file the command wrote; false when it failed.
bool plot_csv(const std::string& script_name, const std::string& csv) {
  const std::string script = std::string(MPM_SCRIPTS_DIR) + "/" + script_name;
  // Debian's interpreter, which sees Debian's python3-matplotlib (a python3 earlier on PATH,
  // e.g. pyenv's, would not).
  const std::string python =
      std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string cmd = python + " " + shell_quote(script) + " " + shell_quote(csv);
  std::cout << std::flush;
  if (std::system(cmd.c_str()) == 0) return true;
  std::cerr << fmt::format("mpm: the study finished, but plotting failed ({})\n", cmd);
  return false;
}

// `mpm study --work-precision`: the runs one at a time, timed in alternated rounds.
int cmd_work_precision(const mpm::Config& cfg, const mpm::StudyOptions& opt,
                       const mpm::WorkPrecisionOptions& wp, bool plot) {
  if (opt.jobs > 1)
    throw mpm::InputError(
        fmt::format("--work-precision times each run alone, so --jobs {} is refused; the runs' own "
                    "threads are --threads",
                    opt.jobs));
  const auto r = mpm::run_work_precision(cfg, opt, wp);
  std::cout << mpm::work_precision_table(opt, wp, r);
  std::cout << fmt::format("work_precision.csv and work_precision.txt in {}/\n", opt.out_dir);
  if (plot && !plot_csv("plot_work_precision.py", opt.out_dir + "/work_precision.csv"))
    return mpm::exit_code::kInternal;
  for (const auto& run : r.runs)
    if (run.result.exit_code == mpm::exit_code::kInterrupted) return run.result.exit_code;
  return 0;
}

int cmd_study(const std::string& config, const std::vector<std::string>& refine,
              const std::string& methods, const std::vector<std::string>& sets, std::string out,
              int jobs, bool plot, bool overwrite, const mpm::WorkPrecisionOptions* wp) {
  const auto cfg = mpm::Config::load(config, sets);
  auto opt = mpm::parse_refine(refine);
  if (!methods.empty()) opt.methods = mpm::parse_methods(methods);
  opt.out_dir = out.empty() ? default_out("studies", config) : out;
  opt.jobs = jobs;
  opt.overwrite = overwrite;
  if (wp) return cmd_work_precision(cfg, opt, *wp, plot);
  const auto r = mpm::run_study(cfg, opt);
  std::cout << mpm::study_table(opt, r);
  std::cout << fmt::format("study.csv and each run's outputs in {}/\n", opt.out_dir);
  // Convergence plots (PNG and SVG) by the repository's matplotlib script.
  if (plot && !plot_csv("plot_study.py", opt.out_dir + "/study.csv"))
    return mpm::exit_code::kInternal;
  for (const auto& run : r.runs)
    if (run.exit_code != 0) return run.exit_code;
  return 0;
}

// The verification report (scripts/verify.py), run with this executable.
int cmd_verify(bool quick, bool long_runs, const std::string& out, int jobs, const char* argv0) {
  std::error_code ec;
  auto self = std::filesystem::canonical("/proc/self/exe", ec);
  if (ec) self = std::filesystem::absolute(argv0);
  const std::string python =
      std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  std::string cmd = python + " " + shell_quote(std::string(MPM_SCRIPTS_DIR) + "/verify.py") +
                    " --mpm " + shell_quote(self.string());
  if (quick) cmd += " --quick";
  if (long_runs) cmd += " --long";
  if (!out.empty()) cmd += " --out " + shell_quote(out);
  if (jobs > 0) cmd += fmt::format(" --jobs {}", jobs);
  std::cout << std::flush;
  const int status = std::system(cmd.c_str());
  if (status == -1 || !WIFEXITED(status)) return mpm::exit_code::kInternal;
  return WEXITSTATUS(status);
}

// `mpm bench --messages` (under mpirun): the exchange times and the model's alpha and beta,
// printed by rank 0.
int cmd_bench_messages(const mpm::BenchOptions& opt) {
  const mpm::Comm& comm = mpm::Comm::world();
  const auto m = mpm::bench_messages(comm, opt.repeats);
  if (!comm.root()) return 0;
  std::cout << fmt::format(
      "messages: {} processes, each pair of ranks (2k, 2k + 1) exchanging at once "
      "(Comm::exchange, both ways), the slowest pair, best and median of {}\n"
      "  {:>9}  {:>14}  {:>14}  {:>10}\n",
      m.processes, opt.repeats, "bytes", "us, best", "us, median", "GB/s");
  for (const auto& t : m.sizes)
    std::cout << fmt::format("  {:>9}  {:>14.3f}  {:>14.3f}  {:>10.3f}\n", t.bytes,
                             t.best_seconds * 1e6, t.median_seconds * 1e6,
                             static_cast<double>(t.bytes) / t.median_seconds / 1e9);
  std::cout << fmt::format(
      "alpha = {:.3f} us, beta = {:.3f} GB/s (alpha: the best time of {} bytes; beta: from {} to "
      "{} bytes, medians)\n",
      m.alpha_seconds * 1e6, m.beta_bytes_per_second / 1e9, m.sizes.front().bytes,
      m.sizes[m.sizes.size() - 2].bytes, m.sizes.back().bytes);
  return 0;
}

int cmd_bench(const mpm::BenchOptions& opt) {
  if (opt.messages) return cmd_bench_messages(opt);
  // (Checked here rather than ignored: the 1D bench has one problem, the vibrating bar.)
  if (opt.dim == 1 && opt.problem != "plate")
    throw mpm::InputError(fmt::format(
        "mpm bench: --problem {} is a 2D and 3D problem; --dim 1 times the vibrating bar "
        "(leave --problem out, or give --dim 2 or 3)",
        opt.problem));
  const auto r = opt.dim == 3   ? mpm::bench_3d(opt)
                 : opt.dim == 2 ? mpm::bench_2d(opt)
                                : mpm::bench_1d(opt);
  // Of the last repeat's run (each run of the repeats starts a new record: driver::run).
  const double peak = mpm::peak_memory_bytes();
  const std::string basis =
      opt.basis == "bspline" ? fmt::format("bspline degree {}", opt.degree) : opt.basis;
  std::cout << fmt::format(
      "{}D {} step{}, {} basis, {} mapping, {} mass: {} particles, {} cells{}, {} steps, "
      "{} thread(s), best of {}\n  {:.2f} ns per particle-step (median {:.2f})\n",
      opt.dim, opt.solver != "mpm" ? opt.solver : opt.scheme,
      opt.dim >= 2 ? fmt::format(" ({} problem)",
                                 opt.dim == 3 && opt.problem == "plate" ? "cube" : opt.problem)
                   : "",
      basis, opt.mapping,
      opt.mass == "consistent" ? fmt::format("consistent ({} solve)", opt.mass_solver) : opt.mass,
      r.particles, r.cells, opt.dim >= 2 ? " per direction" : "", r.steps, r.threads, opt.repeats,
      r.best_ns_per_particle_step, r.median_ns_per_particle_step);
  // Every step above; the first step allocates and first touches the step's arrays, which a long
  // run pays once (with TLS about five later steps' worth), so the steps after it are shown too.
  std::cout << fmt::format(
      "  the first step {:.2f} ns per particle (median){}\n", r.median_ns_first_step,
      r.steps >= 2 ? fmt::format("; the steps after it {:.2f} ns per "
                                 "particle-step (median {:.2f})",
                                 r.best_ns_after_first, r.median_ns_after_first)
                   : "");
  std::cout << fmt::format(
      "  {:.1f} bytes per particle (particle state, cached stencil, grid share)\n",
      r.bytes_per_particle);
  // Measured: everything the process held at the peak of a run (the set-up, the program and its
  // libraries, the outputs' buffers), which the count above leaves out.
  if (peak > 0.0)
    std::cout << fmt::format(
        "  peak resident memory of a run {:.1f} MB, {:.1f} bytes per particle\n", peak / 1e6,
        peak / static_cast<double>(std::max<mpm::Index>(r.particles, 1)));
  std::cout << fmt::format(
      "  particles {}, method.sort = \"{}\": {} sort(s) per run{}; sort buffers {:.1f} bytes per "
      "particle\n",
      opt.shuffle ? "shuffled" : "in seeded order", opt.sort, r.sorts,
      r.sorts > 0 ? fmt::format(", {:.1f} ns per particle per sort", r.ns_per_particle_sort) : "",
      r.sort_bytes_per_particle);
  if (opt.stages) {
    // Where the step's time goes (core/stage_clock.hpp): the material laws are part of the
    // grid-to-particle updates; "other" is the rest of the step (re-sorting, the body force,
    // the run's checks and records).
    using mpm::Stage;
    const auto at = [&](Stage s) { return r.stage_ns[static_cast<std::size_t>(s)]; };
    double timed = 0.0;
    for (const Stage s : {Stage::kBasis, Stage::kToGrid, Stage::kGrid, Stage::kToParticles})
      timed += at(s);
    std::string line;
    for (const Stage s : {Stage::kBasis, Stage::kToGrid, Stage::kGrid, Stage::kToParticles})
      line += fmt::format("{} {:.2f}, ", mpm::kStageNames[static_cast<std::size_t>(s)], at(s));
    std::cout << fmt::format(
        "  stages [ns per particle-step, mean of every step]: {}other {:.2f} (of {:.2f}); "
        "the material laws {:.2f} of the grid-to-particle updates\n",
        line, r.mean_ns_per_particle_step - timed, r.mean_ns_per_particle_step,
        at(Stage::kMaterial));
  }
  return 0;
}

}  // namespace

// OpenMP's default wait policy lets idle threads spin: on a busy or shared machine a run with
// nproc threads then waits for spinning threads that have no core (a 50x slowdown measured on 2
// cores with one busy). libgomp reads OMP_WAIT_POLICY when it is loaded, before main,
// so when the user has not set it the program sets "passive" and executes itself again, once
// (the variable is set the second time). If that fails it goes on with the default.
void prefer_passive_waiting(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  if (::setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
  ::execv("/proc/self/exe", argv);
}

namespace {
int run_main(int argc, char** argv);
}  // namespace

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f) would kill the process at the write that crosses it, with no
  // message and no summary; ignored, that write fails with EFBIG and the run stops as on a full
  // disk (exit code 8, a failed summary if it still fits).
  std::signal(SIGXFSZ, SIG_IGN);
  prefer_passive_waiting(argv);
  // Under mpirun every process runs this program: MPI starts here (core/comm.hpp), errors that
  // every process meets alike are printed once (by rank 0), and one process's internal error
  // ends them all (Comm::abort) rather than leaving the others waiting.
  try {
    mpm::Comm::init(&argc, &argv);
  } catch (const mpm::InputError& e) {
    std::cerr << "mpm: error: " << e.what() << "\n";
    return mpm::exit_code::kInput;
  }
  const int rc = run_main(argc, argv);
  mpm::Comm::finalize();
  return rc;
}

namespace {
// The message of an error every process met (rank 0 prints it), or of one this process alone met
// (printed with its rank, then every process ends).
void report_error(const std::string& text, bool all_ranks) {
  const mpm::Comm& comm = mpm::Comm::world();
  if (!comm.distributed()) {
    std::cerr << text << "\n";
  } else if (!all_ranks) {
    std::cerr << fmt::format("[rank {} of {}] {}\n", comm.rank(), comm.size(), text);
  } else if (comm.root()) {
    std::cerr << text << "\n";
  }
}

// mpm run --batch FILE (setup/config.hpp, read_batch): the runs in order, each as `mpm run`
// would make it. A run that fails or is refused does not stop the others (its message names
// the run's table); an interrupted one (SIGINT, SIGTERM) ends the batch. Under mpirun every
// process makes every run: an error every process meets (input, a failed run) moves them all
// to the next run together.
int cmd_batch(const std::string& file, bool quiet, bool overwrite, int threads) {
  const std::vector<mpm::BatchRun> runs = mpm::read_batch(file);
  const mpm::Comm& comm = mpm::Comm::world();
  int first = 0;
  std::size_t failed = 0;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const mpm::BatchRun& r = runs[k];
    // A signal that came after the last run's time loop (its summary, the next set-up) ends the
    // batch here, before another run starts (every process alike).
    int sig = mpm::interrupt_signal();
    if (comm.distributed()) sig = static_cast<int>(comm.max(static_cast<double>(sig)));
    if (sig != 0) {
      if (comm.root())
        std::cout << fmt::format("mpm: batch interrupted by {}; runs {} to {} not made\n",
                                 mpm::signal_name(sig), k + 1, runs.size());
      return mpm::exit_code::kInterrupted;
    }
    int rc = 0;
    try {
      rc = cmd_run(r.config, r.sets, r.out, quiet, "", overwrite, threads);
    } catch (const mpm::InputError& e) {
      report_error(fmt::format("mpm: error: {} (the run of {})", e.what(), r.where), true);
      rc = mpm::exit_code::kInput;
    } catch (const mpm::RunError& e) {
      report_error(fmt::format("mpm: error: {} (the run of {})", e.what(), r.where), true);
      rc = e.exit_code();
    }
    if (comm.root())
      std::cout << fmt::format("mpm: batch run {} of {} ({}, out {}): {}\n", k + 1, runs.size(),
                               r.config, r.out, rc == 0 ? "ok" : fmt::format("exit code {}", rc))
                << std::flush;
    if (rc != 0) {
      ++failed;
      if (first == 0) first = rc;
    }
    if (rc == mpm::exit_code::kInterrupted) {
      if (comm.root())
        std::cout << fmt::format("mpm: batch interrupted; runs {} to {} not made\n", k + 2,
                                 runs.size());
      return rc;
    }
  }
  if (comm.root())
    std::cout << fmt::format(
        "mpm: batch of {} runs: {}\n", runs.size(),
        failed == 0 ? std::string("all ok") : fmt::format("{} failed", failed));
  return first;
}

int run_main(int argc, char** argv) {
  CLI::App app{"mpmlab: material point methods, verified side by side"};
  app.set_version_flag("--version", fmt::format("mpm (mpmlab) {}", mpm::kVersion));
  app.require_subcommand(1);

  std::string config, out, methods;
  std::vector<std::string> sets;
  bool quiet = false, overwrite = false;
  int jobs = 0;

  auto* run = app.add_subcommand("run", "run one configuration and write its outputs");
  std::string restart;
  run->add_option("config", config, "TOML configuration file (optional with --restart)");
  run->add_option("--restart", restart,
                  "continue from a checkpoint.bin (output.checkpoint_every) to time.end; CONFIG, "
                  "if given, may differ from the stored configuration only in output.* and "
                  "time.end (default --out: the checkpoint's directory)");
  run->add_option("--set", sets, "override a key: section.key=value (repeatable)");
  run->add_option("--out", out, "output directory (default runs/<config name>)");
  run->add_flag("--quiet,-q", quiet, "no progress line or report");
  int threads = 0;
  run->add_option("--threads", threads,
                  "OpenMP threads (default: OMP_NUM_THREADS if set, else the cores, at most one "
                  "per 5000 particles in 2D and 50000 in 1D)")
      ->check(CLI::Range(1, 4096));
  run->add_flag("--overwrite", overwrite,
                "replace the files of an earlier run in the output directory (otherwise the run "
                "is refused)");
  std::string batch;
  run->add_option("--batch", batch,
                  "run the [[run]] tables of a TOML file (config, out, set) one after another in "
                  "this start of the program (one mpirun for many runs); the exit code is the "
                  "first non-zero one of its runs");

  auto* study = app.add_subcommand("study", "run a refinement series and print observed orders");
  study->add_option("config", config, "TOML configuration file")->required();
  std::vector<std::string> refine;
  study
      ->add_option("--refine", refine,
                   "key and values, e.g. grid.cells=5,10,20,40; repeated, the further keys are "
                   "refined in lockstep with the first (e.g. --refine time.dt=4e-4,2e-4,1e-4,5e-5)")
      ->required()
      ->allow_extra_args(false);  // one value per --refine, so CONFIG may follow it
  study->add_option("--methods", methods,
                    "method matrix: [solver:]basis[degree]/mapping[/mass],... e.g. "
                    "\"linear/direct, bspline2/tls/consistent, otm:maxent/direct/consistent\"");
  study->add_option("--set", sets, "override a key: section.key=value (repeatable)");
  study->add_option("--out", out, "output directory (default studies/<config name>)");
  study->add_option("--jobs,-j", jobs, "parallel runs (default: hardware threads)");
  study->add_flag("--overwrite", overwrite,
                  "replace the files of earlier runs in the runs' output directories");
  bool plot = false;
  study->add_flag("--plot", plot,
                  "write convergence plots (PNG, SVG) of every error against h, one line per "
                  "method with its fitted order (scripts/plot_study.py; needs python3-matplotlib); "
                  "with --work-precision the error against wall time and particle-steps "
                  "(scripts/plot_work_precision.py)");
  bool work_precision = false;
  mpm::WorkPrecisionOptions wp;
  std::string targets;
  study->add_flag("--work-precision", work_precision,
                  "time every run alone, alternated over --repeats rounds, and set its error "
                  "against its cost (wall time, particle-steps, memory): per target error the "
                  "cheapest run of each method (work_precision.csv, work_precision.txt)");
  study->add_option("--error", wp.error, "the error column of --work-precision")
      ->capture_default_str();
  study->add_option("--targets", targets,
                    "target errors of --work-precision, e.g. 1e-2,1e-3 (default: the decades the "
                    "errors span)");
  study->add_option("--repeats", wp.repeats, "timed rounds of --work-precision")
      ->capture_default_str();
  study->add_option("--threads", wp.threads, "OpenMP threads of each --work-precision run")
      ->capture_default_str();

  mpm::BenchOptions bopt;
  auto* bench = app.add_subcommand("bench", "time the explicit step (ns per particle-step)");
  bench
      ->add_option("--dim", bopt.dim,
                   "1: vibrating bar; 2: neo-Hookean plate (--problem); 3: the cube of "
                   "cube_mms_3d (--problem)")
      ->check(CLI::IsMember({1, 2, 3}))
      ->capture_default_str();
  bench->add_option("--particles", bopt.particles, "number of particles (about, in 2D)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bench
      ->add_option("--per-cell", bopt.per_cell,
                   "particles per cell per direction (default 4 in 1D, 3 in 2D, 2 in 3D)")
      ->check(CLI::PositiveNumber);
  bench->add_option("--threads", bopt.threads, "OpenMP threads (default: OMP_NUM_THREADS)")
      ->check(CLI::PositiveNumber);
  bench->add_option("--steps", bopt.steps, "steps per repeat")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bench->add_option("--repeats", bopt.repeats, "repeats (best and median reported)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bench->add_option("--scheme", bopt.scheme, "usl, usf, musl or usavg")->capture_default_str();
  bench->add_option("--basis", bopt.basis, "grid basis (mpm list)")->capture_default_str();
  bench->add_option("--degree", bopt.degree, "B-spline degree")->capture_default_str();
  bench->add_option("--mapping", bopt.mapping, "particle-to-grid mapping")->capture_default_str();
  bench
      ->add_option(
          "--solver", bopt.solver,
          "mpm; otm (1D, 2D: basis linear or maxent); unified (1D, 2D: bspline; 2D: powell_sabin)")
      ->capture_default_str();
  bench->add_option("--mass", bopt.mass, "lumped or consistent")->capture_default_str();
  bench
      ->add_option("--mass-solver", bopt.mass_solver,
                   "method.mass_solver with --mass consistent: direct, cg or pmg")
      ->check(CLI::IsMember({"direct", "cg", "pmg"}))
      ->capture_default_str();
  bench
      ->add_option("--problem", bopt.problem,
                   "2D and 3D problem: plate (2D plate_mms_2d, 3D the cube of cube_mms_3d: "
                   "body force b(X, t)) or refkernel (the problem of "
                   "../shared/tools/refkernel.cpp, in 3D of scripts/refkernel3d.cpp: padded "
                   "unit square or cube, no body force, free sides, dt = 1e-6 s)")
      ->check(CLI::IsMember({"plate", "refkernel"}))
      ->capture_default_str();
  bench->add_flag("--shuffle", bopt.shuffle,
                  "start from the particles in random order (to measure method.sort)");
  bench->add_flag("--stages", bopt.stages,
                  "also time the step's stages (basis, particles to grid, grid, grid to "
                  "particles, the material laws among them); with --threads 1");
  bench->add_option("--sort", bopt.sort, "method.sort: auto or never")
      ->check(CLI::IsMember({"auto", "never"}))
      ->capture_default_str();
  bench->add_flag("--messages", bopt.messages,
                  "under mpirun with an even number of processes: time the exchange between "
                  "pairs of processes from 8 bytes to 2 MiB, and print the alpha and beta of the "
                  "communication model (BENCHMARKS.md, \"Processes\"); takes --repeats only");

  mpm::ReconstructOptions ropt;
  auto* rec = app.add_subcommand(
      "reconstruct",
      "reconstruct f(x) or f(x, y) from points with a mapping's reconstruction (D 5.2.3, 6.2.1)");
  rec->add_option("--dim", ropt.dim,
                  "1: f(x) on [lower, upper]; 2: f(x, y) on [lower, upper]^2 (tls only)")
      ->capture_default_str();
  rec->add_option("--function", ropt.function, "f(x) or f(x, y), muparser syntax")
      ->capture_default_str();
  rec->add_option("--lower", ropt.lower, "lower end of the domain")->capture_default_str();
  rec->add_option("--upper", ropt.upper, "upper end of the domain")->capture_default_str();
  rec->add_option("--cells", ropt.cells, "elements (per direction)")->capture_default_str();
  rec->add_option("--mapping", ropt.mapping, "tls, cubic_spline, mls or imls")
      ->capture_default_str();
  rec->add_option("--mls-degree", ropt.mls_degree, "MLS/IMLS polynomial degree (1 or 2)")
      ->capture_default_str();
  rec->add_option("--terms", ropt.terms, "TLS Taylor terms (1D: 1-3; 2D: 1, 3 or 6)")
      ->capture_default_str();
  rec->add_option("--completion", ropt.completion,
                  "TLS completion: none, reduce, virtual, "
                  "neighbour")
      ->capture_default_str();
  rec->add_option("--max-condition", ropt.max_condition, "TLS condition-number limit")
      ->capture_default_str();
  rec->add_flag("!--plain", ropt.conservative,
                "TLS: plain least squares instead of keeping the element integrals");
  rec->add_option("--points", ropt.points,
                  "uniform:N, random:N (per element) or list:X1,X2,...; 2D also uniform:NXxNY, "
                  "inner:NXxNY (k/(n+1), D 6.2.1: inner:2x3), list:X1;Y1,X2;Y2,...")
      ->capture_default_str();
  rec->add_option("--seed", ropt.seed, "seed of random:N")->capture_default_str();
  rec->add_option("--mesh", ropt.mesh,
                  "2D on triangles (tls, D 6.2.2): right or criss-cross (--cells squares, "
                  "triangulated) or a Gmsh .msh file; points random:N per triangle or domain:N");
  rec->add_option("--strategy", ropt.strategy,
                  "with --mesh: deficient triangles none, reduce, min-norm or graded")
      ->capture_default_str();
  rec->add_flag("--share-faces", ropt.share_faces,
                "a point on an interior face belongs to both elements");
  rec->add_option("--error-points", ropt.error_points,
                  "Gauss points per element (2D: per direction) for the RMS")
      ->capture_default_str();
  rec->add_option("--integration-points", ropt.integration_points,
                  "Gauss points per element (2D: per direction) for the integral")
      ->capture_default_str();

  mpm::MassMatrixOptions mopt;
  std::string m_smoother = "gauss-seidel", m_restriction = "transpose";
  auto* mass = app.add_subcommand(
      "massmatrix",
      "condition numbers, CG iterations and p-multigrid V-cycles of B-spline mass matrices "
      "(004 Tables 4.2-4.4)");
  mass->add_option("--dim", mopt.dim, "1 or 2 (004: 2)")->capture_default_str();
  mass->add_option("--degrees", mopt.degrees, "B-spline degrees (1-5)")
      ->delimiter(',')
      ->capture_default_str();
  mass->add_option("--cells", mopt.cells, "cells per direction of the unit box (h^-1)")
      ->delimiter(',')
      ->capture_default_str();
  mass->add_option("--boundary", mopt.boundary,
                   "dirichlet (boundary functions eliminated) or free (all functions)")
      ->check(CLI::IsMember({"dirichlet", "free"}))
      ->capture_default_str();
  mass->add_option("--tolerance", mopt.tolerance, "relative residual (004 eq. 4.53)")
      ->capture_default_str();
  mass->add_option("--smoother", m_smoother, "p-multigrid smoother: gauss-seidel or jacobi")
      ->check(CLI::IsMember({"gauss-seidel", "jacobi"}))
      ->capture_default_str();
  mass->add_option("--restriction", m_restriction,
                   "p-multigrid residual restriction: transpose (of the prolongation) or "
                   "projection (lumped L2)")
      ->check(CLI::IsMember({"transpose", "projection"}))
      ->capture_default_str();
  mass->add_option("--smoothing-steps", mopt.pmg.pre, "nu1 = nu2 (004: 8)")->capture_default_str();
  mass->add_option("--particles", mopt.particles,
                   "0: exact Gauss quadrature (004); N: the MPM matrix of N regular particles "
                   "per cell and direction")
      ->capture_default_str();
  mass->add_flag("--matrix-free", mopt.matrix_free,
                 "also run CG with the matrix-free application (no assembled matrix)");
  mass->add_option("--max-iterations", mopt.max_iterations, "CG iterations before giving up")
      ->capture_default_str();
  mass->add_option("--max-cycles", mopt.max_cycles, "V-cycles before giving up")
      ->capture_default_str();
  mass->add_flag("!--no-coarse-correction", mopt.pmg.coarse_correction,
                 "p-multigrid cycles of smoothing only (what the coarse levels contribute)");
  mass->add_option("--csv", mopt.csv, "also write the rows to this CSV file");

  auto* verify = app.add_subcommand(
      "verify",
      "regenerate docs/verification.md and docs/figures/ from fresh runs (scripts/verify.py)");
  bool verify_quick = false, verify_long = false;
  verify->add_flag("--quick", verify_quick,
                   "coarse convergence guard: print observed orders against thresholds, fail "
                   "if one is below; writes nothing into docs/");
  verify->add_flag("--long", verify_long, "also run the 001 plate study at T = 0.2 s (hours)");
  verify->add_option("--out", out, "report directory (default: docs/ of the source tree)");
  verify->add_option("--jobs,-j", jobs, "parallel runs (default 2)");

  std::string mesh_file, mesh_vtu, mesh_pattern = "right";
  std::vector<double> mesh_box;
  std::vector<mpm::Index> mesh_cells;
  mpm::StiffnessOptions sopt;
  auto* stiff = app.add_subcommand(
      "stiffness",
      "eigenvalues of a mapping's linearised grid operator on a frozen particle layout (2D): "
      "growing modes of the force against the strain rate");
  stiff->add_option("config", sopt.config, "TOML configuration file (2D, on the grid)")->required();
  stiff->add_option("--set", sopt.sets, "override a key: section.key=value (repeatable)");
  stiff->add_option("--checkpoint", sopt.checkpoint,
                    "the particles of a run's checkpoint.bin (default: the initial layout)");
  stiff->add_flag("--layout-only", sopt.layout_only,
                  "zero stress and F = I: only the particle layout acts (the operator leaves out "
                  "the geometric stiffness of a stressed state)");
  stiff
      ->add_option("--period", sopt.period,
                   "also print the energy factor exp(2 Re(lambda) period) of the fastest mode "
                   "[s]")
      ->check(CLI::PositiveNumber);

  auto* mesh = app.add_subcommand(
      "mesh",
      "read a Gmsh mesh (or generate a triangulation) and print its vertices, triangles, "
      "quality and named boundaries, and as a body (body.mesh: triangles or tetrahedra) its "
      "volume and parts");
  mesh->add_option("file", mesh_file,
                   "Gmsh .msh file (MSH 4.1 or 2.2, linear triangles or tetrahedra)");
  mesh->add_option("--rectangle", mesh_box, "generate instead: x0,y0,x1,y1 [m]")
      ->delimiter(',')
      ->expected(4);
  mesh->add_option("--cells", mesh_cells, "with --rectangle: cells nx,ny")
      ->delimiter(',')
      ->expected(2);
  mesh->add_option("--pattern", mesh_pattern, "with --rectangle: right or criss-cross")
      ->check(CLI::IsMember({"right", "criss-cross"}))
      ->capture_default_str();
  mesh->add_option("--vtu", mesh_vtu,
                   "also write the mesh with each triangle's area and smallest "
                   "angle as a .vtu (ParaView)");

  auto* keys = app.add_subcommand("keys",
                                  "print every configuration key with type, unit, "
                                  "default, range and description");
  auto* list = app.add_subcommand("list", "list benchmarks, bases, mappings, schemes, materials");

  // Command-line errors are invalid input (exit 2, README "Exit codes"), not CLI11's own codes
  // (106, 109, ...); --help and --version still exit 0.
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : mpm::exit_code::kInput;
  }
  try {
    // A signal ends a run after its current step, with its outputs and an "interrupted"
    // summary (core/interrupt.hpp); a second one ends the process at once.
    if (*run || *study) mpm::install_interrupt_handlers();
    // Under mpirun every process would run the whole command and write the same files.
    if (*bench && bopt.messages)
      for (const CLI::Option* o : bench->get_options())
        if (o->count() > 0 && o->get_name() != "--messages" && o->get_name() != "--repeats")
          throw mpm::InputError(fmt::format(
              "mpm bench --messages times messages alone; leave out {}", o->get_name()));
    if (mpm::Comm::world().distributed() && !*run && !(*bench && bopt.messages))
      throw mpm::InputError(
          fmt::format("only `mpm run` (and `mpm bench --messages`) runs on several processes (this "
                      "is `mpm {}` under mpirun with {} "
                      "processes); start it without mpirun",
                      app.get_subcommands().front()->get_name(), mpm::Comm::world().size()));
    if (*run && !batch.empty()) {
      if (!config.empty() || !restart.empty() || !sets.empty() || !out.empty())
        throw mpm::InputError(
            "mpm run --batch FILE takes each run's configuration, --set overrides and output "
            "directory from FILE ([[run]] tables with config, set and out); leave out CONFIG, "
            "--restart, --set and --out");
      return cmd_batch(batch, quiet, overwrite, threads);
    }
    if (*run) return cmd_run(config, sets, out, quiet, restart, overwrite, threads);
    if (*study) {
      // The options of --work-precision mean nothing without it: refused rather than ignored.
      for (const char* flag : {"--error", "--targets", "--repeats", "--threads"})
        if (!work_precision && study->count(flag) > 0)
          throw mpm::InputError(
              fmt::format("mpm study {} belongs to --work-precision; add --work-precision", flag));
      if (!targets.empty()) wp.targets = mpm::parse_targets(targets);
      return cmd_study(config, refine, methods, sets, out, jobs, plot, overwrite,
                       work_precision ? &wp : nullptr);
    }
    if (*bench) return cmd_bench(bopt);
    if (*verify) return cmd_verify(verify_quick, verify_long, out, jobs, argv[0]);
    if (*mass) {
      mopt.pmg.post = mopt.pmg.pre;
      mopt.pmg.smoother =
          m_smoother == "jacobi" ? mpm::Smoother::Jacobi : mpm::Smoother::GaussSeidel;
      mopt.pmg.restriction = m_restriction == "projection" ? mpm::Restriction::Projection
                                                           : mpm::Restriction::Transpose;
      const auto rows = mpm::massmatrix_study(mopt);
      mpm::print_massmatrix(std::cout, mopt, rows);
      if (!mopt.csv.empty()) mpm::write_massmatrix_csv(mopt.csv, rows);
      return 0;
    }
    if (*stiff) {
      mpm::print_stiffness(std::cout, sopt, mpm::stiffness_spectrum(sopt));
      return 0;
    }
    if (*mesh) {
      if (mesh_file.empty() == mesh_box.empty())
        throw mpm::InputError(
            "mpm mesh: give a Gmsh file or --rectangle x0,y0,x1,y1 with --cells "
            "nx,ny (one of the two)");
      if (!mesh_box.empty() && mesh_cells.empty())
        throw mpm::InputError("mpm mesh: --rectangle needs --cells nx,ny");
      if (!mesh_file.empty() && mpm::gmsh_mesh_dimension(mesh_file) == 3) {
        if (!mesh_vtu.empty())
          throw mpm::InputError(
              "mpm mesh: --vtu writes meshes of triangles; this one holds tetrahedra");
        mpm::print_body_summary(std::cout, mpm::read_gmsh_body<3>(mesh_file));
        return 0;
      }
      const auto m = mesh_file.empty()
                         ? mpm::structured_triangles(
                               {mesh_box[0], mesh_box[1]}, {mesh_box[2], mesh_box[3]},
                               {mesh_cells[0], mesh_cells[1]},
                               mesh_pattern == "right" ? mpm::TrianglePattern::right
                                                       : mpm::TrianglePattern::criss_cross)
                         : mpm::with_box_sides(mpm::read_gmsh_mesh(mesh_file));  // as grid.mesh
      const auto q = mpm::mesh_quality(m);
      mpm::print_mesh_summary(std::cout, m, q);
      if (!mesh_file.empty()) mpm::print_body_summary(std::cout, mpm::read_gmsh_body<2>(mesh_file));
      if (!mesh_vtu.empty()) mpm::write_mesh_vtu(mesh_vtu, m, q);
      return 0;
    }
    if (*rec) {
      const auto r = mpm::reconstruct(ropt);
      if (!ropt.mesh.empty()) {  // triangles (D 6.2.2): the details end with the mesh's size
        std::cout << fmt::format("f(x, y) = {} on [{}, {}]^2, triangles: {}, tls ({})\n",
                                 ropt.function, ropt.lower, ropt.upper, ropt.mesh, ropt.strategy);
        std::cout << r.details;
        std::cout << fmt::format(
            "RMS error (6 points of the degree-4 rule per triangle)   {:.6e}\n", r.rms_error);
        std::cout << fmt::format(
            "integral: exact {:.15g}, reconstructed {:.15g} (a_1 |triangle|)\nrelative integral "
            "error               {:.6e}\n",
            r.integral_exact, r.integral_reconstructed, r.relative_integral_error);
        return 0;
      }
      if (ropt.dim == 2)
        std::cout << fmt::format("f(x, y) = {} on [{}, {}]^2, {} x {} elements, {} points, {}\n",
                                 ropt.function, ropt.lower, ropt.upper, ropt.cells, ropt.cells,
                                 r.xy.size(), ropt.mapping);
      else
        std::cout << fmt::format("f(x) = {} on [{}, {}], {} elements, {} points, {}\n",
                                 ropt.function, ropt.lower, ropt.upper, ropt.cells, r.x.size(),
                                 ropt.mapping);
      std::cout << r.details;
      std::cout << fmt::format("RMS error ({} Gauss points per element{})   {:.6e}\n",
                               ropt.error_points, ropt.dim == 2 ? " and direction" : "",
                               r.rms_error);
      std::cout << fmt::format(
          "integral: exact {:.15g}, reconstructed {:.15g} ({} Gauss points "
          "per element{})\nrelative integral error               {:.6e}\n",
          r.integral_exact, r.integral_reconstructed, ropt.integration_points,
          ropt.dim == 2 ? " and direction" : "", r.relative_integral_error);
      return 0;
    }
    if (*keys) {
      mpm::print_schema(std::cout);
      return 0;
    }
    if (*list) {
      print_list();
      return 0;
    }
  } catch (const mpm::InputError& e) {
    report_error(fmt::format("mpm: error: {}", e.what()), true);
    return mpm::exit_code::kInput;
  } catch (const mpm::RunError& e) {
    // Outside the time loop: an output that could not be written (exit_code::kOutput).
    report_error(fmt::format("mpm: error: {}", e.what()), true);
    return e.exit_code();
  } catch (const std::bad_alloc&) {
    // Sizes that cannot fit are refused before allocation (grid.cells, particles.per_cell);
    // this is what is left: the machine ran out while the run was growing or was busy.
    report_error(
        "mpm: error: out of memory (std::bad_alloc): the run needs more memory than "
        "this machine could give it; use fewer cells (grid.cells) or particles "
        "(particles.per_cell), fewer threads (OMP_NUM_THREADS), or free memory",
        false);
    mpm::Comm::abort(mpm::exit_code::kInternal);
    return mpm::exit_code::kInternal;
  } catch (const std::exception& e) {
    report_error(fmt::format("mpm: internal error: {}", e.what()), false);
    mpm::Comm::abort(mpm::exit_code::kInternal);
    return mpm::exit_code::kInternal;
  }
  return 0;
}
}  // namespace
