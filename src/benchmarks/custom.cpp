#include <fmt/format.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "benchmarks/benchmarks.hpp"
#include "benchmarks/bodies.hpp"
#include "benchmarks/body_set.hpp"
#include "benchmarks/initial_stress.hpp"
#include "core/strings.hpp"
#include "grid/triangle_mesh.hpp"
#include "methods/kinds.hpp"
#include "setup/config.hpp"
#include "setup/expression.hpp"
#include "setup/material_settings.hpp"

namespace mpm {
namespace {

// The sides of the grid (boundary.*) and faces of the body (traction.*, pressure.*) by direction:
// x, y, then z (back: z = min, front: z = max): kSideNames of model/problem.hpp.
constexpr const auto& kSideKeys = kSideNames;

// The key's value is the single expression "0" (the default of the vector keys): every
// component zero, or, for traction.* and exact.*, none given.
bool is_zero(const Config& cfg, const char* key) {
  const std::vector<std::string> texts = cfg.get_expressions(key);
  return texts.size() == 1 && texts[0] == "0";
}

// The compiled expressions of an ExpressionVector key, `count` of them (`what` names them);
// InputError naming its line otherwise. The single value "0" stands for all components zero.
// Expressions are checked when the config is loaded.
std::vector<Expression> expressions(const Config& cfg, const char* key, std::size_t count,
                                    const char* what) {
  std::vector<std::string> texts = cfg.get_expressions(key);
  if (is_zero(cfg, key)) texts.assign(count, "0");
  if (texts.size() != count)
    throw InputError(
        fmt::format("{}: key '{}' needs {} expression{} ({}) for grid.dimension = "
                    "{}, got {}",
                    cfg.where(key), key, count, count > 1 ? "s" : "", what,
                    cfg.get_int("grid.dimension"), texts.size()));
  std::vector<Expression> out;
  for (const auto& t : texts) out.emplace_back(t, cfg.constants());
  return out;
}

// Stress components in the order of initial.stress and exact.stress (Voigt's): 1D xx; 2D xx, yy,
// xy; 3D xx, yy, zz, yz, xz, xy (which drops to the 2D order without the z components).
template <int Dim>
Mat<Dim> stress_from(const std::vector<Expression>& s, double x, double y, double z, double t) {
  Mat<Dim> m = Mat<Dim>::Zero();
  m(0, 0) = s[0](x, y, z, t);
  if constexpr (Dim == 2) {
    m(1, 1) = s[1](x, y, z, t);
    m(0, 1) = m(1, 0) = s[2](x, y, z, t);
  }
  if constexpr (Dim == 3) {
    m(1, 1) = s[1](x, y, z, t);
    m(2, 2) = s[2](x, y, z, t);
    m(1, 2) = m(2, 1) = s[3](x, y, z, t);
    m(0, 2) = m(2, 0) = s[4](x, y, z, t);
    m(0, 1) = m(1, 0) = s[5](x, y, z, t);
  }
  return m;
}

template <int Dim>
Vec<Dim> vector_from(const std::vector<Expression>& e, double x, double y, double z, double t) {
  Vec<Dim> v;
  for (int d = 0; d < Dim; ++d) v[d] = e[static_cast<std::size_t>(d)](x, y, z, t);
  return v;
}

// The coordinates of a point as the expressions' x, y, z (zero beyond Dim).
template <int Dim>
std::array<double, 3> xyz(const Vec<Dim>& X) {
  std::array<double, 3> c{0.0, 0.0, 0.0};
  for (int d = 0; d < Dim; ++d) c[static_cast<std::size_t>(d)] = X[d];
  return c;
}

constexpr const char* kComponents[] = {"", "x", "x, y", "x, y, z"};
constexpr const char* kStressComponents[] = {"", "xx", "xx, yy, xy", "xx, yy, zz, yz, xz, xy"};
constexpr std::size_t kStressCount[] = {0, 1, 3, 6};

// A load of the keys `keys` (a traction and/or a pressure, functions of t) that is a finite
// number at every time: refused at set-up when it is not at t = 0 (InputError naming the keys,
// e.g. "1/0" or "1e308*1e308"), and stopping the run (RunError, exit_code::kNonFinite, naming
// them) at the first step where it is not.
template <class Load>
auto finite_load(const Config& cfg, const std::string& key, const std::string& pkey, Load load) {
  const auto finite = [](const auto& v) {
    if constexpr (std::is_arithmetic_v<std::decay_t<decltype(v)>>)
      return std::isfinite(v);
    else
      return v.allFinite();
  };
  // The keys that give the load (a traction at its default "0" gives none of it).
  const bool traction = !cfg.at_default(key) || pkey.empty();
  const std::string where = traction ? cfg.where(key) : cfg.where(pkey);
  const std::string keys = pkey.empty() ? fmt::format("'{}'", key)
                           : traction   ? fmt::format("'{}' and '{}'", key, pkey)
                                        : fmt::format("'{}'", pkey);
  if (!finite(load(0.0)))
    throw InputError(
        fmt::format("{}: the load of key {} is not a finite number at t = 0 (it "
                    "divides by zero or overflows)",
                    where, keys));
  return [load, finite, where, keys](double t) {
    const auto v = load(t);
    if (!finite(v))
      throw RunError(exit_code::kNonFinite,
                     fmt::format("{}: the load of key {} is not a finite number at t = {:.9g} s",
                                 where, keys, t));
    return v;
  };
}

// The box of prescribed velocities (prescribed.*): the MPM solver with lumped mass (a consistent
// mass matrix couples the prescribed DOFs to the free ones, which the elimination of the
// constrained rows with zero values leaves out).
template <int Dim>
void prescribed_from_config(Problem<Dim>& pb, const Config& cfg) {
  if (cfg.get_string("prescribed.nodes") == "none") {
    // The box's keys are read only with a box: given without one, they would do nothing.
    for (const char* key :
         {"prescribed.min", "prescribed.max", "prescribed.velocity", "prescribed.components"})
      if (!cfg.at_default(key))
        throw InputError(
            fmt::format("{}: {} is read with prescribed.nodes = \"box\", and this run has "
                        "prescribed.nodes = \"none\" (set it to \"box\", or leave {} out)",
                        cfg.where(key), key, key));
    return;
  }
  require_mpm_lumped(cfg, "prescribed.nodes", "prescribes grid velocities of the MPM solver",
                     "a consistent mass matrix couples the prescribed velocities to the free ones");
  const Vec<Dim> lo = per_direction<Dim>(cfg, "prescribed.min");
  const Vec<Dim> hi = per_direction<Dim>(cfg, "prescribed.max");
  const Vec<Dim> v = per_direction<Dim>(cfg, "prescribed.velocity");
  PrescribedVelocity pv;
  for (int d = 0; d < Dim; ++d) {
    if (!(hi[d] >= lo[d]))
      throw InputError(fmt::format("{}: prescribed.max = {} is below prescribed.min = {} in {}",
                                   cfg.where("prescribed.max"), hi[d], lo[d], "xyz"[d]));
    const auto k = static_cast<std::size_t>(d);
    pv.min[k] = lo[d];
    pv.max[k] = hi[d];
    pv.velocity[k] = v[d];
  }
  const std::string c = cfg.get_string("prescribed.components");
  if (c != "all") {
    const auto d = static_cast<int>(c[0] - 'x');
    if (d >= Dim)
      throw InputError(
          fmt::format("{}: prescribed.components = \"{}\" in {}D; the components "
                      "are {}",
                      cfg.where("prescribed.components"), c, Dim,
                      Dim == 1 ? "x" : (Dim == 2 ? "x, y" : "x, y, z")));
    pv.components = 1u << d;
  }
  pb.prescribed = pv;
}

// Dirichlet conditions of the grid sides (boundary.*) and tractions on the body faces
// (traction.*), in Dim directions.
template <int Dim>
void sides_from_config(Problem<Dim>& pb, const Config& cfg, const Vec<Dim>& b0, const Vec<Dim>& b1,
                       int per_cell) {
  // boundary.friction is read with a frictional side: given without one, it would do nothing.
  bool frictional = !cfg.get_string("boundary.frictional").empty();
  for (int d = 0; d < Dim; ++d)
    for (int side = 0; side < 2; ++side)
      frictional = frictional ||
                   cfg.get_string(fmt::format("boundary.{}", kSideKeys[d][side])) == "friction";
  if (!frictional && !cfg.at_default("boundary.friction"))
    throw InputError(
        fmt::format("{}: boundary.friction is the coefficient of the sides whose boundary.* is "
                    "\"friction\", and this run has none (set one, or leave boundary.friction out)",
                    cfg.where("boundary.friction")));
  for (int d = 0; d < Dim; ++d)
    for (int side = 0; side < 2; ++side) {
      const std::string type = cfg.get_string(fmt::format("boundary.{}", kSideKeys[d][side]));
      // A roller fixes the normal component; in 1D that is the only one (as "fixed").
      if (type == "fixed") pb.fixed_sides.push_back({d, side});
      if (type == "roller") pb.fixed_sides.push_back({d, side, 1u << d});
      if (type == "friction") {
        const std::string key = fmt::format("boundary.{}", kSideKeys[d][side]);
        if (pb.mesh)
          throw InputError(fmt::format(
              "{}: boundary.{} = \"friction\": this run's grid is the mesh {}, whose frictional "
              "walls are named boundaries: boundary.frictional = \"{}\" (its boundary edges on "
              "this side; use \"free\" here)",
              cfg.where(key), kSideKeys[d][side], pb.mesh->source(),
              Dim == 2 ? side_name(d, side) : std::string()));
        require_mpm_lumped(cfg, key.c_str(), "is a frictional wall of the MPM solver's grid",
                           "the contact and friction forces of a node are its own mass times "
                           "its velocity change; a consistent mass matrix couples the nodes");
        pb.friction_walls.push_back({d, side, cfg.get_real("boundary.friction")});
      }
      if constexpr (Dim == 2) {
        if (pb.mesh && type != "free" && !pb.mesh->has_boundary(side_name(d, side)))
          throw InputError(fmt::format(
              "{}: boundary.{} = \"{}\", but {} has no boundary edge on the grid's side {} = "
              "{:.9g}; set boundary.{} = \"free\"",
              cfg.where(fmt::format("boundary.{}", kSideKeys[d][side])), kSideKeys[d][side], type,
              pb.mesh->source(), "xy"[d], side == 0 ? pb.grid.origin[d] : pb.grid.upper()[d],
              kSideKeys[d][side]));
      }
      const std::string key = fmt::format("traction.{}", kSideKeys[d][side]);
      const std::string pkey = fmt::format("pressure.{}", kSideKeys[d][side]);
      const Expression p = cfg.get_expression(pkey);
      if (is_zero(cfg, key.c_str()) && p.text() == "0") continue;  // traction-free
      auto tau = expressions(cfg, key.c_str(), Dim, kComponents[Dim]);
      for (const auto& e : tau)
        if (e.uses_position())
          throw InputError(
              fmt::format("{}: key '{}': the traction \"{}\" may depend on t "
                          "only, not on x, y or z (uniform over the face)",
                          cfg.where(key), key, e.text()));
      if (p.uses_position())
        throw InputError(
            fmt::format("{}: key '{}': the pressure \"{}\" may depend on t only, "
                        "not on x, y or z (uniform over the face)",
                        cfg.where(pkey), pkey, p.text()));
      if (cfg.get_int("particles.per_triangle") != 0)
        throw InputError(fmt::format(
            "{}: key '{}': tractions act through the outer layer of particles.per_cell's "
            "particles; with particles.per_triangle they are not available yet",
            cfg.where(is_zero(cfg, key.c_str()) ? pkey : key),
            is_zero(cfg, key.c_str()) ? pkey : key));
      // A pressure p pushes against the outward normal n = sign e_d of the reference face:
      // tau = -p n (a dead load, like the traction).
      const double sign = side == 0 ? -1.0 : 1.0;
      pb.tractions.push_back(body_face_traction<Dim>(
          pb.grid, b0, b1, per_cell, d, side == 0 ? -1 : +1,
          finite_load(cfg, key, p.text() == "0" ? std::string() : pkey,
                      [tau, p, d, sign](double t) {
                        Vec<Dim> v = vector_from<Dim>(tau, 0.0, 0.0, 0.0, t);
                        v[d] -= sign * p(0.0, 0.0, 0.0, t);
                        return v;
                      })));
    }
}

// The names of a comma-separated list key (boundary.fixed, boundary.roller), blanks trimmed,
// empty ones left out.
std::vector<std::string> names_of(const Config& cfg, const char* key) {
  std::vector<std::string> out;
  for (std::string& item : split_trimmed(cfg.get_string(key), ','))
    if (!item.empty()) out.push_back(std::move(item));
  return out;
}

// The body that particle `id` belongs to (bodies in the order of their ids).
template <int Dim>
const Body<Dim>& body_of(const std::vector<const Body<Dim>*>& bodies, Index id) {
  const auto it = std::upper_bound(bodies.begin(), bodies.end(), id,
                                   [](Index x, const Body<Dim>* b) { return x < b->first_id; });
  return **(it - 1);
}

// The material of each part of a body's mesh (TABLE.part_materials; the others TABLE.material's,
// `body_material`), marking the materials it uses in `used`. InputError naming the key: a part
// or material that does not exist, a part named twice, an item not "PART: NAME", parts of a
// body that is not a mesh.
template <int Dim>
std::vector<std::size_t> part_materials(const Config& cfg, const Materials& materials,
                                        const Body<Dim>& body, std::size_t body_material,
                                        std::vector<bool>& used) {
  std::vector<std::string> parts;
  if constexpr (Dim > 1)
    if (body.file) parts = body.file->part_names();
  std::vector<std::size_t> of_part(parts.size(), body_material);
  const std::string key = body.key("part_materials");
  if (cfg.get_string(key).empty()) return of_part;
  bool mesh = false;
  if constexpr (Dim > 1) mesh = body.file && body.file->is_mesh();
  if (!mesh)
    throw InputError(fmt::format(
        "{}: {} gives materials to the parts (physical groups) of {}.mesh, and this body {}; "
        "give the body's material by {}.material",
        cfg.where(key), key, body.table,
        body.file ? "comes from " + body.source() : "is the box " + body.table + ".min, .max",
        body.table));
  std::vector<bool> named(parts.size(), false);
  for (const std::string& item : names_of(cfg, key.c_str())) {
    const auto colon = item.find(':');
    const std::string part = std::string(trim(std::string_view(item).substr(0, colon)));
    const std::string name = colon == std::string::npos
                                 ? ""
                                 : std::string(trim(std::string_view(item).substr(colon + 1)));
    if (colon == std::string::npos || part.empty() || name.empty())
      throw InputError(
          fmt::format("{}: {}: \"{}\" is not PART: NAME (e.g. \"clay: soft_clay, sand: material\")",
                      cfg.where(key), key, item));
    const auto it = std::find(parts.begin(), parts.end(), part);
    if (it == parts.end()) {
      std::string list;
      for (const auto& n : parts) list += (list.empty() ? "\"" : ", \"") + n + "\"";
      throw InputError(
          fmt::format("{}: {}: the body mesh has no part \"{}\"; its parts: {}", cfg.where(key),
                      key, part, list.empty() ? "none (no physical group of its elements)" : list));
    }
    const auto j = static_cast<std::size_t>(it - parts.begin());
    if (named[j])
      throw InputError(
          fmt::format("{}: {}: the part \"{}\" is named twice", cfg.where(key), key, part));
    named[j] = true;
    of_part[j] = material_index(cfg, materials, key, name);
    used[of_part[j]] = true;
  }
  return of_part;
}

// Each particle's material (its body's TABLE.material; with TABLE.part_materials, that of its
// part of the body's mesh) and mass rho0 V0 of its material's density; pb.materials already
// holds the configured materials. A named material no body uses is refused, naming its table.
// Before the initial stress (its law decides whether it may be given). Returns, for each body,
// the material of each part of its mesh (TABLE.material for those part_materials does not name;
// empty without parts) and then the body's own material.
template <int Dim>
std::vector<std::vector<std::size_t>> assign_materials(
    const Config& cfg, Problem<Dim>& pb, const std::vector<const Body<Dim>*>& bodies) {
  if (pb.materials.size() > 1 && cfg.get_string("method.solver") != "mpm")
    throw InputError(fmt::format(
        "{}: [material.{}]: several materials are for method.solver = \"mpm\"; \"{}\" takes "
        "the one of [material]",
        cfg.instance_where("material", pb.materials.name(1)), pb.materials.name(1),
        cfg.get_string("method.solver")));
  std::vector<bool> used(pb.materials.size(), false);
  std::vector<std::vector<std::size_t>> of_part;
  for (const Body<Dim>* b : bodies) {
    const std::size_t own = material_index(cfg, pb.materials, b->key("material"));
    used[own] = true;
    of_part.push_back(part_materials<Dim>(cfg, pb.materials, *b, own, used));
    of_part.back().push_back(own);
  }
  for (std::size_t k = 1; k < pb.materials.size(); ++k)
    if (!used[k])
      throw InputError(fmt::format(
          "{}: [material.{}] is the material of no body (body.material, body.part_materials); "
          "name it there, or leave it out",
          cfg.instance_where("material", pb.materials.name(k)), pb.materials.name(k)));
  auto& P = pb.particles;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    const Body<Dim>& b = body_of(bodies, P.id[i]);
    const auto& mine = of_part[static_cast<std::size_t>(
        std::find(bodies.begin(), bodies.end(), &b) - bodies.begin())];
    std::size_t k = mine.back();
    if constexpr (Dim > 1)
      if (b.file)
        if (const int part = b.file->part_of(P.id[i] - b.first_id); part >= 0)
          k = mine[static_cast<std::size_t>(part)];
    P.material[i] = static_cast<MaterialIndex>(k);
    P.mass[i] = pb.materials.density(k) * P.volume[i];
  }
  return of_part;
}

// The mass above a point per unit area [kg/m^2] of the bodies, for initial.geostatic: each part
// of a body mesh with its material's density (`of_part`, assign_materials'), a box body over the
// part of the vertical through the point that crosses it. None for one box body (Geostatic
// takes its top) or where a particle file has no geometry to integrate (refused there).
template <int Dim>
MassAbove<Dim> mass_above(const Config& cfg, const Problem<Dim>& pb,
                          const std::vector<const Body<Dim>*>& bodies,
                          const std::vector<std::vector<std::size_t>>& of_part) {
  if (bodies.size() == 1 && !(bodies[0]->file && bodies[0]->file->is_mesh())) return {};
  if (cfg.get_string("initial.geostatic") == "none") return {};
  // (Each body by value: the stress functor outlives the set-up, pb.initial_stress. A body mesh
  // is shared, and a particle file is refused below.)
  struct Term {
    Body<Dim> body;
    std::vector<double> rho;  // each part's density, then the body's own
  };
  std::vector<Term> terms;
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const Body<Dim>& b = *bodies[k];
    if (b.file && !b.file->is_mesh())
      throw InputError(fmt::format(
          "{}: initial.geostatic = \"k0\" integrates the weight of the bodies above each "
          "particle, and [{}] comes from {}, which has no volume to integrate (give its stress "
          "in the file's stress columns)",
          cfg.where("initial.geostatic"), b.table, b.source()));
    Term t{b, {}};
    for (const std::size_t m : of_part[k]) t.rho.push_back(pb.materials.density(m));
    terms.push_back(std::move(t));
  }
  return [terms](const Vec<Dim>& X) {
    double sum = 0.0;
    for (const Term& t : terms) {
      const Body<Dim>& b = t.body;
      if (b.file) {
        sum += b.file->integral_above(X, [&](int part) {
          return t.rho[part >= 0 ? static_cast<std::size_t>(part) : t.rho.size() - 1];
        });
        continue;
      }
      bool over = true;
      for (int d = 0; d + 1 < Dim; ++d) over = over && X[d] >= b.lo[d] && X[d] <= b.hi[d];
      const double length = b.hi[Dim - 1] - std::max(X[Dim - 1], b.lo[Dim - 1]);
      if (over && length > 0.0) sum += t.rho.back() * length;
    }
    return sum;
  };
}

