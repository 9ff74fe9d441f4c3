#include "benchmarks/body_set.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "benchmarks/benchmarks.hpp"
#include "grid/triangle_mesh.hpp"
#include "setup/config.hpp"

namespace mpm {

namespace {

std::string point_text(const Vec<2>& x) {
  return fmt::format("({:.6g}, {:.6g})", x[0], x[1]);
}
std::string point_text(const Vec<3>& x) {
  return fmt::format("({:.6g}, {:.6g}, {:.6g})", x[0], x[1], x[2]);
}

template <int Dim>
std::string grid_text(const Grid<Dim>& g) {
  const Vec<Dim> lo = g.origin, hi = g.upper();
  if constexpr (Dim == 2)
    return fmt::format("the grid [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}]", lo[0], hi[0], lo[1], hi[1]);
  else
    return fmt::format("the grid [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}]", lo[0],
                       hi[0], lo[1], hi[1], lo[2], hi[2]);
}

// Whether x lies inside a body: strictly inside its box, inside an element of its mesh (every
// barycentric coordinate above 1e-10), or strictly inside the box of a particle of its file
// (side volume^(1/Dim) about the particle), through a bucket grid of those boxes.
template <int Dim>
class Inside {
 public:
  explicit Inside(const Body<Dim>& b) : body_(b) {
    if (!b.file || b.file->is_mesh()) return;
    b.file->for_each([&](const Vec<Dim>& x, double vol) {
      const double half = 0.5 * std::pow(vol, 1.0 / Dim);
      centre_.push_back(x);
      half_.push_back(half);
      cell_ = std::max(cell_, 2.0 * half);
    });
    lo_ = b.lo - Vec<Dim>::Constant(cell_);
    // About one box per bucket along the body's extent, at most 2^21 buckets in all.
    Index total = 1;
    for (int d = 0; d < Dim; ++d) {
      const double extent = b.hi[d] - b.lo[d] + 2.0 * cell_;
      n_[static_cast<std::size_t>(d)] =
          std::clamp<Index>(static_cast<Index>(std::ceil(extent / cell_)), 1, 1 << (21 / Dim));
      width_[static_cast<std::size_t>(d)] =
          extent / static_cast<double>(n_[static_cast<std::size_t>(d)]);
      total *= n_[static_cast<std::size_t>(d)];
    }
    buckets_.assign(static_cast<std::size_t>(total), {});
    for (std::size_t i = 0; i < centre_.size(); ++i) {
      std::array<Index, Dim> a, z;
      for (int d = 0; d < Dim; ++d) {
        a[static_cast<std::size_t>(d)] = bin(centre_[i][d] - half_[i], d);
        z[static_cast<std::size_t>(d)] = bin(centre_[i][d] + half_[i], d);
      }
      std::array<Index, Dim> k = a;
      while (true) {
        buckets_[static_cast<std::size_t>(flat(k))].push_back(static_cast<Index>(i));
        int d = 0;
        while (d < Dim && ++k[static_cast<std::size_t>(d)] > z[static_cast<std::size_t>(d)]) {
          k[static_cast<std::size_t>(d)] = a[static_cast<std::size_t>(d)];
          ++d;
        }
        if (d == Dim) break;
      }
    }
  }
  bool operator()(const Vec<Dim>& x) const {
    for (int d = 0; d < Dim; ++d)
      if (!(x[d] > body_.lo[d] - cell_ && x[d] < body_.hi[d] + cell_)) return false;
    if (!body_.file)
      return (x.array() > body_.lo.array()).all() && (x.array() < body_.hi.array()).all();
    if (body_.file->is_mesh()) return body_.file->element_holding(x) >= 0;
    std::array<Index, Dim> k;
    for (int d = 0; d < Dim; ++d) k[static_cast<std::size_t>(d)] = bin(x[d], d);
    for (const Index i : buckets_[static_cast<std::size_t>(flat(k))]) {
      const auto I = static_cast<std::size_t>(i);
      if (((x - centre_[I]).cwiseAbs().array() < half_[I]).all()) return true;
    }
    return false;
  }

