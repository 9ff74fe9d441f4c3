#pragma once
// Uniform structured background grid: the cells (knot spans) and their geometry. Which
// degrees of freedom live on it is decided by the basis (nodes for P1, control points for
// B-splines), so nodal storage is sized by the basis, not here.
#include <array>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"
#include "grid/mesh.hpp"

namespace mpm {

// The linear index of the integer coordinates c in a layout of n[d] entries per direction (x
// fastest), and the coordinates of linear index e: the numbering of a grid's cells.
template <int Dim>
Index linear_index(const IVec<Dim>& c, const IVec<Dim>& n) {
  Index idx = 0, stride = 1;
  for (int d = 0; d < Dim; ++d) {
    idx += c[d] * stride;
    stride *= n[d];
  }
  return idx;
}
template <int Dim>
IVec<Dim> linear_coords(Index e, const IVec<Dim>& n) {
  IVec<Dim> c;
  for (int d = 0; d < Dim; ++d) {
    c[d] = e % n[d];
    e /= n[d];
  }
  return c;
}

// A box of a grid's cells, [lo[d], hi[d]) along each direction d, in the grid's linear numbering
// (x fastest) of `cells` per direction. A process of a distributed run integrates the elements
// of one (RunState::own_cells).
template <int Dim>
struct CellBox {
  IVec<Dim> cells{};  // the grid's cells per direction
  IVec<Dim> lo{}, hi{};

  bool empty() const {
    for (int d = 0; d < Dim; ++d)
      if (hi[d] <= lo[d]) return true;
    return false;
  }
  // [first, end) of the linear numbering from the box's first cell to its last: its cells, and
  // between its rows others (holds tells them apart). {0, 0} when empty.
  std::array<Index, 2> span() const {
    if (empty()) return {0, 0};
    IVec<Dim> last = hi;
    for (int d = 0; d < Dim; ++d) --last[d];
    return {linear_index<Dim>(lo, cells), linear_index<Dim>(last, cells) + 1};
  }
  // Whether cell e (linear index) lies in the box.
  bool holds(Index e) const {
    const IVec<Dim> c = linear_coords<Dim>(e, cells);
    for (int d = 0; d < Dim; ++d)
      if (c[d] < lo[d] || c[d] >= hi[d]) return false;
    return true;
  }
};

template <int Dim>
struct Grid {
  static constexpr int kDim = Dim;
  static constexpr int kCellVertices = 1 << Dim;

  Vec<Dim> origin = Vec<Dim>::Zero();  // lower corner [m]
  Vec<Dim> h = Vec<Dim>::Ones();       // cell size per direction [m]
  IVec<Dim> cells{};                   // number of cells per direction

  Grid() { cells.fill(1); }
  Grid(const Vec<Dim>& lo, const Vec<Dim>& hi, const IVec<Dim>& n) : origin(lo), cells(n) {
    for (int d = 0; d < Dim; ++d) h[d] = (hi[d] - lo[d]) / static_cast<double>(n[d]);
  }

  Vec<Dim> upper() const {
    Vec<Dim> hi;
    for (int d = 0; d < Dim; ++d) hi[d] = origin[d] + h[d] * static_cast<double>(cells[d]);
    return hi;
  }
  Index num_cells() const {
    Index n = 1;
    for (int d = 0; d < Dim; ++d) n *= cells[d];
    return n;
  }
  double cell_volume() const { return h.prod(); }
  // Every cell of the grid as a box.
  CellBox<Dim> all_cells() const {
    CellBox<Dim> b;
    b.cells = cells;
    b.lo.fill(0);
    b.hi = cells;
    return b;
  }
  // The integer coordinates of cell e (linear index, x fastest).
  IVec<Dim> cell_coords(Index e) const { return linear_coords<Dim>(e, cells); }

  // Cell containing x along direction d; a point on the upper boundary belongs to the last cell.
  // Returns -1 or cells[d] when x lies outside (callers check with inside()).
  Index cell_of(double x, int d) const {
    const double s = (x - origin[d]) / h[d];
    if (!(s >= 0.0)) return -1;  // also catches NaN
    const auto c = static_cast<Index>(std::floor(s));
    if (c == cells[d] && s <= static_cast<double>(cells[d])) return cells[d] - 1;
    return c;
  }
  bool inside(const Vec<Dim>& x) const {
    for (int d = 0; d < Dim; ++d) {
      const Index c = cell_of(x[d], d);
      if (c < 0 || c >= cells[d]) return false;
    }
    return true;
  }
  // Linear cell index (x fastest) of the cell containing x.
  Index cell_index(const Vec<Dim>& x) const {
    IVec<Dim> c;
    for (int d = 0; d < Dim; ++d) c[d] = cell_of(x[d], d);
    return cell_index(c);
  }
  // Linear index of the cell with integer coordinates c (x fastest), and whether c is a cell of
  // the grid.
  Index cell_index(const IVec<Dim>& c) const { return linear_index<Dim>(c, cells); }
  bool has_cell(const IVec<Dim>& c) const {
    for (int d = 0; d < Dim; ++d)
      if (c[d] < 0 || c[d] >= cells[d]) return false;
    return true;
  }

  // The mesh interface (grid/mesh.hpp): vertices x fastest, (cells[d] + 1) per direction.
  Index num_vertices() const {
    Index n = 1;
    for (int d = 0; d < Dim; ++d) n *= cells[d] + 1;
    return n;
  }
  Vec<Dim> vertex(Index i) const {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) {
      const Index n = cells[d] + 1;
      x[d] = origin[d] + h[d] * static_cast<double>(i % n);
      i /= n;
    }
    return x;
  }
  // The 2^Dim vertices of cell c, lexicographic with x fastest (lower-left first).
  std::array<Index, kCellVertices> cell_vertices(Index c) const {
    const IVec<Dim> ci = cell_coords(c);
    std::array<Index, kCellVertices> out{};
    for (int k = 0; k < kCellVertices; ++k) {
      Index v = 0, stride = 1;
      for (int d = 0; d < Dim; ++d) {
        v += (ci[d] + ((k >> d) & 1)) * stride;
        stride *= cells[d] + 1;
      }
      out[static_cast<std::size_t>(k)] = v;
    }
    return out;
  }
  double cell_volume(Index /*c*/) const { return cell_volume(); }
  // Boundary vertex sets by name: "x-", "x+" (and "y-", "y+" in 2D, "z-", "z+" in 3D), the
  // vertices on the lower or upper grid side normal to that axis. InputError for another name.
  std::vector<std::string> boundary_names() const {
    std::vector<std::string> names;
    for (int d = 0; d < Dim; ++d)
      for (const char* s : {"-", "+"}) names.push_back(std::string(1, "xyz"[d]) + s);
    return names;
  }
  std::vector<Index> boundary_vertices(std::string_view name) const {
    const auto [d, side] = boundary_side<Dim>(name);
    std::vector<Index> out;
    for (Index i = 0; i < num_vertices(); ++i) {
      Index k = i;
      for (int e = 0; e < d; ++e) k /= cells[e] + 1;
      if (k % (cells[d] + 1) == (side == 0 ? 0 : cells[d])) out.push_back(i);
    }
    return out;
  }
};

static_assert(Mesh<Grid<1>>);
static_assert(Mesh<Grid<2>>);
static_assert(Mesh<Grid<3>>);

}  // namespace mpm
