#include "model/problem.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <system_error>
#include <variant>

#include "benchmarks/benchmarks.hpp"
#include "benchmarks/bodies.hpp"
#include "grid/grid_state.hpp"
#include "grid/triangle_mesh.hpp"
#include "setup/config.hpp"
#include "setup/gmsh_mesh.hpp"
#include "setup/registry.hpp"

namespace mpm {

namespace {
// The machine's physical memory [bytes] (0 where unknown).
double physical_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

// Particles per direction of seed_particles: per_cell per cell width, at least one. A body
// whose particle state alone would not fit in the machine's memory is refused here, before
// anything is allocated, with the estimate (instead of std::bad_alloc or a machine swapping).
// `share`: SeedScope::machine_share.
template <int Dim>
IVec<Dim> seed_counts(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi, int per_cell,
                      double share = 1.0) {
  Vec<Dim> per_dim;
  double total = 1.0;
  for (int d = 0; d < Dim; ++d) {
    per_dim[d] = std::max(1.0, std::round((hi[d] - lo[d]) / g.h[d] * per_cell));
    total *= per_dim[d];
  }
  // (The state of an elastic law: a material's internal variables come on top.)
  const double bytes = share * total * static_cast<double>(Particles<Dim>::bytes_per_particle(0));
  const double memory = physical_memory();
  if (!(total < 1e15) || (memory > 0.0 && bytes > memory))
    throw InputError(fmt::format(
        "grid.cells and particles.per_cell seed the body with {:.4g} particles, whose state "
        "alone needs about {:.3g} GB{}; this machine has {:.3g} GB of memory: use fewer cells "
        "or particles per cell{}",
        total, bytes / 1e9, share < 1.0 ? " on the processes of this machine" : "", memory / 1e9,
        share < 1.0 ? ", or more machines" : ""));
  IVec<Dim> n{};
  for (int d = 0; d < Dim; ++d) n[d] = static_cast<Index>(per_dim[d]);
  return n;
}

// f(p, X) for the points of seed_particles' lattice in its order (p = 0, 1, ...; x fastest), n
// points per direction over [lo, hi].
template <int Dim, class F>
void for_each_lattice_point(const IVec<Dim>& n, const Vec<Dim>& lo, const Vec<Dim>& hi, F&& f) {
  Index total = 1;
  for (int d = 0; d < Dim; ++d) total *= n[d];
  for (Index p = 0; p < total; ++p) {
    Index rem = p;
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) {
      const Index k = rem % n[d];
      rem /= n[d];
      x[d] = lo[d] + (hi[d] - lo[d]) * (static_cast<double>(k) + 0.5) / static_cast<double>(n[d]);
    }
    f(p, x);
  }
}

}  // namespace

template <int Dim>
void check_seed_memory(double count, double share, const std::string& what) {
  // (The state of an elastic law: a material's internal variables come on top.)
  const double bytes = share * count * static_cast<double>(Particles<Dim>::bytes_per_particle(0));
  const double memory = physical_memory();
  if (memory > 0.0 && bytes > memory)
    throw InputError(fmt::format(
        "{}: its {:.4g} particles need about {:.3g} GB for their state alone{}; this machine has "
        "{:.3g} GB of memory",
        what, count, bytes / 1e9, share < 1.0 ? " on the processes of this machine" : "",
        memory / 1e9));
}
template void check_seed_memory<2>(double, double, const std::string&);
template void check_seed_memory<3>(double, double, const std::string&);

template <int Dim>
Particles<Dim> seed_particles(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi,
                              int per_cell, double rho0, const SeedScope& scope,
                              const std::function<bool(const Vec<Dim>& X)>& body) {
  const IVec<Dim> n = seed_counts<Dim>(g, lo, hi, per_cell, scope.machine_share);
  Index total = 1;
  for (int d = 0; d < Dim; ++d) total *= n[d];
  const double vol = (hi - lo).prod() / static_cast<double>(total);
  SeedSink<Dim> sink(&g, rho0, scope);
  sink.reserve(total);
  for_each_lattice_point<Dim>(n, lo, hi, [&](Index, const Vec<Dim>& x) {
    if (!body || body(x)) sink.add(x, vol);
  });
  return sink.finish();
}

