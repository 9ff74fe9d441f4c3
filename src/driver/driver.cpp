#include "driver/driver.hpp"

#include <fmt/ranges.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numeric>
#include <span>
#include <utility>

#include "core/comm_file.hpp"
#include "io/checkpoint.hpp"
#include "mpm/version.hpp"

namespace mpm::driver {

template <int Dim>
ErrorNorms error_norms(const Particles<Dim>& P, const Grid<Dim>& grid,
                       const ExactSolution<Dim>& exact, double t, double dt, double velocity_time,
                       int boundary_cells, const Comm* comm) {
  ErrorNorms e;
  if (!exact) return e;
  // (A rank of a distributed run without particles still takes part in the sums.)
  if (comm == nullptr && P.x.empty()) return e;
  IVec<Dim> first = grid.cells, last;
  last.fill(-1);
  for (const auto& X : P.x0)
    for (int d = 0; d < Dim; ++d) {
      const Index c = grid.cell_of(X[d], d);
      first[d] = std::min(first[d], c);
      last[d] = std::max(last[d], c);
    }
  if (comm)
    for (int d = 0; d < Dim; ++d) {
      first[d] = static_cast<Index>(comm->min(static_cast<double>(first[d])));
      last[d] = static_cast<Index>(comm->max(static_cast<double>(last[d])));
    }
  double su = 0, sv = 0, svm = 0, svs = 0, ss = 0, num = 0, den = 0;
  double iu = 0, ivs = 0, is = 0, in = 0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const auto ex = exact(P.x0[i], t);
    const double eu = (ex.u - P.displacement(i)).squaredNorm();
    sv += (ex.v - P.v[i]).squaredNorm();
    svm += (exact(P.x0[i], t - 0.5 * dt).v - P.v[i]).squaredNorm();
    const double evs = (exact(P.x0[i], t + velocity_time * dt).v - P.v[i]).squaredNorm();
    const double es = (ex.stress - P.stress[i]).squaredNorm();
    su += eu;
    svs += evs;
    ss += es;
    num += P.volume0[i] * es;
    den += P.volume0[i] * ex.stress.squaredNorm();
    bool interior = true;
    for (int d = 0; d < Dim; ++d) {
      const Index c = grid.cell_of(P.x0[i][d], d);
      interior = interior && c >= first[d] + boundary_cells && c <= last[d] - boundary_cells;
    }
    if (interior) {
      iu += eu;
      ivs += evs;
      is += es;
      in += 1.0;
    }
  }
  double n = static_cast<double>(P.x.size());
  double computed = 0.0;
  for (std::size_t i = 0; i < P.x.size(); ++i) computed += P.volume0[i] * P.stress[i].squaredNorm();
  if (comm) {
    std::array<double, 13> v{su, sv, svm, svs, ss, num, den, iu, ivs, is, in, n, computed};
    comm->sum(std::span<double>(v));
    su = v[0], sv = v[1], svm = v[2], svs = v[3], ss = v[4], num = v[5], den = v[6];
    iu = v[7], ivs = v[8], is = v[9], in = v[10], n = v[11], computed = v[12];
    if (n == 0.0) return e;
  }
  e.displacement_rms = std::sqrt(su / n);
  e.velocity_rms = std::sqrt(sv / n);
  e.velocity_rms_midstep = std::sqrt(svm / n);
  e.velocity_rms_scheme_time = std::sqrt(svs / n);
  e.stress_rms = std::sqrt(ss / n);
  // A relative norm needs a reference of some size: none when the exact stress vanishes at T
  // (below 1e-8 of the computed one, e.g. mms_1d at a full period).
  if (den > 1e-16 * computed && den > 0.0) e.stress_rel_l2 = std::sqrt(num / den);
  if (in > 0.0) {
    e.displacement_rms_interior = std::sqrt(iu / in);
    e.velocity_rms_scheme_time_interior = std::sqrt(ivs / in);
    e.stress_rms_interior = std::sqrt(is / in);
  }
  return e;
}