// InputError naming `key` and the mesh's boundaries when the mesh has no boundary `name`.
void check_boundary_name(const TriangleMesh& mesh, const Config& cfg, const std::string& name,
                         const char* key) {
  if (mesh.has_boundary(name)) return;
  std::string list;
  for (const auto& n : mesh.boundary_names()) list += (list.empty() ? "\"" : ", \"") + n + "\"";
  throw InputError(fmt::format("{}: {}: {} has no boundary \"{}\"; its boundaries: {}",
                               cfg.where(key), key, mesh.source(), name,
                               list.empty() ? std::string("none") : list));
}

// The triangles at each vertex of a mesh.
std::vector<std::vector<Index>> cells_at_vertices(const TriangleMesh& mesh) {
  std::vector<std::vector<Index>> out(static_cast<std::size_t>(mesh.num_vertices()));
  for (Index c = 0; c < mesh.num_cells(); ++c)
    for (Index v : mesh.cell_vertices(c)) out[static_cast<std::size_t>(v)].push_back(c);
  return out;
}

// A boundary edge's triangle (the one holding both its vertices; -1 if none) and its outward
// unit normal (away from the triangle's third vertex).
std::pair<Index, Vec<2>> edge_cell_and_normal(const TriangleMesh& mesh,
                                              const std::vector<std::vector<Index>>& cells_at,
                                              const TriangleMesh::Edge& e) {
  const Vec<2> a = mesh.vertex(e[0]), b = mesh.vertex(e[1]);
  Index cell = -1;
  for (Index c : cells_at[static_cast<std::size_t>(e[0])]) {
    const auto& t = mesh.cell_vertices(c);
    if (std::find(t.begin(), t.end(), e[1]) != t.end()) cell = c;
  }
  Vec<2> n(b[1] - a[1], a[0] - b[0]);  // (b - a) turned clockwise, then made outward
  n /= n.norm();
  if (cell >= 0) {
    Vec<2> third = -(a + b);
    for (Index v : mesh.cell_vertices(cell)) third += mesh.vertex(v);
    if (n.dot(third - a) > 0.0) n = -n;
  }
  return {cell, n};
}

