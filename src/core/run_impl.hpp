#pragma once
// The machinery of `mpm run` shared by the translation units that instantiate it: the time
// loop, outputs, error norms, checkpoints and run_typed<Dim, Basis, Mapping, Scheme>, the fully
// templated run of one method combination. Each dimension is instantiated in its own file
// (run_1d.cpp, run_2d.cpp) so that the builds run in parallel; run.cpp chooses the variants.
#include <unistd.h>

#include <fmt/format.h>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "benchmarks/problem.hpp"
#include "core/registry.hpp"
#include "core/run.hpp"
#include "core/variants.hpp"
#include "io/checkpoint.hpp"
#include "io/config.hpp"
#include "io/output.hpp"
#include "mapping/quadrature.hpp"
#include "mpm/version.hpp"
#include "solver/ulfem.hpp"

namespace mpm::run_detail {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Terminal progress for runs longer than a second: steps, simulated time, rate, time left.
class Progress {
 public:
  Progress(bool enabled, Index total, Index particles, Index start = 0)
      : enabled_(enabled),
        total_(total),
        particles_(particles),
        start_step_(start),
        tty_(isatty(STDERR_FILENO)) {}
  void update(Index step, double t) {
    if (!enabled_) return;
    const double el = seconds_since(start_);
    if (el < 1.0 || el - last_ < (tty_ ? 0.25 : 10.0)) return;
    last_ = el;
    const double rate = static_cast<double>(step - start_step_) / el;
    const double left = rate > 0 ? static_cast<double>(total_ - step) / rate : 0.0;
    std::cerr << fmt::format("{}step {}/{}  t = {:.4g} s  {:.3g} particle-steps/s  {:.0f} s left{}",
                             tty_ ? "\r" : "", step, total_, t,
                             rate * static_cast<double>(particles_), left, tty_ ? "   " : "\n");
    shown_ = true;
  }
  void finish() {
    if (shown_ && tty_) std::cerr << "\n";
  }

 private:
  bool enabled_;
  Index total_, particles_, start_step_;
  bool tty_;
  Clock::time_point start_ = Clock::now();
  double last_ = 0.0;
  bool shown_ = false;
};

// Error norms at the particles (D eq. 4.92; 001 eq. 43 in 2D, |.| the Euclidean or Frobenius
// norm). The interior norms leave out the particles whose initial position lies in the first or
// last `boundary_cells` grid cells occupied by the body in any direction, where boundary effects of
// some bases concentrate (D Fig. 5.10): one cell for nodal bases, p cells for B-splines of degree
// p, whose asymmetric end functions phi_0 .. phi_{p-1} of the open knot vector reach p cells into
// the domain.
template <int Dim>
ErrorNorms error_norms(const Particles<Dim>& P, const Grid<Dim>& grid,
                       const ExactSolution<Dim>& exact, double t, double dt, double velocity_time,
                       int boundary_cells) {
  ErrorNorms e;
  if (!exact || P.x.empty()) return e;
  IVec<Dim> first = grid.cells, last;
  last.fill(-1);
  for (const auto& X : P.x0)
    for (int d = 0; d < Dim; ++d) {
      const Index c = grid.cell_of(X[d], d);
      first[d] = std::min(first[d], c);
      last[d] = std::max(last[d], c);
    }
  double su = 0, sv = 0, svm = 0, svs = 0, ss = 0, num = 0, den = 0;
  double iu = 0, ivs = 0, is = 0, in = 0;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const auto ex = exact(P.x0[i], t);
    const double eu = (ex.u - P.u[i]).squaredNorm();
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
  const double n = static_cast<double>(P.x.size());
  e.displacement_rms = std::sqrt(su / n);
  e.velocity_rms = std::sqrt(sv / n);
  e.velocity_rms_midstep = std::sqrt(svm / n);
  e.velocity_rms_scheme_time = std::sqrt(svs / n);
  e.stress_rms = std::sqrt(ss / n);
  // A relative norm needs a reference of some size: none when the exact stress vanishes at T
  // (below 1e-8 of the computed one, e.g. mms_1d at a full period).
  double computed = 0.0;
  for (std::size_t i = 0; i < P.x.size(); ++i) computed += P.volume0[i] * P.stress[i].squaredNorm();
  if (den > 1e-16 * computed && den > 0.0) e.stress_rel_l2 = std::sqrt(num / den);
  if (in > 0.0) {
    e.displacement_rms_interior = std::sqrt(iu / in);
    e.velocity_rms_scheme_time_interior = std::sqrt(ivs / in);
    e.stress_rms_interior = std::sqrt(is / in);
  }
  return e;
}

inline nlohmann::ordered_json opt_json(const std::optional<double>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}

// Everything written into the output directory during a run.
template <int Dim>
class OutputSession {
 public:
  OutputSession(const RunOptions& opt, const Config& cfg, const Problem<Dim>& pb)
      : dir_(opt.out_dir), exact_(pb.exact) {
    if (dir_.empty()) return;
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec)
      throw InputError(
          fmt::format("cannot create output directory '{}': {}", dir_.string(), ec.message()));
    csv_ = cfg.get_bool("output.csv");
    vtk_ = cfg.get_bool("output.vtk");
    io::write_file_atomic(dir_ / "config.toml", cfg.to_toml());
    if (vtk_) io::write_file_atomic(dir_ / "grid.vtu", io::grid_vtu(pb.grid));
    history_ = "time,kinetic_energy,strain_energy,total_energy,mass";
    for (int d = 0; d < Dim; ++d) history_ += fmt::format(",momentum_{}", d + 1);
    // MPM: the relative mass and momentum errors of the step's latest mapping, grid sums
    // against particle sums (0 in the first row, before any mapping; D Tables 5.3, 5.5, 5.7
    // report their maxima, which summary.json has).
    mapping_errors_ = cfg.get_string("method.solver") == "mpm";
    if (mapping_errors_) history_ += ",mass_error,momentum_error";
    history_ += "\n";
  }

