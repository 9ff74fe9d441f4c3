#pragma once
// The mesh concept: the cell structure a basis and a mapping are built on. The uniform grid
// (grid/grid.hpp) implements it today; a triangular mesh (Gmsh), an advected node set (OTM, the
// unified approach) and the owned-plus-ghost part of a distributed grid are to implement it next
// (docs/architecture.md). Degrees of freedom are not part of the mesh: the basis decides where
// they live (P1 nodes are the vertices, B-spline control points are not).
#include <fmt/format.h>
#include <concepts>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace mpm {

template <class M>
concept Mesh = requires(const M& m, const Vec<M::kDim>& x, Index c, Index v,
                        std::string_view name) {
  { M::kDim } -> std::convertible_to<int>;
  { m.num_cells() } -> std::convertible_to<Index>;
  { m.num_vertices() } -> std::convertible_to<Index>;
  { m.vertex(v) } -> std::convertible_to<Vec<M::kDim>>;
  { m.inside(x) } -> std::convertible_to<bool>;
  { m.cell_index(x) } -> std::convertible_to<Index>;  // the cell containing x (inside(x))
  {m.cell_vertices(c)};                               // a range of vertex indices
  { m.cell_volume(c) } -> std::convertible_to<double>;
  { m.boundary_names() } -> std::convertible_to<std::vector<std::string>>;
  { m.boundary_vertices(name) } -> std::convertible_to<std::vector<Index>>;
};

// "x-" -> (0, 0), "x+" -> (0, 1), "y-" -> (1, 0), ...: the axis and side of a named side of a
// box-shaped mesh. InputError naming the valid names otherwise.
template <int Dim>
std::pair<int, int> boundary_side(std::string_view name) {
  for (int d = 0; d < Dim; ++d)
    for (int side = 0; side < 2; ++side)
      if (name.size() == 2 && name[0] == "xyz"[d] && name[1] == (side ? '+' : '-'))
        return {d, side};
  std::string valid;
  for (int d = 0; d < Dim; ++d)
    valid += fmt::format("{}\"{}-\", \"{}+\"", d ? ", " : "", "xyz"[d], "xyz"[d]);
  throw InputError(
      fmt::format("no boundary named \"{}\" on this mesh; the sides are {}", name, valid));
}

}  // namespace mpm
