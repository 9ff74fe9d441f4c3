#include "driver/run_mpm.hpp"

#include <algorithm>
#include <array>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <optional>

#include "core/memory.hpp"
#include "driver/driver.hpp"
#include "driver/stepper.hpp"
#include "grid/triangle_mesh.hpp"
#include "io/checkpoint.hpp"
#include "parallel/distribution.hpp"
#include "setup/variant_name.hpp"
#include "state/sort.hpp"

namespace mpm::driver {
namespace {

double velocity_time(const Scheme& scheme) {
  return std::visit([](auto s) { return decltype(s)::kVelocityTime; }, scheme);
}

// After a process has kept its share of a checkpoint's particles (a restart): keep_with_ids
// keeps the vectors' capacity, so without this every process would hold the storage of every
// particle of the problem for the whole run; room for an eighth more stays (Particles::
// keep_room, as after the set-up, which stores only a process's share: SeedScope).
template <int Dim>
void release_the_rest(Particles<Dim>& p) {
  p.keep_room(p.size() / 8);
}

// A distributed run on a mesh from a file: the mesh with its vertices numbered along the slabs'
// axis (y, then x; ties in the file's order), the triangles and boundaries the same, so that a
// process's DOFs (P1: its vertices; Powell-Sabin: three a vertex) form a short window instead of
// the file's order spanning the mesh. Each triangle keeps its vertices' order, so every basis
// function is the same function; only sums over the DOFs (CG's inner products, conservation)
// change order, to round-off. old_to_new[v]: vertex v's new number.
std::shared_ptr<const TriangleMesh> numbered_along_y(const TriangleMesh& m,
                                                     std::vector<Index>& old_to_new) {
  const Index nv = m.num_vertices();
  std::vector<Index> order(static_cast<std::size_t>(nv));
  std::iota(order.begin(), order.end(), Index{0});
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) {
    const Vec<2>&pa = m.vertex(a), &pb = m.vertex(b);
    return pa[1] < pb[1] || (pa[1] == pb[1] && pa[0] < pb[0]);
  });
  old_to_new.assign(static_cast<std::size_t>(nv), 0);
  std::vector<Vec<2>> vertices(static_cast<std::size_t>(nv));
  for (Index k = 0; k < nv; ++k) {
    old_to_new[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = k;
    vertices[static_cast<std::size_t>(k)] = m.vertex(order[static_cast<std::size_t>(k)]);
  }
  const auto to_new = [&](Index v) { return old_to_new[static_cast<std::size_t>(v)]; };
  std::vector<TriangleMesh::Triangle> triangles;
  triangles.reserve(static_cast<std::size_t>(m.num_cells()));
  for (Index c = 0; c < m.num_cells(); ++c) {
    const auto& t = m.cell_vertices(c);
    triangles.push_back({to_new(t[0]), to_new(t[1]), to_new(t[2])});
  }
  std::map<std::string, std::vector<TriangleMesh::Edge>> boundaries;
  for (const std::string& name : m.boundary_names()) {
    auto& edges = boundaries[name];
    for (const auto& e : m.boundary(name).edges) edges.push_back({to_new(e[0]), to_new(e[1])});
  }
  return std::make_shared<const TriangleMesh>(std::move(vertices), std::move(triangles),
                                              std::move(boundaries), m.source());
}

// Checkpoints (io/checkpoint.hpp). The state of an MPM run with its FEM reference: everything a
// step reads that an earlier step wrote (the grid quantities and stencils are rebuilt per step).
// A distributed run (comm, part) puts each process's particles, in its order, with their cells
// and carried basis state into that process's piece; the checkpoint itself (the manifest) holds
// the process grid and its cuts, each rank's count, re-sorting state and grid crossings
// (Checkpoint::distribution) and the particles per cell layer along each axis: a restart on as
// many processes (in a process grid parallel.blocks accepts) continues bit for bit, on another
// number or grid it cuts the blocks from those counts and reads only the pieces its block
// overlaps.
template <int Dim>
struct Captured {
  io::Checkpoint manifest;
  std::optional<std::string> piece;  // a distributed run: this process's, encoded
};

template <int Dim>
Captured<Dim> capture(Stepper<Dim>& stepper, std::string_view mapping,
                      const std::optional<Ulfem1D>& reference, const OutputSession<Dim>& out,
                      const std::string& config, const Comm* comm,
                      const BlockPartition<Dim>& part) {
  const RunState<Dim>& sim = stepper.state();
  Captured<Dim> cap;
  io::Checkpoint& c = cap.manifest;
  c.config = config;
  c.solver = "mpm";
  c.dim = Dim;
  c.step = sim.step;
  c.time = sim.time;
  c.diag = sim.diag;
  if (comm) {
    comm->check();
    const auto& P = sim.particles;
    const std::array<Index, 4> mine{P.size(), sim.sorting.reference, sim.sorting.sorts,
                                    sim.diag.grid_crossings};
    const std::vector<Index> info = comm->allgather(std::span<const Index>(mine));
    const auto per_layer =
        BlockPartition<Dim>::layer_counts(sim.grid, P, *comm, /*replicated=*/false);
    stepper.export_carried();  // the basis's per-particle state (CPDI2's corners)
    cap.piece =
        io::encode_piece<Dim>(sim.step, comm->rank(), comm->size(), P, sim.cell, sim.carried);
    stepper.resize_particle_caches();  // the basis takes it back
    c.particles.dim = Dim;
    // io::Checkpoint::distribution: ranks, processes per axis, the cuts along each axis, then
    // per rank (count, re-sorting reference, sorts, grid crossings); layer_counts: the particles
    // per cell layer along each axis, one axis after the other (whole numbers).
    c.distribution.push_back(comm->size());
    c.distribution.insert(c.distribution.end(), part.procs.begin(), part.procs.end());
    for (const auto& cuts : part.cuts)
      c.distribution.insert(c.distribution.end(), cuts.begin(), cuts.end());
    c.distribution.insert(c.distribution.end(), info.begin(), info.end());
    for (const auto& counts : per_layer)
      c.layer_counts.insert(c.layer_counts.end(), counts.begin(), counts.end());
    c.diag.grid_crossings = 0;
    c.sorts = 0;
    for (std::size_t r = 0; r < static_cast<std::size_t>(comm->size()); ++r) {
      c.diag.grid_crossings += info[4 * r + 3];
      c.sorts += info[4 * r + 2];
    }
    c.sort_reference = -1;
  } else {
    c.particles = io::pack_particles(sim.particles);
    c.cells.assign(sim.cell.begin(), sim.cell.end());
    c.sort_reference = sim.sorting.reference;
    c.sorts = sim.sorting.sorts;
  }
  if (reference) c.fem = io::pack_fem(reference->save());
  c.mapping = std::string(mapping);
  c.frames = out.frames();
  c.frame_times = out.frame_times();
  stepper.save(c);                  // mapping totals, basis state
  if (comm) c.basis_state.clear();  // (in the pieces)
  return cap;
}

// The checkpoint's distribution (Checkpoint::distribution) read back and checked: ranks, the
// process grid and its cuts along each axis, and per rank (count, re-sorting reference, sorts,
// grid crossings), with the pieces and the particles per layer along each axis that the
// manifest of a distributed run holds.
template <int Dim>
struct StoredDistribution {
  Index ranks = 0;
  BlockPartition<Dim> part;
  typename BlockPartition<Dim>::LayerCounts per_layer;
  std::vector<Index> info;
};
template <int Dim>
StoredDistribution<Dim> stored_distribution(const io::Checkpoint& c, Index particles,
                                            const IVec<Dim>& cells, const std::string& what) {
  StoredDistribution<Dim> d;
  const auto& v = c.distribution;
  if (v.empty() && c.pieces.empty() && c.layer_counts.empty()) return d;
  const auto size = static_cast<Index>(v.size());
  const Index r = v.empty() ? 0 : v[0];
  Index layers = 0;
  for (const Index n : cells) layers += n;
  bool ok = r >= 1 && r <= (1 << 24) && size >= 1 + Dim &&
            static_cast<Index>(c.pieces.size()) == r &&
            static_cast<Index>(c.layer_counts.size()) == layers;
  std::size_t at = 1;
  Index product = 1, cut_entries = 0;
  for (std::size_t k = 0; ok && k < Dim; ++k) {
    d.part.procs[k] = v[at++];
    ok = d.part.procs[k] >= 1 && d.part.procs[k] <= cells[k];
    product *= ok ? d.part.procs[k] : 1;
    cut_entries += d.part.procs[k] + 1;
  }
  ok = ok && product == r && size == 1 + Dim + cut_entries + 4 * r;
  for (std::size_t k = 0; ok && k < Dim; ++k) {
    auto& cuts = d.part.cuts[k];
    cuts.assign(v.begin() + static_cast<std::ptrdiff_t>(at),
                v.begin() + static_cast<std::ptrdiff_t>(
                                at + static_cast<std::size_t>(d.part.procs[k]) + 1));
    at += cuts.size();
    ok = cuts.front() == 0 && cuts.back() == cells[k];
    for (std::size_t j = 1; ok && j < cuts.size(); ++j) ok = cuts[j] > cuts[j - 1];
  }
  Index total = 0;
  for (Index k = 0; ok && k < r; ++k) {
    const std::size_t i = at + 4 * static_cast<std::size_t>(k);
    ok = v[i] >= 0 && v[i + 1] >= -1 && v[i + 2] >= 0 && v[i + 3] >= 0;
    total += v[i];
  }
  std::size_t l = 0;
  for (std::size_t k = 0; ok && k < Dim; ++k) {
    Index counted = 0;
    for (Index j = 0; ok && j < cells[k]; ++j, ++l) {
      ok = c.layer_counts[l] >= 0 && c.layer_counts[l] <= particles;
      counted += c.layer_counts[l];
      d.per_layer[k].push_back(static_cast<double>(c.layer_counts[l]));
    }
    // (Every particle lies in a layer along every axis: one outside the grid has stopped the
    // run.)
    ok = ok && counted == particles;
  }
  if (!ok || total != particles)
    throw InputError(
        fmt::format("{} is not a state of this run: its distribution over "
                    "processes does not fit {} particles and {} cell layers",
                    what, particles, layers));
  d.ranks = r;
  d.info.assign(v.begin() + static_cast<std::ptrdiff_t>(at), v.end());
  return d;
}

// Puts the checkpoint's state into a freshly set-up run; returns the step it is at. A
// distributed run (comm) restarting from a checkpoint of as many processes takes its rank's
// piece as it was (bit for bit); from another count (or from a run on one process) it cuts the
// slabs anew and keeps the particles of its slab, reading only the pieces that overlap it (the
// answers then change by round-off, the order of the sums being another). A run on one process
// reads every piece, rank after rank. `particles`: the run's particles in all. Collective in
// nothing: an InputError met on one process is agreed by the caller. (The outputs resume after.)
template <int Dim>
Index restore(const RunOptions& opt, double dt, Stepper<Dim>& stepper, std::string_view mapping,
              std::optional<Ulfem1D>& reference, const Comm* comm, BlockPartition<Dim>& part,
              const BlockShapeRequest& blocks, Index particles) {
  const io::Checkpoint& stored = *opt.restart;
  RunState<Dim>& sim = stepper.state();
  const std::string what = fmt::format("checkpoint '{}'", opt.restart_name);
  if (stored.solver != "mpm" || stored.dim != Dim || stored.mapping != mapping)
    throw InputError(
        fmt::format("{} holds a {} run ({}D, mapping {}), not this {}D mpm run with "
                    "mapping {}",
                    what, stored.solver, stored.dim, stored.mapping, Dim, mapping));
  const bool pieces = !stored.pieces.empty();
  const StoredDistribution<Dim> dist = stored_distribution<Dim>(
      stored, pieces ? particles : static_cast<Index>(stored.particles.count), sim.grid.cells,
      what);
  // A distributed checkpoint: its manifest with the particles of the pieces this process reads.
  io::Checkpoint joined;
  std::vector<std::int64_t> piece_counts;  // the particles of each piece read
  std::vector<int> piece_ranks;            // and its rank
  // As many processes in a process grid parallel.blocks accepts: each takes its piece as it
  // was; otherwise the blocks are cut anew.
  const auto same_count = [&] {
    using Kind = BlockShapeRequest::Kind;
    if (!comm || dist.ranks != comm->size()) return false;
    if (blocks.kind == Kind::Slabs) return dist.part.slabs();
    if (blocks.kind == Kind::Given)
      return std::equal(blocks.procs.begin(), blocks.procs.end(), dist.part.procs.begin(),
                        dist.part.procs.end());
    return true;
  };
  const auto cut = [&](const typename BlockPartition<Dim>::LayerCounts& counts) {
    return BlockPartition<Dim>::cut(counts, comm->size(), blocks);
  };
  if (pieces) {
    std::vector<bool> take(static_cast<std::size_t>(dist.ranks), !comm);
    if (same_count()) {
      take[static_cast<std::size_t>(comm->rank())] = true;
    } else if (comm) {
      // The new blocks from the particles per layer (those a gathering of every piece would
      // count); the pieces whose blocks overlap this process's.
      part = cut(dist.per_layer);
      for (std::size_t r = 0; r < take.size(); ++r)
        take[r] = part.overlaps(comm->rank(), dist.part, static_cast<int>(r));
    }
    joined = stored;
    piece_counts = io::join_pieces(joined, opt.restart_name, take);
    for (std::size_t r = 0; r < take.size(); ++r)
      if (take[r]) piece_ranks.push_back(static_cast<int>(r));
    for (std::size_t k = 0; k < piece_ranks.size(); ++k)
      if (piece_counts[k] != dist.info[4 * static_cast<std::size_t>(piece_ranks[k])])
        throw InputError(fmt::format(
            "{} is not a state of this run: the piece of process {} holds {} particles, the "
            "manifest says {}",
            what, piece_ranks[k], piece_counts[k],
            dist.info[4 * static_cast<std::size_t>(piece_ranks[k])]));
  }
  const io::Checkpoint& c = pieces ? joined : stored;
  auto p = io::unpack_particles<Dim>(c.particles, what);
  try {
    p.state.set_names(sim.materials.state_names());
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{} does not fit the problem: {} (material.model = \"{}\")", what,
                                 e.what(), sim.materials.law_names()));
  }
  for (std::size_t i = 0; i < p.material.size(); ++i)
    if (p.material[i] >= sim.materials.size())
      throw InputError(fmt::format(
          "{} does not fit the problem: particle {} has material {}, the run has {} materials",
          what, p.id[i], static_cast<int>(p.material[i]), sim.materials.size()));
  // (Each particle's cell: OTM keeps none. A distributed run holds a part of them.)
  const std::size_t cells = comm ? static_cast<std::size_t>(p.size()) : sim.cell.size();
  if ((!pieces || !comm) && p.size() != particles)
    throw InputError(fmt::format("{} does not fit the problem: {} particles ({} set up)", what,
                                 p.size(), particles));
  if (c.cells.size() != cells || reference.has_value() != c.fem.has_value())
    throw InputError(fmt::format(
        "{} does not fit the problem: {} particles, {} cells{}", what, p.size(), c.cells.size(),
        reference.has_value() != c.fem.has_value() ? ", FEM reference state missing or unexpected"
                                                   : ""));
  // A checkpoint's hash only proves the bytes are those written; a crafted or foreign one could
  // still hold a state no run reaches: the step and time must be those of this
  // run's time loop (t = step dt exactly, as the driver sets it), the counters non-negative and
  // the cells on the grid.
  if (c.step < 0 || c.time != static_cast<double>(c.step) * dt || c.sorts < 0 ||
      c.sort_reference < -1 || c.diag.grid_crossings < 0 ||
      std::any_of(c.cells.begin(), c.cells.end(),
                  [&](auto cell) { return cell < -1 || cell >= sim.grid.num_cells(); }))
    throw InputError(fmt::format(
        "{} is not a state of this run: step {}, time {:.17g} (time.dt = {:.17g} gives {:.17g}), "
        "{} sorts, {} grid crossings, cells in [{}, {}] of {}",
        what, c.step, c.time, dt, static_cast<double>(c.step) * dt, c.sorts, c.diag.grid_crossings,
        c.cells.empty() ? 0 : *std::min_element(c.cells.begin(), c.cells.end()),
        c.cells.empty() ? 0 : *std::max_element(c.cells.begin(), c.cells.end()),
        sim.grid.num_cells()));
  // Reading only the overlapping pieces keeps every particle once: each piece's particles lie in
  // the block of the process that wrote it (migrated there after every step).
  if (pieces && comm && !same_count()) {
    std::size_t i = 0;
    for (std::size_t k = 0; k < piece_ranks.size(); ++k) {
      const int r = piece_ranks[k];
      for (std::int64_t j = 0; j < piece_counts[k]; ++j, ++i)
        if (dist.part.owner(sim.grid, p.x[i], -1) != r)
          throw InputError(fmt::format(
              "{} is not a state of this run: particle {} of the piece of process {} lies "
              "outside that process's block ({})",
              what, p.id[i], r, dist.part.describe()));
    }
  }
  // The traction lists name their particles by position in the freshly set-up order; the
  // checkpoint holds the particles in its own (re-sorted) order: follow the ids there. (A
  // distributed run's lists follow the ids after the particles are restored:
  // resize_particle_caches.)
  if (!sim.tractions.empty() && !comm) {
    const auto n = static_cast<std::size_t>(p.size());
    std::vector<Index> at(n, -1);  // position in the checkpoint of each id
    for (std::size_t k = 0; k < n; ++k) {
      const auto id = static_cast<std::size_t>(p.id[k]);
      if (id >= n || at[id] >= 0)
        throw InputError(
            fmt::format("{} is not a state of this run: its particle ids are not "
                        "0 .. {} once each",
                        what, n - 1));
      at[id] = static_cast<Index>(k);
    }
    for (auto& tr : sim.tractions)
      for (auto& q : tr.particles)
        q = at[static_cast<std::size_t>(sim.particles.id[static_cast<std::size_t>(q)])];
  }
  std::vector<CompactIndex> cell(c.cells.begin(), c.cells.end());
  // A distributed restart: the basis's per-particle state (CPDI2's corners) is kept with the
  // particles this process keeps (Stepper::load leaves it to resize_particle_caches).
  std::vector<double> carried;
  std::size_t width = 0;
  if (comm && !c.basis_state.empty()) {
    width = p.size() > 0 ? c.basis_state.size() / static_cast<std::size_t>(p.size()) : 0;
    if (width * static_cast<std::size_t>(p.size()) != c.basis_state.size())
      throw InputError(fmt::format("{} holds {} values of basis state for {} particles", what,
                                   c.basis_state.size(), p.size()));
  }
  const auto keep_carried = [&](auto&& keep) {
    for (std::size_t i = 0; i < static_cast<std::size_t>(p.size()); ++i)
      if (keep(i))
        carried.insert(carried.end(),
                       c.basis_state.begin() + static_cast<std::ptrdiff_t>(i * width),
                       c.basis_state.begin() + static_cast<std::ptrdiff_t>((i + 1) * width));
  };
  sim.diag = c.diag;
  sim.sorting.reference = c.sort_reference;
  sim.sorting.sorts = c.sorts;
  if (same_count()) {
    // As many processes: this rank's piece, as it was.
    const auto me = static_cast<std::size_t>(comm->rank());
    keep_carried([](std::size_t) { return true; });
    release_the_rest(p);
    part = dist.part;
    sim.sorting.reference = dist.info[4 * me + 1];
    sim.sorting.sorts = dist.info[4 * me + 2];
    sim.diag.grid_crossings = dist.info[4 * me + 3];
  } else if (comm) {
    // Another number of processes: new slabs (cut above from a distributed checkpoint's counts);
    // the counters go to rank 0, the re-sorting starts afresh.
    if (!pieces)
      part = cut(BlockPartition<Dim>::layer_counts(sim.grid, p, *comm, /*replicated=*/true));
    const int me = comm->rank();
    std::vector<CompactIndex> kept;
    for (std::size_t i = 0; i < cell.size(); ++i)
      if (part.owner(sim.grid, p.x[i], 0) == me) kept.push_back(cell[i]);
    keep_carried([&](std::size_t i) { return part.owner(sim.grid, p.x[i], 0) == me; });
    cell = std::move(kept);
    p.keep_with_ids([&](const Particles<Dim>& P, std::size_t i) {
      return part.owner(sim.grid, P.x[i], 0) == me;
    });
    release_the_rest(p);
    sim.sorting.reference = -1;
    if (!comm->root()) {
      sim.sorting.sorts = 0;
      sim.diag.grid_crossings = 0;
    }
  } else if (dist.ranks > 0) {
    sim.sorting.reference = -1;  // one process after several: re-sorting starts afresh
  }
  sim.particles = std::move(p);
  sim.cell.assign(cell.begin(), cell.end());
  sim.carried = std::move(carried);
  sim.carried_width = static_cast<int>(width);
  sim.step = c.step;
  sim.time = c.time;
  if (reference) reference->restore(io::unpack_fem(*c.fem, what));
  stepper.load(c, what);  // mapping totals, basis state
  stepper.resize_particle_caches();
  return c.step;
}

