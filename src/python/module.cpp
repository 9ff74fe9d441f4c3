// The Python module's native part, mpmlab._mpmlab: configurations, runs (driver/session.hpp),
// studies and the schema as Python objects. The package mpmlab (python/mpmlab) wraps it in the
// API the README documents; its errors (python/mpmlab/errors.py) are raised from here by exit
// code. Every field handed out is a NumPy copy: particle arrays are re-ordered by re-sorting and
// resized between steps, so a view would not stay the same particles.
#include <Python.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "app/massmatrix.hpp"
#include "app/reconstruct.hpp"
#include "app/study.hpp"
#include "core/types.hpp"
#include "driver/run.hpp"
#include "driver/session.hpp"
#include "io/checkpoint.hpp"
#include "mpm/version.hpp"
#include "setup/config.hpp"
#include "setup/registry.hpp"
#include "solver/spline_matrices.hpp"

namespace py = pybind11;

namespace mpm::python {
namespace {

// The package's error class for an exit code (python/mpmlab/errors.py).
py::object error_class(int code) {
  return py::module_::import("mpmlab.errors").attr("error_for_exit_code")(code);
}

// Raises the package's error for `code` with `message` (the GIL held).
[[noreturn]] void raise_error(int code, const std::string& message) {
  PyErr_SetString(error_class(code).ptr(), message.c_str());
  throw py::error_already_set();
}

// The value of a declared key, as Python reads it.
py::object config_get(const Config& cfg, const std::string& key) {
  const KeySpec* spec = find_key(key);
  if (spec == nullptr)
    raise_error(exit_code::kInput,
                fmt::format("'{}' is no configuration key (mpmlab.keys() lists them)", key));
  switch (spec->type) {
    case KeyType::Integer:
      return py::int_(cfg.get_int(key));
    case KeyType::Real:
      return py::float_(cfg.get_real(key));
    case KeyType::Boolean:
      return py::bool_(cfg.get_bool(key));
    case KeyType::String:
    case KeyType::Expression:
      return py::str(cfg.get_string(key));
    case KeyType::RealVector: {
      const std::vector<double> v = cfg.get_reals(key);
      return v.size() == 1 ? py::object(py::float_(v[0])) : py::object(py::cast(v));
    }
    case KeyType::ExpressionVector: {
      const std::vector<std::string> v = cfg.get_expressions(key);
      return v.size() == 1 ? py::object(py::str(v[0])) : py::object(py::cast(v));
    }
  }
  return py::none();
}

py::object value_object(const Value& v) {
  return std::visit([](const auto& x) -> py::object { return py::cast(x); }, v);
}

// mpmlab.keys(): the schema as data.
py::list keys() {
  py::list out;
  for (const KeySpec& s : schema()) {
    py::dict k;
    k["name"] = s.name;
    k["type"] = std::string(type_name(s.type));
    k["unit"] = s.unit;
    k["default"] = s.default_value ? value_object(*s.default_value) : py::none();
    k["required"] = s.required();
    k["min"] = s.min ? py::object(py::float_(*s.min)) : py::none();
    k["max"] = s.max ? py::object(py::float_(*s.max)) : py::none();
    k["min_exclusive"] = s.min_exclusive;
    k["max_exclusive"] = s.max_exclusive;
    k["choices"] = s.choices;
    k["description"] = s.description;
    out.append(k);
  }
  return out;
}

// mpmlab.methods(): what `mpm list` prints, by section.
py::dict methods() {
  py::dict out;
  const auto section = [&](const char* name, const auto& entries) {
    py::list l;
    for (const auto& e : entries) {
      py::dict d;
      d["name"] = std::string(e.name);
      d["description"] = std::string(e.description);
      l.append(d);
    }
    out[name] = l;
  };
  section("benchmarks", registry::kBenchmarks);
  section("bases", registry::kBases);
  section("mappings", registry::kMappings);
  section("schemes", registry::kSchemes);
  section("mass", registry::kMassTypes);
  section("materials", registry::kMaterials);
  return out;
}

template <class T>
py::array_t<T> array(std::vector<py::ssize_t> shape) {
  return py::array_t<T>(std::move(shape));
}

// A run's particles as NumPy copies (n rows in the particles' current order; `id` names them).
template <int Dim>
py::dict particle_fields(const Particles<Dim>& P) {
  const auto n = static_cast<py::ssize_t>(P.x.size());
  py::dict f;
  const auto vectors = [&](const std::vector<Vec<Dim>>& src) {
    auto a = array<double>({n, Dim});
    auto m = a.template mutable_unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i)
      for (int d = 0; d < Dim; ++d) m(i, d) = src[static_cast<std::size_t>(i)][d];
    return a;
  };
  const auto matrices = [&](const std::vector<Mat<Dim>>& src) {
    auto a = array<double>({n, Dim, Dim});
    auto m = a.template mutable_unchecked<3>();
    for (py::ssize_t i = 0; i < n; ++i)
      for (int r = 0; r < Dim; ++r)
        for (int c = 0; c < Dim; ++c) m(i, r, c) = src[static_cast<std::size_t>(i)](r, c);
    return a;
  };
  const auto scalars = [&](const auto& src) {
    using T = std::decay_t<decltype(src[0])>;
    using Out = std::conditional_t<std::is_floating_point_v<T>, double, std::int64_t>;
    auto a = array<Out>({n});
    auto m = a.template mutable_unchecked<1>();
    for (py::ssize_t i = 0; i < n; ++i) m(i) = static_cast<Out>(src[static_cast<std::size_t>(i)]);
    return a;
  };
  f["x"] = vectors(P.x);
  f["x0"] = vectors(P.x0);
  f["v"] = vectors(P.v);
  f["stress"] = matrices(P.stress);
  f["F"] = matrices(P.F);
  f["mass"] = scalars(P.mass);
  f["volume"] = scalars(P.volume);
  f["volume0"] = scalars(P.volume0);
  f["id"] = scalars(P.id);
  f["material"] = scalars(P.material);
  py::dict internal;
  const auto names = P.state.names();
  for (std::size_t k = 0; k < names.size(); ++k) {
    auto a = array<double>({n});
    auto m = a.mutable_unchecked<1>();
    for (py::ssize_t i = 0; i < n; ++i) m(i) = P.state[static_cast<std::size_t>(i)][k];
    internal[py::str(std::string(names[k]))] = a;
  }
  f["internal"] = internal;
  return f;
}

// The grid's nodal arrays of the last step, with the DOFs' positions.
template <int Dim>
py::dict grid_fields(const RunState<Dim>& st, const std::vector<double>& positions) {
  const GridState<Dim>& g = st.nodes;
  const auto n = static_cast<py::ssize_t>(g.size());
  if (g.window()[0] != 0 || g.window()[1] != g.size())
    throw std::logic_error("grid_fields: the grid arrays of a distributed run");
  py::dict f;
  auto pos = array<double>({static_cast<py::ssize_t>(positions.size() / Dim), Dim});
  std::copy(positions.begin(), positions.end(), pos.mutable_data());
  f["x"] = pos;
  const auto vectors = [&](const auto& src) {
    auto a = array<double>({n, Dim});
    auto m = a.template mutable_unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i)
      for (int d = 0; d < Dim; ++d) m(i, d) = src[static_cast<Index>(i)][d];
    return a;
  };
  auto mass = array<double>({n});
  auto active = array<bool>({n});
  auto fixed = array<std::int64_t>({n});
  for (py::ssize_t i = 0; i < n; ++i) {
    mass.mutable_at(i) = g.mass[static_cast<Index>(i)];
    active.mutable_at(i) = g.active[static_cast<Index>(i)] != 0;
    fixed.mutable_at(i) = g.fixed[static_cast<std::size_t>(i)];
  }
  f["mass"] = mass;
  f["momentum"] = vectors(g.momentum);
  f["velocity"] = vectors(g.velocity);
  f["force"] = vectors(g.force);
  f["acceleration"] = vectors(g.accel);
  f["active"] = active;
  f["fixed"] = fixed;
  return f;
}

