#pragma once
// Quadratic Powell-Sabin splines on a triangular mesh (D 3.3: PS-MPM, the B-spline basis of
// unstructured triangulations): C1, piecewise quadratic on the Powell-Sabin 6-split of every
// triangle, three normalized B-splines per mesh vertex (Dierckx, "On calculating normalized
// Powell-Sabin B-splines", CAGD 15 (1997) 61-78; Speleers, Manni, Pelosi, Sampoli, CMAME 221
// (2012) 132-148). The functions are nonnegative, form a partition of unity, reproduce
// quadratics and vanish outside the triangles around their vertex
// (tests/basis/test_powell_sabin.cpp).
//
// Construction (all at construction time):
//  * PS-6 refinement. Z_c, the split point of triangle c, is its incenter. The split point R_e
//    of an interior edge is where the segment between the incenters of its two triangles
//    crosses it (it does: it lies between the points where the two incircles touch the edge),
//    which keeps the split lines Z_c R_e Z_c' straight, as C1 needs; a boundary edge is split
//    at its midpoint. Each triangle splits into six mini-triangles (V_k, R_k, Z), (R_k, V_k+1,
//    Z), k = 0, 1, 2, where R_k splits the edge (V_k, V_k+1).
//  * PS points of vertex V_i: V_i and the midpoints of the refinement's edges at V_i, i.e. of
//    V_i R_e for its edges e and of V_i Z_c for its triangles c.
//  * PS triangle of V_i, Q_i0 Q_i1 Q_i2 (counter-clockwise): any triangle containing the PS
//    points gives a nonnegative basis (Dierckx 1997); a small one gives a well conditioned
//    one. The choice here: the convex hull of the PS points, and as candidate sides
//    its supporting lines along each hull edge and, at each hull vertex, the supporting line
//    whose outward normal bisects those of the vertex's two edges; the PS triangle is the
//    smallest-area triangle bounded by three candidates (on ties the first found: edge lines
//    before vertex lines, each in counter-clockwise hull order from the leftmost, then lowest,
//    point). Every candidate supports the hull, so the triangle contains every PS point and
//    each side touches one. Edge lines alone are not enough (a rectangular hull bounds no
//    triangle with them); with the vertex lines consecutive candidate normals are less than 90
//    degrees apart, so some three bound a triangle. Dierckx computes the minimal-area triangle
//    with small linear or quadratic programs; this search approximates it without an optimizer
//    (for a square hull it finds the minimum, twice the square's area).
//  * The B-splines of V_i: the tangent plane of N_ij at V_i is L_ij, the barycentric coordinate
//    of Q_ij in the PS triangle, and N_ij has value and gradient 0 at every other vertex
//    (Dierckx 1997: the triplets alpha_ij = L_ij(V_i), (beta_ij, gamma_ij) = grad L_ij; they
//    sum to (1, 0, 0) over j, hence the partition of unity). On each triangle the Bezier
//    ordinates of the 19 domain points of its 6-split follow from these Hermite data and the
//    C1 conditions (Dierckx 1997; Speleers et al. 2012), see powell_sabin.cpp.
//
// DOF 3 i + j is N_ij. A quadratic f has the coefficients c_ij = f(V_i) + grad f(V_i) . (Q_ij -
// V_i), the tangent plane of f at V_i evaluated at Q_ij (x = sum_ij Q_ij N_ij for f = x).
#include <fmt/format.h>

#include <array>
#include <cmath>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "basis/basis.hpp"
#include "basis/p1_triangle.hpp"
#include "basis/stencil.hpp"
#include "core/types.hpp"
#include "grid/grid.hpp"
#include "grid/triangle_mesh.hpp"

namespace mpm {

class PowellSabinBasis {
 public:
  static constexpr std::string_view kName = "powell_sabin";
  using StencilT = Stencil<2, 9>;
  // The 19 domain points of the quadratic Bezier nets on a triangle's 6-split, in this order:
  // the vertices V_a (0-2); per edge k = (V_k, V_k+1) the midpoints of V_k R_k and V_k+1 R_k
  // (3 + 2k, 4 + 2k); the midpoints of V_a Z (9-11); R_k (12-14); the midpoints of R_k Z
  // (15-17); Z (18).
  static constexpr int kDomainPoints = 19;

  explicit PowellSabinBasis(const TriangleMesh& mesh);

  Index num_dofs() const { return 3 * mesh_->num_vertices(); }
  // Q_ij for DOF 3 i + j: the control point, since x = sum_ij Q_ij N_ij(x).
  Vec<2> dof_position(Index dof) const {
    return ps_triangle(dof / 3)[static_cast<std::size_t>(dof % 3)];
  }
  const TriangleMesh& mesh() const { return *mesh_; }

