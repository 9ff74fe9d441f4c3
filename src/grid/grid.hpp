#pragma once
// Uniform structured background grid: the cells (knot spans) and their geometry. Which
// degrees of freedom live on it is decided by the basis (nodes for P1, control points for
// B-splines), so nodal storage is sized by the basis, not here.
#include <cmath>

#include "core/types.hpp"

namespace mpm {

template <int Dim>
struct Grid {
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
  // Linear cell index (x fastest).
  Index cell_index(const Vec<Dim>& x) const {
    Index idx = 0, stride = 1;
    for (int d = 0; d < Dim; ++d) {
      idx += cell_of(x[d], d) * stride;
      stride *= cells[d];
    }
    return idx;
  }
};

}  // namespace mpm
