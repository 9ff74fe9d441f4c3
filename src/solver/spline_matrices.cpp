// B-spline mass matrices by quadrature (solver/spline_matrices.hpp).
#include "solver/spline_matrices.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <type_traits>

#include "basis/bspline.hpp"
#include "basis/gauss_legendre.hpp"

namespace mpm {

namespace {
// The tensor product, in every cell of g, of the 1D points t[a] in [0, 1] (cell units) with
// weights w[a] (fractions of the cell), weights times rho and the cell's volume.
template <int Dim>
PointSet<Dim> tensor_points(const Grid<Dim>& g, const std::vector<double>& t,
                            const std::vector<double>& w, double rho) {
  PointSet<Dim> out;
  const Index nc = g.num_cells();
  const std::size_t n = t.size();
  const auto per_cell = static_cast<std::size_t>(ipow(static_cast<int>(n), Dim));
  out.x.reserve(static_cast<std::size_t>(nc) * per_cell);
  out.w.reserve(static_cast<std::size_t>(nc) * per_cell);
  for (Index c = 0; c < nc; ++c) {
    const IVec<Dim> cell = g.cell_coords(c);
    for (std::size_t k = 0; k < per_cell; ++k) {
      std::size_t kk = k;
      Vec<Dim> x;
      double weight = rho;
      for (int d = 0; d < Dim; ++d) {
        const std::size_t a = kk % n;
        kk /= n;
        x[d] = g.origin[d] + g.h[d] * (static_cast<double>(cell[d]) + t[a]);
        weight *= g.h[d] * w[a];
      }
      out.x.push_back(x);
      out.w.push_back(weight);
    }
  }
  return out;
}
}  // namespace

template <int Dim>
PointSet<Dim> gauss_points(const Grid<Dim>& g, int n, double rho) {
  const GaussRule r = gauss_legendre(n);
  std::vector<double> t(r.xi.size()), w(r.w.size());
  for (std::size_t a = 0; a < t.size(); ++a) {
    t[a] = 0.5 * (r.xi[a] + 1.0);
    w[a] = 0.5 * r.w[a];
  }
  return tensor_points(g, t, w, rho);
}

template <int Dim>
PointSet<Dim> regular_points(const Grid<Dim>& g, int n, double rho) {
  if (n < 1) throw InputError(fmt::format("regular_points: {} points per direction", n));
  std::vector<double> t(static_cast<std::size_t>(n)), w(static_cast<std::size_t>(n), 1.0 / n);
  for (int a = 0; a < n; ++a) t[static_cast<std::size_t>(a)] = (a + 0.5) / n;
  return tensor_points(g, t, w, rho);
}

template <int Dim>
SparseMatrixD spline_values(const Grid<Dim>& g, int p, const std::vector<Vec<Dim>>& x) {
  if (p < 1 || p > 5)
    throw InputError(fmt::format("B-spline degree {}: the degrees are 1 to 5", p));
  return with_bspline_degree(p, [&](auto degree) {
    constexpr int P = decltype(degree)::value;
    const BSplineBasis<Dim, P> basis(g);
    typename BSplineBasis<Dim, P>::StencilT s;
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(x.size() * static_cast<std::size_t>(s.kSize));
    for (std::size_t k = 0; k < x.size(); ++k) {
      if (!g.inside(x[k]))
        throw InputError(fmt::format("spline_values: point {} lies outside the grid", k));
      basis.evaluate_point(x[k], s);
      for (int a = 0; a < s.kSize; ++a)
        if (s.w[a] != 0.0) t.emplace_back(static_cast<Index>(k), s.dof[a], s.w[a]);
    }
    SparseMatrixD B(static_cast<Index>(x.size()), basis.num_dofs());
    B.setFromTriplets(t.begin(), t.end());
    return B;
  });
}

template <int Dim>
SparseMatrixD spline_mass(const Grid<Dim>& g, int p, int q, const PointSet<Dim>& pts) {
  const SparseMatrixD Bp = spline_values(g, p, pts.x);
  const SparseMatrixD Bq = p == q ? Bp : spline_values(g, q, pts.x);
  const Eigen::Map<const Eigen::VectorXd> w(pts.w.data(), static_cast<Index>(pts.w.size()));
  SparseMatrixD M = Bp.transpose() * (w.asDiagonal() * Bq);
  M.makeCompressed();
  return M;
}

template <int Dim>
SparseMatrixD spline_mass_exact(const Grid<Dim>& g, int p, int q, double rho) {
  return spline_mass(g, p, q, gauss_points(g, std::max(p, q) + 1, rho));
}

template <int Dim>
Eigen::VectorXd spline_load_exact(const Grid<Dim>& g, int p, double f) {
  const PointSet<Dim> pts = gauss_points(g, p + 1, f);
  const SparseMatrixD B = spline_values(g, p, pts.x);
  const Eigen::Map<const Eigen::VectorXd> w(pts.w.data(), static_cast<Index>(pts.w.size()));
  return B.transpose() * w;
}

template <int Dim>
SplineMassOperator<Dim>::SplineMassOperator(const Grid<Dim>& g, int p, PointSet<Dim> pts,
                                            const std::vector<unsigned char>& keep)
    : g_(g), p_(p), pts_(std::move(pts)) {
  to_kept_.assign(keep.size(), -1);
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) {
      to_kept_[i] = static_cast<Index>(kept_.size());
      kept_.push_back(static_cast<Index>(i));
    }
  for (std::size_t k = 0; k < pts_.x.size(); ++k)
    if (!g_.inside(pts_.x[k]))
      throw InputError(fmt::format("SplineMassOperator: point {} lies outside the grid", k));
}