// The vertex normals of a roller along a bent boundary (P1: one DOF per vertex). A vertex on
// two edges that turn by at most 45 degrees gets the normal of the chord between its neighbours
// (the edges' normals weighted by their lengths), exact for vertices on a circle; one where the
// boundary turns more (a corner, e.g. of a rectangle) gets both edges' normals, which fix it; an
// end vertex its edge's normal.
std::vector<std::pair<Index, std::array<double, 3>>> roller_vertex_normals(const TriangleMesh& mesh,
                                                                           std::string_view name) {
  const auto cells_at = cells_at_vertices(mesh);
  std::map<Index, std::vector<Vec<2>>> weighted;  // per vertex: length x normal of its edges
  for (const auto& e : mesh.boundary(name).edges) {
    const Vec<2> n = edge_cell_and_normal(mesh, cells_at, e).second;
    const double length = (mesh.vertex(e[1]) - mesh.vertex(e[0])).norm();
    for (Index v : e) weighted[v].push_back(length * n);
  }
  std::vector<std::pair<Index, std::array<double, 3>>> out;
  auto add = [&](Index v, Vec<2> n) {
    n /= n.norm();
    out.push_back({v, {n[0], n[1], 0.0}});
  };
  const double cos45 = std::sqrt(0.5);
  for (const auto& [v, ns] : weighted) {
    const bool smooth = ns.size() == 2 && ns[0].dot(ns[1]) >= cos45 * ns[0].norm() * ns[1].norm();
    if (ns.size() == 1 || smooth) {
      add(v, smooth ? Vec<2>(ns[0] + ns[1]) : ns[0]);
    } else {
      for (const auto& n : ns) add(v, n);
    }
  }
  return out;
}

