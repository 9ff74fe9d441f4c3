#pragma once
// A benchmark owns its geometry, initial and boundary conditions and (where known) its exact
// solution; it hands the runner a Problem. Exact solutions are evaluated only for outputs and
// error norms, never inside the time-step loops.
#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "grid/grid.hpp"
#include "material/material_set.hpp"
#include "model/loads.hpp"
#include "particles/particles.hpp"

namespace mpm {

class TriangleMesh;  // grid/triangle_mesh.hpp

template <int Dim>
struct ExactState {
  Vec<Dim> u;       // displacement at the material point X [m]
  Vec<Dim> v;       // velocity [m/s]
  Mat<Dim> stress;  // Cauchy stress [Pa]
};

template <int Dim>
using ExactSolution = std::function<ExactState<Dim>(const Vec<Dim>& X, double t)>;

// A Dirichlet condition u_d = 0 on the grid side normal to `direction` (side 0 lower, 1 upper),
// for the velocity components whose bit is set in `components` (bit d: component d; default
// all). A roller (normal component only) is components = 1 << direction.
struct FixedSide {
  int direction = 0;
  int side = 0;
  unsigned components = ~0u;
  // Not empty: the named boundary of the run's triangle mesh (a mesh file's physical group,
  // boundary.fixed / boundary.roller) instead of the grid side (direction, side).
  std::string boundary = {};
  // Not zero: a roller on an inclined straight `boundary`: the velocity component along this
  // unit normal (x, y[, z]) is zero, whatever `components` says.
  std::array<double, 3> normal = {};
  // Not empty: a roller on a bent `boundary` of a mesh whose degrees of freedom are its vertices
  // (P1): v_i . n = 0 for each (vertex i, unit normal n); a corner vertex is listed with the
  // normals of both its edges.
  std::vector<std::pair<Index, std::array<double, 3>>> vertex_normals = {};
};

// A velocity prescribed on the degrees of freedom whose positions (Basis::dof_position: the grid
// nodes, a B-spline's Greville abscissae, a mesh's vertices) lie in the box [min, max]: a rigid
// footing or plate pushed at constant speed (prescribed.*). `components`: bit d set where
// component d is prescribed (all: a rough footing; the normal one: a smooth footing).
struct PrescribedVelocity {
  std::array<double, 3> min = {}, max = {};  // [m]
  std::array<double, 3> velocity = {};       // [m/s]
  unsigned components = ~0u;
};

// A grid side (boundary.* = "friction") or a straight named boundary of the run's triangle mesh
// (boundary.frictional) that is a rigid wall with Coulomb friction: the body cannot cross it but
// may leave it; where it presses on it, the tangential velocity sticks while the friction force
// it needs stays below mu times the contact force, and slips otherwise
// (stages::solve_acceleration).
struct FrictionWall {
  int direction = 0;
  int side = 0;     // 0: the lower side (outward normal -e_d), 1: the upper (+e_d)
  double mu = 0.0;  // Coulomb's coefficient [-]
  // Not empty: the named boundary of the mesh (its vertices' DOFs) instead of the grid side, with
  // its unit normal pointing out of the mesh, into the wall (x, y, z).
  std::string boundary = {};
  std::array<double, 3> normal = {};
};

// The names of the sides of the grid by direction (0 lower, 1 upper), as the boundary.* keys.
inline constexpr const char* kSideNames[3][2] = {
    {"left", "right"}, {"bottom", "top"}, {"back", "front"}};

// One body of a problem: its table ("body", or "body.NAME" of a custom problem's named bodies),
// where it comes from (for messages and summary.json), and its particles' ids [first_id,
// first_id + count): the bodies are seeded in order, each after the one before.
struct BodyRange {
  std::string table;
  std::string source;
  Index first_id = 0;
  Index count = 0;
};

template <int Dim>
struct Problem {
  static constexpr int kDim = Dim;
  std::string benchmark;
  Grid<Dim> grid;
  Particles<Dim> particles;
  // The laws of the body's materials (one in every problem but a custom one whose bodies name
  // several: [material.NAME]); each particle's is Particles::material.
  Materials materials;
  std::vector<FixedSide> fixed_sides;
  std::vector<FrictionWall> friction_walls;  // MPM solver, lumped mass
  // At most one box of prescribed velocities (MPM solver, lumped mass).
  std::optional<PrescribedVelocity> prescribed;
  // output.reactions: history.csv gets the reaction force on each constrained boundary (each of
  // fixed_sides, then of friction_walls, then the prescribed box), reaction_names() in order.
  bool reactions = false;
  // The triangles of a mesh file (grid.mesh; 2D, P1 and Powell-Sabin bases), shared with the
  // basis; then `grid` is the mesh's bounding box. Null: the basis lives on the grid (for the
  // triangle bases, a structured triangulation of it).
  std::shared_ptr<const TriangleMesh> mesh;
  BodyForce<Dim> body_force;
  std::vector<Traction<Dim>> tractions;
  // The body before deformation and its initial fields as functions of the material position,
  // for solvers that discretise the body themselves (the updated-Lagrangian FEM reference).
  Vec<Dim> body_min = Vec<Dim>::Zero(), body_max = Vec<Dim>::Zero();
  std::function<Vec<Dim>(const Vec<Dim>& X)> initial_velocity;
  std::function<Mat<Dim>(const Vec<Dim>& X)> initial_stress;  // empty: zero
  ExactSolution<Dim> exact;
  // No exact solution: compare with an updated-Lagrangian FEM reference computed alongside
  // (reference.dofs nodes, D 5.4.1).
  bool fem_reference = false;  // empty when the benchmark has no exact solution
  // What the set-up found questionable but not wrong (an input that makes the problem itself
  // unstable, ...): printed when the run starts and kept in summary.json's "warnings".
  std::vector<std::string> warnings;
  // The bodies of a custom problem of several ([body.NAME] tables), [body] first; empty for one.
  std::vector<BodyRange> bodies;
};

// The boundaries whose reactions history.csv has (Problem::reactions): a grid side by its key
// (left, right, bottom, top, back, front), a named boundary of a mesh by its name, and
// "prescribed" for the box of prescribed velocities.
template <int Dim>
std::vector<std::string> reaction_names(const Problem<Dim>& pb) {
  std::vector<std::string> names;
  for (const FixedSide& f : pb.fixed_sides)
    names.emplace_back(
        f.boundary.empty()
            ? kSideNames[static_cast<std::size_t>(f.direction)][static_cast<std::size_t>(f.side)]
            : f.boundary);
  for (const FrictionWall& w : pb.friction_walls)
    names.emplace_back(
        w.boundary.empty()
            ? kSideNames[static_cast<std::size_t>(w.direction)][static_cast<std::size_t>(w.side)]
            : w.boundary);
  if (pb.prescribed) names.emplace_back("prescribed");
  return names;
}

using AnyProblem = std::variant<Problem<1>, Problem<2>, Problem<3>>;

// Which of a problem's particles this process stores. On one process: every particle.
// A process of a distributed run stores only those of its block, so that no process holds the
// whole body, not even while the problem is set up: every process generates every particle in
// the one process's order and numbers them as one process does (Particles::id: the position in
// that order), and keeps those `keep` accepts. A counting pass (`layer_counts` set) keeps none
// and counts the particles in each cell layer along each axis, from which the blocks are cut
// (driver/run.cpp).
// The seeders below take a scope; the problems' constructors (benchmarks/benchmarks.hpp) pass
// theirs on.
struct SeedScope {
  // Keeps a particle in the cell with coordinates `cell` (one per axis; empty: outside the
  // grid). Empty: every particle.
  std::function<bool(std::span<const Index> cell)> keep;
  // Not null: the counting pass. Each seeded particle inside the grid adds 1 to the entry of its
  // cell layer along every axis (one vector per axis, resized to the grid's layers along it);
  // none is kept.
  std::vector<std::vector<double>>* layer_counts = nullptr;
  // The share of the body the processes on this machine hold together (1 on one process;
  // processes here / processes in all for a distributed run): the memory checks of the seeders
  // compare that share of the body's state with the machine's memory.
  double machine_share = 1.0;
  // The processes on this machine (1 on one process): each holds the grid's per-DOF velocity
  // conditions whole, beside its window of the grid arrays (the grid memory check).
  int machine_processes = 1;
  // The particles `keep` accepts, when known (the counting pass's): the seeders reserve room for
  // them and an eighth more (Particles::keep_room) before the first, so no array grows.
  Index expected = 0;
  // Added to by the seeders: the particles of the body on all processes (mutable: counted
  // through the const scope the constructors pass on).
  mutable Index seeded = 0;
};

// Where a seeder puts its particles: each point of the body it generates, in its order, gets the
// next id, and the scope decides which are stored (SeedScope; a counting pass stores none).
template <int Dim>
class SeedSink {
 public:
  // `g`: the grid whose layers the scope names (null only with the default scope: every
  // particle kept, none counted).
  SeedSink(const Grid<Dim>* g, double rho0, const SeedScope& scope)
      : grid_(g), rho0_(rho0), scope_(scope) {
    if ((scope.layer_counts || scope.keep) && g == nullptr)
      throw std::logic_error("SeedSink: a scope that keeps or counts by layer needs the grid");
    // (Several bodies are seeded one sink after the other: their counts add up.)
    if (scope.layer_counts && scope.layer_counts->size() != static_cast<std::size_t>(Dim)) {
      scope.layer_counts->resize(static_cast<std::size_t>(Dim));
      for (int d = 0; d < Dim; ++d)
        (*scope.layer_counts)[static_cast<std::size_t>(d)].assign(
            static_cast<std::size_t>(g->cells[d]), 0.0);
    }
  }
  // `total` points to come: room for every one when all are kept (one process), for the
  // scope's expected share and an eighth more when it keeps some (a distributed run), for none
  // in a counting pass.
  void reserve(Index total) {
    if (!scope_.layer_counts) particles_.reserve(scope_.keep ? scope_.expected * 9 / 8 : total);
  }
  void add(const Vec<Dim>& x, double volume) {
    const auto id = static_cast<CompactIndex>(next_++);
    if (scope_.layer_counts || scope_.keep) {
      // Inside the grid iff every cell coordinate is in [0, cells) (as Grid::inside).
      std::array<Index, Dim> cell{};
      bool inside = true;
      for (int d = 0; d < Dim; ++d) {
        cell[static_cast<std::size_t>(d)] = grid_->cell_of(x[d], d);
        inside = inside && cell[static_cast<std::size_t>(d)] >= 0 &&
                 cell[static_cast<std::size_t>(d)] < grid_->cells[d];
      }
      if (scope_.layer_counts) {
        if (inside)
          for (std::size_t d = 0; d < Dim; ++d)
            (*scope_.layer_counts)[d][static_cast<std::size_t>(cell[d])] += 1.0;
        return;
      }
      if (!scope_.keep(inside ? std::span<const Index>(cell) : std::span<const Index>())) return;
    }
    particles_.append(x, volume, rho0_ * volume, id);
  }
  // The particles kept; a process of a distributed run with room for an eighth more
  // (Particles::keep_room: particles that arrive from others).
  Particles<Dim> finish() {
    scope_.seeded += next_;
    if (scope_.keep && particles_.x.capacity() < particles_.x.size() * 9 / 8)
      particles_.keep_room(particles_.size() / 8);
    return std::move(particles_);
  }