  // Values and gradients [1/m] at x in triangle `cell`: the polynomial piece of the
  // mini-triangle containing x (on an edge between two, either: they agree to first order; for
  // x outside the triangle, the piece whose smallest barycentric coordinate at x is largest,
  // extrapolated). Entry 3 a + j is N_ij of i = cell_vertices(cell)[a].
  void evaluate_in(Index cell, const Vec<2>& x, StencilT& s) const;
  // The same at any point of the mesh; false (s untouched) when x lies outside it.
  bool evaluate_point(const Vec<2>& x, StencilT& s) const {
    const Index c = mesh_->cell_index(x);
    if (c < 0) return false;
    evaluate_in(c, x, s);
    return true;
  }
  // The quadratic piece of mini-triangle `mini` (0-5) of `cell` at x, wherever x lies: both
  // sides of an edge of the refinement (continuity checks).
  void evaluate_piece(Index cell, int mini, const Vec<2>& x, StencilT& s) const;

  // The refinement and the PS triangles.
  const Vec<2>& split_point(Index cell) const { return cells_[static_cast<std::size_t>(cell)].z; }
  // R_k of edge (V_k, V_k+1), k = 0, 1, 2, V_k = cell_vertices(cell)[k].
  const Vec<2>& edge_split_point(Index cell, int k) const {
    return cells_[static_cast<std::size_t>(cell)].r[static_cast<std::size_t>(k)];
  }
  // Mini-triangle m (0-5) of `cell`, counter-clockwise: (V_k, R_k, Z) for m = 2k, (R_k, V_k+1, Z)
  // for m = 2k + 1.
  std::array<Vec<2>, 3> mini_triangle(Index cell, int mini) const;
  // The PS points of vertex v: v itself, then one per edge at v and one per triangle at v.
  std::span<const Vec<2>> ps_points(Index v) const {
    const auto b = static_cast<std::size_t>(ps_start_[static_cast<std::size_t>(v)]);
    const auto e = static_cast<std::size_t>(ps_start_[static_cast<std::size_t>(v) + 1]);
    return {ps_points_.data() + b, e - b};
  }
  // Q_v0, Q_v1, Q_v2, counter-clockwise.
  const std::array<Vec<2>, 3>& ps_triangle(Index v) const {
    return ps_triangle_[static_cast<std::size_t>(v)];
  }
  // The Bezier ordinates of entry f = 3 a + j of the cell's stencil at its 19 domain points.
  const std::array<double, kDomainPoints>& bezier_ordinates(Index cell, int f) const {
    return cells_[static_cast<std::size_t>(cell)].ordinate[static_cast<std::size_t>(f)];
  }

 private:
  struct Cell {
    Vec<2> z;
    std::array<Vec<2>, 3> r;
    // Per mini-triangle: its first vertex and the gradients [1/m] of its barycentric
    // coordinates.
    std::array<Vec<2>, 6> origin;
    std::array<std::array<Vec<2>, 3>, 6> gradient;
    std::array<std::array<double, kDomainPoints>, 9> ordinate;
  };
  const TriangleMesh* mesh_;
  std::vector<Cell> cells_;
  std::vector<Index> ps_start_;
  std::vector<Vec<2>> ps_points_;
  std::vector<std::array<Vec<2>, 3>> ps_triangle_;
};

// Powell-Sabin splines on a structured triangulation of the run's grid (method.basis =
// "powell_sabin", method.triangles = "right" | "criss_cross"; D 3.3, PS-MPM): as
// TriangleP1Basis (basis/p1_triangle.hpp), the grid keeps seeding, the named sides, the
// stability length and the inside check, and the functions live on its triangles. DOFs 3 v + j
// of mesh vertex v. A side's DOFs are the three of each vertex on it: those are the functions
// that do not vanish on the side (the others vanish with their gradient on every edge away
// from their vertex), so fixing them fixes the velocity on the whole side.
template <int Dim>
class PowellSabinGridBasis {
  static_assert(Dim == 2, "Powell-Sabin splines are two-dimensional");

 public:
  static constexpr std::string_view kName = "powell_sabin";
  static constexpr bool kTensorProduct = false, kParticleDomain = false, kPrepare = false,
                        kNodalSums = false, kTrackedCorners = false, kIterative = false,
                        kTriangleMesh = true;
  using StencilT = Stencil<Dim, 9>;
  // With consistent mass, runs whose triangles hold fewer particles than this stop with a
  // non-finite stress at a time a smaller step does not change, and partial lumping does not
  // prevent it (docs/verification.md, "D Fig. 3.9 on unstructured meshes": 6 per triangle stop
  // on every mesh, 12 on the finest, 24 run on all); set-up warns (driver/stepper_impl.hpp).
  static constexpr int kConsistentMassPoints = 12;