// Conditions on the named boundaries of a mesh file (its physical groups of lines):
// boundary.fixed (every component) and boundary.roller (the normal component of a boundary on
// one straight line: per component where it is parallel to x or y, else v . n = 0; along a
// bent boundary, P1 only, v_i . n_i = 0 with a normal per vertex).
void named_boundaries(Problem<2>& pb, const Config& cfg) {
  const auto fixed = names_of(cfg, "boundary.fixed"), roller = names_of(cfg, "boundary.roller");
  const auto frictional = names_of(cfg, "boundary.frictional");
  if (fixed.empty() && roller.empty() && frictional.empty()) return;
  const char* first_key = !fixed.empty()    ? "boundary.fixed"
                          : !roller.empty() ? "boundary.roller"
                                            : "boundary.frictional";
  if (!pb.mesh)
    throw InputError(fmt::format(
        "{}: {} names boundaries of a mesh file (grid.mesh); without one the grid's sides take "
        "boundary.left, right, bottom, top",
        cfg.where(first_key), first_key));
  auto check = [&](const std::string& name, const char* key) {
    check_boundary_name(*pb.mesh, cfg, name, key);
  };
  for (const auto& name : fixed) {
    check(name, "boundary.fixed");
    if (std::find(roller.begin(), roller.end(), name) != roller.end())
      throw InputError(
          fmt::format("{}: boundary \"{}\" is in boundary.fixed and in "
                      "boundary.roller; name it in one of them",
                      cfg.where("boundary.roller"), name));
    pb.fixed_sides.push_back({0, 0, ~0u, name});
  }
  for (const auto& name : roller) {
    check(name, "boundary.roller");
    const auto line = straight_boundary(*pb.mesh, name);
    if (!line) {
      const std::string basis = cfg.get_string("method.basis");
      const auto vertex_dofs = [](const auto& k) { return k.kVertexDofs; };
      if (!basis_named_has(basis, vertex_dofs))
        throw InputError(fmt::format(
            "{}: boundary.roller: boundary \"{}\" of {} does not lie on one straight line, so it "
            "has no single normal; method.basis = {} follows a bent boundary (a normal per "
            "vertex), \"{}\" needs it split into straight physical groups (or fixed)",
            cfg.where("boundary.roller"), name, pb.mesh->source(), basis_names_where(vertex_dofs),
            basis));
      FixedSide f{0, 0, 0u, name};
      f.vertex_normals = roller_vertex_normals(*pb.mesh, name);
      pb.fixed_sides.push_back(std::move(f));
      continue;
    }
    const Vec<2>& n = line->normal;
    const int d = std::abs(n[0]) > 1.0 - 1e-12 ? 0 : std::abs(n[1]) > 1.0 - 1e-12 ? 1 : -1;
    if (d >= 0)
      pb.fixed_sides.push_back({d, 0, 1u << d, name});
    else  // inclined: v . n = 0, which couples the components (GridState::projected)
      pb.fixed_sides.push_back({0, 0, 0u, name, {n[0], n[1], 0.0}});
  }
  // Frictional walls on named boundaries: straight lines on the mesh's outside, whose DOFs are
  // its vertices (the wall acts on nodal velocities), each named in no other list.
  const auto cells_at =
      frictional.empty() ? std::vector<std::vector<Index>>{} : cells_at_vertices(*pb.mesh);
  for (const auto& name : frictional) {
    const char* key = "boundary.frictional";
    check(name, key);
    for (const auto* other : {&fixed, &roller})
      if (std::find(other->begin(), other->end(), name) != other->end())
        throw InputError(fmt::format(
            "{}: boundary \"{}\" is in boundary.frictional and in {}; name it in one of them",
            cfg.where(key), name, other == &fixed ? "boundary.fixed" : "boundary.roller"));
    const std::string basis = cfg.get_string("method.basis");
    const auto vertex_dofs = [](const auto& k) { return k.kVertexDofs; };
    if (!basis_named_has(basis, vertex_dofs))
      throw InputError(
          fmt::format("{}: boundary.frictional: a frictional wall acts on nodal velocities, which "
                      "method.basis = {} has at the mesh's vertices; \"{}\" has none",
                      cfg.where(key), basis_names_where(vertex_dofs), basis));
    require_mpm_lumped(cfg, key, "names frictional walls of the MPM solver's grid",
                       "the contact and friction forces of a node are its own mass times its "
                       "velocity change; a consistent mass matrix couples the nodes");
    if (!straight_boundary(*pb.mesh, name) || !pb.mesh->boundary(name).outer)
      throw InputError(fmt::format(
          "{}: boundary.frictional: boundary \"{}\" of {} {}; a frictional wall is a straight "
          "line on the mesh's outer boundary (split a bent one into straight physical groups)",
          cfg.where(key), name, pb.mesh->source(),
          pb.mesh->boundary(name).outer ? "does not lie on one straight line"
                                        : "runs through the mesh's inside"));
    const Vec<2> n =
        edge_cell_and_normal(*pb.mesh, cells_at, pb.mesh->boundary(name).edges.front()).second;
    FrictionWall w{0, 0, cfg.get_real("boundary.friction"), name, {n[0], n[1], 0.0}};
    pb.friction_walls.push_back(std::move(w));
  }
}