// The MPM run of one problem (also OTM and the unified solver, through their stepper): set up in
// the constructor, stepped by the time loop, finished into its result.
template <int Dim>
class MpmRun final : public SolverRun {
 public:
  MpmRun(Problem<Dim>& pb, const RunSettings& settings, const std::string& config_text,
         const RunOptions& opt);
  bool advance_to(Index to) override { return loop_->advance_to(to); }
  bool running() const override { return loop_->running(); }
  Index step() const override { return loop_->step(); }
  double time() const override { return stepper_->state().time; }
  void stop(const std::string& why) override { loop_->stop(why); }
  void checkpoint() override { loop_->checkpoint(); }
  RunResult finish() override;
  const RunResult& result() const override { return res_; }
  ParticlesRef particles() const override { return &stepper_->state().particles; }
  const Materials& materials() const override { return stepper_->state().materials; }
  RunStateRef run_state() override { return &stepper_->state(); }
  std::vector<double> dof_positions() const override {
    std::vector<double> flat;
    for (const Vec<Dim>& x : stepper_->dof_positions()) flat.insert(flat.end(), x.begin(), x.end());
    return flat;
  }
  const std::vector<std::string>& history_columns() const override {
    return out_->history_columns();
  }
  const std::vector<double>& history_values() const override { return out_->history_values(); }