template <int Dim>
OutputSession<Dim>::OutputSession(const RunOptions& opt, const RunSettings& s,
                                  const std::string& config_text, const Problem<Dim>& pb)
    : dir_(opt.out_dir), exact_(pb.exact) {
  if (opt.comm != nullptr && opt.comm->distributed()) {
    comm_ = opt.comm;
    writer_ = comm_->root();
  }
  mapping_errors_ = s.method.solver == Solver::Mpm;
  // history.csv's columns, also those of the rows kept in memory (RunOptions::keep_history).
  keep_history_ = opt.keep_history;
  auto& cols = history_columns_;
  cols = {"time", "kinetic_energy", "strain_energy", "total_energy", "mass"};
  for (int d = 0; d < Dim; ++d) cols.push_back(fmt::format("momentum_{}", d + 1));
  // MPM: the relative mass and momentum errors of the step's latest mapping, grid sums
  // against particle sums (0 in the first row, before any mapping; D Tables 5.3, 5.5, 5.7
  // report their maxima, which summary.json has).
  if (mapping_errors_) cols.insert(cols.end(), {"mass_error", "momentum_error"});
  // output.reactions: the reaction [N; N/m in 2D] on each constrained boundary, per component
  // (0 in the first row, before any step).
  if (pb.reactions)
    for (const std::string& name : reaction_names(pb))
      for (int d = 0; d < Dim; ++d) {
        cols.push_back(fmt::format("reaction_{}_{}", name, "xyz"[d]));
        ++reaction_columns_;
      }
  history_header_ = fmt::format("{}\n", fmt::join(cols, ","));
  if (dir_.empty()) return;
  csv_ = s.output.csv;
  vtk_ = s.output.vtk;
  vtk_binary_ = s.output.vtk_binary;
  if (!writer_) return;
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec)
    throw InputError(
        fmt::format("cannot create output directory '{}': {}", dir_.string(), ec.message()));
  lock_ = io::DirectoryLock(dir_);
  // What an earlier run into this directory left when it was killed in a write.
  io::remove_stale_temporaries(dir_);
  // An earlier run's files would mix with this run's (frames beyond this run's last, a summary
  // of other parameters): refused, or removed with --overwrite. A restart continues them.
  if (!opt.restart) {
    const std::vector<std::string> earlier = io::run_files(dir_);
    if (!earlier.empty() && !opt.overwrite)
      throw InputError(fmt::format(
          "output directory '{}' holds an earlier run ({}{}); pass --overwrite to replace it, or "
          "choose another --out",
          dir_.string(),
          fmt::join(earlier.begin(),
                    earlier.begin() + std::min<std::ptrdiff_t>(4, std::ssize(earlier)), ", "),
          earlier.size() > 4 ? fmt::format(" and {} more", earlier.size() - 4) : ""));
    for (const std::string& name : earlier) {
      std::error_code rm;
      std::filesystem::remove(dir_ / name, rm);
      if (rm)
        throw InputError(fmt::format("--overwrite: cannot remove '{}': {}", (dir_ / name).string(),
                                     rm.message()));
    }
  }
  io::write_file_atomic(dir_ / "config.toml", config_text);
  if (vtk_) {
    // The background the basis lives on: the grid's cells, or their triangles.
    std::string grid = io::grid_vtu(pb.grid, {}, vtk_binary_);
    if constexpr (Dim == 2) {
      const std::optional<TrianglePattern> pattern = triangle_pattern(s.method.basis);
      if (pb.mesh)
        grid = io::triangle_mesh_vtu(*pb.mesh, {}, {}, vtk_binary_);
      else if (pattern)
        grid = io::triangle_mesh_vtu(
            structured_triangles(pb.grid.origin, pb.grid.upper(), pb.grid.cells, *pattern), {}, {},
            vtk_binary_);
    }
    io::write_file_atomic(dir_ / "grid.vtu", grid);
  }
}

template <int Dim>
template <class Write>
void OutputSession<Dim>::agreed(Write&& write) const {
  if (!comm_) {
    write();
    return;
  }
  std::optional<Comm::Failure> mine;
  try {
    write();
  } catch (const RemoteRunError&) {
    throw std::logic_error("OutputSession::agreed: a collective call inside a one-process write");
  } catch (const RunError& e) {
    mine = Comm::Failure{comm_->rank(), e.exit_code(), e.what()};
  }
  if (const auto f = comm_->agree(mine ? &*mine : nullptr))
    throw RemoteRunError(f->exit_code,
                         fmt::format("rank {} of {}: {}", f->rank, comm_->size(), f->message));
}

template <int Dim>
void OutputSession<Dim>::history_row(const StateView<Dim>& sim) {
  if (!enabled() && !keep_history_) return;
  const auto& P = sim.particles;
  double kin = 0.0, strain = 0.0, mass = 0.0;
  Vec<Dim> mom = Vec<Dim>::Zero();
  sim.materials.for_each_particle(
      P.material, 0, P.x.size(),
      [&](const auto& law, std::size_t, std::size_t offset, std::size_t i) {
        kin += 0.5 * P.mass[i] * P.v[i].squaredNorm();
        strain +=
            law.energy(P.stress[i], state_row<std::decay_t<decltype(law)>>(P.state, i, offset),
                       P.F[i], P.volume[i], P.volume0[i]);
        mass += P.mass[i];
        mom += P.mass[i] * P.v[i];
      });
  if (comm_) {
    // The sums over every rank's particles (rank order: the same bits in every run).
    comm_->check();
    std::array<double, 3 + Dim> v{kin, strain, mass};
    for (int d = 0; d < Dim; ++d) v[3 + static_cast<std::size_t>(d)] = mom[d];
    comm_->sum(std::span<double>(v));
    kin = v[0];
    strain = v[1];
    mass = v[2];
    for (int d = 0; d < Dim; ++d) mom[d] = v[3 + static_cast<std::size_t>(d)];
  }
  std::vector<double> values{sim.time, kin, strain, kin + strain, mass};
  for (int d = 0; d < Dim; ++d) values.push_back(mom[d]);
  if (mapping_errors_) {
    values.push_back(sim.diag ? sim.diag->rel_mass_error : 0.0);
    values.push_back(sim.diag ? sim.diag->rel_momentum_error : 0.0);
  }
  if (reaction_columns_ > 0) {
    const std::vector<double>* r = sim.diag ? &sim.diag->reactions : nullptr;
    if (r != nullptr && !r->empty() && r->size() != reaction_columns_)
      throw std::logic_error("history_row: reactions of another set of boundaries");
    for (std::size_t k = 0; k < reaction_columns_; ++k)
      values.push_back(r != nullptr && !r->empty() ? (*r)[k] : 0.0);
  }
  if (keep_history_) history_values_.insert(history_values_.end(), values.begin(), values.end());
  if (!enabled()) return;
  const std::string row = fmt::format("{:.17g}\n", fmt::join(values, ","));
  // Appended as the run goes (io::AppendFile): constant memory, and a killed run keeps every row
  // written so far. A fresh run starts the file with the header at its first row.
  agreed([&] {
    if (!writer_) return;
    if (!history_.is_open()) history_.open(dir_ / "history.csv", history_header_);
    history_.append(row, fmt::format("row {} (t = {:.6g} s)", history_rows_ + 1, sim.time));
    ++history_rows_;
  });
}

