#include "model/problem.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <variant>

#include "benchmarks/benchmarks.hpp"
#include "grid/grid_state.hpp"
#include "setup/config.hpp"

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
template <int Dim>
IVec<Dim> seed_counts(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi, int per_cell) {
  Vec<Dim> per_dim;
  double total = 1.0;
  for (int d = 0; d < Dim; ++d) {
    per_dim[d] = std::max(1.0, std::round((hi[d] - lo[d]) / g.h[d] * per_cell));
    total *= per_dim[d];
  }
  const double bytes = total * static_cast<double>(Particles<Dim>::bytes_per_particle());
  const double memory = physical_memory();
  if (!(total < 1e15) || (memory > 0.0 && bytes > memory))
    throw InputError(fmt::format(
        "grid.cells and particles.per_cell seed the body with {:.4g} particles, whose state "
        "alone needs about {:.3g} GB; this machine has {:.3g} GB of memory: use fewer cells "
        "or particles per cell",
        total, bytes / 1e9, memory / 1e9));
  IVec<Dim> n{};
  for (int d = 0; d < Dim; ++d) n[d] = static_cast<Index>(per_dim[d]);
  return n;
}
}  // namespace

template <int Dim>
Particles<Dim> seed_particles(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi,
                              int per_cell, double rho0) {
  const IVec<Dim> n = seed_counts<Dim>(g, lo, hi, per_cell);
  Index total = 1;
  for (int d = 0; d < Dim; ++d) total *= n[d];
  Particles<Dim> P;
  P.resize(total);
  const double vol = (hi - lo).prod() / static_cast<double>(total);
  for (Index p = 0; p < total; ++p) {
    Index rem = p;
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) {
      const Index k = rem % n[d];
      rem /= n[d];
      x[d] = lo[d] + (hi[d] - lo[d]) * (static_cast<double>(k) + 0.5) / static_cast<double>(n[d]);
    }
    const auto i = static_cast<std::size_t>(p);
    P.x[i] = P.x0[i] = x;
    P.volume[i] = P.volume0[i] = vol;
    P.density[i] = rho0;
    P.mass[i] = rho0 * vol;
  }
  return P;
}

template <int Dim>
Traction<Dim> body_face_traction(const Grid<Dim>& g, const Particles<Dim>& P, const Vec<Dim>& lo,
                                 const Vec<Dim>& hi, int per_cell, int direction, int side,
                                 std::function<Vec<Dim>(double t)> value) {
  const IVec<Dim> n = seed_counts<Dim>(g, lo, hi, per_cell);
  Vec<Dim> spacing;
  for (int d = 0; d < Dim; ++d) spacing[d] = (hi[d] - lo[d]) / static_cast<double>(n[d]);
  // Each particle's share of the face: the product of its spacings along the face (1D: 1).
  double area = 1.0;
  for (int d = 0; d < Dim; ++d)
    if (d != direction) area *= spacing[d];
  Traction<Dim> tr;
  tr.direction = direction;
  tr.side = side;
  tr.value = std::move(value);
  // The outer layer lies half a spacing inside the face, the next one and a half spacings.
  const double face = side > 0 ? hi[direction] : lo[direction];
  for (Index p = 0; p < P.size(); ++p)
    if (std::abs(P.x0[static_cast<std::size_t>(p)][direction] - face) < spacing[direction]) {
      tr.particles.push_back(p);
      tr.area.push_back(area);
      tr.half_width.push_back(0.5 * spacing[direction]);
    }
  return tr;
}

template Traction<1> body_face_traction<1>(const Grid<1>&, const Particles<1>&, const Vec<1>&,
                                           const Vec<1>&, int, int, int,
                                           std::function<Vec<1>(double)>);
template Traction<2> body_face_traction<2>(const Grid<2>&, const Particles<2>&, const Vec<2>&,
                                           const Vec<2>&, int, int, int,
                                           std::function<Vec<2>(double)>);

template Particles<1> seed_particles<1>(const Grid<1>&, const Vec<1>&, const Vec<1>&, int, double);
template Particles<2> seed_particles<2>(const Grid<2>&, const Vec<2>&, const Vec<2>&, int, double);
template Particles<3> seed_particles<3>(const Grid<3>&, const Vec<3>&, const Vec<3>&, int, double);

namespace {
// A grid whose nodal state alone would not fit in memory is refused before it is allocated
// (issue 16, 10: std::bad_alloc was an "internal error" naming nothing). The particles are
// checked as they are seeded (seed_counts).
template <int Dim>
void check_grid_memory(const Config& cfg, const Grid<Dim>& g) {
  double nodes = 1.0;
  for (int d = 0; d < Dim; ++d) nodes *= static_cast<double>(g.cells[d]) + 1.0;
  const double bytes = nodes * static_cast<double>(GridState<Dim>::bytes_per_dof());
  const double memory = physical_memory();
  if (memory > 0.0 && bytes > memory)
    throw InputError(fmt::format(
        "{}: grid.cells = {} gives {:.4g} grid nodes, whose state alone needs about {:.3g} GB; "
        "this machine has {:.3g} GB of memory: use fewer cells",
        cfg.where("grid.cells"), cfg.get_int("grid.cells"), nodes, bytes / 1e9, memory / 1e9));
}

AnyProblem make_any_problem(const Config& cfg) {
  const std::string name = cfg.get_string("benchmark");
  if (name != "custom" && cfg.get_int("grid.dimension") != 1)
    throw InputError(
        fmt::format("{}: grid.dimension applies to benchmark = \"custom\" only; "
                    "\"{}\" fixes its own dimension",
                    cfg.where("grid.dimension"), name));
  if (name == "vibrating_bar") return make_vibrating_bar(cfg, /*large=*/false);
  if (name == "vibrating_bar_large") return make_vibrating_bar(cfg, /*large=*/true);
  if (name == "column_compaction") return make_column_compaction(cfg);
  if (name == "traction_bar") return make_traction_bar(cfg);
  if (name == "mms_1d") return make_mms_1d(cfg);
  if (name == "custom") {
    if (cfg.get_int("grid.dimension") == 2) return make_custom_2d(cfg);
    return make_custom_1d(cfg);
  }
  if (name == "plate_mms_2d") return make_plate_mms_2d(cfg);
  throw InputError(
      fmt::format("{}: benchmark \"{}\" is not implemented", cfg.where("benchmark"), name));
}
}  // namespace

AnyProblem make_problem(const Config& cfg) {
  AnyProblem pb = make_any_problem(cfg);
  std::visit([&](const auto& p) { check_grid_memory(cfg, p.grid); }, pb);
  return pb;
}

}  // namespace mpm