// A run (driver::Session) with the Python side of it: stepping with the GIL released, the
// fields, and errors raised by exit code.
class Run {
 public:
  Run(const Config& cfg, const std::string& out, bool overwrite, int threads, bool progress,
      const std::string& restart) {
    RunOptions ro;
    ro.out_dir = out;
    ro.overwrite = overwrite;
    ro.threads = threads;
    ro.quiet = !progress;
    ro.keep_history = true;
    if (!restart.empty()) {
      ro.restart = std::make_shared<const io::Checkpoint>(io::read_checkpoint(restart));
      ro.restart_name = restart;
    }
    session_ = std::make_unique<driver::Session>(cfg, ro);
  }

  // Takes steps until step `to` (at most the last). A failure finishes the run (summary.json)
  // and raises its error; Ctrl-C raises KeyboardInterrupt between two steps, the run intact.
  void advance_to(Index to) {
    driver::Session& s = *session_;
    if (s.finished()) raise_error(exit_code::kInput, "the run is finished");
    while (s.running() && s.step() < to) {
      {
        py::gil_scoped_release release;
        s.advance_to(s.step() + 1);
      }
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
    raise_if_failed();
  }

  py::dict finish() {
    RunResult r;
    {
      py::gil_scoped_release release;
      r = session_->finish();
    }
    result_ = std::make_unique<RunResult>(std::move(r));
    return summary();
  }

  py::dict summary() const {
    if (!result_) raise_error(exit_code::kInput, "the run has no summary before finish()");
    return py::module_::import("json").attr("loads")(result_->summary.dump());
  }

  void stop(const std::string& why) { session_->stop(why); }

  void checkpoint() {
    if (prescribed_changed_)
      raise_error(exit_code::kInput,
                  "the prescribed velocity was changed by set_prescribed_velocity: a checkpoint "
                  "holds the configuration's, so a restart from it would not continue this run");
    py::gil_scoped_release release;
    session_->checkpoint();
  }

  py::dict particles() const {
    return std::visit([](const auto* P) { return particle_fields(*P); },
                      session_->solver().particles());
  }

  py::dict grid() {
    const std::vector<double> positions = session_->solver().dof_positions();
    return std::visit(
        [&](auto* st) -> py::dict {
          if (st == nullptr)
            raise_error(exit_code::kInput,
                        "method.solver = \"ulfem\" has no grid: its elements are the particles");
          return grid_fields(*st, positions);
        },
        session_->solver().run_state());
  }

  py::tuple history() const {
    const auto& cols = session_->solver().history_columns();
    const auto& v = session_->solver().history_values();
    const auto width = static_cast<py::ssize_t>(cols.size());
    auto a = array<double>({static_cast<py::ssize_t>(v.size()) / width, width});
    std::copy(v.begin(), v.end(), a.mutable_data());
    return py::make_tuple(cols, a);
  }

  // The reaction on each constrained boundary of the last step (output.reactions: history.csv's
  // reaction_* columns, by name).
  py::dict reactions() {
    py::dict out;
    const auto& cols = session_->solver().history_columns();
    std::visit(
        [&](auto* st) {
          const std::vector<double>* r = st != nullptr ? &st->diag.reactions : nullptr;
          std::size_t k = 0;
          for (const std::string& c : cols)
            if (c.starts_with("reaction_")) {
              out[py::str(c)] = r != nullptr && k < r->size() ? (*r)[k] : 0.0;
              ++k;
            }
        },
        session_->solver().run_state());
    return out;
  }

  // Sets the velocity of the box of prescribed velocities (prescribed.*) from the next step on,
  // in its prescribed components.
  void set_prescribed_velocity(const std::vector<double>& velocity) {
    if (session_->settings().output.checkpoint_every > 0)
      raise_error(exit_code::kInput,
                  "set_prescribed_velocity: the run writes checkpoints (output.checkpoint_every), "
                  "which hold the configuration's prescribed velocity; a restart would not "
                  "continue this run");
    std::visit(
        [&](auto* st) {
          if (st == nullptr || st->nodes.prescribed.empty())
            raise_error(exit_code::kInput,
                        "set_prescribed_velocity: the run has no prescribed velocities "
                        "([prescribed] nodes = \"box\" with a box that holds grid nodes)");
          constexpr int Dim = std::decay_t<decltype(*st)>::kDim;
          if (static_cast<int>(velocity.size()) != Dim)
            raise_error(exit_code::kInput,
                        fmt::format("set_prescribed_velocity: {} components for a {}D run",
                                    velocity.size(), Dim));
          for (auto& [dof, v] : st->nodes.prescribed)
            for (int d = 0; d < Dim; ++d) v[d] = velocity[static_cast<std::size_t>(d)];
        },
        session_->solver().run_state());
    prescribed_changed_ = true;
  }

  std::vector<std::string> warnings() const { return session_->result().warnings; }
  const driver::Session& session() const { return *session_; }

 private:
  void raise_if_failed() {
    if (session_->running() || session_->finished()) return;
    const RunResult& r = session_->result();
    if (r.exit_code == exit_code::kOk) return;
    const std::string failure = r.failure;
    const int code = r.exit_code;
    finish();
    raise_error(code, failure);
  }

  std::unique_ptr<driver::Session> session_;
  std::unique_ptr<RunResult> result_;
  bool prescribed_changed_ = false;
};

// mpmlab.study: the command line's study (app/study.hpp; study.csv and study.txt in `out` when
// given), as rows: study.csv's columns, the failure, and the observed order of each error
// against the method's previous value (observed_order, as study.txt prints them).
py::list study(const Config& base, const std::vector<std::string>& refine,
               const std::string& methods, const std::string& out, int jobs, bool overwrite) {
  StudyOptions opt = parse_refine(refine);
  if (!methods.empty()) opt.methods = parse_methods(methods);
  opt.out_dir = out;
  opt.jobs = jobs;
  opt.overwrite = overwrite;
  opt.quiet = true;
  StudyResult r;
  {
    py::gil_scoped_release release;
    r = run_study(base, opt);
  }
  const std::size_t nv = opt.values.size();
  py::list rows;
  for (std::size_t k = 0; k < r.runs.size(); ++k) {
    const RunResult& run = r.runs[k];
    py::dict row;
    row["method"] = r.labels[k / nv];
    row[py::str(opt.key)] = opt.values[k % nv];
    row["cells"] = run.cells;
    row["h"] = run.h;
    row["particles"] = run.particles;
    row["steps"] = run.steps;
    row["status"] = run.exit_code == exit_code::kOk            ? "ok"
                    : run.exit_code == exit_code::kInterrupted ? "interrupted"
                                                               : "failed";
    row["exit_code"] = run.exit_code;
    row["failure"] = run.failure;
    for (const std::string_view name : study_error_columns()) {
      const std::optional<double> e = error_named(run.errors, name);
      row[py::str(std::string(name))] = e ? py::object(py::float_(*e)) : py::none();
      std::optional<double> order;
      if (k % nv > 0) {
        const RunResult& prev = r.runs[k - 1];
        const std::optional<double> ep = error_named(prev.errors, name);
        if (e && ep) order = observed_order(*ep, *e, prev.h, run.h);
      }
      row[py::str(fmt::format("order_{}", name))] =
          order && std::isfinite(*order) ? py::object(py::float_(*order)) : py::none();
    }
    row["max_rel_mass_error"] = run.diag.max_rel_mass_error;
    row["max_rel_momentum_error"] = run.diag.max_rel_momentum_error;
    row["grid_crossings"] = run.diag.grid_crossings;
    row["wall_seconds"] = run.wall_seconds;
    row["ns_per_particle_step"] = run.ns_per_particle_step;
    rows.append(row);
  }
  return rows;
}

// mpmlab.reconstruct: the 1D reconstruction of `mpm reconstruct` (Reconstruction1D) of values f
// at points x on `cells` elements of [lower, upper], evaluated at `at` (each point in the element
// Grid::cell_of gives it). Returns (values, details).
py::tuple reconstruct_at(const std::vector<double>& x, const std::vector<double>& f, double lower,
                         double upper, Index cells, const std::vector<double>& at,
                         const std::string& mapping, int terms, const std::string& completion,
                         double max_condition, int mls_degree,
                         const std::vector<double>& element_integrals, bool share_faces) {
  if (!(upper > lower))
    raise_error(exit_code::kInput, fmt::format("upper ({}) must exceed lower ({})", upper, lower));
  if (cells < 1) raise_error(exit_code::kInput, "cells must be at least 1");
  ReconstructOptions opt;
  opt.mapping = mapping;
  opt.terms = terms;
  opt.completion = completion;
  opt.max_condition = max_condition;
  opt.mls_degree = mls_degree;
  opt.share_faces = share_faces;
  const Grid<1> g(Vec<1>(lower), Vec<1>(upper), IVec<1>{cells});
  Reconstruction1D rec(opt, g, x, f, element_integrals);
  auto values = array<double>({static_cast<py::ssize_t>(at.size())});
  for (std::size_t k = 0; k < at.size(); ++k) {
    if (!g.inside(Vec<1>(at[k])))
      raise_error(exit_code::kInput,
                  fmt::format("at[{}] = {} lies outside [{}, {}]", k, at[k], lower, upper));
    values.mutable_at(static_cast<py::ssize_t>(k)) = rec.value(g.cell_of(at[k], 0), at[k]);
  }
  return py::make_tuple(values, rec.details());
}

// The same in 2D: TLS on cells[0] x cells[1] rectangles of [lower, upper] (Reconstruction2D, D
// 6.2.1), points x and `at` as (n, 2) arrays.
py::tuple reconstruct_at_2d(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
    const std::vector<double>& f, const std::vector<double>& lower,
    const std::vector<double>& upper, const std::vector<Index>& cells,
    const py::array_t<double, py::array::c_style | py::array::forcecast>& at, int terms,
    const std::string& completion, double max_condition,
    const std::vector<double>& element_integrals, bool share_faces) {
  if (x.ndim() != 2 || x.shape(1) != 2 || at.ndim() != 2 || at.shape(1) != 2)
    raise_error(exit_code::kInput, "x and at: arrays of shape (n, 2)");
  if (lower.size() != 2 || upper.size() != 2 || cells.size() != 2 || !(upper[0] > lower[0]) ||
      !(upper[1] > lower[1]) || cells[0] < 1 || cells[1] < 1)
    raise_error(exit_code::kInput,
                "lower, upper and cells: two values each, upper above lower, cells at least 1");
  ReconstructOptions opt;
  opt.dim = 2;
  opt.mapping = "tls";
  opt.terms = terms;
  opt.completion = completion;
  opt.max_condition = max_condition;
  opt.share_faces = share_faces;
  const Grid<2> g(Vec<2>(lower[0], lower[1]), Vec<2>(upper[0], upper[1]),
                  IVec<2>{cells[0], cells[1]});
  std::vector<Vec<2>> points(static_cast<std::size_t>(x.shape(0)));
  for (std::size_t k = 0; k < points.size(); ++k)
    points[k] = Vec<2>(x.at(static_cast<py::ssize_t>(k), 0), x.at(static_cast<py::ssize_t>(k), 1));
  Reconstruction2D rec(opt, g, points, f, element_integrals);
  auto values = array<double>({at.shape(0)});
  for (py::ssize_t k = 0; k < at.shape(0); ++k) {
    const Vec<2> p(at.at(k, 0), at.at(k, 1));
    if (!g.inside(p))
      raise_error(exit_code::kInput,
                  fmt::format("at[{}] = ({}, {}) lies outside the rectangle", k, p[0], p[1]));
    values.mutable_at(k) = rec.value(g.cell_index(p), p);
  }
  return py::make_tuple(values, rec.details());
}

// A sparse matrix as CSR arrays (data, indices, indptr, shape), for scipy.sparse.csr_matrix.
py::tuple csr(SparseMatrixD m) {
  Eigen::SparseMatrix<double, Eigen::RowMajor> r(m);
  r.makeCompressed();
  auto data = array<double>({static_cast<py::ssize_t>(r.nonZeros())});
  auto indices = array<std::int64_t>({static_cast<py::ssize_t>(r.nonZeros())});
  auto indptr = array<std::int64_t>({static_cast<py::ssize_t>(r.rows()) + 1});
  std::copy(r.valuePtr(), r.valuePtr() + r.nonZeros(), data.mutable_data());
  std::copy(r.innerIndexPtr(), r.innerIndexPtr() + r.nonZeros(), indices.mutable_data());
  std::copy(r.outerIndexPtr(), r.outerIndexPtr() + r.rows() + 1, indptr.mutable_data());
  return py::make_tuple(data, indices, indptr, py::make_tuple(r.rows(), r.cols()));
}

// The B-splines of degree p on the grid of `cells` over [lower, upper]: their values at the
// points x (rows: points, columns: functions) and, with weights w, the mass matrix
// sum_k w_k phi_i(x_k) phi_j(x_k) (solver/spline_matrices.hpp).
template <int Dim>
py::tuple spline_matrix(const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
                        const std::vector<double>& w, const std::vector<double>& lower,
                        const std::vector<double>& upper, const std::vector<Index>& cells, int p,
                        bool mass) {
  if (lower.size() != Dim || upper.size() != Dim || cells.size() != Dim)
    raise_error(
        exit_code::kInput,
        fmt::format("lower, upper and cells need {} values each (the points' columns)", Dim));
  if (p < 1 || p > 5) raise_error(exit_code::kInput, fmt::format("degree {}: choose 1-5", p));
  Vec<Dim> lo, hi;
  IVec<Dim> nc;
  for (int d = 0; d < Dim; ++d) {
    lo[d] = lower[static_cast<std::size_t>(d)];
    hi[d] = upper[static_cast<std::size_t>(d)];
    nc[d] = cells[static_cast<std::size_t>(d)];
    if (!(hi[d] > lo[d]) || nc[d] < 1)
      raise_error(exit_code::kInput, "upper must exceed lower and cells be at least 1");
  }
  const Grid<Dim> g(lo, hi, nc);
  PointSet<Dim> pts;
  const auto n = static_cast<std::size_t>(x.shape(0));
  pts.x.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    for (int d = 0; d < Dim; ++d) pts.x[k][d] = x.at(static_cast<py::ssize_t>(k), d);
  if (!mass) return csr(spline_values(g, p, pts.x));
  if (w.size() != n)
    raise_error(exit_code::kInput, fmt::format("{} points and {} weights", n, w.size()));
  pts.w = w;
  return csr(spline_mass(g, p, p, pts));
}

py::tuple spline_matrix_any(const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
                            const std::vector<double>& w, const std::vector<double>& lower,
                            const std::vector<double>& upper, const std::vector<Index>& cells,
                            int p, bool mass) {
  if (x.ndim() != 2 || x.shape(1) < 1 || x.shape(1) > 3)
    raise_error(exit_code::kInput, "points: an array of shape (n, dim), dim 1, 2 or 3");
  switch (x.shape(1)) {
    case 1:
      return spline_matrix<1>(x, w, lower, upper, cells, p, mass);
    case 2:
      return spline_matrix<2>(x, w, lower, upper, cells, p, mass);
    default:
      return spline_matrix<3>(x, w, lower, upper, cells, p, mass);
  }
}

// mpmlab.massmatrix: `mpm massmatrix`'s rows (004 Tables 4.2-4.4), as dicts.
py::list massmatrix(int dim, const std::vector<int>& degrees, const std::vector<Index>& cells,
                    const std::string& boundary, int particles, double tolerance,
                    bool matrix_free) {
  MassMatrixOptions opt;
  opt.dim = dim;
  opt.degrees = degrees;
  opt.cells = cells;
  opt.boundary = boundary;
  opt.particles = particles;
  opt.tolerance = tolerance;
  opt.matrix_free = matrix_free;
  std::vector<MassMatrixRow> rows;
  {
    py::gil_scoped_release release;
    rows = massmatrix_study(opt);
  }
  const auto num = [](double v) { return std::isnan(v) ? py::object(py::none()) : py::float_(v); };
  py::list out;
  for (const MassMatrixRow& r : rows) {
    py::dict d;
    d["degree"] = r.degree;
    d["cells"] = r.cells;
    d["unknowns"] = r.unknowns;
    d["kappa"] = r.kappa;
    d["kappa_published"] = num(r.kappa_published);
    d["singular"] = r.singular;
    d["cg_iterations"] = r.cg_iterations;
    d["cg_converged"] = r.cg_converged;
    d["cg_published"] = num(r.cg_published);
    d["cg_bound"] = num(r.cg_bound);
    d["cg_error"] = num(r.cg_error);
    d["pmg_cycles"] = r.pmg_cycles;
    d["pmg_converged"] = r.pmg_converged;
    d["pmg_published"] = num(r.pmg_published);
    d["pmg_error"] = num(r.pmg_error);
    if (matrix_free) {
      d["cg_free_iterations"] = r.cg_free_iterations;
      d["cg_free_converged"] = r.cg_free_converged;
      d["cg_free_difference"] = r.cg_free_difference;
    }
    d["direct_seconds"] = r.direct_seconds;
    d["cg_seconds"] = r.cg_seconds;
    d["pmg_seconds"] = r.pmg_seconds;
    out.append(d);
  }
  return out;
}

}  // namespace
}  // namespace mpm::python

