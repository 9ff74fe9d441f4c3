#pragma once
// A body given as a mesh of simplices (body.mesh: a Gmsh file of triangles in 2D, tetrahedra in
// 3D): where the material is at the start, not a background grid. Particles are seeded in its
// elements (benchmarks/bodies.cpp) over the run's own grid. Each element belongs to at most one
// physical group of the body's dimension (a named part of the body: layers, inclusions).
#include <array>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace mpm {

template <int Dim>
class BodyMesh {
 public:
  static_assert(Dim == 2 || Dim == 3, "a body mesh has triangles (2D) or tetrahedra (3D)");
  using Element = std::array<Index, Dim + 1>;

  // Validates and prepares: at least one element, finite coordinates whose volumes do not
  // overflow, vertex indices in range, no element of zero volume (below 1e-12 of the cube of
  // its longest edge: a sliver that a quadrature rule cannot seed), negatively oriented elements
  // turned (two vertices swapped). `tags`: each element's number in the file, for messages;
  // `group`: each element's index into `group_names` (-1: in no group). `source` names the mesh
  // in messages. InputError naming the source and the element otherwise.
  BodyMesh(std::vector<Vec<Dim>> vertices, std::vector<Element> elements,
           std::vector<std::size_t> tags, std::vector<int> group,
           std::vector<std::string> group_names, std::string source);

  Index num_elements() const { return static_cast<Index>(elements_.size()); }
  Index num_vertices() const { return static_cast<Index>(vertices_.size()); }
  const Vec<Dim>& vertex(Index v) const { return vertices_[static_cast<std::size_t>(v)]; }
  const Element& element(Index e) const { return elements_[static_cast<std::size_t>(e)]; }
  // The element's area (2D) or volume (3D) [m^Dim], positive.
  double element_volume(Index e) const { return volume_[static_cast<std::size_t>(e)]; }
  // The element's number in the file (Gmsh's element tag).
  std::size_t tag(Index e) const { return tags_[static_cast<std::size_t>(e)]; }
  // The element's physical group (an index into group_names), -1 for none.
  int group(Index e) const { return group_[static_cast<std::size_t>(e)]; }
  const std::vector<std::string>& group_names() const { return group_names_; }
  // The sum of the elements' volumes [m^Dim].
  double volume() const { return total_; }
  const Vec<Dim>& lower() const { return lo_; }
  const Vec<Dim>& upper() const { return hi_; }
  const std::string& source() const { return source_; }
  // The element's shape quality [degrees]: its smallest angle (2D, 60 for an equilateral
  // triangle) or its smallest dihedral angle (3D, 70.53 for a regular tetrahedron).
  double min_angle(Index e) const;
  // An element other than `except` whose inside holds x (every barycentric coordinate above
  // 1e-10: a point on a shared face or edge is in neither), -1 for none; through a bucket grid of
  // the elements' bounding boxes, built on the first call. For the check that no two elements
  // overlap (benchmarks/bodies.cpp).
  Index other_element_holding(const Vec<Dim>& x, Index except) const;
  // The integral along the vertical (the last axis) above x of a weight per element:
  // sum_e weight(e) |{s >= x_v : (x with x_v = s) in e}| [weight m], element by element in the
  // order of the bucket grid (the same bits wherever it is evaluated). The overburden of a point:
  // weight = density gives the mass above it per unit area. A vertical face that the line runs
  // along counts for the element on its far side (larger x, then y) alone.
  double integral_above(const Vec<Dim>& x, const std::function<double(Index)>& weight) const;

 private:
  std::vector<Vec<Dim>> vertices_;
  std::vector<Element> elements_;
  std::vector<std::size_t> tags_;
  std::vector<int> group_;
  std::vector<std::string> group_names_;
  std::vector<double> volume_;
  double total_ = 0.0;
  std::string source_;
  Vec<Dim> lo_, hi_;
  // The bucket grid: bins_ per direction over [lo_, hi_], each bin listing the elements whose
  // bounding boxes overlap it (compressed rows).
  mutable std::array<Index, Dim> bins_{};
  mutable std::vector<Index> bin_start_, bin_elements_;
  void build_buckets() const;
  std::array<Index, Dim> bin_of(const Vec<Dim>& x) const;
  Index flat_bin(const std::array<Index, Dim>& b) const;
  // The length of element e's chord along the vertical through x above x_v (0 if none).
  double chord_above(Index e, const Vec<Dim>& x) const;
};

extern template class BodyMesh<2>;
extern template class BodyMesh<3>;

}  // namespace mpm
