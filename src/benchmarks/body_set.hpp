#pragma once
// The bodies of a 2D or 3D custom problem: [body] and the named bodies of [body.NAME] tables,
// each a box (min, max), a Gmsh body mesh (mesh) or a particle file (particles) with its own
// material (material, part_materials). They share the one background grid and its velocity
// field, so bodies that meet move together there: there is no contact algorithm between them.
// They are seeded in order, [body] first and the named ones by name, each one's particle ids
// following the one before's.
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "benchmarks/bodies.hpp"
#include "model/problem.hpp"

namespace mpm {

class Config;

// One body: [body] or a [body.NAME] table.
template <int Dim>
struct Body {
  std::string table;                  // "body" or "body.NAME"
  std::optional<FileBody<Dim>> file;  // its mesh or particle file; none: the box [lo, hi]
  Vec<Dim> lo = Vec<Dim>::Zero();     // the box, or the file body's bounding box [m]
  Vec<Dim> hi = Vec<Dim>::Zero();
  Index first_id = 0;  // its particles' ids: [first_id, first_id + count)
  Index count = 0;
  // TABLE.leaf, e.g. "body.footing.material".
  std::string key(std::string_view leaf) const { return table + "." + std::string(leaf); }
  // "the box body.min, body.max", or the file's source ("body mesh \"FILE\"", ...).
  std::string source() const;
  BodyRange range() const { return {table, source(), first_id, count}; }
};

// The values of a RealVector key, one per direction; InputError naming its line otherwise.
template <int Dim>
Vec<Dim> per_direction(const Config& cfg, const std::string& key);

// InputError naming WHAT.max unless hi - lo along `axis` is a finite number.
void check_extent(const Config& cfg, double lo, double hi, std::string_view what, char axis);

// InputError naming the key and the direction unless the grid [g0, g1] is non-empty and the box
// body [b0, b1] of `table` is non-empty and inside it.
template <int Dim>
void check_boxes(const Config& cfg, const Vec<Dim>& g0, const Vec<Dim>& g1, const Vec<Dim>& b0,
                 const Vec<Dim>& b1, const std::string& table = "body");

// The [body.NAME] tables of `cfg` in name order, their files read, not yet seeded. InputError
// naming the table: a table that gives no body (neither min and max, nor mesh, nor particles),
// a body that does not lie on pb's grid (its box outside the grid, a file body's point outside
// it or outside the triangles of grid.mesh), a box body on a mesh grid (grid.mesh), or named
// bodies with another solver than method.solver = "mpm".
template <int Dim>
std::vector<Body<Dim>> named_bodies_from_config(const Config& cfg, const Problem<Dim>& pb);

// The named bodies' particles after pb's (those of [body], ids [0, first_id)), each body's with
// the ids that follow the one before's (their first_id and count are set here), of density rho
// until their materials are assigned. A process of a distributed run keeps its slab's (scope).
template <int Dim>
void seed_named_bodies(const Config& cfg, Problem<Dim>& pb, std::vector<Body<Dim>>& named,
                       Index first_id, double rho, const SeedScope& scope);

// InputError naming both tables and the point where a point of one body's seeding lies inside
// another body: inside a box or an element of a body mesh, or inside the box of a particle-file
// particle (its volume's cube, or square in 2D, about it). Bodies may touch.
template <int Dim>
void check_bodies_apart(const Config& cfg, const Problem<Dim>& pb,
                        const std::vector<const Body<Dim>*>& bodies);

// The seeding keys the bodies of [body] and [body.NAME] use, from their keys: InputError naming
// the key for particles.per_cell without a box body, and particles.per_element without a body
// mesh. Before anything is read or seeded.
void check_seeding_keys(const Config& cfg);

// The points of a box body's seeding, f(X, volume), storing none ([body] on a 2D mesh grid is
// seeded by the main set-up, not here).
template <int Dim>
void for_each_box_point(const Config& cfg, const Grid<Dim>& g, const Body<Dim>& body,
                        const std::function<void(const Vec<Dim>& X, double volume)>& f);

}  // namespace mpm