 private:
  // An input error that only some processes meet (the stepper's checks of their own particles,
  // rank 0's output directory), or a write that fails on one (config.toml, grid.vtu), stops
  // every process with the message and exit code of the lowest.
  template <class Build>
  void agreed(Build&& build);
  void advance(Index s);
  void save();

  Problem<Dim>& pb_;
  const RunSettings& settings_;
  const std::string& config_text_;
  RunOptions opt_;
  std::string_view mapping_name_;
  bool otm_ = false, unified_ = false;
  double scheme_velocity_time_ = 0.0;
  Clock::time_point t_start_ = Clock::now();
  // The FEM reference of benchmarks without an exact solution, stepped alongside (untimed).
  std::optional<Ulfem1D> reference_;
  const Comm* comm_ = nullptr;
  BlockPartition<Dim> part_;
  std::unique_ptr<Stepper<Dim>> stepper_;
  std::optional<OutputSession<Dim>> out_;
  RunResult res_;
  Index migrated_ = 0;  // particles this rank sent to another
  Index rebalances_ = 0;
  double worst_imbalance_ = 0.0;
  std::optional<TimeLoop<Dim>> loop_;
};

template <int Dim>
template <class Build>
void MpmRun<Dim>::agreed(Build&& build) {
  std::optional<Comm::Failure> failed;
  try {
    build();
  } catch (const InputError& e) {
    if (!comm_) throw;
    failed = Comm::Failure{comm_->rank(), exit_code::kInput, e.what()};
  } catch (const RemoteRunError&) {
    throw;  // (agreed already: every process has it)
  } catch (const RunError& e) {
    if (!comm_) throw;
    failed = Comm::Failure{comm_->rank(), e.exit_code(), e.what()};
  }
  if (comm_)
    if (const auto f = comm_->agree(failed ? &*failed : nullptr)) {
      if (f->exit_code == exit_code::kInput) throw InputError(f->message);
      throw RemoteRunError(f->exit_code,
                           fmt::format("rank {} of {}: {}", f->rank, comm_->size(), f->message));
    }
}