namespace {
// The exact solution at the particles as extra output columns: u_exact, v_exact, stress_exact in
// 1D; per component (u_exact_1, ..., stress_exact_12, ...) in more dimensions, like the particle
// columns. `values` holds the columns the fields point to.
template <int Dim>
std::vector<io::ScalarField> exact_fields(
    const ExactSolution<Dim>& exact, const Particles<Dim>& P, double t,
    std::array<std::vector<double>, 2 * Dim + Dim * Dim>& values) {
  std::vector<io::ScalarField> extra;
  if (!exact) return extra;
  constexpr int kFields = 2 * Dim + Dim * Dim;
  std::array<std::string, kFields> names;
  int k = 0;
  for (const char* f : {"u_exact", "v_exact"})
    for (int d = 0; d < Dim; ++d) names[k++] = Dim == 1 ? f : fmt::format("{}_{}", f, d + 1);
  for (int r = 0; r < Dim; ++r)
    for (int c = 0; c < Dim; ++c)
      names[k++] = Dim == 1 ? "stress_exact" : fmt::format("stress_exact_{}{}", r + 1, c + 1);
  for (auto& v : values) v.resize(P.x.size());
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const auto ex = exact(P.x0[i], t);
    for (int d = 0; d < Dim; ++d) {
      values[d][i] = ex.u[d];
      values[Dim + d][i] = ex.v[d];
    }
    for (int r = 0; r < Dim; ++r)
      for (int c = 0; c < Dim; ++c) values[2 * Dim + r * Dim + c][i] = ex.stress(r, c);
  }
  for (int f = 0; f < kFields; ++f) extra.push_back({names[f], &values[f]});
  return extra;
}

// In a run of several materials, each particle's material (its index in summary.json's
// "materials") as the column "material" after `extra`; `column` holds its values.
template <int Dim>
void add_material_field(const Materials& materials, const Particles<Dim>& P,
                        std::vector<double>& column, std::vector<io::ScalarField>& extra) {
  if (materials.size() < 2) return;
  column.assign(P.material.begin(), P.material.end());
  extra.push_back({"material", &column});
}

// A frame's VTU: the exact displacement and velocity (the first 2 Dim of exact_fields' columns)
// as vectors u_exact and v_exact like u and v, so that an error is one calculator line; the
// exact stress per component; in 2D the stress normal to the plane of the (plane-strain) law in
// the stress tensor's zz component.
template <int Dim>
std::string frame_vtu(const Particles<Dim>& P, double time,
                      const std::vector<io::ScalarField>& extra,
                      const std::array<std::vector<double>, 2 * Dim + Dim * Dim>& values,
                      const Materials& materials, bool binary) {
  const std::size_t n = P.x.size();
  std::vector<io::ScalarField> scalars;
  std::vector<double> material_column;
  std::array<std::vector<Vec<Dim>>, 2> uv;
  std::vector<io::VectorField<Dim>> vectors;
  if (!extra.empty()) {
    for (int k = 0; k < 2; ++k) {
      uv[k].resize(n);
      for (std::size_t i = 0; i < n; ++i)
        for (int d = 0; d < Dim; ++d)
          uv[k][i][d] = values[static_cast<std::size_t>(k * Dim + d)][i];
    }
    vectors = {{"u_exact", &uv[0]}, {"v_exact", &uv[1]}};
    scalars.assign(extra.begin() + 2 * Dim, extra.end());
  }
  std::vector<double> zz;
  if constexpr (Dim == 2) {
    zz.resize(n);
    materials.for_each_particle(
        P.material, 0, n, [&](const auto& law, std::size_t, std::size_t offset, std::size_t i) {
          using Law = std::decay_t<decltype(law)>;
          zz[i] = law.out_of_plane_stress(P.stress[i], state_row<Law>(P.state, i, offset), P.F[i]);
        });
  }
  add_material_field(materials, P, material_column, scalars);
  return io::particles_vtu(P, time, scalars, binary, vectors, Dim == 2 ? &zz : nullptr);
}
}  // namespace