template <int Dim>
Traction<Dim> body_face_traction(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi,
                                 int per_cell, int direction, int side,
                                 std::function<Vec<Dim>(double t)> value) {
  // (It stores no particle: no memory check.)
  const IVec<Dim> n = seed_counts<Dim>(g, lo, hi, per_cell, /*share=*/0.0);
  Vec<Dim> spacing;
  for (int d = 0; d < Dim; ++d) spacing[d] = (hi[d] - lo[d]) / static_cast<double>(n[d]);
  // Each particle's share of the face: the product of its spacings along the face (1D: 1).
  double area = 1.0;
  for (int d = 0; d < Dim; ++d)
    if (d != direction) area *= spacing[d];
  Traction<Dim> tr;
  tr.direction = direction;
  tr.side = side;
  if constexpr (Dim > 1) {
    tr.patch = spacing;
    tr.patch[direction] = 0.0;
  }
  tr.value = std::move(value);
  // The outer layer lies half a spacing inside the face, the next one and a half spacings.
  const double face = side > 0 ? hi[direction] : lo[direction];
  for_each_lattice_point<Dim>(n, lo, hi, [&](Index p, const Vec<Dim>& x) {
    if (std::abs(x[direction] - face) < spacing[direction]) {
      tr.particles.push_back(p);
      tr.area.push_back(area);
      Vec<Dim> offset = Vec<Dim>::Zero();
      offset[direction] = side * (0.5 * spacing[direction]);
      tr.offset.push_back(offset);
    }
  });
  return tr;
}

template Traction<1> body_face_traction<1>(const Grid<1>&, const Vec<1>&, const Vec<1>&, int, int,
                                           int, std::function<Vec<1>(double)>);
template Traction<2> body_face_traction<2>(const Grid<2>&, const Vec<2>&, const Vec<2>&, int, int,
                                           int, std::function<Vec<2>(double)>);
template Traction<3> body_face_traction<3>(const Grid<3>&, const Vec<3>&, const Vec<3>&, int, int,
                                           int, std::function<Vec<3>(double)>);

template Particles<1> seed_particles<1>(const Grid<1>&, const Vec<1>&, const Vec<1>&, int, double,
                                        const SeedScope&,
                                        const std::function<bool(const Vec<1>&)>&);
template Particles<2> seed_particles<2>(const Grid<2>&, const Vec<2>&, const Vec<2>&, int, double,
                                        const SeedScope&,
                                        const std::function<bool(const Vec<2>&)>&);
template Particles<3> seed_particles<3>(const Grid<3>&, const Vec<3>&, const Vec<3>&, int, double,
                                        const SeedScope&,
                                        const std::function<bool(const Vec<3>&)>&);

std::pair<int, int> triangle_seed_pattern(int per_triangle) {
  for (int m : {1, 3, 6}) {
    if (per_triangle <= 0 || per_triangle % m != 0) continue;
    const int k2 = per_triangle / m;
    const int k = static_cast<int>(std::lround(std::sqrt(static_cast<double>(k2))));
    if (k * k == k2) return {m, k};
  }
  return {0, 0};
}

