#include "driver/run.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "benchmarks/benchmarks.hpp"
#include "core/input_file.hpp"
#include "core/memory.hpp"
#include "core/parallel.hpp"
#include "driver/driver.hpp"
#include "driver/run_mpm.hpp"
#include "driver/session.hpp"
#include "io/checkpoint.hpp"
#include "parallel/distribution.hpp"
#include "setup/config.hpp"
#include "setup/run_settings.hpp"

namespace mpm {
namespace {

using namespace driver;

// A TOML basic string holding `s`: quotes, backslashes and control characters escaped.
std::string toml_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\')
      out += std::string("\\") + c;
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      out += fmt::format("\\u{:04x}", static_cast<unsigned>(static_cast<unsigned char>(c)));
    else
      out += c;
  }
  return out + "\"";
}

// method.solver = "ulfem": the updated-Lagrangian FEM on the problem's body, one linear element
// per grid cell covered by the body; outputs and errors at the element midpoints.
class UlfemRun final : public SolverRun {
 public:
  UlfemRun(Problem<1>& pb, const RunSettings& settings, const std::string& config_text,
           const RunOptions& opt)
      : pb_(pb),
        settings_(settings),
        config_text_(config_text),
        out_(opt, settings, config_text, pb),
        elements_(
            std::max<Index>(1, std::llround((pb.body_max[0] - pb.body_min[0]) / pb.grid.h[0]))) {
    const TimeSettings& ts = settings.time;
    const double h = (pb.body_max[0] - pb.body_min[0]) / static_cast<double>(elements_);
    check_stability(ts, h, pb.materials, 1.0, 1, "linear elements");
    fem_.emplace(pb, elements_);
    res_.benchmark = pb.benchmark;
    res_.warnings = pb.warnings;
    res_.dim = 1;
    res_.cells = elements_;
    res_.h = h;
    res_.particles = elements_;
    Index start = 0;
    if (opt.restart) {
      const io::Checkpoint& c = *opt.restart;
      const std::string what = fmt::format("checkpoint '{}'", opt.restart_name);
      if (c.solver != "ulfem" || !c.fem)
        throw InputError(fmt::format("{} holds a {} run, not a ulfem run", what, c.solver));
      fem_->restore(io::unpack_fem(*c.fem, what));
      out_.resume(c);
      start = c.step;
    }
    loop_.emplace(
        settings, opt, out_, start,
        TimeLoop<1>::Hooks{[this](Index) { fem_->step(settings_.time.dt); }, [] {},
                           [this] {
                             return StateView<1>{fem_->elements(), fem_->time(), pb_.materials};
                           },
                           [this](Index step) { save(step); }},
        res_);
  }
  bool advance_to(Index to) override { return loop_->advance_to(to); }
  bool running() const override { return loop_->running(); }
  Index step() const override { return loop_->step(); }
  double time() const override { return fem_->time(); }
  void stop(const std::string& why) override { loop_->stop(why); }
  void checkpoint() override { loop_->checkpoint(); }
  const RunResult& result() const override { return res_; }
  ParticlesRef particles() const override { return &fem_->elements(); }
  const Materials& materials() const override { return pb_.materials; }
  RunStateRef run_state() override { return static_cast<RunState<1>*>(nullptr); }
  std::vector<double> dof_positions() const override { return {}; }
  const std::vector<std::string>& history_columns() const override {
    return out_.history_columns();
  }
  const std::vector<double>& history_values() const override { return out_.history_values(); }

  RunResult finish() override {
    loop_->finish();
    if (res_.exit_code == exit_code::kOk) {
      // Element midpoints of equal length: no cell of the body is special, so no interior cut.
      Grid<1> element_grid(pb_.body_min, pb_.body_max, IVec<1>{elements_});
      res_.errors = error_norms<1>(fem_->elements(), element_grid, pb_.exact, fem_->time(),
                                   settings_.time.dt, /*velocity_time=*/-0.5,
                                   /*boundary_cells=*/1);
      check_error_norms(res_);
    }
    res_.wall_seconds = seconds_since(t_start_);
    res_.summary =
        make_summary(res_, settings_, pb_.materials, fem_->time(),
                     {{"solver", "ulfem"}, {"elements", elements_}, {"mass", "lumped"}}, -0.5);
    out_.summary(res_.summary);
    out_.close();
    return res_;
  }