PYBIND11_MODULE(_mpmlab, m) {
  using namespace mpm;
  using mpm::python::Run;
  m.doc() = "mpmlab's native part; use the package mpmlab";
  m.attr("__version__") = std::string(kVersion);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(mpm::python::error_class(exit_code::kInput).ptr(), e.what());
    } catch (const RunError& e) {
      PyErr_SetString(mpm::python::error_class(e.exit_code()).ptr(), e.what());
    }
  });

  py::class_<Config>(m, "_Config")
      .def_static("load", &Config::load, py::arg("path"), py::arg("overrides"))
      .def_static("parse", &Config::parse, py::arg("text"), py::arg("source"), py::arg("overrides"))
      .def("set", &Config::set, py::arg("key"), py::arg("value_text"), py::arg("origin"))
      .def("get", &mpm::python::config_get)
      .def("is_set", &Config::is_set)
      .def("where", &Config::where)
      .def("to_toml", &Config::to_toml)
      .def("instances", &Config::instances)
      .def_property_readonly("source", &Config::source)
      .def("copy", [](const Config& c) { return Config(c); });

  m.def("_restart_config", [](const std::string& checkpoint, const Config* given,
                              const std::vector<std::string>& sets) {
    const io::Checkpoint c = io::read_checkpoint(checkpoint);
    return io::restart_config(c, checkpoint, given, sets);
  });

  py::class_<Run>(m, "_Run")
      .def(py::init<const Config&, const std::string&, bool, int, bool, const std::string&>(),
           py::arg("config"), py::arg("out"), py::arg("overwrite"), py::arg("threads"),
           py::arg("progress"), py::arg("restart"))
      .def("advance_to", &Run::advance_to)
      .def("finish", &Run::finish)
      .def("summary", &Run::summary)
      .def("stop", &Run::stop)
      .def("checkpoint", &Run::checkpoint)
      .def("particles", &Run::particles)
      .def("grid", &Run::grid)
      .def("history", &Run::history)
      .def("reactions", &Run::reactions)
      .def("set_prescribed_velocity", &Run::set_prescribed_velocity)
      .def_property_readonly("warnings", &Run::warnings)
      .def_property_readonly("dim", [](const Run& r) { return r.session().dim(); })
      .def_property_readonly("dt", [](const Run& r) { return r.session().settings().time.dt; })
      .def_property_readonly("steps", [](const Run& r) { return r.session().steps(); })
      .def_property_readonly("step", [](const Run& r) { return r.session().step(); })
      .def_property_readonly("time", [](const Run& r) { return r.session().time(); })
      .def_property_readonly("running", [](const Run& r) { return r.session().running(); })
      .def_property_readonly("finished", [](const Run& r) { return r.session().finished(); })
      .def_property_readonly("exit_code",
                             [](const Run& r) { return r.session().result().exit_code; })
      .def_property_readonly("failure", [](const Run& r) { return r.session().result().failure; })
      .def_property_readonly("config_text", [](const Run& r) { return r.session().config_text(); });

  m.def("keys", &mpm::python::keys);
  m.def("methods", &mpm::python::methods);
  m.def("_study", &mpm::python::study);
  m.def("_reconstruct", &mpm::python::reconstruct_at);
  m.def("_reconstruct_2d", &mpm::python::reconstruct_at_2d);
  m.def("_spline_matrix", &mpm::python::spline_matrix_any);
  m.def("_massmatrix", &mpm::python::massmatrix);
}