// The pattern of seed_particles_in_triangles in reference coordinates (xi, eta): the centroids
// of the parts, each with the same share 1 / per_triangle of the area.
std::vector<Vec<2>> triangle_seed_reference(int per_triangle) {
  // Not a structured binding: the lambda below captures m (clang 14 refuses that).
  const std::pair<int, int> mk = triangle_seed_pattern(per_triangle);
  const int m = mk.first, k = mk.second;
  if (m == 0)
    throw InputError(
        fmt::format("{} particles per triangle is not of the form m k^2 with m = 1, "
                    "3 or 6 (3, 4, 6, 9, 12, 16, 24, 25, 27, 36, ...)",
                    per_triangle));
  std::vector<Vec<2>> ref;
  const double inv = 1.0 / k;
  auto parts = [&](const Vec<2>& a, const Vec<2>& b, const Vec<2>& c) {
    const Vec<2> g = (a + b + c) / 3.0;
    if (m == 1) {
      ref.push_back(g);
      return;
    }
    const std::array<Vec<2>, 3> v{a, b, c};
    for (std::size_t e = 0; e < 3; ++e) {
      const Vec<2>& p = v[e];
      const Vec<2>& q = v[(e + 1) % 3];
      if (m == 3) {
        ref.push_back((g + p + q) / 3.0);
      } else {  // the medians cut the part (g, p, q) at the edge's midpoint
        const Vec<2> mid = 0.5 * (p + q);
        ref.push_back((g + p + mid) / 3.0);
        ref.push_back((g + mid + q) / 3.0);
      }
    }
  };
  for (int j = 0; j < k; ++j)
    for (int i = 0; i + j < k; ++i) {
      const Vec<2> o(i * inv, j * inv);
      parts(o, o + Vec<2>(inv, 0.0), o + Vec<2>(0.0, inv));  // pointing up
      if (i + j + 1 < k)                                     // pointing down
        parts(o + Vec<2>(inv, 0.0), o + Vec<2>(inv, inv), o + Vec<2>(0.0, inv));
    }
  return ref;
}

namespace {
// A triangulation whose particle state alone would not fit in memory (`share`:
// SeedScope::machine_share) is refused before anything is allocated.
void check_triangle_seed_memory(const TriangleMesh& mesh, Index per, double share) {
  const double total = static_cast<double>(mesh.num_cells()) * static_cast<double>(per);
  // (The state of an elastic law: a material's internal variables come on top.)
  const double bytes = share * total * static_cast<double>(Particles<2>::bytes_per_particle(0));
  const double memory = physical_memory();
  if (memory > 0.0 && bytes > memory)
    throw InputError(fmt::format(
        "{} triangles with {} particles each need about {:.3g} GB for the particle state "
        "alone{}; this machine has {:.3g} GB of memory",
        mesh.num_cells(), per, bytes / 1e9, share < 1.0 ? " on the processes of this machine" : "",
        memory / 1e9));
}

// seed_particles_in_triangles' points, triangle after triangle: f(X, volume).
void triangle_seeds(const TriangleMesh& mesh, const std::vector<Vec<2>>& ref,
                    const std::function<void(const Vec<2>&, double)>& f) {
  const auto per = static_cast<Index>(ref.size());
  for (Index c = 0; c < mesh.num_cells(); ++c) {
    const auto& t = mesh.cell_vertices(c);
    const Vec<2>& x0 = mesh.vertex(t[0]);
    const Vec<2> e1 = mesh.vertex(t[1]) - x0, e2 = mesh.vertex(t[2]) - x0;
    const double vol = mesh.cell_volume(c) / static_cast<double>(per);
    for (const Vec<2>& r : ref) f(x0 + r[0] * e1 + r[1] * e2, vol);
  }
}

}  // namespace

Particles<2> seed_particles_in_triangles(const TriangleMesh& mesh, int per_triangle, double rho0) {
  const std::vector<Vec<2>> ref = triangle_seed_reference(per_triangle);
  const auto per = static_cast<Index>(ref.size());
  check_triangle_seed_memory(mesh, per, 1.0);
  const SeedScope every;
  SeedSink<2> sink(nullptr, rho0, every);
  sink.reserve(mesh.num_cells() * per);
  triangle_seeds(mesh, ref, [&](const Vec<2>& x, double vol) { sink.add(x, vol); });
  return sink.finish();
}