  bool enabled() const { return !dir_.empty(); }

  template <class Sim>
  void history_row(const Sim& sim) {
    if (!enabled()) return;
    const auto& P = sim.particles;
    double kin = 0.0, strain = 0.0, mass = 0.0;
    Vec<Dim> mom = Vec<Dim>::Zero();
    std::visit(
        [&](const auto& law) {
          for (std::size_t i = 0; i < P.x.size(); ++i) {
            kin += 0.5 * P.mass[i] * P.v[i].squaredNorm();
            strain += law.energy(P.stress[i], P.F[i], P.volume[i], P.volume0[i]);
            mass += P.mass[i];
            mom += P.mass[i] * P.v[i];
          }
        },
        sim.material);
    history_ += fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}", sim.time, kin, strain,
                            kin + strain, mass);
    for (int d = 0; d < Dim; ++d) history_ += fmt::format(",{:.17g}", mom[d]);
    if (mapping_errors_)
      history_ += sim.diag ? fmt::format(",{:.17g},{:.17g}", sim.diag->rel_mass_error,
                                         sim.diag->rel_momentum_error)
                           : ",0,0";
    history_ += "\n";
  }

  template <class Sim>
  void frame(const Sim& sim) {
    if (!enabled()) return;
    // In id order, whatever order re-sorting (scheme/sort.hpp) left them in.
    std::optional<Particles<Dim>> ordered;
    if (!sim.particles.in_id_order()) ordered = particles_in_id_order(sim.particles);
    const Particles<Dim>& P = ordered ? *ordered : sim.particles;
    // The exact solution at the particles: u_exact, v_exact, stress_exact in 1D; per component
    // (u_exact_1, ..., stress_exact_12, ...) in more dimensions, like the particle columns.
    std::vector<io::ScalarField> extra;
    constexpr int kFields = 2 * Dim + Dim * Dim;
    std::array<std::vector<double>, kFields> values;
    if (exact_) {
      std::array<std::string, kFields> names;
      int k = 0;
      for (const char* f : {"u_exact", "v_exact"})
        for (int d = 0; d < Dim; ++d) names[k++] = Dim == 1 ? f : fmt::format("{}_{}", f, d + 1);
      for (int r = 0; r < Dim; ++r)
        for (int c = 0; c < Dim; ++c)
          names[k++] = Dim == 1 ? "stress_exact" : fmt::format("stress_exact_{}{}", r + 1, c + 1);
      for (auto& v : values) v.resize(P.x.size());
      for (std::size_t i = 0; i < P.x.size(); ++i) {
        const auto ex = exact_(P.x0[i], sim.time);
        for (int d = 0; d < Dim; ++d) {
          values[d][i] = ex.u[d];
          values[Dim + d][i] = ex.v[d];
        }
        for (int r = 0; r < Dim; ++r)
          for (int c = 0; c < Dim; ++c) values[2 * Dim + r * Dim + c][i] = ex.stress(r, c);
      }
      for (int f = 0; f < kFields; ++f) extra.push_back({names[f], &values[f]});
    }
    frame_times_.push_back(sim.time);
    const std::string stem = fmt::format("particles_{:05d}", frames_);
    if (csv_) io::write_file_atomic(dir_ / (stem + ".csv"), io::particles_csv(P, extra));
    if (vtk_) {
      io::write_file_atomic(dir_ / (stem + ".vtu"), io::particles_vtu(P, sim.time, extra));
      pvd_.add(sim.time, stem + ".vtu");
      io::write_file_atomic(dir_ / "particles.pvd", pvd_.str());
    }
    io::write_file_atomic(dir_ / "history.csv", history_);
    ++frames_;
  }

  void summary(const nlohmann::ordered_json& j) {
    if (enabled()) io::write_file_atomic(dir_ / "summary.json", j.dump(2) + "\n");
  }

  // Checkpoints: the frames written so far, and continuing after a restart (numbering goes on;
  // particles.pvd lists the earlier frames again, history.csv starts anew).
  int frames() const { return frames_; }
  const std::vector<double>& frame_times() const { return frame_times_; }
  void resume(const io::Checkpoint& c) {
    frames_ = static_cast<int>(c.frames);
    frame_times_ = c.frame_times;
    if (vtk_)
      for (std::size_t k = 0; k < frame_times_.size(); ++k)
        pvd_.add(frame_times_[k], fmt::format("particles_{:05d}.vtu", k));
  }
  void checkpoint(const io::Checkpoint& c) {
    if (enabled()) io::write_checkpoint(dir_ / io::kCheckpointFile, c);
  }

 private:
  std::filesystem::path dir_;
  ExactSolution<Dim> exact_;
  bool csv_ = true, vtk_ = true;
  std::string history_;
  bool mapping_errors_ = false;  // history.csv has mass_error, momentum_error
  io::PvdSeries pvd_;
  int frames_ = 0;
  std::vector<double> frame_times_;
};

