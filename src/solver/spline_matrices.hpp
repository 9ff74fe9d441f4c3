#pragma once
// B-spline mass matrices assembled by exact Gauss quadrature (004 eq. 4.58) and the matrices
// between B-spline spaces of two degrees on the same knot spans, for the iterative mass solvers
// (solver/iterative.hpp) and `mpm massmatrix`. The basis is the project's (basis/bspline.hpp:
// open uniform knot vectors whose spans are the grid cells, cells + p functions per direction,
// x fastest); the degree is a run-time argument here, compiled once per dimension.
//
// Every matrix is B_p^T W B_q with B_p the values of the degree-p functions at a point set (rows:
// points, columns: functions) and W the point weights: with the tensor Gauss rule of
// max(p, q) + 1 points per direction and cell this is the exact integral
// int rho phi^p_i phi^q_j dOmega for constant rho; with the particles and their masses it is the
// MPM mass matrix sum_p m_p phi_i(x_p) phi_j(x_p) (D eq. 2.34).
#include <Eigen/Sparse>
#include <vector>

#include "core/types.hpp"
#include "grid/grid.hpp"

namespace mpm {

using SparseMatrixD = Eigen::SparseMatrix<double>;

template <int Dim>
struct PointSet {
  std::vector<Vec<Dim>> x;
  std::vector<double> w;  // quadrature weight times density [kg], or the particle mass
};

// The tensor Gauss-Legendre rule with n points per direction in every cell of g, weights times
// rho (constant density) [kg].
template <int Dim>
PointSet<Dim> gauss_points(const Grid<Dim>& g, int n, double rho = 1.0);

// n regular points per direction in every cell, at (k + 1/2) / n of the cell, each weighted by
// rho times the cell volume / n^Dim: the particles of a body seeded n per direction and cell
// with their masses (D eq. 2.34).
template <int Dim>
PointSet<Dim> regular_points(const Grid<Dim>& g, int n, double rho = 1.0);

// phi^p_j(x_k) for every point (row k) and function (column j) of the B-splines of degree p
// (1-5) on g. Points must lie in g (InputError otherwise, naming the point).
template <int Dim>
SparseMatrixD spline_values(const Grid<Dim>& g, int p, const std::vector<Vec<Dim>>& x);

// sum_k w_k phi^p_i(x_k) phi^q_j(x_k): rows degree p, columns degree q.
template <int Dim>
SparseMatrixD spline_mass(const Grid<Dim>& g, int p, int q, const PointSet<Dim>& pts);

// The exact mass matrix int rho phi^p_i phi^p_j (004 eq. 4.58) and the mixed one of degrees p
// and q, by Gauss quadrature with max(p, q) + 1 points per direction (exact for the integrand
// of degree p + q per direction).
template <int Dim>
SparseMatrixD spline_mass_exact(const Grid<Dim>& g, int p, int q, double rho = 1.0);

// int phi^p_i f dOmega for a constant f (per component), exact.
template <int Dim>
Eigen::VectorXd spline_load_exact(const Grid<Dim>& g, int p, double f);

// The functions of degree p on g that do not vanish on the boundary of the box (the ones a
// Dirichlet condition on every side fixes), in increasing order.
template <int Dim>
std::vector<Index> spline_boundary_functions(const Grid<Dim>& g, int p);

// y = M x for the kept functions (keep[i] != 0) of the degree-p B-splines, M = sum_k w_k phi
// phi^T over the point set, without assembling M: per application every point's functions are
// evaluated again, gather x and scatter back (the matrix-free form; memory: the points only).
// Serial, in point order (the same rounding every application).
template <int Dim>
class SplineMassOperator {
 public:
  SplineMassOperator(const Grid<Dim>& g, int p, PointSet<Dim> pts,
                     const std::vector<unsigned char>& keep);
  Index size() const { return static_cast<Index>(kept_.size()); }
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;

 private:
  Grid<Dim> g_;
  int p_;
  PointSet<Dim> pts_;
  std::vector<Index> to_kept_;  // function -> kept index, -1 when eliminated
  std::vector<Index> kept_;
};

// Number of functions of degree p on g.
template <int Dim>
Index spline_count(const Grid<Dim>& g, int p);

}  // namespace mpm