std::shared_ptr<const TriangleMesh> mesh_from_config(const Config& cfg) {
  const std::string file = cfg.get_string("grid.mesh");
  if (file.empty()) return nullptr;
  const std::string basis = cfg.get_string("method.basis");
  const auto triangles = [](const auto& k) { return k.kOnTriangles; };
  if (!basis_named_has(basis, triangles))
    throw InputError(fmt::format(
        "{}: grid.mesh = \"{}\" holds triangles, which carry method.basis = {}; method.basis = "
        "\"{}\" lives on the grid's cells (leave grid.mesh out)",
        cfg.where("grid.mesh"), file, basis_names_where(triangles), basis));
  if (!cfg.at_default("method.triangles"))
    throw InputError(fmt::format(
        "{}: method.triangles splits the grid's cells into triangles; with grid.mesh = \"{}\" "
        "the triangles come from the file (leave method.triangles out)",
        cfg.where("method.triangles"), file));
  const std::filesystem::path path = cfg.file_path("grid.mesh");
  std::error_code ec;
  const bool from_file = std::filesystem::is_regular_file(cfg.source(), ec);
  try {
    return std::make_shared<const TriangleMesh>(with_box_sides(read_gmsh_mesh(path.string())));
  } catch (const InputError& e) {
    throw InputError(fmt::format(
        "{}: grid.mesh: {}{}", cfg.where("grid.mesh"), e.what(),
        path.is_relative() && !from_file
            ? " (taken from the working directory: the configuration is not a file, as in a "
              "restart from a checkpoint alone; give the configuration file too)"
            : ""));
  }
}

void check_mesh_box(const Config& cfg, const TriangleMesh& m, const Grid<2>& g) {
  const double tol = 1e-9 * (g.upper() - g.origin).norm();
  if ((m.lower() - g.origin).cwiseAbs().maxCoeff() > tol ||
      (m.upper() - g.upper()).cwiseAbs().maxCoeff() > tol)
    throw InputError(fmt::format(
        "{}: the mesh's bounding box [{:.9g}, {:.9g}] x [{:.9g}, {:.9g}] is not the grid's "
        "[{:.9g}, "
        "{:.9g}] x [{:.9g}, {:.9g}]; the grid's sides are where the boundary conditions act, so "
        "the two must agree",
        cfg.where("grid.mesh"), m.lower()[0], m.upper()[0], m.lower()[1], m.upper()[1], g.origin[0],
        g.upper()[0], g.origin[1], g.upper()[1]));
}