// Explicit stability (Euler-Cromer, lumped mass): dt <= 2 / omega_max, omega_max^2 bounded by
// Gershgorin's theorem on M_L^-1 K of a uniform 1D bar (E = rho = h = 1), so
// dt_crit = factor h / c. P1: factor 1 exactly (h / c). B-splines of degree p: computed from
// exact Gauss integrals of their stiffness and lumped mass over a grid of 4p + 4 cells (the
// small end functions of the open knot vector set the bound). GIMP, CPDI and DDMPM use the P1
// bound (their gradients are averages of P1's).
template <int P>
double bspline_stability_factor() {
  const Index n = 4 * P + 4;
  const Grid<1> g(Vec<1>(0.0), Vec<1>(static_cast<double>(n)), IVec<1>{n});
  const BSplineBasis<1, P> basis(g);
  const auto nd = static_cast<std::size_t>(basis.num_dofs());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(static_cast<Index>(nd), static_cast<Index>(nd));
  Eigen::VectorXd m = Eigen::VectorXd::Zero(static_cast<Index>(nd));
  const GaussRule rule = gauss_legendre(P + 1);
  typename BSplineBasis<1, P>::StencilT st;
  for (Index c = 0; c < n; ++c)
    for (std::size_t k = 0; k < rule.xi.size(); ++k) {
      basis.evaluate_point(Vec<1>(static_cast<double>(c) + 0.5 + 0.5 * rule.xi[k]), st);
      const double w = 0.5 * rule.w[k];
      for (int a = 0; a < st.kSize; ++a) {
        m[st.dof[a]] += w * st.w[a];
        for (int b = 0; b < st.kSize; ++b)
          K(st.dof[a], st.dof[b]) += w * st.grad[a][0] * st.grad[b][0];
      }
    }
  double omega2 = 0.0;
  for (Index i = 0; i < K.rows(); ++i) omega2 = std::max(omega2, K.row(i).cwiseAbs().sum() / m[i]);
  return 2.0 / std::sqrt(omega2);
}

