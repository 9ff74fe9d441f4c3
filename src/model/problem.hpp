#pragma once
// A benchmark owns its geometry, initial and boundary conditions and (where known) its exact
// solution; it hands the runner a Problem. Exact solutions are evaluated only for outputs and
// error norms, never inside the time-step loops.
#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "grid/grid.hpp"
#include "material/materials.hpp"
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

template <int Dim>
struct Problem {
  static constexpr int kDim = Dim;
  std::string benchmark;
  Grid<Dim> grid;
  Particles<Dim> particles;
  Material material;
  std::vector<FixedSide> fixed_sides;
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
};

using AnyProblem = std::variant<Problem<1>, Problem<2>, Problem<3>>;

// Particles evenly spaced over the body [lo, hi] (per direction), `per_cell` per grid cell
// width, each carrying an equal share of the volume; mass = rho0 V, F = I, zero stress.
template <int Dim>
Particles<Dim> seed_particles(const Grid<Dim>& g, const Vec<Dim>& lo, const Vec<Dim>& hi,
                              int per_cell, double rho0);

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
// per_cell, .) placed (P: those particles), each with its share of the face (Traction).
template <int Dim>
Traction<Dim> body_face_traction(const Grid<Dim>& g, const Particles<Dim>& P, const Vec<Dim>& lo,
                                 const Vec<Dim>& hi, int per_cell, int direction, int side,
                                 std::function<Vec<Dim>(double t)> value);

}  // namespace mpm