  // The mesh is shared, so that copies of the basis (the run's state holds one by value) keep
  // the address the spline construction refers to.
  PowellSabinGridBasis(const Grid<Dim>& g, TrianglePattern pattern)
      : PowellSabinGridBasis(std::make_shared<const TriangleMesh>(
            structured_triangles(g.origin, g.upper(), g.cells, pattern))) {}
  // A given mesh (grid.mesh: a Gmsh file).
  explicit PowellSabinGridBasis(std::shared_ptr<const TriangleMesh> mesh)
      : mesh_(std::move(mesh)), ps_(*mesh_) {}

  Index num_dofs() const { return ps_.num_dofs(); }
  // Not a tensor-product layout (dof_strides of it is unused, the stencils hold their DOFs).
  IVec<Dim> dofs_per_dim() const { return {num_dofs(), 1}; }
  Vec<Dim> dof_position(Index i) const { return ps_.dof_position(i); }
  // The DOFs whose PS-triangle vertex Q_vj lies on the side's line, two per vertex on it. The
  // third function of such a vertex has value and tangential derivative 0 along the side (its
  // barycentric coordinate L_vj vanishes on the PS triangle's side there), so fixing the two
  // makes the velocity zero on the side and leaves its normal derivative free; fixing all three
  // would also force that derivative to zero. The PS triangles of boundary vertices have a
  // side on the boundary (the hull's supporting line along it; checked here).
  std::vector<Index> boundary_dofs(int d, int side) const {
    Vec<Dim> point = side == 0 ? mesh_->lower() : mesh_->upper(), normal = Vec<Dim>::Zero();
    normal[d] = 1.0;
    return dofs_on_line(side_name(d, side), point, normal);
  }
  // The same on a named boundary (FixedSide::boundary), which must lie on one straight line.
  std::vector<Index> boundary_dofs(std::string_view name) const {
    const auto line = straight_boundary(*mesh_, name);
    if (!line)
      throw InputError(fmt::format(
          "{}: boundary \"{}\" does not lie on one straight line; Powell-Sabin splines fix the "
          "velocity along straight boundaries (the two functions per vertex whose PS-triangle "
          "vertex lies on the line); split it into straight physical groups",
          mesh_->source(), name));
    return dofs_on_line(name, line->point, line->normal);
  }
  // False, with zero weights, outside the mesh.
  bool evaluate_point(const Vec<Dim>& x, StencilT& s) const {
    if (ps_.evaluate_point(x, s)) return true;
    clear_stencil(s);
    return false;
  }
  bool evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
    return evaluate_point(P.x[static_cast<std::size_t>(p)], s);
  }
  const PowellSabinBasis& splines() const { return ps_; }
  const TriangleMesh& mesh() const { return *mesh_; }  // the macro triangles
  // The polynomial pieces of a triangle: its six mini-triangles.
  static constexpr int pieces() { return 6; }
  std::array<Vec<2>, 3> piece(Index c, int k) const { return ps_.mini_triangle(c, k); }

 private:
  std::shared_ptr<const TriangleMesh> mesh_;
  PowellSabinBasis ps_;

  // The DOFs of boundary `name` whose PS-triangle vertex lies on the line through `point` with
  // unit `normal` (within 1e-12 of the mesh's box diagonal), two per boundary vertex. Always
  // found on the structured triangulations; a mesh from a file may place a vertex where the
  // construction's smallest triangle leaves the line (then the input is refused).
  std::vector<Index> dofs_on_line(std::string_view name, const Vec<Dim>& point,
                                  const Vec<Dim>& normal) const {
    const double tol = 1e-12 * (mesh_->upper() - mesh_->lower()).norm();
    std::vector<Index> dofs;
    for (Index v : mesh_->boundary_vertices(name)) {
      int on_line = 0;
      for (Index j = 0; j < 3; ++j)
        if (std::abs((ps_.ps_triangle(v)[static_cast<std::size_t>(j)] - point).dot(normal)) <=
            tol) {
          dofs.push_back(3 * v + j);
          ++on_line;
        }
      if (on_line != 2)
        throw InputError(fmt::format(
            "{}: the Powell-Sabin triangle of vertex {} at ({:.6g}, {:.6g}) on boundary \"{}\" "
            "has {} corner(s) on the boundary's line, not 2, so the velocity cannot be fixed "
            "there without constraining the normal derivative; refine the mesh near that vertex "
            "or leave the boundary free",
            mesh_->source(), v, mesh_->vertex(v)[0], mesh_->vertex(v)[1], name, on_line));
    }
    return dofs;
  }
};

static_assert(Basis<PowellSabinGridBasis<2>, 2>);

}  // namespace mpm