template <class Basis>
double stability_factor() {
  if constexpr (requires { Basis::kDegree; })
    return bspline_stability_factor<Basis::kDegree>();
  else
    return 1.0;
}

// Stops before the first step when dt exceeds the limit, unless time.allow_unstable.
inline void check_stability(const Config& cfg, double dt, double h, const Material& material,
                            double factor, int dim, std::string_view what) {
  const double c = wave_speed(material);
  const double limit = factor * h / (c * std::sqrt(static_cast<double>(dim)));
  if (dt > limit && !cfg.get_bool("time.allow_unstable"))
    throw InputError(fmt::format(
        "{}: time.dt = {:.6g} s exceeds the explicit stability limit {:.6g} s = {:.4g} h / c "
        "(h = {:.6g} m, c = {:.6g} m/s, {}); reduce time.dt or set time.allow_unstable = true",
        cfg.where("time.dt"), dt, limit, factor, h, c, what));
}

// Before the first step: with method.tls_completion = "none" every element holding particles
// must support the Taylor basis on its own (D 5.2.3, 6.3.1); otherwise the run would stop at
// step 0, so the input is refused with what to change.
template <int Dim, class Mapping>
void check_reconstruction_input(const Config& cfg, const Grid<Dim>& grid, const Particles<Dim>& P,
                                const Mapping& mapping) {
  if constexpr (std::is_same_v<Mapping, TlsMapping>) {
    const TlsSettings& s = mapping.settings();
    if (s.completion != TlsCompletion::None) return;
    BasicTlsReconstruction<Dim> recon(s);
    const TlsReport& rep = recon.set_points(grid, P);
    if (rep.failed > 0)
      throw InputError(fmt::format(
          "{}: method.tls_completion = \"none\", but the initial particles cannot support {} "
          "Taylor terms in {} element(s): element {} has {} particle(s) (condition number "
          "{:.3g}, limit method.tls_max_condition = {:.3g}); seed more particles "
          "(particles.per_cell), use fewer terms (method.tls_terms) or set "
          "method.tls_completion = \"reduce\", \"virtual\" or \"neighbour\"",
          cfg.where("method.tls_completion"), s.terms_used(Dim), rep.failed,
          recon.describe(rep.failed_element), rep.failed_points, rep.failed_condition,
          s.max_condition));
  }
}

template <class Basis>
constexpr int boundary_cells() {
  if constexpr (requires { Basis::kDegree; })
    return Basis::kDegree;
  else
    return 1;
}

struct TimeSetup {
  double dt;
  Index steps;
};

inline TimeSetup time_setup(const Config& cfg) {
  const double dt = cfg.get_real("time.dt"), end = cfg.get_real("time.end");
  const double ratio = end / dt;
  const auto steps = static_cast<Index>(std::llround(ratio));
  if (steps < 1 || std::abs(ratio - static_cast<double>(steps)) > 1e-6 * std::max(1.0, ratio))
    throw InputError(fmt::format(
        "{}: time.end = {} must be a positive whole multiple of time.dt = {} (it is {:.6g} "
        "steps)",
        cfg.where("time.end"), end, dt, ratio));
  return {dt, steps};
}

// What the time loop sees of a solver's state: the particles (MPM) or element midpoints (FEM)
// with the time and the material, for history rows and frames.
template <int Dim>
struct StateView {
  const Particles<Dim>& particles;
  double time;
  const Material& material;
  // The MPM mapping's conservation errors (history.csv columns); null for other solvers.
  const Diagnostics* diag = nullptr;
};