 private:
  const Body<Dim>& body_;
  std::vector<Vec<Dim>> centre_;
  std::vector<double> half_;
  double cell_ = 0.0;  // the largest particle box's side (0 for a box or mesh body)
  Vec<Dim> lo_ = Vec<Dim>::Zero();
  std::array<Index, Dim> n_{};
  std::array<double, Dim> width_{};
  std::vector<std::vector<Index>> buckets_;
  Index bin(double v, int d) const {
    const auto D = static_cast<std::size_t>(d);
    return std::clamp<Index>(static_cast<Index>(std::floor((v - lo_[d]) / width_[D])), 0,
                             n_[D] - 1);
  }
  Index flat(const std::array<Index, Dim>& k) const {
    Index f = 0;
    for (int d = Dim - 1; d >= 0; --d)
      f = f * n_[static_cast<std::size_t>(d)] + k[static_cast<std::size_t>(d)];
    return f;
  }
};

}  // namespace

template <int Dim>
std::string Body<Dim>::source() const {
  return file ? file->source() : fmt::format("the box {}.min, {}.max", table, table);
}

void check_extent(const Config& cfg, double lo, double hi, std::string_view what, char axis) {
  if (std::isfinite(hi - lo)) return;
  throw InputError(fmt::format(
      "{}: {}.max - {}.min = {} - ({}) in {} is not a finite number of metres (it overflows); "
      "give the {} in units that keep its size below about 1e300",
      cfg.where(fmt::format("{}.max", what)), what, what, hi, lo, axis, what));
}

template <int Dim>
void check_boxes(const Config& cfg, const Vec<Dim>& g0, const Vec<Dim>& g1, const Vec<Dim>& b0,
                 const Vec<Dim>& b1, const std::string& table) {
  const std::string min = table + ".min", max = table + ".max";
  for (int d = 0; d < Dim; ++d) {
    const char axis = "xyz"[d];
    if (!(g1[d] > g0[d]))
      throw InputError(fmt::format("{}: grid.max = {} must exceed grid.min = {} in {}",
                                   cfg.where("grid.max"), g1[d], g0[d], axis));
    check_extent(cfg, g0[d], g1[d], "grid", axis);
    check_extent(cfg, b0[d], b1[d], table, axis);
    if (!(b1[d] > b0[d]))
      throw InputError(fmt::format("{}: {} = {} must exceed {} = {} in {}", cfg.where(max), max,
                                   b1[d], min, b0[d], axis));
    if (b0[d] < g0[d] || b1[d] > g1[d])
      throw InputError(fmt::format(
          "{}: the body [{}, {}] must lie inside the grid [{}, {}] in {} (grid.min, grid.max)",
          cfg.where(b0[d] < g0[d] ? min : max), b0[d], b1[d], g0[d], g1[d], axis));
  }
}

template <int Dim>
Vec<Dim> per_direction(const Config& cfg, const std::string& key) {
  const std::vector<double> v = cfg.get_reals(key);
  if (v.size() != static_cast<std::size_t>(Dim))
    throw InputError(fmt::format(
        "{}: key '{}' needs {} values (one per direction, {}) for grid.dimension = {}, got {}",
        cfg.where(key), key, Dim,
        Dim == 1   ? "x"
        : Dim == 2 ? "x, y"
                   : "x, y, z",
        Dim, v.size()));
  Vec<Dim> out;
  for (int d = 0; d < Dim; ++d) out[d] = v[static_cast<std::size_t>(d)];
  return out;
}

template <int Dim>
std::vector<Body<Dim>> named_bodies_from_config(const Config& cfg, const Problem<Dim>& pb) {
  std::vector<Body<Dim>> out;
  for (const std::string& name : cfg.instances("body")) {
    Body<Dim> b;
    b.table = "body." + name;
    const std::string where = cfg.instance_where("body", name);
    if (cfg.get_string("method.solver") != "mpm")
      throw InputError(fmt::format(
          "{}: [{}]: several bodies are for method.solver = \"mpm\"; \"{}\" discretises the box "
          "body of [body] alone",
          where, b.table, cfg.get_string("method.solver")));
    b.file = FileBody<Dim>::from_config(cfg, b.table);
    if (b.file) {
      b.lo = b.file->lower();
      b.hi = b.file->upper();
      if constexpr (Dim == 2) {
        if (pb.mesh)
          b.file->check_inside(
              cfg, [&](const Vec<2>& x) { return pb.mesh->inside(x); },
              fmt::format("the triangles of {}", pb.mesh->source()));
      }
      b.file->check_inside(
          cfg, [&](const Vec<Dim>& x) { return pb.grid.inside(x); }, grid_text(pb.grid));
    } else {
      if (cfg.at_default(b.key("min")) && cfg.at_default(b.key("max")))
        throw InputError(fmt::format(
            "{}: [{}] gives no body: give its box ({}.min and {}.max), a body mesh ({}.mesh) or "
            "a particle file ({}.particles)",
            where, b.table, b.table, b.table, b.table, b.table));
      if (pb.mesh)
        throw InputError(fmt::format(
            "{}: [{}] is a box body, and the grid is the triangles of {} (grid.mesh), which "
            "seed [body] alone; give this body as a body mesh ({}.mesh) or a particle file",
            where, b.table, pb.mesh->source(), b.table));
      if (cfg.get_int("particles.per_triangle") != 0)
        throw InputError(fmt::format(
            "{}: [{}] is a box body, seeded per cell (particles.per_cell), and "
            "particles.per_triangle seeds the grid's triangles for [body] alone; give this body "
            "as a body mesh ({}.mesh) or a particle file, or seed by particles.per_cell",
            where, b.table, b.table));
      b.lo = per_direction<Dim>(cfg, b.key("min"));
      b.hi = per_direction<Dim>(cfg, b.key("max"));
      check_boxes<Dim>(cfg, pb.grid.origin, pb.grid.upper(), b.lo, b.hi, b.table);
    }
    out.push_back(std::move(b));
  }
  return out;
}

template <int Dim>
void for_each_box_point(const Config& cfg, const Grid<Dim>& g, const Body<Dim>& body,
                        const std::function<void(const Vec<Dim>& X, double volume)>& f) {
  // The seeder itself, storing none (no memory to check: share 0).
  SeedScope visit;
  visit.machine_share = 0.0;
  const auto per_cell = static_cast<int>(cfg.get_int("particles.per_cell"));
  Particles<Dim> none =
      seed_particles<Dim>(g, body.lo, body.hi, per_cell, 1.0, visit, [&](const Vec<Dim>& X) {
        f(X, 0.0);
        return false;
      });
  (void)none;
}

template <int Dim>
void seed_named_bodies(const Config& cfg, Problem<Dim>& pb, std::vector<Body<Dim>>& named,
                       Index first_id, double rho, const SeedScope& scope) {
  auto& P = pb.particles;
  for (Body<Dim>& b : named) {
    // Seeded by the seeders' own sinks (ids from 0, the scope deciding what is kept and
    // counting the layers), then appended with their ids moved on.
    SeedScope own = scope;
    own.expected = 0;
    Particles<Dim> Q;
    if (b.file) {
      check_seed_memory<Dim>(static_cast<double>(b.file->count()), scope.machine_share,
                             b.file->source());
      SeedSink<Dim> sink(&pb.grid, rho, own);
      b.file->for_each([&](const Vec<Dim>& x, double vol) { sink.add(x, vol); });
      Q = sink.finish();
    } else {
      Q = seed_particles<Dim>(pb.grid, b.lo, b.hi,
                              static_cast<int>(cfg.get_int("particles.per_cell")), rho, own);
    }
    b.first_id = first_id;
    b.count = own.seeded - scope.seeded;
    scope.seeded = own.seeded;
    P.reserve(P.size() + Q.size());
    for (std::size_t i = 0; i < Q.x.size(); ++i)
      P.append(Q.x[i], Q.volume[i], Q.mass[i], static_cast<CompactIndex>(Q.id[i] + first_id));
    first_id += b.count;
  }
  // Room for the particles that arrive from other processes (SeedSink::finish).
  if (scope.keep && P.x.capacity() < P.x.size() * 9 / 8) P.keep_room(P.size() / 8);
}

template <int Dim>
void check_bodies_apart(const Config& cfg, const Problem<Dim>& pb,
                        const std::vector<const Body<Dim>*>& bodies) {
  for (const Body<Dim>* a : bodies) {
    const Inside<Dim> inside(*a);
    for (const Body<Dim>* b : bodies) {
      if (a == b) continue;
      auto check = [&](const Vec<Dim>& x, double) {
        if (inside(x))
          throw InputError(fmt::format(
              "{}: the bodies of [{}] ({}) and [{}] ({}) overlap: a particle of the second at {} "
              "lies inside the first; bodies may touch but not overlap (their particles would "
              "count the same volume twice)",
              cfg.instance_where("body", (b->table == "body" ? a : b)->table.substr(5)), a->table,
              a->source(), b->table, b->source(), point_text(x)));
      };
      if (b->file) {
        b->file->for_each(check);
      } else if (Dim == 2 && b->table == "body") {
        // (As [body] is seeded: on a mesh grid's triangles, or particles.per_triangle.)
        if constexpr (Dim == 2)
          for_each_body_seed_2d(cfg, pb.grid, b->lo, b->hi, pb.mesh.get(), 0.0, check);
      } else {
        for_each_box_point<Dim>(cfg, pb.grid, *b, check);
      }
    }
  }
}

void check_seeding_keys(const Config& cfg) {
  std::vector<std::string> tables{"body"};
  for (const std::string& n : cfg.instances("body")) tables.push_back("body." + n);
  bool box = false, mesh = false;
  std::string sources;
  for (const std::string& t : tables) {
    const bool m = !cfg.get_string(t + ".mesh").empty();
    const bool p = !cfg.get_string(t + ".particles").empty();
    box = box || (!m && !p);
    mesh = mesh || m;
    sources += fmt::format("{}{} of [{}]", sources.empty() ? "" : ", ",
                           m ? "a body mesh" : "a particle file", t);
  }
  if (!box && !cfg.at_default("particles.per_cell"))
    throw InputError(fmt::format(
        "{}: particles.per_cell seeds the cells of a box body, and this run's bodies are {} "
        "(a body mesh is seeded by particles.per_element, a particle file gives every particle; "
        "leave particles.per_cell out)",
        cfg.where("particles.per_cell"), sources));
  if (!mesh && !cfg.at_default("particles.per_element"))
    throw InputError(fmt::format(
        "{}: particles.per_element seeds the elements of a body mesh, and this run has none "
        "(give body.mesh, or leave particles.per_element out)",
        cfg.where("particles.per_element")));
}

template struct Body<1>;
template struct Body<2>;
template struct Body<3>;
template void check_boxes<2>(const Config&, const Vec<2>&, const Vec<2>&, const Vec<2>&,
                             const Vec<2>&, const std::string&);
template void check_boxes<3>(const Config&, const Vec<3>&, const Vec<3>&, const Vec<3>&,
                             const Vec<3>&, const std::string&);
template Vec<1> per_direction<1>(const Config&, const std::string&);
template Vec<2> per_direction<2>(const Config&, const std::string&);
template Vec<3> per_direction<3>(const Config&, const std::string&);
template std::vector<Body<2>> named_bodies_from_config<2>(const Config&, const Problem<2>&);
template std::vector<Body<3>> named_bodies_from_config<3>(const Config&, const Problem<3>&);
template void seed_named_bodies<2>(const Config&, Problem<2>&, std::vector<Body<2>>&, Index, double,
                                   const SeedScope&);
template void seed_named_bodies<3>(const Config&, Problem<3>&, std::vector<Body<3>>&, Index, double,
                                   const SeedScope&);
template void check_bodies_apart<2>(const Config&, const Problem<2>&,
                                    const std::vector<const Body<2>*>&);
template void check_bodies_apart<3>(const Config&, const Problem<3>&,
                                    const std::vector<const Body<3>*>&);
template void for_each_box_point<2>(const Config&, const Grid<2>&, const Body<2>&,
                                    const std::function<void(const Vec<2>&, double)>&);
template void for_each_box_point<3>(const Config&, const Grid<3>&, const Body<3>&,
                                    const std::function<void(const Vec<3>&, double)>&);

}  // namespace mpm