 private:
  void save(Index step) {
    io::Checkpoint c;
    c.config = config_text_;
    c.solver = "ulfem";
    c.dim = 1;
    c.step = step;
    c.time = fem_->time();
    c.fem = io::pack_fem(fem_->save());
    c.frames = out_.frames();
    c.frame_times = out_.frame_times();
    out_.checkpoint(c);
  }

  Problem<1>& pb_;
  const RunSettings& settings_;
  const std::string& config_text_;
  const Clock::time_point t_start_ = Clock::now();
  OutputSession<1> out_;
  Index elements_;
  std::optional<Ulfem1D> fem_;
  RunResult res_;
  std::optional<TimeLoop<1>> loop_;
};

// A distributed run's problem: each process stores only the particles of its block,
// so that no process holds the whole body, not even while the problem is set up. A counting pass
// (the same on every process, storing no particle) gives the particles in each cell layer along
// each axis of the grid; the process grid is shaped (parallel.blocks) and the blocks cut from
// them (BlockPartition::choose_shape and balanced, as MpmRun cuts them again from the stored
// particles' layers, summed over the processes) and every process seeds again, keeping its
// block's particles (SeedScope). Both passes generate every particle, so the set-up takes twice
// one process's generation; what a process stores is its share.
// `seeded`: the body's particles on all processes.
AnyProblem make_distributed_problem(const Config& cfg, const Comm& comm, Index& seeded) {
  std::vector<std::vector<double>> per_layer;
  SeedScope counting;
  counting.layer_counts = &per_layer;
  counting.machine_share = static_cast<double>(comm.local_size()) / comm.size();
  counting.machine_processes = comm.local_size();
  const AnyProblem counted = make_problem(cfg, counting);
  seeded = counting.seeded;
  SeedScope scope;
  scope.machine_share = counting.machine_share;
  scope.machine_processes = counting.machine_processes;
  std::visit(
      [&](const auto& pb) {
        constexpr int Dim = std::decay_t<decltype(pb)>::kDim;
        using Part = BlockPartition<Dim>;
        typename Part::LayerCounts counts;
        for (std::size_t d = 0; d < Dim; ++d) counts[d] = per_layer.at(d);
        // (The errors name the key to change; every process meets them alike.)
        const Part part = Part::cut(counts, comm.size(), blocks_request(cfg));
        const int me = comm.rank();
        scope.keep = [part, me](std::span<const Index> cell) { return part.keeps(me, cell); };
        // The particles this process will hold, for the seeders' reserve: its share of the
        // particles along each axis, as if they were spread evenly over the others (exact for
        // slabs, whose span along the other axes is the whole grid).
        double total = 0.0;
        for (double c : counts[0]) total += c;
        double expected = total;
        for (int d = 0; d < Dim; ++d) {
          const auto [lo, hi] = part.span(me, d);
          double mine = 0.0;
          for (Index l = lo; l < hi; ++l)
            mine += counts[static_cast<std::size_t>(d)][static_cast<std::size_t>(l)];
          expected = total > 0.0 ? expected * (mine / total) : 0.0;
        }
        scope.expected = static_cast<Index>(std::ceil(expected));
      },
      counted);
  // A check of the particles a process stores (a custom problem's initial fields) may fail on
  // some processes only: every process stops with the message of the lowest.
  std::optional<Comm::Failure> failed;
  AnyProblem pb;
  try {
    pb = make_problem(cfg, scope);
  } catch (const InputError& e) {
    failed = Comm::Failure{comm.rank(), exit_code::kInput, e.what()};
  }
  if (const auto f = comm.agree(failed ? &*failed : nullptr)) throw InputError(f->message);
  return pb;
}

}  // namespace