void for_each_body_seed_2d(const Config& cfg, const Grid<2>& g, const Vec<2>& lo, const Vec<2>& hi,
                           const TriangleMesh* mesh, double machine_share,
                           const std::function<void(const Vec<2>& X, double volume)>& f,
                           const std::function<void(Index total)>& begin) {
  const auto per_triangle = static_cast<int>(cfg.get_int("particles.per_triangle"));
  if (per_triangle == 0) {
    const int per_cell = static_cast<int>(cfg.get_int("particles.per_cell"));
    const IVec<2> n = seed_counts<2>(g, lo, hi, per_cell, machine_share);
    const Index total = n[0] * n[1];
    const double vol = (hi - lo).prod() / static_cast<double>(total);
    if (mesh != nullptr) {
      // A mesh need not fill its box: every particle must lie in a triangle.
      Index outside = 0;
      Vec<2> first;
      for_each_lattice_point<2>(n, lo, hi, [&](Index, const Vec<2>& x) {
        if (!mesh->inside(x) && outside++ == 0) first = x;
      });
      if (outside > 0)
        throw InputError(fmt::format(
            "{}: {} of the {} particles of the body [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] "
            "(particles.per_cell) lie in no triangle of {} (the first at ({:.6g}, {:.6g})); make "
            "the body (body.min, body.max) lie inside the mesh, or seed its triangles with "
            "particles.per_triangle",
            cfg.where("grid.mesh"), outside, total, lo[0], hi[0], lo[1], hi[1], mesh->source(),
            first[0], first[1]));
    }
    if (begin) begin(total);
    for_each_lattice_point<2>(n, lo, hi, [&](Index, const Vec<2>& x) { f(x, vol); });
    return;
  }
  const std::string basis = cfg.get_string("method.basis");
  const auto triangles = [](const auto& k) { return k.kOnTriangles; };
  if (!basis_named_has(basis, triangles))
    throw InputError(fmt::format(
        "{}: particles.per_triangle = {} seeds the triangles of method.basis = {}, not of \"{}\" "
        "(use particles.per_cell, or 0 here)",
        cfg.where("particles.per_triangle"), per_triangle, basis_names_where(triangles), basis));
  // (To round-off: the grid's upper corner is origin + cells h, which need not give back the
  // box of a mesh file bit for bit.)
  const double tol = 1e-9 * (g.upper() - g.origin).norm();
  if ((lo - g.origin).cwiseAbs().maxCoeff() > tol || (hi - g.upper()).cwiseAbs().maxCoeff() > tol)
    throw InputError(fmt::format(
        "{}: particles.per_triangle fills whole triangles, so the body must be the grid "
        "(body.min = grid.min and body.max = grid.max); use particles.per_cell for a body that "
        "fills part of the grid",
        cfg.where("particles.per_triangle")));
  if (triangle_seed_pattern(per_triangle).first == 0)
    throw InputError(fmt::format(
        "{}: particles.per_triangle = {} is not of the form m k^2 with m = 1, 3 or 6; choose "
        "one of 1, 3, 4, 6, 9, 12, 16, 24, 25, 27, 36, 48, 49, 54, 64, ...",
        cfg.where("particles.per_triangle"), per_triangle));
  const std::vector<Vec<2>> ref = triangle_seed_reference(per_triangle);
  const auto seed = [&](const TriangleMesh& m) {
    check_triangle_seed_memory(m, static_cast<Index>(ref.size()), machine_share);
    if (begin) begin(m.num_cells() * static_cast<Index>(ref.size()));
    triangle_seeds(m, ref, f);
  };
  if (mesh != nullptr) {
    seed(*mesh);
    return;
  }
  const TrianglePattern pattern = cfg.get_string("method.triangles") == "criss_cross"
                                      ? TrianglePattern::criss_cross
                                      : TrianglePattern::right;
  seed(structured_triangles(g.origin, g.upper(), g.cells, pattern));
}

Particles<2> seed_body_2d(const Config& cfg, const Grid<2>& g, const Vec<2>& lo, const Vec<2>& hi,
                          double rho0, const TriangleMesh* mesh, const SeedScope& scope,
                          const std::function<bool(const Vec<2>& X)>& body) {
  SeedSink<2> sink(&g, rho0, scope);
  for_each_body_seed_2d(
      cfg, g, lo, hi, mesh, scope.machine_share,
      [&](const Vec<2>& x, double vol) {
        if (!body || body(x)) sink.add(x, vol);
      },
      [&](Index total) { sink.reserve(total); });
  return sink.finish();
}