 private:
  const Grid<Dim>* grid_;
  double rho0_;
  const SeedScope& scope_;
  Index next_ = 0;
  Particles<Dim> particles_;
};

// Particles evenly spaced over the body [lo, hi] (per direction), `per_cell` per grid cell
// width, each carrying an equal share of the volume; mass = rho0 V, F = I, zero stress. Numbered
// with x fastest, then y, then z. `body` (optional): only the points X with body(X) belong to
// the body (numbered among themselves: a body cut out of the box).
template <int Dim>
Particles<Dim> seed_particles(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi,
                              int per_cell, double rho0, const SeedScope& scope = {},
                              const std::function<bool(const Vec<Dim>& X)>& body = {});

// Particles in every triangle of m, per_triangle = m k^2 (m = 1, 3 or 6, k >= 1) each: the
// triangle is cut into k^2 similar sub-triangles (lines parallel to its edges at 1/k steps) and
// each sub-triangle into m parts of equal area (m = 3: joining its centroid to its vertices;
// m = 6: its three medians); one particle sits at the centroid of every part and carries its
// area. Volumes are exact shares of the mesh's area, the layout is the same in every triangle's
// reference coordinates, and a particle never lies on an edge. D 6.3.1 runs 12, 16 and 24
// "uniformly distributed" points per triangle without saying how; 12 = 3 * 4, 16 = 1 * 16 and
// 24 = 6 * 4 here. Particles are numbered by triangle, then by part. mass = rho0 V, F = I.
Particles<2> seed_particles_in_triangles(const TriangleMesh& m, int per_triangle, double rho0);
// (m, k) of a count, or {0, 0} when it is not of the form m k^2.
std::pair<int, int> triangle_seed_pattern(int per_triangle);

// The traction tau(t) on the face of the body box [lo, hi] normal to `direction` (side +1: at
// hi, -1: at lo), applied through the outer layer of the particles seed_particles(g, lo, hi,
// per_cell, .) places, each with its share of the face (Traction). The loaded points name their
// particles by id (the position in seed_particles' order), from the seeding pattern alone: the
// same points on every process of a distributed run, whichever particles it stores.
template <int Dim>
Traction<Dim> body_face_traction(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi,
                                 int per_cell, int direction, int side,
                                 std::function<Vec<Dim>(double t)> value);

}  // namespace mpm