// Loads on the named boundaries of a mesh file (boundary.loaded): the nominal traction
// traction.loaded and the pressure pressure.loaded (along the inward reference normal of each
// edge), functions of t only, as dead loads through the particles (model/loads.hpp). Each
// boundary edge gets q points at the midpoints of q equal pieces, q the edge length over the
// mean particle spacing of its triangle (sqrt(area / particles), at least 1); each point rides on
// the nearest particle of that triangle and carries the length of its piece.
void named_loads(Problem<2>& pb, const Config& cfg, const SeedScope& scope) {
  const auto names = names_of(cfg, "boundary.loaded");
  const bool traction = !is_zero(cfg, "traction.loaded");
  const Expression p = cfg.get_expression("pressure.loaded");
  const bool pressure = p.text() != "0";
  if (names.empty()) {
    if (traction || pressure)
      throw InputError(
          fmt::format("{}: {} loads the boundaries that boundary.loaded names, and it names none",
                      cfg.where(traction ? "traction.loaded" : "pressure.loaded"),
                      traction ? "traction.loaded" : "pressure.loaded"));
    return;
  }
  for (const char* key : {"body.mesh", "body.particles"})
    if (!cfg.get_string(key).empty())
      throw InputError(fmt::format(
          "{}: boundary.loaded loads the particles of a box body next to the mesh's boundaries; "
          "with {} the body's particles come from a file (load through the grid: prescribed.*)",
          cfg.where("boundary.loaded"), key));
  if (!pb.mesh)
    throw InputError(fmt::format(
        "{}: boundary.loaded names boundaries of a mesh file (grid.mesh); without one the body's "
        "faces take traction.left, right, bottom, top",
        cfg.where("boundary.loaded")));
  if (!traction && !pressure)
    throw InputError(
        fmt::format("{}: boundary.loaded names boundaries, but traction.loaded and "
                    "pressure.loaded are both zero; give the load or leave boundary.loaded out",
                    cfg.where("boundary.loaded")));
  auto tau = expressions(cfg, "traction.loaded", 2, kComponents[2]);
  for (const auto& e : tau)
    if (e.uses_position())
      throw InputError(
          fmt::format("{}: key 'traction.loaded': the traction \"{}\" may depend on "
                      "t only, not on x, y or z (uniform over the boundary)",
                      cfg.where("traction.loaded"), e.text()));
  if (p.uses_position())
    throw InputError(
        fmt::format("{}: key 'pressure.loaded': the pressure \"{}\" may depend on t "
                    "only, not on x, y or z (uniform over the boundary)",
                    cfg.where("pressure.loaded"), p.text()));
  const TriangleMesh& mesh = *pb.mesh;
  const auto cells_at = cells_at_vertices(mesh);
  for (const auto& name : names) {
    check_boundary_name(mesh, cfg, name, "boundary.loaded");
    // A load acts on the body's surface: a line through the mesh's inside has no outward normal
    // (a pressure there would push on both sides at once, through the particles of one).
    if (!mesh.boundary(name).outer)
      throw InputError(fmt::format(
          "{}: boundary.loaded: boundary \"{}\" of {} runs through the mesh's inside (an edge "
          "shared by two triangles), where a load has no outward normal; load boundaries on the "
          "mesh's outer boundary",
          cfg.where("boundary.loaded"), name, mesh.source()));
  }
  // The body's particles (id, reference position) in each triangle next to a loaded edge, from
  // the seeding itself: a process of a distributed run stores only its slab's particles, and
  // every process needs these (each loaded point names its particle by id).
  std::vector<char> loaded_cell(static_cast<std::size_t>(mesh.num_cells()), 0);
  for (const auto& name : names)
    for (const auto& e : mesh.boundary(name).edges)
      if (const Index cell = edge_cell_and_normal(mesh, cells_at, e).first; cell >= 0)
        loaded_cell[static_cast<std::size_t>(cell)] = 1;
  std::vector<std::vector<std::pair<Index, Vec<2>>>> in_cell(
      static_cast<std::size_t>(mesh.num_cells()));
  Index id = 0;
  for_each_body_seed_2d(cfg, pb.grid, pb.body_min, pb.body_max, pb.mesh.get(), scope.machine_share,
                        [&](const Vec<2>& X, double) {
                          const Index c = mesh.cell_index(X);
                          if (c >= 0 && loaded_cell[static_cast<std::size_t>(c)])
                            in_cell[static_cast<std::size_t>(c)].push_back({id, X});
                          ++id;
                        });
  Traction<2> tr;
  tr.value = finite_load(cfg, "traction.loaded", "",
                         [tau](double t) { return vector_from<2>(tau, 0.0, 0.0, 0.0, t); });
  if (pressure)
    tr.pressure =
        finite_load(cfg, "pressure.loaded", "", [p](double t) { return p(0.0, 0.0, 0.0, t); });
  for (const auto& name : names) {
    for (const auto& e : mesh.boundary(name).edges) {
      const Vec<2> a = mesh.vertex(e[0]), b = mesh.vertex(e[1]);
      const auto [cell, n] = edge_cell_and_normal(mesh, cells_at, e);
      const auto& own = in_cell[static_cast<std::size_t>(cell)];
      if (own.empty())
        throw InputError(fmt::format(
            "{}: boundary.loaded: the triangle of {} next to the edge ({:.6g}, {:.6g}) - "
            "({:.6g}, {:.6g}) of boundary \"{}\" holds no particle; a loaded boundary needs "
            "the body along it (seed it with particles.per_triangle, or move body.min, "
            "body.max)",
            cfg.where("boundary.loaded"), mesh.source(), a[0], a[1], b[0], b[1], name));
      const double length = (b - a).norm();
      const double spacing = std::sqrt(mesh.cell_volume(cell) / static_cast<double>(own.size()));
      const auto q = std::max<long long>(1, std::llround(length / spacing));
      for (long long j = 0; j < q; ++j) {
        const Vec<2> X = a + ((static_cast<double>(j) + 0.5) / static_cast<double>(q)) * (b - a);
        // The nearest particle; among those as near to round-off, the first (so that a turned
        // copy of the mesh picks the same one).
        auto d2 = [&](const std::pair<Index, Vec<2>>& k) { return (k.second - X).squaredNorm(); };
        double nearest = d2(own[0]);
        for (const auto& k : own) nearest = std::min(nearest, d2(k));
        const std::pair<Index, Vec<2>>* host = &own[0];
        for (const auto& k : own)
          if (d2(k) <= nearest * (1.0 + 1e-9)) {
            host = &k;
            break;
          }
        tr.particles.push_back(host->first);
        tr.area.push_back(length / static_cast<double>(q));
        tr.offset.push_back(X - host->second);
        tr.normal.push_back(n);
      }
    }
  }
  pb.tractions.push_back(std::move(tr));
}

// The exact solution of exact.*: none when all three keys are "0" (their default); otherwise a
// key left at "0" means that field is zero (e.g. the velocity of a static solution).
template <int Dim>
ExactSolution<Dim> exact_from_config(const Config& cfg) {
  if (is_zero(cfg, "exact.displacement") && is_zero(cfg, "exact.velocity") &&
      is_zero(cfg, "exact.stress"))
    return {};
  auto u = expressions(cfg, "exact.displacement", Dim, kComponents[Dim]);
  auto v = expressions(cfg, "exact.velocity", Dim, kComponents[Dim]);
  auto s = expressions(cfg, "exact.stress", kStressCount[Dim], kStressComponents[Dim]);
  // Evaluated at the material position X (x, y, z in the expressions), only for outputs and
  // norms.
  return [u, v, s](const Vec<Dim>& X, double t) {
    const auto [x, y, z] = xyz<Dim>(X);
    return ExactState<Dim>{vector_from<Dim>(u, x, y, z, t), vector_from<Dim>(v, x, y, z, t),
                           stress_from<Dim>(s, x, y, z, t)};
  };
}

// Keys that only a custom problem of more dimensions reads are refused, naming the key, when
// their value is not the default: traction.* "0", pressure.* "0", grid.cells_y and cells_z 0,
// boundary.* "fixed" (a restarted run's stored configuration holds every key, so a default
// value cannot tell a given key from an absent one; boundary.bottom and top are not refused in
// 1D, as before 3D). `dim` is the problem's dimension.
void refuse_keys_of_more_dimensions(const Config& cfg, int dim) {
  struct Only {
    const char* key;
    int from;  // the lowest dimension that reads it
  };
  static constexpr Only kOnly[] = {
      {"grid.cells_y", 2},  {"traction.bottom", 2}, {"traction.top", 2},  {"pressure.bottom", 2},
      {"pressure.top", 2},  {"grid.cells_z", 3},    {"traction.back", 3}, {"traction.front", 3},
      {"pressure.back", 3}, {"pressure.front", 3},  {"boundary.back", 3}, {"boundary.front", 3},
  };
  for (const Only& o : kOnly) {
    if (o.from <= dim) continue;
    const std::string_view key = o.key;
    bool given = false;
    if (key.starts_with("traction."))
      given = !is_zero(cfg, o.key);
    else if (key.starts_with("pressure."))
      given = cfg.get_string(o.key) != "0";
    else if (key.starts_with("grid."))
      given = cfg.get_int(o.key) != 0;
    else
      given = cfg.get_string(o.key) != "fixed";
    if (given)
      throw InputError(fmt::format(
          "{}: key '{}' applies to {} custom problem only (set grid.dimension = {}); this one "
          "is {}D",
          cfg.where(o.key), o.key, o.from == 2 ? "a 2D or 3D" : "a 3D",
          o.from == 2 ? "2 or 3" : "3", dim));
  }
}