// A distributed run's CSV frame, in id order, without any process holding more than its share
// of it: the ids are taken in rounds, each round's ids [first, end) cut into R equal ranges (R
// processes), one a process. In each round every process sends its particles of the round to
// the processes of their ranges, formats the rows of its own range in id order and appends them
// (core/comm_file.hpp: rank after rank, so the rows follow in id order). A round ends before the
// id where some process would send more than kRowsPerRound particles, and after at most
// R kRowsPerRound ids: no process sends, or formats, more than kRowsPerRound rows a round
// (about 0.3 kB a particle sent and 0.5 kB a row of text in 2D), beside its own particles;
// particles in slabs, whose ids follow the slabs, take about N / kRowsPerRound rounds, mixed
// ones down to N / (R kRowsPerRound). Collective.
template <int Dim>
void OutputSession<Dim>::write_distributed_csv(const std::filesystem::path& path,
                                               const Particles<Dim>& P, const Materials& materials,
                                               double time) {
  constexpr Index kRowsPerRound = Index{1} << 17;
  // Written under a temporary name (rank 0's pid: io::remove_stale_temporaries removes it after
  // a killed run), renamed by rank 0 once every process has written: a frame is whole or absent.
  if (root_pid_ < 0) {
    std::vector<std::byte> pid(sizeof(Index));
    const auto p = static_cast<Index>(::getpid());
    std::memcpy(pid.data(), &p, sizeof p);
    comm_->broadcast(pid, 0);
    std::memcpy(&root_pid_, pid.data(), sizeof root_pid_);
  }
  std::filesystem::path tmp = path;
  tmp += fmt::format(".tmp.{}", root_pid_);

  const auto ranks = static_cast<Index>(comm_->size());
  // The positions of a set of particles in id order (any ids: not particles_in_id_order's
  // 0 .. n-1).
  const auto id_order = [](const Particles<Dim>& Q) {
    std::vector<CompactIndex> order(Q.id.size());
    std::iota(order.begin(), order.end(), CompactIndex{0});
    std::sort(order.begin(), order.end(),
              [&](CompactIndex a, CompactIndex b) { return Q.id[a] < Q.id[b]; });
    return order;
  };
  // This process's particles in id order, walked round after round.
  const std::vector<CompactIndex> by_id = id_order(P);
  const auto id_at = [&](std::size_t k) { return static_cast<Index>(P.id[by_id[k]]); };
  std::array<std::vector<double>, 2 * Dim + Dim * Dim> values;
  std::vector<double> material_column;
  OrderedFile file(*comm_, tmp.string(), path.string());
  {
    const Particles<Dim> none = P.empty_like();  // the header line, rank 0's
    auto extra = exact_fields(exact_, none, time, values);
    add_material_field(materials, none, material_column, extra);
    file.append(comm_->root() ? io::particles_csv(none, extra, /*header=*/true) : std::string());
  }
  // (Ids are below 2^31: exact as doubles, the reductions' type.)
  constexpr double kNone = 1e300;
  const auto n = by_id.size();
  std::size_t next = 0;
  while (true) {
    // The round starts at the lowest id not yet written (none left: done).
    const double lowest = comm_->min(next < n ? static_cast<double>(id_at(next)) : kNone);
    if (lowest >= kNone) break;
    const auto first = static_cast<Index>(lowest);
    // The round's end: the first id a process cannot take any more, or R kRowsPerRound ids on.
    const auto k = next + static_cast<std::size_t>(kRowsPerRound);
    const double mine = k < n ? static_cast<double>(id_at(k)) : kNone;
    const Index end = std::min(static_cast<Index>(std::min(comm_->min(mine), 1e18)),
                               first + ranks * kRowsPerRound);
    std::vector<std::vector<std::byte>> send(static_cast<std::size_t>(ranks));
    for (; next < n && id_at(next) < end; ++next) {
      const Index r = (id_at(next) - first) * ranks / (end - first);
      P.pack(by_id[next], send[static_cast<std::size_t>(r)]);
    }
    Particles<Dim> mine_rows = P.empty_like();
    for (const auto& buf : comm_->alltoall(send)) mine_rows.unpack_append(buf);
    send.clear();
    Permutation perm;
    perm.order = id_order(mine_rows);
    mine_rows.for_each_field([&](auto& field) { perm.apply(field); });
    auto extra = exact_fields(exact_, mine_rows, time, values);
    add_material_field(materials, mine_rows, material_column, extra);
    file.append(io::particles_csv(mine_rows, extra, /*header=*/false));
  }
  if (const auto f = file.close()) {
    // The frame is absent, never partial (the earlier frames stay).
    std::error_code ec;
    if (writer_) std::filesystem::remove(tmp, ec);
    throw RemoteRunError(f->exit_code,
                         fmt::format("rank {} of {}: {}", f->rank, comm_->size(), f->message));
  }
  agreed([&] {
    if (!writer_) return;
    std::error_code ec;
    // Never renamed over what is not a regular file (a link: over its target).
    io::OutputTarget target;
    try {
      target = io::output_target(path);
      if (target.write_through)
        throw RunError(exit_code::kOutput,
                       fmt::format("cannot write '{}': it is a device; a distributed run writes "
                                   "its CSV frames into regular files only",
                                   path.string()));
    } catch (const RunError&) {
      std::filesystem::remove(tmp, ec);
      throw;
    }
    std::filesystem::rename(tmp, target.path, ec);
    if (ec) {
      std::filesystem::remove(tmp, ec);
      throw RunError(exit_code::kOutput, fmt::format("cannot write '{}': rename from {}: {}",
                                                     path.string(), tmp.string(), ec.message()));
    }
  });
}