// The time loop shared by every solver: `advance(s)` takes step s to s + 1 (timed; may throw
// RunError), `after()` runs untimed companions (the FEM reference), `view()` exposes the state.
// Writes history rows and frames, shows progress, and on a RunError keeps the failing state as
// the last frame and records the failure in `res`. `start`: the step the state is at (non-zero
// after a restart: no initial frame then). `save(step)` writes a checkpoint every
// output.checkpoint_every steps.
template <int Dim, class Advance, class After, class View, class Save>
void drive(const TimeSetup& ts, const Config& cfg, const RunOptions& opt, OutputSession<Dim>& out,
           Index start, Advance&& advance, After&& after, View&& view, Save&& save,
           RunResult& res) {
  const int frames = static_cast<int>(cfg.get_int("output.frames"));
  const Index history_every = cfg.get_int("output.history_every");
  const Index checkpoint_every = cfg.get_int("output.checkpoint_every");
  if (start > ts.steps)
    throw InputError(
        fmt::format("{}: the checkpoint is at step {}, beyond time.end = {} ({} steps of time.dt)",
                    cfg.where("time.end"), start, cfg.get_real("time.end"), ts.steps));
  Index next_frame = 1;
  auto frame_step = [&](Index k) {
    return frames > 0 ? (k * ts.steps + frames - 1) / frames : ts.steps;
  };
  while (next_frame <= frames && start >= frame_step(next_frame)) ++next_frame;
  out.history_row(view());
  if (start == 0) out.frame(view());
  Progress progress(!opt.quiet, ts.steps, res.particles, start);
  double step_seconds = 0.0;
  Index step = start;
  try {
    while (step < ts.steps) {
      const auto t0 = Clock::now();
      advance(step);
      step_seconds += seconds_since(t0);
      ++step;
      after();
      const bool last = step == ts.steps;
      if (step % history_every == 0 || last) out.history_row(view());
      if (last || (frames > 0 && step >= frame_step(next_frame))) {
        while (next_frame <= frames && step >= frame_step(next_frame)) ++next_frame;
        out.frame(view());
      }
      if (checkpoint_every > 0 && step % checkpoint_every == 0) save(step);
      progress.update(step, view().time);
    }
  } catch (const RunError& e) {
    res.exit_code = e.exit_code();
    res.failure = e.what();
    out.history_row(view());
    out.frame(view());  // the state the failure was detected in, for diagnosis
  }
  progress.finish();
  res.steps = step;
  const Index taken = step - start;
  res.ns_per_particle_step =
      taken > 0
          ? 1e9 * step_seconds / (static_cast<double>(taken) * static_cast<double>(res.particles))
          : 0.0;
}

// The fields of summary.json common to every solver; `method` describes the solver.
inline nlohmann::ordered_json make_summary(const RunResult& res, const Config& cfg,
                                           const Material& material, const TimeSetup& ts,
                                           double t_end, nlohmann::ordered_json method,
                                           double velocity_time) {
  nlohmann::ordered_json j;
  j["mpmlab_version"] = kVersion;
  j["status"] = res.exit_code == exit_code::kOk ? "ok" : "failed";
  if (res.exit_code != exit_code::kOk) {
    j["exit_code"] = res.exit_code;
    j["failure"] = res.failure;
  }
  j["benchmark"] = res.benchmark;
  j["dim"] = res.dim;
  j["method"] = std::move(method);
  j["material"] = {{"model", std::string(material_name(material))},
                   {"density", cfg.get_real("material.density")},
                   {"youngs_modulus", cfg.get_real("material.youngs_modulus")},
                   {"poisson_ratio", cfg.get_real("material.poisson_ratio")}};
  j["cells"] = res.cells;
  j["h"] = res.h;
  j["particles"] = res.particles;
  j["dt"] = ts.dt;
  j["t_end"] = t_end;
  j["steps"] = res.steps;
  j["velocity_time_offset_dt"] = velocity_time;
  j["wall_seconds"] = res.wall_seconds;
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
  j["conservation"] = {{"max_rel_mass_error", res.diag.max_rel_mass_error},
                       {"max_rel_momentum_error", res.diag.max_rel_momentum_error}};
  j["grid_crossings"] = res.diag.grid_crossings;
  return j;
}

