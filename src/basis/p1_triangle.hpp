#pragma once
// P1 on triangles (D 3.3: the linear Lagrange basis of the triangular background mesh): one
// degree of freedom per mesh vertex, phi_i = the barycentric coordinate of vertex i in the
// triangle that contains the point, with the triangle's constant gradients. Partition of unity,
// linear reproduction and C0 continuity across edges hold exactly
// (tests/basis/test_p1_triangle.cpp).
#include <string_view>

#include "basis/stencil.hpp"
#include "grid/triangle_mesh.hpp"

namespace mpm {

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
    const auto& t = mesh_->cell_vertices(cell);
    const auto l = mesh_->barycentric(cell, x);
    const auto& g = mesh_->barycentric_gradients(cell);
    for (std::size_t a = 0; a < 3; ++a) {
      s.dof[a] = t[a];
      s.w[a] = l[a];
      s.grad[a] = g[a];
    }
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

}  // namespace mpm