template <int Dim>
void OutputSession<Dim>::frame(const StateView<Dim>& sim) {
  if (!enabled()) return;
  // Numbered before anything is written: a frame whose write fails on one process keeps its
  // number on every process (the next frame's CSV is one file that all of them open).
  const std::string stem = fmt::format("particles_{:05d}", frames_++);
  frame_times_.push_back(sim.time);
  std::array<std::vector<double>, 2 * Dim + Dim * Dim> values;
  if (comm_) {
    // A distributed run: the CSV frame first, which is collective (its failure is agreed), so
    // that a rank whose VTU write fails below leaves no other waiting in it. Each process
    // writes the rows of its range of ids, in id order, into the one file (MPI-IO; no process
    // gathers the body), then its VTU piece; rank 0 writes the .pvtu over the pieces.
    comm_->check();
    if (csv_) write_distributed_csv(dir_ / (stem + ".csv"), sim.particles, sim.materials, sim.time);
    if (vtk_) {
      const auto extra = exact_fields(exact_, sim.particles, sim.time, values);
      const std::string piece =
          frame_vtu(sim.particles, sim.time, extra, values, sim.materials, vtk_binary_);
      // Every piece on disk (agreed) before rank 0 writes the .pvtu that names them all.
      agreed([&] {
        io::write_file_atomic(dir_ / fmt::format("{}_p{:04d}.vtu", stem, comm_->rank()), piece);
      });
      agreed([&] {
        if (!writer_) return;
        std::vector<std::string> sources;
        for (int r = 0; r < comm_->size(); ++r)
          sources.push_back(fmt::format("{}_p{:04d}.vtu", stem, r));
        io::write_file_atomic(dir_ / (stem + ".pvtu"), io::particles_pvtu(piece, sources));
        pvd_.add(sim.time, stem + ".pvtu");
        io::write_file_atomic(dir_ / "particles.pvd", pvd_.str());
      });
    }
    return;
  }
  // In id order, whatever order re-sorting (state/sort.hpp) left them in.
  std::optional<Particles<Dim>> ordered;
  if (!sim.particles.in_id_order()) ordered = particles_in_id_order(sim.particles);
  const Particles<Dim>& P = ordered ? *ordered : sim.particles;
  const auto extra = exact_fields(exact_, P, sim.time, values);
  if (csv_) {
    auto columns = extra;
    std::vector<double> material_column;
    add_material_field(sim.materials, P, material_column, columns);
    io::write_file_atomic(dir_ / (stem + ".csv"), io::particles_csv(P, columns));
  }
  if (vtk_) {
    io::write_file_atomic(dir_ / (stem + ".vtu"),
                          frame_vtu(P, sim.time, extra, values, sim.materials, vtk_binary_));
    pvd_.add(sim.time, stem + ".vtu");
    io::write_file_atomic(dir_ / "particles.pvd", pvd_.str());
  }
}

template <int Dim>
void OutputSession<Dim>::summary(const nlohmann::ordered_json& j) {
  if (!enabled()) return;
  agreed([&] {
    if (!writer_) return;
    try {
      io::write_file_atomic(dir_ / "summary.json", j.dump(2) + "\n");
    } catch (const RunError& e) {
      // The failure that stopped the run (often the first write a full disk refused) comes
      // first; the summary that could not record it second.
      if (!j.contains("failure")) throw;
      throw RunError(j.value("exit_code", e.exit_code()),
                     fmt::format("{}; and its failed summary could not be written either: {}",
                                 j["failure"].get<std::string>(), e.what()));
    }
  });
}

