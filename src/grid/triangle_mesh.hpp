#pragma once
// Unstructured triangular mesh in 2D (D 3.3: the P1 and Powell-Sabin backgrounds; D 6.1.2: TLS
// on triangles): vertices, counter-clockwise triangles, named boundaries (vertex sets and the
// edges between them), and point location through a bucket grid. It implements the mesh
// concept (grid/mesh.hpp). Meshes come from structured_triangles() below or from a Gmsh file
// (setup/gmsh_mesh.hpp).
#include <array>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"
#include "grid/mesh.hpp"

namespace mpm {

class TriangleMesh {
 public:
  static constexpr int kDim = 2;
  using Triangle = std::array<Index, 3>;
  using Edge = std::array<Index, 2>;
  // A named boundary: its edges (vertex pairs, each an edge of a triangle) and their vertices
  // (sorted, unique); outer: every edge lies on the mesh's outer boundary (one triangle), so it
  // has an outward normal (a line through the mesh's inside has none).
  struct Boundary {
    std::vector<Edge> edges;
    std::vector<Index> vertices;
    bool outer = true;
  };

  // Validates and prepares: vertex indices in range, no triangle of zero area (relative to the
  // mesh's extent), coordinates whose areas do not overflow, clockwise triangles turned
  // counter-clockwise (two vertices swapped), the boundaries' edges edges of its triangles.
  // `source` names the mesh in messages (a file, or "the generated mesh"). InputError otherwise.
  TriangleMesh(std::vector<Vec<2>> vertices, std::vector<Triangle> triangles,
               std::map<std::string, std::vector<Edge>> boundaries,
               std::string source = "the mesh");

  // The mesh concept.
  Index num_cells() const { return static_cast<Index>(triangles_.size()); }
  Index num_vertices() const { return static_cast<Index>(vertices_.size()); }
  const Vec<2>& vertex(Index v) const { return vertices_[static_cast<std::size_t>(v)]; }
  // The triangle containing x, -1 when x lies outside the mesh. A point on an edge or a vertex
  // shared by several triangles gets the lowest-numbered of them (barycentric coordinates
  // >= -1e-12), so the answer does not depend on the search order.
  Index cell_index(const Vec<2>& x) const;
  bool inside(const Vec<2>& x) const { return cell_index(x) >= 0; }
  const Triangle& cell_vertices(Index c) const { return triangles_[static_cast<std::size_t>(c)]; }
  double cell_volume(Index c) const { return area_[static_cast<std::size_t>(c)]; }
  std::vector<std::string> boundary_names() const;
  bool has_boundary(std::string_view name) const { return boundaries_.contains(name); }
  // InputError naming the mesh's boundaries for an unknown name.
  std::vector<Index> boundary_vertices(std::string_view name) const {
    return boundary(name).vertices;
  }
  const Boundary& boundary(std::string_view name) const;

  // The barycentric coordinates (lambda_0, lambda_1, lambda_2) of x in triangle c: the P1 shape
  // functions of its vertices, in cell_vertices order.
  std::array<double, 3> barycentric(Index c, const Vec<2>& x) const;
  // The constant gradients [1/m] of the barycentric coordinates in triangle c.
  const std::array<Vec<2>, 3>& barycentric_gradients(Index c) const {
    return gradient_[static_cast<std::size_t>(c)];
  }
  // The smallest altitude of any triangle [m] (twice its area over its longest edge): the CFL
  // length of P1 on the mesh (triangle_stability_factor's structured values are this over h).
  double min_altitude() const;
  // The smallest box holding the mesh.
  const Vec<2>& lower() const { return lo_; }
  const Vec<2>& upper() const { return hi_; }
  const std::string& source() const { return source_; }

 private:
  std::vector<Vec<2>> vertices_;
  std::vector<Triangle> triangles_;
  std::vector<double> area_;
  std::vector<std::array<Vec<2>, 3>> gradient_;
  std::map<std::string, Boundary, std::less<>> boundaries_;
  std::string source_;
  Vec<2> lo_, hi_;
  // Bucket grid over [lo_, hi_]: bins_ x bins_ square-ish bins, each listing (in ascending
  // order) the triangles whose bounding boxes overlap it; compressed rows.
  std::array<Index, 2> bins_{};
  Vec<2> bin_size_;
  std::vector<Index> bin_start_, bin_cells_;
  void build_buckets();
};

static_assert(Mesh<TriangleMesh>);

// The name of grid side (d, side) among a mesh's boundaries: "x-", "x+", "y-", "y+" (the
// structured triangulations, with_box_sides).
inline std::string side_name(int d, int side) {
  return std::string(1, "xy"[d]) + (side == 0 ? "-" : "+");
}

// The two structured triangulations of a rectangle: `right` splits each of the n[0] x n[1]
// rectangles along its diagonal from the lower-left to the upper-right corner (two right
// triangles); `criss_cross` adds a vertex at each rectangle's centre and joins it to the four
// corners (four triangles). Boundaries "x-", "x+", "y-", "y+" as on the uniform grid. Vertices:
// the rectangle corners x fastest, then (criss_cross) the centres.
enum class TrianglePattern { right, criss_cross };
TriangleMesh structured_triangles(const Vec<2>& lo, const Vec<2>& hi, const IVec<2>& n,
                                  TrianglePattern pattern);

// The mesh with the boundary edges (those of one triangle) that lie on the sides of its bounding
// box named as the grid's sides, "x-", "x+", "y-", "y+" (within 1e-10 of the box's diagonal),
// so that conditions on the sides of a rectangle (FixedSide, boundary.left = "fixed", ...)
// apply to a mesh read from a file. A side that holds no boundary edge is not added; a boundary
// of m named like a side is refused (InputError naming it).
TriangleMesh with_box_sides(const TriangleMesh& m);

// A named boundary that lies on one straight line (every vertex within 1e-10 of the mesh's box
// diagonal of the line through its first edge): a point on it and its unit normal; nullopt for a
// boundary that bends. InputError for an unknown name (as TriangleMesh::boundary).
struct BoundaryLine {
  Vec<2> point, normal;
};
std::optional<BoundaryLine> straight_boundary(const TriangleMesh& m, std::string_view name);

// dt_crit = factor h / c on the triangles of `pattern` over square cells of side h: the
// smallest altitude over h (right: 1 / sqrt 2; criss-cross: 1 / 2), the CFL length of the
// triangles, as the other bases' factors scale the cell size (driver/stepper.cpp).
double triangle_stability_factor(TrianglePattern pattern);

}  // namespace mpm
