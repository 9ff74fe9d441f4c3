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
RunResult run_ulfem(Problem<1>& pb, const RunSettings& settings, const std::string& config_text,
                    const RunOptions& opt) {
  const auto t_start = Clock::now();
  const TimeSettings& ts = settings.time;
  OutputSession<1> out(opt, settings, config_text, pb);
  const auto elements =
      std::max<Index>(1, std::llround((pb.body_max[0] - pb.body_min[0]) / pb.grid.h[0]));
  check_stability(ts, (pb.body_max[0] - pb.body_min[0]) / static_cast<double>(elements),
                  pb.materials, 1.0, 1, "linear elements");
  Ulfem1D fem(pb, elements);
  RunResult res;
  res.benchmark = pb.benchmark;
  res.warnings = pb.warnings;
  res.dim = 1;
  res.cells = elements;
  res.h = (pb.body_max[0] - pb.body_min[0]) / static_cast<double>(elements);
  res.particles = elements;
  Index start = 0;
  if (opt.restart) {
    const io::Checkpoint& c = *opt.restart;
    const std::string what = fmt::format("checkpoint '{}'", opt.restart_name);
    if (c.solver != "ulfem" || !c.fem)
      throw InputError(fmt::format("{} holds a {} run, not a ulfem run", what, c.solver));
    fem.restore(io::unpack_fem(*c.fem, what));
    out.resume(c);
    start = c.step;
  }
  drive<1>(
      settings, opt, out, start, [&](Index) { fem.step(ts.dt); }, [] {},
      [&] {
        return StateView<1>{fem.elements(), fem.time(), pb.materials};
      },
      [&](Index step) {
        io::Checkpoint c;
        c.config = config_text;
        c.solver = "ulfem";
        c.dim = 1;
        c.step = step;
        c.time = fem.time();
        c.fem = io::pack_fem(fem.save());
        c.frames = out.frames();
        c.frame_times = out.frame_times();
        out.checkpoint(c);
      },
      res);
  if (res.exit_code == exit_code::kOk) {
    // Element midpoints of equal length: no cell of the body is special, so no interior cut.
    Grid<1> element_grid(pb.body_min, pb.body_max, IVec<1>{elements});
    res.errors = error_norms<1>(fem.elements(), element_grid, pb.exact, fem.time(), ts.dt,
                                /*velocity_time=*/-0.5, /*boundary_cells=*/1);
    check_error_norms(res);
  }
  res.wall_seconds = seconds_since(t_start);
  res.summary =
      make_summary(res, settings, pb.materials, fem.time(),
                   {{"solver", "ulfem"}, {"elements", elements}, {"mass", "lumped"}}, -0.5);
  out.summary(res.summary);
  return res;
}

// A distributed run's problem: each process stores only the particles of its slab,
// so that no process holds the whole body, not even while the problem is set up. A counting pass
// (the same on every process, storing no particle) gives the particles in each cell layer along
// the grid's last axis; the slabs are cut from them (SlabPartition::balanced, as run_mpm cuts
// them again from the stored particles' layers, summed over the processes) and every process
// seeds again, keeping its slab's particles (SeedScope). Both passes generate every particle, so
// the set-up takes twice one process's generation; what a process stores is its share.
// `seeded`: the body's particles on all processes.
AnyProblem make_distributed_problem(const Config& cfg, const Comm& comm, Index& seeded) {
  std::vector<double> per_layer;
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
        // (The error names the key to change; every process meets it alike.)
        const SlabPartition<Dim> part = SlabPartition<Dim>::balanced(
            per_layer, comm.size(),
            fmt::format("grid.cells (along {})", SlabPartition<Dim>::axis_name()));
        // A particle outside the grid goes to process 0, as SlabPartition::owner sends it.
        const int me = comm.rank();
        scope.keep = [part, me](Index layer) {
          return (layer < 0 ? 0 : part.owner_of_layer(layer)) == me;
        };
        for (Index l = part.cuts[static_cast<std::size_t>(me)];
             l < part.cuts[static_cast<std::size_t>(me) + 1]; ++l)
          scope.expected += static_cast<Index>(per_layer[static_cast<std::size_t>(l)]);
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

RunResult run(const Config& given, const RunOptions& given_options) {
  RunOptions opt = given_options;
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
  AnyProblem problem =
      distributed ? make_distributed_problem(cfg, *opt.comm, particles) : make_problem(cfg);
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
  const ScopedThreads threads(run_threads(opt.threads, particles / ranks, dim, available));
  const RunSettings settings = run_settings(cfg, dim);
  const std::string config_text = cfg.to_toml();
  // MPM and OTM (which shares the driver through its Stepper; driver/otm_stepper.cpp).
  if (settings.method.solver == Solver::Ulfem) {
    if (ranks > 1)
      throw InputError(
          fmt::format("{}: method.solver = \"ulfem\" runs on one process; start it without mpirun",
                      settings.method.where_solver));
    return run_ulfem(std::get<Problem<1>>(problem), settings, config_text, opt);
  }
  return std::visit(
      [&](auto& pb) {
        constexpr int Dim = std::decay_t<decltype(pb)>::kDim;
        return run_mpm<Dim>(pb, settings, config_text, opt);
      },
      problem);
}

}  // namespace mpm