int run_threads(int requested, Index particles, int dim, int available) {
  if (requested > 0) return requested;
  if (requested < 0) return available;
  const Index per = kMinParticlesPerThread[std::clamp(dim, 1, 3)];
  return static_cast<int>(std::clamp<Index>(particles / per, 1, std::max(1, available)));
}

driver::Session::Session(const Config& given, const RunOptions& given_options)
    : opt_(given_options) {
  RunOptions& opt = opt_;
  // The stored configuration (config.toml, checkpoints) names the files a run reads (the mesh
  // of grid.mesh, the body of body.mesh or body.particles) by their absolute paths, so that
  // `mpm run DIR/config.toml` and a restart from the checkpoint alone read the same files
  // wherever they are started; the checkpoints hold their hash, so that a restart refuses a
  // file that changed since.
  Config cfg = given;
  std::vector<std::string> files;  // "key 'path'" of each file read, for the restart's message
  for (const std::string& key : io::hashed_input_keys(cfg)) {
    if (cfg.get_string(key).empty()) continue;
    std::error_code ec;
    const std::filesystem::path file = cfg.file_path(key);
    const std::filesystem::path absolute = std::filesystem::absolute(file, ec).lexically_normal();
    std::uint64_t hash = 0;
    try {
      hash = io::fnv1a64(
          read_input_file(file, key.ends_with(".particles") ? "particle file" : "mesh file"));
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}: {}", cfg.where(key), key, e.what()));
    }
    // One hash for every file (with grid.mesh alone: its bytes' hash).
    opt.mesh_hash =
        opt.mesh_hash == 0 ? hash : io::fnv1a64(fmt::format("{:016x}{:016x}", opt.mesh_hash, hash));
    files.push_back(fmt::format("{} '{}'", key, file.string()));
    if (!ec) {
      try {
        cfg.set(key, toml_string(absolute.string()), cfg.where(key));
      } catch (const InputError&) {
        // (A path TOML cannot hold, e.g. not UTF-8: stored as given.)
      }
    }
  }
  if (opt.restart && opt.restart->mesh_hash != opt.mesh_hash) {
    std::string list;
    for (const auto& f : files) list += (list.empty() ? "" : ", ") + f;
    throw InputError(fmt::format(
        "{}: {} {} checkpoint '{}' was written with (the bytes hash to {:016x}, the "
        "checkpoint's to {:016x}); restore {}, or start a new run",
        cfg.where(files.empty() ? "grid.mesh" : files.front().substr(0, files.front().find(' '))),
        list.empty() ? "no input file (grid.mesh, body.mesh, body.particles)" : list,
        files.size() > 1 ? "are not the ones" : "is not the one", opt.restart_name, opt.mesh_hash,
        opt.restart->mesh_hash, files.size() > 1 ? "those files" : "that file"));
  }
  // summary.json's peak_memory_bytes: this run's, the problem's set-up included (a batch runs
  // several in one process).
  reset_peak_memory();
  const bool distributed = opt.comm != nullptr && opt.comm->distributed();
  Index particles = 0;  // the body's, on all processes
  problem_ = distributed ? make_distributed_problem(cfg, *opt.comm, particles) : make_problem(cfg);
  AnyProblem& problem = problem_;
  const int dim =
      std::visit([](const auto& pb) { return std::decay_t<decltype(pb)>::kDim; }, problem);
  if (!distributed)
    particles = std::visit([](const auto& pb) { return pb.particles.size(); }, problem);
  // Named materials ([material.NAME]) are for the bodies of the custom problem, which reads them;
  // a problem that did not is refused rather than run without them.
  const std::vector<std::string> named = cfg.instances("material");
  const std::size_t materials =
      std::visit([](const auto& pb) { return pb.materials.size(); }, problem);
  if (!named.empty() && materials != named.size() + 1)
    throw InputError(fmt::format(
        "{}: [material.{}] is a named material, for the bodies of benchmark = \"custom\" "
        "(body.material, body.part_materials); benchmark = \"{}\" has the one material of "
        "[material]",
        cfg.instance_where("material", named.front()), named.front(), cfg.get_string("benchmark")));
  // Named bodies ([body.NAME]) likewise: a problem that did not seed them is refused.
  const std::vector<std::string> named_bodies = cfg.instances("body");
  const std::size_t bodies = std::visit([](const auto& pb) { return pb.bodies.size(); }, problem);
  if (!named_bodies.empty() && bodies != named_bodies.size() + 1)
    throw InputError(fmt::format(
        "{}: [body.{}] is a named body, for benchmark = \"custom\" in 2D and 3D; benchmark = "
        "\"{}\" has its own body",
        cfg.instance_where("body", named_bodies.front()), named_bodies.front(),
        cfg.get_string("benchmark")));
  // Before the first step, so that a long run shows them at once (opt.quiet on all but rank 0).
  if (!opt.quiet)
    std::visit(
        [](const auto& pb) {
          for (const std::string& w : pb.warnings) std::cerr << "mpm: warning: " << w << "\n";
        },
        problem);
  // A distributed run shares the cores of a machine among its processes there, and each holds
  // about its share of the particles.
  const int ranks = opt.comm ? opt.comm->size() : 1;
  const int available =
      std::max(1, omp_get_max_threads() / (opt.comm ? opt.comm->local_size() : 1));
  threads_ = run_threads(opt.threads, particles / ranks, dim, available);
  if (opt.stage_times && threads_ != 1)
    throw InputError(fmt::format(
        "the stage times are taken on one thread (the material laws are timed inside the "
        "particle loop), and this run has {}: run it with one thread (mpm bench --threads 1)",
        threads_));
  dim_ = dim;
  const ScopedThreads threads(threads_);
  settings_ = run_settings(cfg, dim);
  config_text_ = cfg.to_toml();
  // MPM and OTM (which shares the driver through its Stepper; driver/otm_stepper.cpp).
  if (settings_.method.solver == Solver::Ulfem) {
    if (ranks > 1)
      throw InputError(
          fmt::format("{}: method.solver = \"ulfem\" runs on one process; start it without mpirun",
                      settings_.method.where_solver));
    solver_ =
        std::make_unique<UlfemRun>(std::get<Problem<1>>(problem), settings_, config_text_, opt);
    return;
  }
  solver_ = std::visit(
      [&](auto& pb) {
        constexpr int Dim = std::decay_t<decltype(pb)>::kDim;
        return start_mpm<Dim>(pb, settings_, config_text_, opt);
      },
      problem);
}

driver::Session::~Session() = default;

bool driver::Session::advance_to(Index to) {
  if (finished_) return false;
  const ScopedThreads threads(threads_);
  return solver_->advance_to(to);
}

void driver::Session::stop(const std::string& why) {
  if (finished_) return;
  const ScopedThreads threads(threads_);
  solver_->stop(why);
}

void driver::Session::checkpoint() {
  if (finished_) throw InputError("a finished run writes no checkpoint");
  if (opt_.out_dir.empty())
    throw InputError("a checkpoint is written into the run's output directory; the run has none");
  const ScopedThreads threads(threads_);
  solver_->checkpoint();
}

RunResult driver::Session::finish() {
  if (finished_) throw std::logic_error("Session::finish: the run is finished already");
  const ScopedThreads threads(threads_);
  if (solver_->running())
    solver_->stop(fmt::format("finished by the caller after step {} of {} (t = {:.6g} s)",
                              solver_->step(), steps(), solver_->time()));
  finished_ = true;
  return solver_->finish();
}

RunResult run(const Config& cfg, const RunOptions& opt) {
  driver::Session session(cfg, opt);
  session.advance_to(session.steps());
  return session.finish();
}

}  // namespace mpm
