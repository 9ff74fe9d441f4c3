#pragma once
// P1 on triangles (D 3.3: the linear Lagrange basis of the triangular background mesh): one
// degree of freedom per mesh vertex, phi_i = the barycentric coordinate of vertex i in the
// triangle that contains the point, with the triangle's constant gradients. Partition of unity,
// linear reproduction and C0 continuity across edges hold exactly
// (tests/basis/test_p1_triangle.cpp).
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "basis/basis.hpp"
#include "basis/stencil.hpp"
#include "grid/grid.hpp"
#include "grid/triangle_mesh.hpp"

namespace mpm {

// The P1 functions of triangle `cell` at x: the barycentric coordinates of its vertices and
// their constant gradients.
inline void p1_triangle_stencil(const TriangleMesh& m, Index cell, const Vec<2>& x,
                                Stencil<2, 3>& s) {
  const auto& t = m.cell_vertices(cell);
  const auto l = m.barycentric(cell, x);
  const auto& g = m.barycentric_gradients(cell);
  for (std::size_t a = 0; a < 3; ++a) {
    s.dof[a] = t[a];
    s.w[a] = l[a];
    s.grad[a] = g[a];
  }
}

// A stencil with no weight (a point outside the mesh).
template <int N>
void clear_stencil(Stencil<2, N>& s) {
  for (std::size_t a = 0; a < static_cast<std::size_t>(N); ++a)
    s.dof[a] = 0, s.w[a] = 0.0, s.grad[a].setZero();
}

class P1TriangleBasis {
 public:
  static constexpr std::string_view kName = "linear";
  using StencilT = Stencil<2, 3>;

  explicit P1TriangleBasis(const TriangleMesh& mesh) : mesh_(&mesh) {}

  Index num_dofs() const { return mesh_->num_vertices(); }
  Vec<2> dof_position(Index i) const { return mesh_->vertex(i); }
  const TriangleMesh& mesh() const { return *mesh_; }

  // Values and gradients at x in triangle `cell` (which must contain x: barycentric
  // coordinates outside [0, 1] extrapolate).
  void evaluate_in(Index cell, const Vec<2>& x, StencilT& s) const {
    p1_triangle_stencil(*mesh_, cell, x, s);
  }
  // The same at any point of the mesh; false (s untouched) when x lies outside it.
  bool evaluate_point(const Vec<2>& x, StencilT& s) const {
    const Index c = mesh_->cell_index(x);
    if (c < 0) return false;
    evaluate_in(c, x, s);
    return true;
  }

 private:
  const TriangleMesh* mesh_;
};

// P1 on the run's triangles (method.basis = "p1_triangles"; D 3.3's P1 background on
// triangles): a structured triangulation of the grid (method.triangles = "right" |
// "criss_cross"), or a Gmsh mesh (grid.mesh), whose bounding box is then the grid. The grid
// keeps what it does for the other bases (particle seeding, the stability length, the check that
// particles stay inside, the re-sorting by cell); the functions live on the triangles. Structured
// vertex numbering: the grid's corners as Grid<2>::vertex (x fastest), then the criss-cross
// centres. A full stencil of the 3 vertices of the triangle holding the particle
// (kTensorProduct = false).
template <int Dim>
class TriangleP1Basis {
  static_assert(Dim == 2, "P1 on triangles is two-dimensional");

 public:
  static constexpr std::string_view kName = "p1_triangles";
  static constexpr bool kTensorProduct = false, kParticleDomain = false, kPrepare = false,
                        kNodalSums = false, kTrackedCorners = false, kIterative = false,
                        kTriangleMesh = true;
  using StencilT = Stencil<Dim, 3>;

  TriangleP1Basis(const Grid<Dim>& g, TrianglePattern pattern)
      : TriangleP1Basis(std::make_shared<const TriangleMesh>(
            structured_triangles(g.origin, g.upper(), g.cells, pattern))) {}
  // Shared: copies of the basis (the run's state holds one by value) share the mesh.
  explicit TriangleP1Basis(std::shared_ptr<const TriangleMesh> mesh) : mesh_(std::move(mesh)) {}

  Index num_dofs() const { return mesh_->num_vertices(); }
  // Not a tensor-product layout: one row of all DOFs (dof_strides of it is unused, the stencils
  // hold their DOFs).
  IVec<Dim> dofs_per_dim() const { return {num_dofs(), 1}; }
  Vec<Dim> dof_position(Index i) const { return mesh_->vertex(i); }
  // The vertices of the mesh boundary on the grid side (d, side): "x-", "x+", "y-", "y+"
  // (with_box_sides for a Gmsh mesh).
  std::vector<Index> boundary_dofs(int d, int side) const {
    return mesh_->boundary_vertices(side_name(d, side));
  }
  // The vertices of a named boundary (a mesh file's physical group, FixedSide::boundary).
  std::vector<Index> boundary_dofs(std::string_view name) const {
    return mesh_->boundary_vertices(name);
  }
  // False, with zero weights, outside the mesh.
  bool evaluate_point(const Vec<Dim>& x, StencilT& s) const {
    const Index c = mesh_->cell_index(x);
    if (c >= 0) {
      p1_triangle_stencil(*mesh_, c, x, s);
      return true;
    }
    clear_stencil(s);
    return false;
  }
  bool evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
    return evaluate_point(P.x[static_cast<std::size_t>(p)], s);
  }
  const TriangleMesh& mesh() const { return *mesh_; }
  // One polynomial piece per triangle: the triangle.
  static constexpr int pieces() { return 1; }
  std::array<Vec<2>, 3> piece(Index c, int) const {
    const auto& t = mesh_->cell_vertices(c);
    return {mesh_->vertex(t[0]), mesh_->vertex(t[1]), mesh_->vertex(t[2])};
  }

 private:
  std::shared_ptr<const TriangleMesh> mesh_;
};

static_assert(Basis<TriangleP1Basis<2>, 2>);

}  // namespace mpm