// The body of a 2D or 3D custom problem from body.mesh or body.particles, seeded on pb.grid (and
// in 2D inside the triangles of grid.mesh): every point must lie on the grid. What acts on the
// faces of a box body (traction.*, pressure.*), the discretisations of a box body (OTM and the
// unified solver) and the seeding of a mesh grid's triangles are refused, naming the key.
template <int Dim>
Particles<Dim> seed_file_body(const Config& cfg, const Problem<Dim>& pb, const FileBody<Dim>& body,
                              double rho, const SeedScope& scope) {
  const std::string where = cfg.where(body.key());
  if (cfg.get_string("method.solver") != "mpm")
    throw InputError(fmt::format(
        "{}: {} gives the body by its particles; method.solver = \"{}\" discretises a box body "
        "(body.min, body.max) itself (use method.solver = \"mpm\")",
        where, body.key(), cfg.get_string("method.solver")));
  if (cfg.get_int("particles.per_triangle") != 0)
    throw InputError(fmt::format(
        "{}: particles.per_triangle seeds the triangles of the grid; the body of {} is seeded "
        "by {} (leave particles.per_triangle out)",
        cfg.where("particles.per_triangle"), body.key(),
        std::string_view(body.key()) == "body.mesh" ? "particles.per_element" : "its file"));
  for (int d = 0; d < Dim; ++d)
    for (int side = 0; side < 2; ++side)
      for (const char* what : {"traction", "pressure"}) {
        const std::string key = fmt::format("{}.{}", what, kSideKeys[d][side]);
        if (what[0] == 't' ? !is_zero(cfg, key.c_str()) : cfg.get_string(key) != "0")
          throw InputError(fmt::format(
              "{}: {} loads a face of the box body (body.min, body.max); this run's body comes "
              "from {} (load it through the grid: prescribed.*, boundary.*)",
              cfg.where(key), key, body.source()));
      }
  if constexpr (Dim == 2) {
    if (pb.mesh) {
      body.check_inside(
          cfg, [&](const Vec<2>& x) { return pb.mesh->inside(x); },
          fmt::format("the triangles of {}", pb.mesh->source()));
    }
  }
  const Vec<Dim> lo = pb.grid.origin, hi = pb.grid.upper();
  body.check_inside(
      cfg, [&](const Vec<Dim>& x) { return pb.grid.inside(x); },
      Dim == 2
          ? fmt::format("the grid [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}]", lo[0], hi[0], lo[1], hi[1])
          : fmt::format("the grid [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] x "
                        "[{:.6g}, {:.6g}]",
                        lo[0], hi[0], lo[1], hi[1], lo[Dim - 1], hi[Dim - 1]));
  check_seed_memory<Dim>(static_cast<double>(body.count()), scope.machine_share, body.source());
  SeedSink<Dim> sink(&pb.grid, rho, scope);
  sink.reserve(body.count());
  body.for_each([&](const Vec<Dim>& x, double vol) { sink.add(x, vol); });
  return sink.finish();
}

// The initial velocity and stress a body's particle file gives (FileBody), on the particles of
// the body this process keeps (each named by its row: its id less the body's first); the keys
// that would give them too must be at their defaults. Called after set_initial_stress, which
// checks initial.stress's keys.
template <int Dim>
void file_initial_fields(const Config& cfg, Problem<Dim>& pb, const Body<Dim>& of) {
  auto& P = pb.particles;
  const FileBody<Dim>& body = *of.file;
  // The row of particle i in the body's file, -1 for another body's particle.
  const auto row_of = [&](std::size_t i) {
    const Index row = P.id[i] - of.first_id;
    return row >= 0 && row < of.count ? row : Index{-1};
  };
  if (!body.velocity().empty()) {
    if (!cfg.at_default("initial.velocity"))
      throw InputError(
          fmt::format("{}: initial.velocity, and {} gives the velocity of every particle (leave "
                      "initial.velocity out, or the velocity columns)",
                      cfg.where("initial.velocity"), body.source()));
    for (std::size_t i = 0; i < P.x.size(); ++i)
      if (const Index row = row_of(i); row >= 0)
        P.v[i] = body.velocity()[static_cast<std::size_t>(row)];
  }
  if (body.stress().empty() && body.stress_zz().empty()) return;
  for (const char* key : {"initial.stress", "initial.stress_zz", "initial.geostatic"})
    if (!cfg.at_default(key))
      throw InputError(fmt::format(
          "{}: {}, and {} gives the stress of every particle (leave {} out, or the stress "
          "columns)",
          cfg.where(key), key, body.source(), key));
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    if (row_of(i) < 0) continue;
    const auto row = static_cast<std::size_t>(row_of(i));
    const Material& law = pb.materials[P.material[i]];
    const bool stressed = (!body.stress().empty() && body.stress()[row] != Mat<Dim>::Zero()) ||
                          (!body.stress_zz().empty() && body.stress_zz()[row] != 0.0);
    if (stressed) refuse_initial_stress(cfg, law, Dim, body.key());
    if (!body.stress().empty()) P.stress[i] = body.stress()[row];
    if (body.stress_zz().empty() || body.stress_zz()[row] == 0.0) continue;
    const auto names = state_names(law);
    const auto column = std::find(names.begin(), names.end(), kOutOfPlaneStressName);
    if (column == names.end())
      throw InputError(fmt::format(
          "{}: {} gives stress_zz, and material.model = \"{}\" keeps no stress normal to the "
          "plane (leave the column out)",
          cfg.where(body.key()), body.source(), material_name(law)));
    P.state[i][pb.materials.state_offset(P.material[i]) +
               static_cast<std::size_t>(column - names.begin())] = body.stress_zz()[row];
  }
}

// [body] (seeded: `main`, its count set) and the named bodies after it: seeded, with the seeding
// keys they use and no two overlapping; pb.bodies lists them when there are several. Returns
// them in the order of their ids.
template <int Dim>
std::vector<const Body<Dim>*> set_up_bodies(const Config& cfg, Problem<Dim>& pb,
                                            const Body<Dim>& main, std::vector<Body<Dim>>& named,
                                            double rho, const SeedScope& scope) {
  seed_named_bodies<Dim>(cfg, pb, named, main.count, rho, scope);
  std::vector<const Body<Dim>*> bodies{&main};
  for (const Body<Dim>& b : named) bodies.push_back(&b);
  if (named.empty()) return bodies;
  check_bodies_apart<Dim>(cfg, pb, bodies);
  for (const Body<Dim>* b : bodies) pb.bodies.push_back(b->range());
  return bodies;
}
}  // namespace

bool read_by_custom_alone(std::string_view key) {
  if (key == "traction.amplitude") return false;  // (the traction bar's)
  if (key == "particles.per_element") return true;
  for (std::string_view section : {"boundary.", "traction.", "pressure.", "body.", "initial.",
                                   "loading.", "exact.", "prescribed."})
    if (key.starts_with(section)) return true;
  return false;
}