template <int Dim>
MpmRun<Dim>::MpmRun(Problem<Dim>& pb, const RunSettings& settings, const std::string& config_text,
                    const RunOptions& opt)
    : pb_(pb), settings_(settings), config_text_(config_text), opt_(opt) {
  // run_settings() has checked that the basis and mapping exist in Dim, and the time step.
  const MethodSettings& method = settings.method;
  const BasisKind& basis = method.basis;
  mapping_name_ = name_of(method.mapping);
  otm_ = method.solver == Solver::Otm;
  unified_ = method.solver == Solver::Unified;
  // OTM's particle velocity is (x_p^{s+1} - x_p^s) / dt, a velocity at t - dt / 2; the unified
  // approach updates it as USL does (Usl::kVelocityTime, also t - dt / 2).
  scheme_velocity_time_ = otm_       ? -0.5
                          : unified_ ? Usl::kVelocityTime
                                     : velocity_time(method.scheme);
  const TimeSettings& ts = settings.time;

  if constexpr (Dim == 1)
    if (pb.fem_reference) reference_.emplace(pb, settings.reference_dofs - 1);

  if constexpr (Dim == 2) {
    if (pb.mesh)  // h: the smallest altitude of the mesh's triangles
      check_stability(ts, pb.mesh->min_altitude(), pb.materials, altitude_stability_factor(basis),
                      Dim,
                      fmt::format("{} basis on {}, lumped-mass bound, h the smallest triangle "
                                  "altitude",
                                  basis_name(basis), pb.mesh->source()));
  }
  if (!pb.mesh)
    check_stability(ts, pb.grid.h.minCoeff(), pb.materials, stability_factor(basis), Dim,
                    fmt::format("{} basis, lumped-mass bound", basis_name(basis)));

  // A distributed run: each process has set up only the particles of its block
  // (parallel/distribution.hpp), cut so that each holds about as many (driver/run.cpp).
  comm_ = opt.comm != nullptr && opt.comm->distributed() ? opt.comm : nullptr;
  if (opt.shuffle_seed != 0 && !opt.restart) {
    // (The one process's random order cannot be had from a slab's particles.)
    if (comm_)
      throw InputError("shuffling the particles (mpm bench --shuffle) runs on one process");
    shuffle_particles(pb.particles, pb.tractions, opt.shuffle_seed);
  }
  if (comm_) {
    constexpr std::string_view kHow = "run it on one process (without mpirun)";
    if (otm_ || unified_)
      throw InputError(
          fmt::format("{}: method.solver = \"{}\" does not run on several "
                      "processes yet; {}",
                      method.where_solver, otm_ ? "otm" : "unified", kHow));
    if constexpr (Dim == 2)
      if (pb.mesh) {
        std::vector<Index> old_to_new;
        pb.mesh = numbered_along_y(*pb.mesh, old_to_new);
        for (auto& f : pb.fixed_sides)
          for (auto& [v, n] : f.vertex_normals) v = old_to_new[static_cast<std::size_t>(v)];
      }
    // The cuts the set-up seeded by, from the same counts (each layer's particles are on one
    // process). The traction points name their particles by id (RunState::all_tractions).
    const auto counts =
        BlockPartition<Dim>::layer_counts(pb.grid, pb.particles, *comm_, /*replicated=*/false);
    part_ = BlockPartition<Dim>::cut(counts, comm_->size(), settings.parallel.blocks);
    const int me = comm_->rank();
    for (const auto& x : pb.particles.x)
      if (part_.owner(pb.grid, x, 0) != me)
        throw std::logic_error("run_mpm: a process set up a particle of another's block");
  }
  // OTM and the unified solver are one- and two-dimensional (run_settings refuses them in 3D).
  const std::size_t problem_warnings = pb.warnings.size();
  agreed([&] {
    if constexpr (Dim <= 2)
      if (otm_ || unified_) {
        stepper_ = make_otm_stepper<Dim>({pb, method, !opt.restart});
        return;
      }
    stepper_ = make_stepper<Dim>(basis, {pb, method, !opt.restart, comm_});
  });
  RunState<Dim>& sim = stepper_->state();
  if (opt.stage_times) sim.clock = &res_.stages;  // one thread (driver/run.cpp)
  // The stepper's own warnings (its checks of the basis against the particles), shown as the
  // problem's were (driver/run.cpp).
  if (!opt.quiet)
    for (std::size_t w = problem_warnings; w < pb.warnings.size(); ++w)
      std::cerr << "mpm: warning: " << pb.warnings[w] << "\n";

  // Outputs start once the input has passed every check above. Only rank 0 writes: when it
  // cannot (its directory), every rank stops with its message.
  agreed([&] { out_.emplace(opt, settings, config_text, pb); });
  RunResult& res = res_;
  res.benchmark = pb.benchmark;
  res.warnings = pb.warnings;
  res.bodies = pb.bodies;
  res.dim = Dim;
  res.cells = sim.grid.num_cells();
  res.h = sim.grid.h.maxCoeff();
  if constexpr (Dim == 2)
    if (pb.mesh) {
      // A mesh from a file: its own size, not its bounding box's cells (which only sort the
      // particles and draw the outputs), so that a study over meshes gets its orders.
      res.cells = pb.mesh->num_cells();
      res.h = 0.0;
      for (Index c = 0; c < pb.mesh->num_cells(); ++c) {
        const auto& t = pb.mesh->cell_vertices(c);
        for (std::size_t i = 0; i < 3; ++i)
          res.h = std::max(res.h, (pb.mesh->vertex(t[(i + 1) % 3]) - pb.mesh->vertex(t[i])).norm());
      }
    }
  res.cell_size.assign(sim.grid.h.data(), sim.grid.h.data() + Dim);
  res.particles = comm_ ? comm_->sum(sim.particles.size()) : sim.particles.size();
  worst_imbalance_ = comm_ ? imbalance(sim, *comm_) : 0.0;
  // (A distributed restart reads only some pieces on each process: a damaged one stops all.)
  Index start = 0;
  if (opt.restart)
    agreed([&] {
      start = restore<Dim>(opt, ts.dt, *stepper_, mapping_name_, reference_, comm_, part_,
                           settings.parallel.blocks, res.particles);
    });
  if (opt.restart) out_->resume(*opt.restart);  // (collective)
  loop_.emplace(settings, opt, *out_, start,
                typename TimeLoop<Dim>::Hooks{
                    [this](Index s) { advance(s); },
                    [this] {
                      if (reference_) reference_->step(settings_.time.dt);
                    },
                    [this] {
                      RunState<Dim>& st = stepper_->state();
                      return StateView<Dim>{st.particles, st.time, st.materials, &st.diag};
                    },
                    [this](Index) { save(); }},
                res);
}