template <int Dim>
void OutputSession<Dim>::resume(const io::Checkpoint& c) {
  // history.csv continues: the rows of the earlier run up to the checkpoint's time are kept (a
  // run killed after its last checkpoint may have written later ones), and the restarted run
  // appends the steps after it, so the file is that of an uninterrupted run. A file with another
  // header (another run, another version) or none is started anew, from the checkpoint's row.
  if (enabled())
    agreed([&] {
      if (!writer_) return;
      std::string kept = history_header_;
      std::ifstream in(dir_ / "history.csv");
      std::string line;
      if (in && std::getline(in, line) && line + "\n" == history_header_) {
        while (std::getline(in, line)) {
          if (in.eof()) break;  // a last line without its newline: cut off by a kill
          const double t = std::strtod(line.c_str(), nullptr);
          if (!(t <= c.time)) break;
          kept += line + "\n";
          ++history_rows_;
          history_continues_ = true;
        }
      }
      history_.open(dir_ / "history.csv", kept);
    });
  // Whether the next row is written is decided by every rank alike (history_row is collective).
  if (comm_ && enabled()) history_continues_ = comm_->any(history_continues_);
  frames_ = static_cast<int>(c.frames);
  frame_times_ = c.frame_times;
  // (A frame of a distributed run is a .pvtu over its pieces.)
  if (vtk_)
    for (std::size_t k = 0; k < frame_times_.size(); ++k) {
      const std::string stem = fmt::format("particles_{:05d}", k);
      pvd_.add(frame_times_[k],
               std::filesystem::exists(dir_ / (stem + ".pvtu")) ? stem + ".pvtu" : stem + ".vtu");
    }
}
template <int Dim>
void OutputSession<Dim>::checkpoint(io::Checkpoint& c, const std::string* piece) {
  if (!enabled()) return;
  if (comm_ && piece) {
    // Every process writes its piece; once all are on disk (a process whose write failed stops
    // every one, agreed), rank 0 writes the manifest naming them. Until it has, the previous
    // manifest and its pieces are the checkpoint, whole: the pieces are named by their step.
    const std::string name = io::checkpoint_piece_name(c.step, comm_->rank());
    agreed([&] { io::write_file_atomic(dir_ / name, *piece); });
    const io::Checkpoint::Piece mine = io::describe_piece(name, *piece);
    const std::vector<Index> all = comm_->allgather(std::span<const Index>(
        std::array<Index, 2>{static_cast<Index>(mine.bytes), std::bit_cast<Index>(mine.hash)}));
    c.pieces.clear();
    for (int r = 0; r < comm_->size() && writer_; ++r)
      c.pieces.push_back({io::checkpoint_piece_name(c.step, r),
                          static_cast<std::uint64_t>(all[2 * static_cast<std::size_t>(r)]),
                          std::bit_cast<std::uint64_t>(all[2 * static_cast<std::size_t>(r) + 1])});
  }
  agreed([&] {
    if (!writer_) return;
    io::write_checkpoint(dir_ / io::kCheckpointFile, c);
    // The pieces of an earlier checkpoint (also those a run on another number of processes, or
    // a distributed run before this one-process restart, left), no longer named by the manifest.
    std::vector<std::string> keep;
    for (const auto& p : c.pieces) keep.push_back(p.file);
    io::remove_checkpoint_pieces(dir_, keep);
  });
}

// Stops before the first step when dt exceeds the limit, unless time.allow_unstable.
void check_stability(const TimeSettings& time, double h, const Materials& materials, double factor,
                     int dim, std::string_view what) {
  const double c = materials.max_wave_speed();
  const double limit = factor * h / (c * std::sqrt(static_cast<double>(dim)));
  if (time.dt > limit && !time.allow_unstable)
    throw InputError(fmt::format(
        "{}: time.dt = {:.6g} s exceeds the explicit stability limit {:.6g} s = {:.4g} h / c "
        "(h = {:.6g} m, c = {:.6g} m/s{}, {}); reduce time.dt or set time.allow_unstable = true",
        time.where_dt, time.dt, limit, factor, h, c,
        materials.size() > 1 ? " of the stiffest material" : "", what));
}