Problem<1> make_custom_1d(const Config& cfg, const SeedScope& scope) {
  Problem<1> pb;
  pb.benchmark = "custom";
  for (const char* key : {"body.mesh", "body.particles", "particles.per_element"})
    if (!cfg.at_default(key))
      throw InputError(fmt::format(
          "{}: {} gives a body of a 2D or 3D custom problem (set grid.dimension = 2 or 3); a 1D "
          "body is the segment body.min, body.max",
          cfg.where(key), key));
  const double g0 = cfg.get_real("grid.min"), g1 = cfg.get_real("grid.max");
  const double b0 = cfg.get_real("body.min"), b1 = cfg.get_real("body.max");
  if (!(g1 > g0))
    throw InputError(
        fmt::format("{}: grid.max = {} must exceed grid.min = {}", cfg.where("grid.max"), g1, g0));
  if (!(b1 > b0))
    throw InputError(
        fmt::format("{}: body.max = {} must exceed body.min = {}", cfg.where("body.max"), b1, b0));
  check_extent(cfg, g0, g1, "grid", 'x');
  check_extent(cfg, b0, b1, "body", 'x');
  if (b0 < g0 || b1 > g1)
    throw InputError(
        fmt::format("{}: the body [{}, {}] must lie inside the grid [{}, {}] (grid.min, grid.max)",
                    cfg.where(b0 < g0 ? "body.min" : "body.max"), b0, b1, g0, g1));
  pb.materials = materials_from_config(cfg, 1);
  const double rho = cfg.get_real("material.density");
  const auto cells = static_cast<Index>(cfg.get_int("grid.cells"));
  pb.grid = Grid<1>(Vec<1>(g0), Vec<1>(g1), IVec<1>{cells});
  if (const auto named = cfg.instances("body"); !named.empty())
    throw InputError(fmt::format(
        "{}: [body.{}]: named bodies are for 2D and 3D custom problems; a 1D one has the one "
        "body of [body]",
        cfg.instance_where("body", named.front()), named.front()));
  Body<1> main;
  main.table = "body";
  main.lo = Vec<1>(b0);
  main.hi = Vec<1>(b1);
  pb.particles = seed_particles<1>(pb.grid, Vec<1>(b0), Vec<1>(b1),
                                   static_cast<int>(cfg.get_int("particles.per_cell")), rho, scope);
  main.count = std::numeric_limits<Index>::max();  // (every id)
  (void)assign_materials<1>(cfg, pb, {&main});

  const auto& constants = cfg.constants();
  const Expression v0(cfg.get_string("initial.velocity"), constants);
  const Expression s0(cfg.get_string("initial.stress"), constants);
  pb.body_min = Vec<1>(b0);
  pb.body_max = Vec<1>(b1);
  pb.initial_velocity = [v0](const Vec<1>& X) { return Vec<1>(v0(X[0])); };
  pb.initial_stress = [s0](const Vec<1>& X) {
    Mat<1> m;
    m(0, 0) = s0(X[0]);
    return m;
  };
  auto& P = pb.particles;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    P.v[i][0] = v0(P.x0[i][0]);
    P.stress[i](0, 0) = s0(P.x0[i][0]);
    // A non-finite initial field would stop the run at its first step with a message about
    // the stress; name the key and the first point instead.
    for (const auto& [key, value] :
         {std::pair{"initial.velocity", P.v[i][0]}, std::pair{"initial.stress", P.stress[i](0, 0)}})
      if (!std::isfinite(value))
        throw InputError(fmt::format("{}: {} = \"{}\" is not finite at x = {:.6g} (particle {})",
                                     cfg.where(key), key, cfg.get_string(key), P.x0[i][0],
                                     P.id[i]));
    if (P.stress[i](0, 0) != 0.0) refuse_initial_stress(cfg, pb.materials[P.material[i]], 1);
  }

  const Expression b(cfg.get_string("loading.body_force"), constants);
  pb.body_force.time_dependent = b.uses_time();
  pb.body_force.position_dependent = b.uses_position();
  pb.body_force.fill = [b](const Particles<1>& P, double t, std::vector<Vec<1>>& out) {
    if (!b.uses_position()) {
      const double value = b(0.0, 0.0, 0.0, t);
      for (auto& o : out) o[0] = value;
      return;
    }
    for (std::size_t i = 0; i < P.x.size(); ++i) out[i][0] = b(P.x[i][0], 0.0, 0.0, t);
  };

  refuse_keys_of_more_dimensions(cfg, 1);
  sides_from_config<1>(pb, cfg, Vec<1>(b0), Vec<1>(b1),
                       static_cast<int>(cfg.get_int("particles.per_cell")));
  prescribed_from_config<1>(pb, cfg);
  pb.exact = exact_from_config<1>(cfg);
  return pb;
}

Problem<2> make_custom_2d(const Config& cfg, const SeedScope& scope) {
  Problem<2> pb;
  pb.benchmark = "custom";
  refuse_keys_of_more_dimensions(cfg, 2);
  // With a mesh file the grid is its bounding box unless given (and then checked against it),
  // and the body the grid unless given. (A key at its default, one value, as a stored
  // config.toml writes every key, is not given.)
  pb.mesh = mesh_from_config(cfg);
  auto given_or = [&](const char* key, const Vec<2>& fallback) {
    return pb.mesh && cfg.at_default(key) ? fallback : per_direction<2>(cfg, key);
  };
  const Vec<2> g0 = given_or("grid.min", pb.mesh ? pb.mesh->lower() : Vec<2>::Zero());
  const Vec<2> g1 = given_or("grid.max", pb.mesh ? pb.mesh->upper() : Vec<2>::Zero());
  check_seeding_keys(cfg);
  Body<2> main;
  main.table = "body";
  main.file = FileBody<2>::from_config(cfg);
  const FileBody<2>* file_body = main.file ? &*main.file : nullptr;
  const Vec<2> b0 = file_body ? file_body->lower() : given_or("body.min", g0);
  const Vec<2> b1 = file_body ? file_body->upper() : given_or("body.max", g1);
  main.lo = b0;
  main.hi = b1;
  check_boxes<2>(cfg, g0, g1, file_body ? g0 : b0, file_body ? g1 : b1);
  pb.materials = materials_from_config(cfg, 2);
  const double rho = cfg.get_real("material.density");
  const auto cx = static_cast<Index>(cfg.get_int("grid.cells"));
  auto cy = static_cast<Index>(cfg.get_int("grid.cells_y"));
  if (cy == 0) cy = std::max<Index>(1, std::llround((g1[1] - g0[1]) / ((g1[0] - g0[0]) / cx)));
  pb.grid = Grid<2>(g0, g1, IVec<2>{cx, cy});
  if (pb.mesh) check_mesh_box(cfg, *pb.mesh, pb.grid);
  const auto per_cell = static_cast<int>(cfg.get_int("particles.per_cell"));
  const Index before = scope.seeded;
  pb.particles = file_body ? seed_file_body<2>(cfg, pb, *file_body, rho, scope)
                           : seed_body_2d(cfg, pb.grid, b0, b1, rho, pb.mesh.get(), scope);
  main.count = scope.seeded - before;
  pb.body_min = b0;
  pb.body_max = b1;
  auto named = named_bodies_from_config<2>(cfg, pb);
  const auto bodies = set_up_bodies<2>(cfg, pb, main, named, rho, scope);
  const auto of_part = assign_materials<2>(cfg, pb, bodies);

  const auto v0 = expressions(cfg, "initial.velocity", 2, kComponents[2]);
  const auto s0 = expressions(cfg, "initial.stress", 3, kStressComponents[2]);
  const auto b = expressions(cfg, "loading.body_force", 2, kComponents[2]);
  pb.initial_velocity = [v0](const Vec<2>& X) { return vector_from<2>(v0, X[0], X[1], 0.0, 0.0); };
  auto& P = pb.particles;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    P.v[i] = pb.initial_velocity(P.x0[i]);
    if (!P.v[i].allFinite())
      throw InputError(fmt::format(
          "{}: initial.velocity is not finite at (x, y) = ({:.6g}, {:.6g}) (particle {})",
          cfg.where("initial.velocity"), P.x0[i][0], P.x0[i][1], P.id[i]));
  }
  set_initial_stress<2>(
      cfg, pb, [s0](const Vec<2>& X) { return stress_from<2>(s0, X[0], X[1], 0.0, 0.0); }, b,
      mass_above<2>(cfg, pb, bodies, of_part));
  for (const Body<2>* body : bodies)
    if (body->file) file_initial_fields<2>(cfg, pb, *body);

  pb.body_force.time_dependent = b[0].uses_time() || b[1].uses_time();
  pb.body_force.position_dependent = b[0].uses_position() || b[1].uses_position();
  // Serial: an Expression is not thread-safe (one parser per copy); the fill is once a step.
  pb.body_force.fill = [b, uniform = !pb.body_force.position_dependent](
                           const Particles<2>& P, double t, std::vector<Vec<2>>& out) {
    if (uniform) {
      const Vec<2> value = vector_from<2>(b, 0.0, 0.0, 0.0, t);
      for (auto& o : out) o = value;
      return;
    }
    for (std::size_t i = 0; i < P.x.size(); ++i)
      out[i] = vector_from<2>(b, P.x[i][0], P.x[i][1], 0.0, t);
  };

  sides_from_config<2>(pb, cfg, b0, b1, per_cell);
  named_boundaries(pb, cfg);
  prescribed_from_config<2>(pb, cfg);
  named_loads(pb, cfg, scope);
  pb.exact = exact_from_config<2>(cfg);
  return pb;
}