template <int Dim>
void SplineMassOperator<Dim>::apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  y.setZero(size());
  with_bspline_degree(p_, [&](auto degree) {
    constexpr int P = decltype(degree)::value;
    const BSplineBasis<Dim, P> basis(g_);
    typename BSplineBasis<Dim, P>::StencilT s;
    for (std::size_t k = 0; k < pts_.x.size(); ++k) {
      basis.evaluate_point(pts_.x[k], s);
      double v = 0.0;
      for (int a = 0; a < s.kSize; ++a) {
        const Index i = to_kept_[static_cast<std::size_t>(s.dof[a])];
        if (i >= 0) v += s.w[a] * x[i];
      }
      v *= pts_.w[k];
      for (int a = 0; a < s.kSize; ++a) {
        const Index i = to_kept_[static_cast<std::size_t>(s.dof[a])];
        if (i >= 0) y[i] += s.w[a] * v;
      }
    }
  });
}

template class SplineMassOperator<1>;
template class SplineMassOperator<2>;
template class SplineMassOperator<3>;

template <int Dim>
Index spline_count(const Grid<Dim>& g, int p) {
  Index n = 1;
  for (int d = 0; d < Dim; ++d) n *= g.cells[d] + p;
  return n;
}

template <int Dim>
std::vector<Index> spline_boundary_functions(const Grid<Dim>& g, int p) {
  IVec<Dim> n;
  for (int d = 0; d < Dim; ++d) n[d] = g.cells[d] + p;
  std::vector<Index> out;
  for (Index i = 0; i < spline_count(g, p); ++i) {
    Index rem = i;
    bool boundary = false;
    for (int d = 0; d < Dim; ++d) {
      const Index c = rem % n[d];
      rem /= n[d];
      // Open knot vectors: only the first and last function of a direction are nonzero on the
      // box's sides (they interpolate there).
      boundary = boundary || c == 0 || c == n[d] - 1;
    }
    if (boundary) out.push_back(i);
  }
  return out;
}

template PointSet<1> gauss_points<1>(const Grid<1>&, int, double);
template PointSet<2> gauss_points<2>(const Grid<2>&, int, double);
template PointSet<3> gauss_points<3>(const Grid<3>&, int, double);
template PointSet<1> regular_points<1>(const Grid<1>&, int, double);
template PointSet<2> regular_points<2>(const Grid<2>&, int, double);
template PointSet<3> regular_points<3>(const Grid<3>&, int, double);
template SparseMatrixD spline_values<1>(const Grid<1>&, int, const std::vector<Vec<1>>&);
template SparseMatrixD spline_values<2>(const Grid<2>&, int, const std::vector<Vec<2>>&);
template SparseMatrixD spline_values<3>(const Grid<3>&, int, const std::vector<Vec<3>>&);
template SparseMatrixD spline_mass<1>(const Grid<1>&, int, int, const PointSet<1>&);
template SparseMatrixD spline_mass<2>(const Grid<2>&, int, int, const PointSet<2>&);
template SparseMatrixD spline_mass<3>(const Grid<3>&, int, int, const PointSet<3>&);
template SparseMatrixD spline_mass_exact<1>(const Grid<1>&, int, int, double);
template SparseMatrixD spline_mass_exact<2>(const Grid<2>&, int, int, double);
template SparseMatrixD spline_mass_exact<3>(const Grid<3>&, int, int, double);
template Eigen::VectorXd spline_load_exact<1>(const Grid<1>&, int, double);
template Eigen::VectorXd spline_load_exact<2>(const Grid<2>&, int, double);
template Eigen::VectorXd spline_load_exact<3>(const Grid<3>&, int, double);
template Index spline_count<1>(const Grid<1>&, int);
template Index spline_count<2>(const Grid<2>&, int);
template Index spline_count<3>(const Grid<3>&, int);
template std::vector<Index> spline_boundary_functions<1>(const Grid<1>&, int);
template std::vector<Index> spline_boundary_functions<2>(const Grid<2>&, int);
template std::vector<Index> spline_boundary_functions<3>(const Grid<3>&, int);

}  // namespace mpm