namespace {
// A grid whose nodal state alone would not fit in memory is refused before it is allocated
// (std::bad_alloc was an "internal error" naming nothing). The particles are
// checked as they are seeded (seed_counts).
template <int Dim>
void check_grid_memory(const Config& cfg, const Grid<Dim>& g, const SeedScope& scope) {
  double nodes = 1.0;
  for (int d = 0; d < Dim; ++d) nodes *= static_cast<double>(g.cells[d]) + 1.0;
  // The grid arrays over the DOFs, on one process; a distributed run's processes on this
  // machine hold windows over about their share of them (GridState's window, a slab's DOFs and
  // two layers of vertices either side: left out), and each the velocity-condition bits whole.
  const double bytes =
      nodes * (static_cast<double>(GridState<Dim>::bytes_per_dof()) * scope.machine_share +
               static_cast<double>(scope.machine_processes));
  const double memory = physical_memory();
  const bool distributed = scope.machine_share < 1.0 || scope.machine_processes > 1;
  if (memory > 0.0 && bytes > memory)
    throw InputError(fmt::format(
        "{}: grid.cells = {} gives {:.4g} grid nodes, whose state alone needs about {:.3g} GB{}; "
        "this machine has {:.3g} GB of memory: use fewer cells{}",
        cfg.where("grid.cells"), cfg.get_int("grid.cells"), nodes, bytes / 1e9,
        distributed ? fmt::format(" for the {} process(es) of the run on this machine",
                                  scope.machine_processes)
                    : "",
        memory / 1e9, distributed ? " or more machines" : ""));
}

// The constructor of each benchmark of registry::kBenchmarks (its name and description), by name.
struct BenchmarkMaker {
  std::string_view name;
  AnyProblem (*make)(const Config& cfg, const SeedScope& scope);
};
constexpr BenchmarkMaker kBenchmarkMakers[] = {
    {"vibrating_bar",
     [](const Config& c, const SeedScope& s) -> AnyProblem {
       return make_vibrating_bar(c, /*large=*/false, s);
     }},
    {"vibrating_bar_large",
     [](const Config& c, const SeedScope& s) -> AnyProblem {
       return make_vibrating_bar(c, /*large=*/true, s);
     }},
    {"column_compaction",
     [](const Config& c, const SeedScope& s) -> AnyProblem {
       return make_column_compaction(c, s);
     }},
    {"traction_bar",
     [](const Config& c, const SeedScope& s) -> AnyProblem { return make_traction_bar(c, s); }},
    {"mms_1d", [](const Config& c, const SeedScope& s) -> AnyProblem { return make_mms_1d(c, s); }},
    {"custom",
     [](const Config& c, const SeedScope& s) -> AnyProblem {
       const auto dim = c.get_int("grid.dimension");
       if (dim == 3) return make_custom_3d(c, s);
       if (dim == 2) return make_custom_2d(c, s);
       return make_custom_1d(c, s);
     }},
    {"plate_mms_2d",
     [](const Config& c, const SeedScope& s) -> AnyProblem { return make_plate_mms_2d(c, s); }},
    {"cube_mms_3d",
     [](const Config& c, const SeedScope& s) -> AnyProblem { return make_cube_mms_3d(c, s); }},
    {"vortex_2d",
     [](const Config& c, const SeedScope& s) -> AnyProblem { return make_vortex_2d(c, s); }},
};

// Every benchmark the registry lists (the choices of `benchmark`) has its constructor here, and
// every constructor its entry there: a benchmark added to one and not the other does not compile.
constexpr bool makers_match_registry() {
  bool ok = std::size(kBenchmarkMakers) == std::size(registry::kBenchmarks);
  for (const auto& e : registry::kBenchmarks) {
    int found = 0;
    for (const auto& m : kBenchmarkMakers) found += m.name == e.name ? 1 : 0;
    ok = ok && found == 1;
  }
  return ok;
}
static_assert(makers_match_registry(),
              "benchmarks/problem.cpp: kBenchmarkMakers and registry::kBenchmarks must name the "
              "same benchmarks");

AnyProblem make_any_problem(const Config& cfg, const SeedScope& scope) {
  const std::string name = cfg.get_string("benchmark");
  // A key that this benchmark would ignore is refused, not dropped in silence.
  if (name != "custom")
    for (const KeySpec& spec : schema())
      if (read_by_custom_alone(spec.name) && !cfg.at_default(spec.name))
        throw InputError(fmt::format(
            "{}: key '{}' is read by benchmark = \"custom\" only; \"{}\" sets its own body, "
            "conditions, loads and exact solution (leave the key out)",
            cfg.where(spec.name), spec.name, name));
  if (name != "custom" && cfg.get_int("grid.dimension") != 1)
    throw InputError(
        fmt::format("{}: grid.dimension applies to benchmark = \"custom\" only; "
                    "\"{}\" fixes its own dimension",
                    cfg.where("grid.dimension"), name));
  for (const auto& m : kBenchmarkMakers)
    if (m.name == name) return m.make(cfg, scope);
  throw InputError(
      fmt::format("{}: benchmark \"{}\" is not implemented", cfg.where("benchmark"), name));
}
}  // namespace