nlohmann::ordered_json make_summary(const RunResult& res, const RunSettings& settings,
                                    const Materials& materials, double t_end,
                                    nlohmann::ordered_json method, double velocity_time) {
  nlohmann::ordered_json j;
  j["mpmlab_version"] = kVersion;
  j["status"] = res.exit_code == exit_code::kOk            ? "ok"
                : res.exit_code == exit_code::kInterrupted ? "interrupted"
                                                           : "failed";
  if (res.exit_code != exit_code::kOk) {
    j["exit_code"] = res.exit_code;
    j["failure"] = res.failure;
  }
  j["benchmark"] = res.benchmark;
  if (!res.warnings.empty()) j["warnings"] = res.warnings;
  j["dim"] = res.dim;
  j["method"] = std::move(method);
  // Each material's law and parameters as configured: [material] as "material" and, in a run of
  // several, every one (with its name) under "materials", in the order of their indices.
  const auto material_json = [&](std::size_t k) {
    const MaterialSettings& ms = settings.materials.at(k);
    nlohmann::ordered_json m = {{"model", std::string(material_name(materials[k]))},
                                {"density", ms.elastic.density},
                                {"youngs_modulus", ms.elastic.youngs_modulus},
                                {"poisson_ratio", ms.elastic.poisson_ratio}};
    for (const MaterialParameterValue& p : ms.parameters) {
      if (p.choice.empty())
        m[p.name] = p.value;
      else
        m[p.name] = p.choice;
    }
    return m;
  };
  j["material"] = material_json(0);
  if (materials.size() > 1) {
    j["materials"] = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < materials.size(); ++k) {
      nlohmann::ordered_json m = {{"name", materials.name(k)}, {"index", k}};
      m.update(material_json(k));
      j["materials"].push_back(std::move(m));
    }
  }
  // A custom problem's bodies, when several ([body.NAME]): each one's table, source and the
  // range of its particles' ids (to tell them apart in the frames).
  if (!res.bodies.empty()) {
    j["bodies"] = nlohmann::ordered_json::array();
    for (const BodyRange& b : res.bodies)
      j["bodies"].push_back({{"table", b.table},
                             {"source", b.source},
                             {"first_id", b.first_id},
                             {"particles", b.count}});
  }
  j["cells"] = res.cells;
  j["h"] = res.h;
  if (res.cell_size.size() > 1) j["cell_size"] = res.cell_size;
  j["particles"] = res.particles;
  j["dt"] = settings.time.dt;
  j["t_end"] = t_end;
  j["steps"] = res.steps;
  j["velocity_time_offset_dt"] = velocity_time;
  j["wall_seconds"] = res.wall_seconds;
  // The threads the run used and OpenMP's wait policy (passive unless the user chose otherwise:
  // app/main.cpp): what the timings were taken with.
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  j["openmp"] = {{"threads", omp_get_max_threads()},
                 {"wait_policy", policy ? std::string(policy) : std::string("(default)")}};
  j["ns_per_particle_step"] = res.ns_per_particle_step;
  j["sorts"] = res.sorts;
  j["errors"] = {
      {"displacement_rms", opt_json(res.errors.displacement_rms)},
      {"velocity_rms", opt_json(res.errors.velocity_rms)},
      {"velocity_rms_midstep", opt_json(res.errors.velocity_rms_midstep)},
      {"velocity_rms_scheme_time", opt_json(res.errors.velocity_rms_scheme_time)},
      {"stress_rms", opt_json(res.errors.stress_rms)},
      {"stress_rel_l2", opt_json(res.errors.stress_rel_l2)},
      {"displacement_rms_interior", opt_json(res.errors.displacement_rms_interior)},
      {"velocity_rms_scheme_time_interior", opt_json(res.errors.velocity_rms_scheme_time_interior)},
      {"stress_rms_interior", opt_json(res.errors.stress_rms_interior)}};
  // Two readings of "the error" of a run (D's tables do not say which they give): the largest
  // over the steps, and that of the final step's mapping. The momentum error's denominator
  // sum m_p |v_p| nears zero when the whole body turns round (the column near t = 0.2 s and
  // 0.4 s), where the first reading is dominated by it.
  j["conservation"] = {{"max_rel_mass_error", res.diag.max_rel_mass_error},
                       {"max_rel_momentum_error", res.diag.max_rel_momentum_error},
                       {"final_rel_mass_error", res.diag.rel_mass_error},
                       {"final_rel_momentum_error", res.diag.rel_momentum_error}};
  j["grid_crossings"] = res.diag.grid_crossings;
  return j;
}

void check_error_norms(RunResult& res) {
  if (res.exit_code != exit_code::kOk) return;
  const ErrorNorms& e = res.errors;
  std::string bad;
  for (const auto& [name, value] :
       {std::pair{"displacement_rms", e.displacement_rms},
        std::pair{"velocity_rms", e.velocity_rms}, std::pair{"stress_rms", e.stress_rms},
        std::pair{"stress_rel_l2", e.stress_rel_l2},
        std::pair{"velocity_rms_midstep", e.velocity_rms_midstep},
        std::pair{"velocity_rms_scheme_time", e.velocity_rms_scheme_time}})
    if (value && !std::isfinite(*value)) bad += fmt::format("{}{}", bad.empty() ? "" : ", ", name);
  if (bad.empty()) return;
  res.exit_code = exit_code::kNonFinite;
  res.failure = fmt::format(
      "the error norms {} are not finite: the exact solution is not finite at some particle at "
      "t = T (check the exact.* expressions)",
      bad);
}

void reference_errors(const Particles<1>& P, const Ulfem1D& ref, ErrorNorms& e) {
  double ss = 0, num = 0, den = 0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const double sr = ref.stress_at(P.x0[i][0]);
    const double d = P.stress[i](0, 0) - sr;
    ss += d * d;
    num += P.volume0[i] * d * d;
    den += P.volume0[i] * sr * sr;
  }
  e.stress_rms = std::sqrt(ss / static_cast<double>(P.x.size()));
  if (den > 0.0) e.stress_rel_l2 = std::sqrt(num / den);
}

template <int Dim>
TimeLoop<Dim>::TimeLoop(const RunSettings& settings, const RunOptions& opt, OutputSession<Dim>& out,
                        Index start, Hooks hooks, RunResult& res)
    : settings_(settings),
      out_(out),
      hooks_(std::move(hooks)),
      res_(res),
      progress_(!opt.quiet, settings.time.steps, res.particles, start),
      start_(start),
      step_(start) {
  const TimeSettings& ts = settings.time;
  if (start > ts.steps)
    throw InputError(
        fmt::format("{}: the checkpoint is at step {}, beyond time.end = {} ({} steps of time.dt)",
                    ts.where_end, start, ts.end, ts.steps));
  while (next_frame_ <= settings.output.frames && start >= frame_step(next_frame_)) ++next_frame_;
  try {
    if (start == 0 || !out.history_continues()) out.history_row(hooks_.view());
    if (start == 0) out.frame(hooks_.view());
  } catch (const RunError& e) {
    fail(e);
  }
}