template <int Dim>
void MpmRun<Dim>::advance(Index s) {
  RunState<Dim>& sim = stepper_->state();
  const TimeSettings& ts = settings_.time;
  stepper_->step(ts.dt);
  sim.step = s + 1;
  sim.time = static_cast<double>(sim.step) * ts.dt;
  if (comm_) {
    stepper_->export_carried();
    migrated_ += migrate(sim, part_, *comm_);
    if (settings_.parallel.rebalance > 0.0) {
      // (The imbalance the run has reached before any re-cut, for the summary.)
      double measured = 0.0;
      rebalances_ +=
          rebalance_if_due(sim, part_, *comm_, settings_.parallel.rebalance, migrated_, measured);
      worst_imbalance_ = std::max(worst_imbalance_, measured);
    }
    stepper_->resize_particle_caches();
  }
  // Re-sorting for the next step, timed with this one. Here rather than before the step:
  // the decision reads this step's chunk ranges, and a checkpoint written after the step
  // (also the last one of a shortened run) holds the sorted state, so a restart repeats it.
  const Index sorts = sim.sorting.sorts;
  const auto t0 = Clock::now();
  if (stepper_->sort_if_due()) {
    res_.sort_seconds += seconds_since(t0);
    res_.sorts += sim.sorting.sorts - sorts;
  }
}