// Stress errors of the particles against the FEM reference at their material positions
// (D 5.4.1: the large-deformation bar is compared with ULFEM, 120 DOFs).
inline void reference_errors(const Particles<1>& P, const Ulfem1D& ref, ErrorNorms& e) {
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

// The mapping built with its settings from the configuration (reconstruction mappings),
// validated for the problem's dimension.
template <int Dim, class Mapping>
Mapping make_mapping(const Config& cfg) {
  try {
    if constexpr (requires { Mapping::from_config(cfg); })
      return Mapping::from_config(cfg);
    else if constexpr (std::is_same_v<Mapping, TlsMapping>)
      return TlsMapping(tls_settings_from_config(cfg, Dim), Dim);
    else
      return Mapping{};
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", cfg.where("method.mapping"), e.what()));
  }
}

// Checkpoints (io/checkpoint.hpp). The state of an MPM run with its FEM reference: everything a
// step reads that an earlier step wrote (the grid quantities and stencils are rebuilt per step).
template <int Dim, class Sim>
io::Checkpoint capture(const Sim& sim, const std::optional<Ulfem1D>& reference,
                       const OutputSession<Dim>& out, const std::string& config) {
  io::Checkpoint c;
  c.config = config;
  c.solver = "mpm";
  c.dim = Dim;
  c.step = sim.step;
  c.time = sim.time;
  c.particles = io::pack_particles(sim.particles);
  c.cells.assign(sim.cell.begin(), sim.cell.end());
  c.sort_reference = sim.sorting.reference;
  c.sorts = sim.sorting.sorts;
  c.diag = sim.diag;
  if (reference) c.fem = io::pack_fem(reference->save());
  c.mapping = std::string(Sim::MappingT::kName);
  if constexpr (requires { io::encode_totals(sim.mapping.totals()); })
    c.mapping_totals = io::encode_totals(sim.mapping.totals());
  c.frames = out.frames();
  c.frame_times = out.frame_times();
  if constexpr (requires { sim.basis.corners(); })
    for (const auto& corners : sim.basis.corners())
      for (const auto& x : corners)
        for (int d = 0; d < Dim; ++d) c.basis_state.push_back(x[d]);
  return c;
}

// Puts the checkpoint's state into a freshly set-up run; returns the step it is at.
template <int Dim, class Sim>
Index restore(const RunOptions& opt, Sim& sim, std::optional<Ulfem1D>& reference,
              OutputSession<Dim>& out) {
  const io::Checkpoint& c = *opt.restart;
  const std::string what = fmt::format("checkpoint '{}'", opt.restart_name);
  if (c.solver != "mpm" || c.dim != Dim || c.mapping != Sim::MappingT::kName)
    throw InputError(
        fmt::format("{} holds a {} run ({}D, mapping {}), not this {}D mpm run with "
                    "mapping {}",
                    what, c.solver, c.dim, c.mapping, Dim, Sim::MappingT::kName));
  auto p = io::unpack_particles<Dim>(c.particles, what);
  if (p.size() != sim.particles.size() || c.cells.size() != sim.cell.size() ||
      reference.has_value() != c.fem.has_value())
    throw InputError(fmt::format("{} does not fit the problem: {} particles ({} set up){}", what,
                                 p.size(), sim.particles.size(),
                                 reference.has_value() != c.fem.has_value()
                                     ? ", FEM reference state missing or unexpected"
                                     : ""));
  sim.particles = std::move(p);
  sim.cell.assign(c.cells.begin(), c.cells.end());
  sim.sorting.reference = c.sort_reference;
  sim.sorting.sorts = c.sorts;
  sim.diag = c.diag;
  sim.step = c.step;
  sim.time = c.time;
  if (reference) reference->restore(io::unpack_fem(*c.fem, what));
  if constexpr (requires { io::encode_totals(sim.mapping.totals()); }) {
    auto t = sim.mapping.totals();
    io::decode_totals(c.mapping_totals, t);
    sim.mapping.set_totals(t);
  }
  if constexpr (requires { sim.basis.corners(); }) {
    // CPDI2: the tracked corners, 2^Dim per particle.
    using Corners = typename std::decay_t<decltype(sim.basis.corners())>::value_type;
    constexpr std::size_t kPer = std::tuple_size_v<Corners> * Dim;
    if (c.basis_state.size() != kPer * sim.particles.x.size())
      throw InputError(fmt::format("{} holds {} values of basis state; the {} basis needs {}", what,
                                   c.basis_state.size(), Sim::BasisT::kName,
                                   kPer * sim.particles.x.size()));
    std::vector<Corners> corners(sim.particles.x.size());
    std::size_t k = 0;
    for (auto& cs : corners)
      for (auto& x : cs)
        for (int d = 0; d < Dim; ++d) x[d] = c.basis_state[k++];
    sim.basis.set_corners(std::move(corners));
  }
  out.resume(c);
  return c.step;
}

template <int Dim, class Basis, class Mapping, class Scheme>
RunResult run_typed(Problem<Dim>& pb, const Config& cfg, const RunOptions& opt) {
  const auto t_start = Clock::now();
  const TimeSetup ts = time_setup(cfg);

  // The FEM reference of benchmarks without an exact solution, stepped alongside (untimed).
  std::optional<Ulfem1D> reference;
  if constexpr (Dim == 1)
    if (pb.fem_reference) reference.emplace(pb, cfg.get_int("reference.dofs") - 1);

  check_stability(cfg, ts.dt, pb.grid.h.minCoeff(), pb.material, stability_factor<Basis>(), Dim,
                  fmt::format("{} basis, lumped-mass bound", Basis::kName));

  if (opt.shuffle_seed != 0 && !opt.restart)
    shuffle_particles(pb.particles, pb.tractions, opt.shuffle_seed);
  using Sim = Simulation<Dim, Basis, Mapping>;
  Sim sim(pb.grid, Basis(pb.grid), make_mapping<Dim, Mapping>(cfg), std::move(pb.particles),
          pb.material);
  if (!opt.restart) check_reconstruction_input<Dim>(cfg, sim.grid, sim.particles, sim.mapping);
  sim.mass_type =
      cfg.get_string("method.mass") == "consistent" ? MassType::Consistent : MassType::Lumped;
  sim.mass_tolerance = cfg.get_real("method.mass_tolerance");
  sim.sorting.mode = cfg.get_string("method.sort") == "never" ? SortMode::Never : SortMode::Auto;
  for (const auto& f : pb.fixed_sides) sim.fix_side(f.direction, f.side, f.components);
  sim.body_force = pb.body_force;
  sim.tractions = pb.tractions;
  if (sim.body_force.fill) sim.body_force.fill(sim.particles, 0.0, sim.particles.body);

  // Outputs start once the input has passed every check above.
  OutputSession<Dim> out(opt, cfg, pb);
  RunResult res;
  res.benchmark = pb.benchmark;
  res.dim = Dim;
  res.cells = sim.grid.num_cells();
  res.h = sim.grid.h[0];
  res.particles = sim.particles.size();
  const Index start = opt.restart ? restore<Dim>(opt, sim, reference, out) : 0;
  const std::string config_text = cfg.to_toml();
  drive<Dim>(
      ts, cfg, opt, out, start,
      [&](Index s) {
        Scheme::step(sim, ts.dt);
        sim.step = s + 1;
        sim.time = static_cast<double>(sim.step) * ts.dt;
        // Re-sorting for the next step, timed with this one. Here rather than before the step:
        // the decision reads this step's chunk ranges, and a checkpoint written after the step
        // (also the last one of a shortened run) holds the sorted state, so a restart repeats it.
        const Index sorts = sim.sorting.sorts;
        const auto t0 = Clock::now();
        sort_particles_if_due(sim);
        if (sim.sorting.sorts != sorts) {
          res.sort_seconds += seconds_since(t0);
          res.sorts += sim.sorting.sorts - sorts;
        }
      },
      [&] {
        if (reference) reference->step(ts.dt);
      },
      [&] {
        return StateView<Dim>{sim.particles, sim.time, sim.material, &sim.diag};
      },
      [&](Index) { out.checkpoint(capture<Dim>(sim, reference, out, config_text)); }, res);

  if (res.exit_code == exit_code::kOk) {
    res.errors = error_norms<Dim>(sim.particles, sim.grid, pb.exact, sim.time, ts.dt,
                                  Scheme::kVelocityTime, boundary_cells<Basis>());
    if constexpr (Dim == 1)
      if (reference) reference_errors(sim.particles, *reference, res.errors);
  }
  res.diag = sim.diag;
  res.wall_seconds = seconds_since(t_start);

  nlohmann::ordered_json method = {{"solver", "mpm"},
                                   {"basis", std::string(Basis::kName)},
                                   {"mapping", std::string(Mapping::kName)},
                                   {"scheme", std::string(Scheme::kName)},
                                   {"mass", cfg.get_string("method.mass")}};
  if constexpr (requires { Basis::kDegree; }) method["degree"] = Basis::kDegree;
  res.summary =
      make_summary(res, cfg, sim.material, ts, sim.time, std::move(method), Scheme::kVelocityTime);
  if constexpr (std::is_same_v<Mapping, TlsMapping>) {
    // How often the TLS completions were needed over the run (D 5.2.3).
    const auto& t = sim.mapping.totals();
    res.summary["tls"] = {{"element_fits", t.active},
                          {"full", t.full},
                          {"reduced", t.reduced},
                          {"with_virtual", t.with_virtual},
                          {"with_neighbours", t.with_neighbours},
                          {"min_terms", t.min_terms},
                          {"max_condition", t.max_condition}};
  }
  if constexpr (std::is_same_v<Mapping, MlsMapping> || std::is_same_v<Mapping, ImlsMapping>) {
    // Where MLS moment matrices were ill-conditioned or IMLS dropped terms (001, 003).
    const auto& t = sim.mapping.totals();
    res.summary["mls"] = {{"degree", sim.mapping.settings().degree},
                          {"dilation", sim.mapping.settings().dilation},
                          {"evaluations", t.points},
                          {"empty_support", t.empty},
                          {"ill_conditioned", t.ill_conditioned},
                          {"singular", t.singular},
                          {"reduced", t.reduced},
                          {"widened", t.widened},
                          {"max_condition", t.max_condition},
                          {"worst_x", t.worst_x}};
    if constexpr (Dim == 2) res.summary["mls"]["worst_y"] = t.worst_y;
  }
  if (reference)
    res.summary["reference"] = {{"solver", "ulfem"},
                                {"dofs", cfg.get_int("reference.dofs")},
                                {"compared", "stress at the particles' material positions"}};
  out.summary(res.summary);
  return res;
}

// method.solver = "ulfem": the updated-Lagrangian FEM on the problem's body, one linear element

// The run of one problem of dimension Dim with the chosen variants (run_1d.cpp, run_2d.cpp):
// one std::visit into run_typed, with a clear error for a basis or mapping that does not exist
// in this dimension.
template <int Dim>
RunResult run_dim(Problem<Dim>& pb, const Config& cfg, const RunOptions& opt,
                  const BasisKind& basis, const MappingKind& mapping, const Scheme& scheme);
template <>
RunResult run_dim<1>(Problem<1>& pb, const Config& cfg, const RunOptions& opt,
                     const BasisKind& basis, const MappingKind& mapping, const Scheme& scheme);
template <>
RunResult run_dim<2>(Problem<2>& pb, const Config& cfg, const RunOptions& opt,
                     const BasisKind& basis, const MappingKind& mapping, const Scheme& scheme);

template <int Dim>
RunResult visit_dim(Problem<Dim>& pb, const Config& cfg, const RunOptions& opt,
                    const BasisKind& basis, const MappingKind& mapping, const Scheme& scheme) {
  return std::visit(
      [&](auto b, auto m, auto s) -> RunResult {
        using K = decltype(b);
        using M = decltype(m);
        if constexpr (!supports_dimension<K>(Dim)) {
          throw InputError(fmt::format("{}: method.basis = \"{}\" is not available in {}D",
                                       cfg.where("method.basis"), K::kName, Dim));
        } else if constexpr (!supports_dimension<M>(Dim)) {
          throw InputError(fmt::format("{}: method.mapping = \"{}\" is not available in {}D",
                                       cfg.where("method.mapping"), M::kName, Dim));
        } else {
          using B = typename K::template type<Dim>;
          return run_typed<Dim, B, M, decltype(s)>(pb, cfg, opt);
        }
      },
      basis, mapping, scheme);
}

}  // namespace mpm::run_detail