template <int Dim>
Index TimeLoop<Dim>::frame_step(Index k) const {
  const Index steps = settings_.time.steps;
  const int frames = settings_.output.frames;
  return frames > 0 ? (k * steps + frames - 1) / frames : steps;
}

template <int Dim>
bool TimeLoop<Dim>::advance_to(Index to) {
  const Index steps = settings_.time.steps;
  const int frames = settings_.output.frames;
  const Index history_every = settings_.output.history_every;
  const Index checkpoint_every = settings_.output.checkpoint_every;
  to = std::min(to, steps);
  try {
    while (!stopped_ && step_ < to) {
      const auto t0 = Clock::now();
      hooks_.advance(step_);
      const double seconds = seconds_since(t0);
      step_seconds_ += seconds;
      if (step_ == start_) res_.first_step_seconds = seconds;
      ++step_;
      hooks_.after();
      const bool last = step_ == steps;
      wrote_row_ = step_ % history_every == 0 || last;
      wrote_frame_ = last || (frames > 0 && step_ >= frame_step(next_frame_));
      wrote_checkpoint_ = checkpoint_every > 0 && step_ % checkpoint_every == 0;
      if (wrote_row_) out_.history_row(hooks_.view());
      if (wrote_frame_) {
        while (next_frame_ <= frames && step_ >= frame_step(next_frame_)) ++next_frame_;
        out_.frame(hooks_.view());
      }
      if (wrote_checkpoint_) hooks_.save(step_);
      progress_.update(step_, hooks_.view().time);
      int sig = interrupt_signal();
      if (const Comm* comm = out_.comm()) {
        // Every rank ends after the same step: a signal that reached any of them ends them all,
        // each recording the signal it was (the highest number if several came).
        comm->check();
        sig = static_cast<int>(comm->max(static_cast<double>(sig)));
      }
      if (sig != 0 && !last) {
        // A signal (core/interrupt.hpp): the state after this step, complete, ends the run.
        res_.exit_code = exit_code::kInterrupted;
        res_.failure = fmt::format("interrupted by {} after step {} of {} (t = {:.6g} s)",
                                   signal_name(sig), step_, steps, hooks_.view().time);
        stopped_ = true;
        write_final_state();
      }
    }
  } catch (const RunError& e) {
    fail(e);
  }
  return running();
}

template <int Dim>
void TimeLoop<Dim>::write_final_state() {
  if (!wrote_row_) out_.history_row(hooks_.view());
  if (!wrote_frame_) out_.frame(hooks_.view());
  if (settings_.output.checkpoint_every > 0 && !wrote_checkpoint_) hooks_.save(step_);
}

template <int Dim>
void TimeLoop<Dim>::stop(const std::string& why) {
  if (!running()) return;
  res_.exit_code = exit_code::kInterrupted;
  res_.failure = why;
  stopped_ = true;
  try {
    write_final_state();
  } catch (const RunError& e) {
    fail(e);
  }
}

template <int Dim>
void TimeLoop<Dim>::fail(const RunError& e) {
  stopped_ = true;
  res_.exit_code = e.exit_code();
  res_.failure = e.what();
  // A distributed run: a failure met on this rank is told to the others, which wait for it at
  // their next collective operation (Comm::check); every rank reports the lowest failing one.
  if (const Comm* comm = out_.comm(); comm && !dynamic_cast<const RemoteRunError*>(&e)) {
    const Comm::Failure mine{comm->rank(), e.exit_code(), e.what()};
    const Comm::Failure first = *comm->agree(&mine);
    res_.exit_code = first.exit_code;
    res_.failure = fmt::format("rank {} of {}: {}", first.rank, comm->size(), first.message);
  }
  try {
    out_.history_row(hooks_.view());
    out_.frame(hooks_.view());  // the state the failure was detected in, for diagnosis
  } catch (const RunError&) {
    // An output failing again (a full disk): the failure above is what the summary reports.
  }
}

template <int Dim>
void TimeLoop<Dim>::finish() {
  progress_.finish();
  res_.steps = step_;
  const Index taken = step_ - start_;
  res_.ns_per_particle_step =
      taken > 0
          ? 1e9 * step_seconds_ / (static_cast<double>(taken) * static_cast<double>(res_.particles))
          : 0.0;
}

template class TimeLoop<1>;
template class TimeLoop<2>;
template class TimeLoop<3>;
template ErrorNorms error_norms<1>(const Particles<1>&, const Grid<1>&, const ExactSolution<1>&,
                                   double, double, double, int, const Comm*);
template ErrorNorms error_norms<2>(const Particles<2>&, const Grid<2>&, const ExactSolution<2>&,
                                   double, double, double, int, const Comm*);
template ErrorNorms error_norms<3>(const Particles<3>&, const Grid<3>&, const ExactSolution<3>&,
                                   double, double, double, int, const Comm*);
template class OutputSession<1>;
template class OutputSession<2>;
template class OutputSession<3>;

}  // namespace mpm::driver