void require_mpm_lumped(const Config& cfg, const char* key, std::string_view what,
                        std::string_view why_lumped) {
  const std::string where = cfg.where(key);
  if (cfg.get_string("method.solver") != "mpm")
    throw InputError(
        fmt::format("{}: {} {}; method.solver = \"{}\" has none (use method.solver = \"mpm\")",
                    where, key, what, cfg.get_string("method.solver")));
  if (cfg.get_string("method.mass") != "lumped")
    throw InputError(fmt::format("{}: {} needs method.mass = \"lumped\" ({}), got \"{}\"", where,
                                 key, why_lumped, cfg.get_string("method.mass")));
}

AnyProblem make_problem(const Config& cfg, const SeedScope& scope) {
  AnyProblem pb = make_any_problem(cfg, scope);
  const int dim = std::visit([](const auto& p) { return std::decay_t<decltype(p)>::kDim; }, pb);
  if (cfg.get_int("particles.per_triangle") != 0 && dim != 2)
    throw InputError(fmt::format(
        "{}: particles.per_triangle seeds the triangles of a 2D run; this problem is {}D (use "
        "particles.per_cell)",
        cfg.where("particles.per_triangle"), dim));
  // grid.mesh is read by the problems that place the body on it (plate_mms_2d, 2D custom).
  const bool meshed = std::visit([](const auto& p) { return p.mesh != nullptr; }, pb);
  if (!meshed && !cfg.get_string("grid.mesh").empty())
    throw InputError(fmt::format(
        "{}: grid.mesh applies to the 2D problems plate_mms_2d and custom; benchmark = \"{}\"{} "
        "builds its own grid (leave grid.mesh out)",
        cfg.where("grid.mesh"), cfg.get_string("benchmark"),
        dim != 2 ? fmt::format(" in {}D", dim) : ""));
  // boundary.fixed / roller / frictional name the boundaries of a mesh file in the 2D custom
  // problem, which reads them; every other problem fixes its own.
  // (So do boundary.loaded and the loads on it.)
  const bool custom_mesh = meshed && cfg.get_string("benchmark") == "custom";
  for (const char* key :
       {"boundary.fixed", "boundary.roller", "boundary.frictional", "boundary.loaded"})
    if (!cfg.get_string(key).empty() && !custom_mesh)
      throw InputError(fmt::format(
          "{}: {} names boundaries of a mesh file (grid.mesh) in the 2D custom problem; "
          "benchmark = \"{}\"{} sets its own conditions",
          cfg.where(key), key, cfg.get_string("benchmark"), meshed ? "" : " without grid.mesh"));
  const bool traction = cfg.get_expressions("traction.loaded") != std::vector<std::string>{"0"};
  if ((traction || cfg.get_string("pressure.loaded") != "0") && !custom_mesh) {
    const char* key = traction ? "traction.loaded" : "pressure.loaded";
    throw InputError(fmt::format(
        "{}: {} loads named boundaries of a mesh file (grid.mesh, boundary.loaded) in the 2D "
        "custom problem; benchmark = \"{}\"{} has none",
        cfg.where(key), key, cfg.get_string("benchmark"), meshed ? "" : " without grid.mesh"));
  }
  if (cfg.get_bool("output.reactions")) {
    const std::string where = cfg.where("output.reactions");
    require_mpm_lumped(cfg, "output.reactions", "sums the grid forces of the MPM solver",
                       "the reaction -f_i of a constrained degree of freedom; with a consistent "
                       "mass matrix it would need the inertia of its neighbours");
    std::visit(
        [&](auto& p) {
          p.reactions = true;
          if (reaction_names(p).empty())
            throw InputError(fmt::format(
                "{}: output.reactions: benchmark = \"{}\" has no constrained boundary (no "
                "boundary.* is \"fixed\", \"roller\" or \"friction\" and prescribed.nodes = "
                "\"none\")",
                where, cfg.get_string("benchmark")));
        },
        pb);
  }
  std::visit([&](const auto& p) { check_grid_memory(cfg, p.grid, scope); }, pb);
  return pb;
}

}  // namespace mpm