Problem<3> make_custom_3d(const Config& cfg, const SeedScope& scope) {
  Problem<3> pb;
  pb.benchmark = "custom";
  // Named boundaries and their loads are the physical groups of a Gmsh file of triangles, which
  // only the 2D problem reads (grid.mesh); the six faces of a 3D grid take boundary.left, right,
  // bottom, top, back, front and the body's faces traction.* and pressure.*.
  for (const char* key :
       {"boundary.fixed", "boundary.roller", "boundary.frictional", "boundary.loaded"})
    if (!cfg.get_string(key).empty())
      throw InputError(fmt::format(
          "{}: {} names boundaries of a 2D mesh file (grid.mesh: triangles); a 3D custom "
          "problem has no mesh file: its grid's six sides take boundary.left, right, bottom, "
          "top, back, front",
          cfg.where(key), key));
  for (const char* key : {"traction.loaded", "pressure.loaded"})
    if (key[0] == 't' ? !is_zero(cfg, key) : cfg.get_string(key) != "0")
      throw InputError(fmt::format(
          "{}: {} loads the named boundaries of a 2D mesh file (grid.mesh, boundary.loaded); a "
          "3D custom problem loads its body's faces with traction.left ... front and "
          "pressure.left ... front",
          cfg.where(key), key));
  const Vec<3> g0 = per_direction<3>(cfg, "grid.min"), g1 = per_direction<3>(cfg, "grid.max");
  check_seeding_keys(cfg);
  Body<3> main;
  main.table = "body";
  main.file = FileBody<3>::from_config(cfg);
  const FileBody<3>* file_body = main.file ? &*main.file : nullptr;
  const Vec<3> b0 = file_body ? file_body->lower() : per_direction<3>(cfg, "body.min");
  const Vec<3> b1 = file_body ? file_body->upper() : per_direction<3>(cfg, "body.max");
  main.lo = b0;
  main.hi = b1;
  check_boxes<3>(cfg, g0, g1, file_body ? g0 : b0, file_body ? g1 : b1);
  pb.materials = materials_from_config(cfg, 3);
  const double rho = cfg.get_real("material.density");
  // Cells in y and z: given, or (0) the count closest to the cell width in x (cubic cells).
  const auto cx = static_cast<Index>(cfg.get_int("grid.cells"));
  auto cells_along = [&](const char* key, int d) {
    const auto given = static_cast<Index>(cfg.get_int(key));
    if (given != 0) return given;
    return std::max<Index>(1, std::llround((g1[d] - g0[d]) / ((g1[0] - g0[0]) / cx)));
  };
  pb.grid =
      Grid<3>(g0, g1, IVec<3>{cx, cells_along("grid.cells_y", 1), cells_along("grid.cells_z", 2)});
  // particles.per_cell per cell and direction, as in 2D and cube_mms_3d (x fastest, then y, z).
  const auto per_cell = static_cast<int>(cfg.get_int("particles.per_cell"));
  const Index before = scope.seeded;
  pb.particles = file_body ? seed_file_body<3>(cfg, pb, *file_body, rho, scope)
                           : seed_particles<3>(pb.grid, b0, b1, per_cell, rho, scope);
  main.count = scope.seeded - before;
  pb.body_min = b0;
  pb.body_max = b1;
  auto named = named_bodies_from_config<3>(cfg, pb);
  const auto bodies = set_up_bodies<3>(cfg, pb, main, named, rho, scope);
  const auto of_part = assign_materials<3>(cfg, pb, bodies);

  const auto v0 = expressions(cfg, "initial.velocity", 3, kComponents[3]);
  const auto s0 = expressions(cfg, "initial.stress", kStressCount[3], kStressComponents[3]);
  const auto b = expressions(cfg, "loading.body_force", 3, kComponents[3]);
  pb.initial_velocity = [v0](const Vec<3>& X) { return vector_from<3>(v0, X[0], X[1], X[2], 0.0); };
  auto& P = pb.particles;
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    P.v[i] = pb.initial_velocity(P.x0[i]);
    if (!P.v[i].allFinite())
      throw InputError(
          fmt::format("{}: initial.velocity is not finite at (x, y, z) = ({:.6g}, {:.6g}, {:.6g}) "
                      "(particle {})",
                      cfg.where("initial.velocity"), P.x0[i][0], P.x0[i][1], P.x0[i][2], P.id[i]));
  }
  set_initial_stress<3>(
      cfg, pb, [s0](const Vec<3>& X) { return stress_from<3>(s0, X[0], X[1], X[2], 0.0); }, b,
      mass_above<3>(cfg, pb, bodies, of_part));
  for (const Body<3>* body : bodies)
    if (body->file) file_initial_fields<3>(cfg, pb, *body);

  pb.body_force.time_dependent = b[0].uses_time() || b[1].uses_time() || b[2].uses_time();
  pb.body_force.position_dependent =
      b[0].uses_position() || b[1].uses_position() || b[2].uses_position();
  // Serial: an Expression is not thread-safe (one parser per copy); the fill is once a step.
  pb.body_force.fill = [b, uniform = !pb.body_force.position_dependent](
                           const Particles<3>& P, double t, std::vector<Vec<3>>& out) {
    if (uniform) {
      const Vec<3> value = vector_from<3>(b, 0.0, 0.0, 0.0, t);
      for (auto& o : out) o = value;
      return;
    }
    for (std::size_t i = 0; i < P.x.size(); ++i)
      out[i] = vector_from<3>(b, P.x[i][0], P.x[i][1], P.x[i][2], t);
  };

  sides_from_config<3>(pb, cfg, b0, b1, per_cell);
  prescribed_from_config<3>(pb, cfg);
  pb.exact = exact_from_config<3>(cfg);
  return pb;
}

}  // namespace mpm