template <int Dim>
void MpmRun<Dim>::save() {
  Captured<Dim> cap =
      capture<Dim>(*stepper_, mapping_name_, reference_, *out_, config_text_, comm_, part_);
  cap.manifest.mesh_hash = opt_.mesh_hash;
  out_->checkpoint(cap.manifest, cap.piece ? &*cap.piece : nullptr);
}

template <int Dim>
RunResult MpmRun<Dim>::finish() {
  loop_->finish();
  RunState<Dim>& sim = stepper_->state();
  const MethodSettings& method = settings_.method;
  const BasisKind& basis = method.basis;
  RunResult& res = res_;
  if (res.exit_code == exit_code::kOk) {
    res.errors = error_norms<Dim>(sim.particles, sim.grid, pb_.exact, sim.time, settings_.time.dt,
                                  scheme_velocity_time_, boundary_cells(basis), comm_);
    if constexpr (Dim == 1)
      if (reference_) reference_errors(sim.particles, *reference_, res.errors);
    check_error_norms(res);
  }
  res.diag = sim.diag;
  nlohmann::ordered_json mpi_json;
  // Resident memory at its peak [bytes] (-1: not known on this system): the process's on one,
  // the most of one process on several (each process's in "mpi").
  double peak_memory = peak_memory_bytes();
  if (comm_) {
    res.diag.grid_crossings = comm_->sum(res.diag.grid_crossings);
    const auto [window_first, window_end] = sim.nodes.window();
    // The DOFs this process shared with others at the last exchange of the grid sums.
    const std::vector<Index> shared = DofRanges::union_of(sim.shared.shared_by_peer(comm_->rank()));
    const std::vector<Index> counts = comm_->allgather(std::span<const Index>(std::array<Index, 6>{
        sim.particles.size(), migrated_, window_end - window_first, static_cast<Index>(peak_memory),
        static_cast<Index>(shared.size()), sim.ghosts.last_count}));
    std::vector<Index> per_rank, sent, window, memory, shared_dofs, ghosts;
    for (std::size_t r = 0; r < counts.size(); r += 6) {
      per_rank.push_back(counts[r]);
      sent.push_back(counts[r + 1]);
      window.push_back(counts[r + 2]);
      memory.push_back(counts[r + 3]);
      shared_dofs.push_back(counts[r + 4]);
      ghosts.push_back(counts[r + 5]);
    }
    peak_memory = static_cast<double>(*std::max_element(memory.begin(), memory.end()));
    nlohmann::ordered_json cuts_json = nlohmann::ordered_json::object();
    for (int d = 0; d < Dim; ++d)
      cuts_json[std::string(1, axis_name(d))] = part_.cuts[static_cast<std::size_t>(d)];
    mpi_json = {{"processes", comm_->size()},
                {"decomposition", part_.describe() + ", cut to balance the particles"},
                {"blocks", part_.procs},
                {"cuts", cuts_json},
                {"particles_per_process", per_rank},
                {"particles_sent_per_process", sent},
                {"rebalance_threshold", settings_.parallel.rebalance},
                {"rebalances", rebalances_},
                {"largest_imbalance", worst_imbalance_},
                // The grid arrays each process holds at the end (GridState's window) against
                // the basis's DOFs.
                {"grid_dofs", sim.nodes.size()},
                {"grid_window_dofs_per_process", window},
                // The DOFs each shared with other processes at the last exchange of the grid
                // sums (DofRanges: a slab's two sides; a block's faces, edges and corners).
                {"shared_dofs_per_process", shared_dofs},
                // The other processes' particles each held as ghosts at its last exchange of
                // them (a reconstruction's sums, DDMPM's node volumes; 0 without one): those
                // within the reach of the box of its particles' cells (append_ghosts).
                {"ghost_particles_per_process", ghosts},
                {"peak_memory_bytes_per_process", memory}};
  }
  res.wall_seconds = seconds_since(t_start_);

  nlohmann::ordered_json method_json = {
      {"solver", otm_       ? "otm"
                 : unified_ ? "unified"
                            : "mpm"},
      {"basis", std::string(basis_name(basis))},
      {"mapping", std::string(mapping_name_)},
      {"scheme", otm_       ? std::string("otm (D Algorithm 3)")
                 : unified_ ? std::string("unified (D Algorithm 4)")
                            : std::string(name_of(method.scheme))},
      {"mass", method.mass == MassType::Consistent ? "consistent" : "lumped"}};
  if (basis_degree(basis) > 0) method_json["degree"] = basis_degree(basis);
  if (method.mass == MassType::Consistent) {
    const MassSolverSettings& ms = method.mass_solver;
    method_json["mass_solver"] = ms.kind == MassSolver::Direct ? "direct"
                                 : ms.kind == MassSolver::Cg   ? "cg"
                                                               : "pmg";
    if (method.partial_lumping > 0.0) {
      // Active DOFs with lumped rows in the step with the most (a restart counts from there).
      method_json["partial_lumping"] = method.partial_lumping;
      method_json["partially_lumped_dofs_max"] = res.diag.max_lumped_dofs;
    }
    if (ms.kind != MassSolver::Direct) {
      method_json["mass_solver_tolerance"] = ms.tolerance;
      // CG iterations or V-cycles over the run and the most of one solve (a restart counts
      // from the restart).
      method_json["mass_solver_iterations"] = res.diag.mass_solver_iterations;
      method_json["mass_solver_max_iterations_per_solve"] = res.diag.max_mass_solver_iterations;
    }
  }
  res.summary = make_summary(res, settings_, sim.materials, sim.time, std::move(method_json),
                             scheme_velocity_time_);
  stepper_->report(res.summary);
  res.summary["peak_memory_bytes"] = peak_memory;
  if (comm_) res.summary["mpi"] = std::move(mpi_json);
  if (reference_)
    res.summary["reference"] = {{"solver", "ulfem"},
                                {"dofs", settings_.reference_dofs},
                                {"compared", "stress at the particles' material positions"}};
  out_->summary(res.summary);
  out_->close();
  return res;
}

}  // namespace

template <int Dim>
std::unique_ptr<SolverRun> start_mpm(Problem<Dim>& pb, const RunSettings& settings,
                                     const std::string& config_text, const RunOptions& opt) {
  return std::make_unique<MpmRun<Dim>>(pb, settings, config_text, opt);
}

template std::unique_ptr<SolverRun> start_mpm<1>(Problem<1>&, const RunSettings&,
                                                 const std::string&, const RunOptions&);
template std::unique_ptr<SolverRun> start_mpm<2>(Problem<2>&, const RunSettings&,
                                                 const std::string&, const RunOptions&);
template std::unique_ptr<SolverRun> start_mpm<3>(Problem<3>&, const RunSettings&,
                                                 const std::string&, const RunOptions&);

}  // namespace mpm::driver
