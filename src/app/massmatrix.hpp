#pragma once
// `mpm massmatrix`: condition numbers, CG iterations and p-multigrid V-cycles of B-spline mass
// matrices on 004's test problem (sections 4.6-4.7, Tables 4.2-4.4): the unit square (or
// interval), rho = 1, a constant force of 9.81 in -x and -y, relative residual 1e-8 from a zero
// initial guess; every degree and grid of the options, with the published values beside.
#include <iosfwd>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "solver/iterative.hpp"

namespace mpm {

struct MassMatrixOptions {
  int dim = 2;
  std::vector<int> degrees{1, 2, 3, 4, 5};
  std::vector<Index> cells{8, 16, 32, 64, 128};  // per direction (h^-1 on the unit box)
  // "dirichlet": the functions on the boundary are eliminated (fixed); "free": all functions.
  // 004 does not say; the table prints both readings' kappa when asked (--boundary).
  std::string boundary = "dirichlet";
  // 0: exact Gauss quadrature (004). N > 0: the MPM mass matrix sum_p m_p phi_i phi_j of N
  // particles per cell and direction at (k + 1/2) / N of the cell, each of mass rho h^d / N^d
  // (the initial particles of the vibrating bar and the plate, D eq. 2.34).
  int particles = 0;
  // Also run CG with the matrix-free application (SplineMassOperator: the functions evaluated
  // at the points in every application) and time it.
  bool matrix_free = false;
  double tolerance = 1e-8;  // 004 eq. 4.53
  int max_iterations = 100000;
  int max_cycles = 1000;
  PmgSettings pmg;
  std::string csv;  // write the rows here as CSV when not empty
};

struct MassMatrixRow {
  int degree = 0;
  Index cells = 0;
  Index unknowns = 0;     // per component
  double kappa = 0.0;     // lambda_max / lambda_min (004 eq. 4.56); inf: singular
  bool singular = false;  // lambda_min <= 1e-13 lambda_max, or the factorisation failed
  // Wall times [s]: the direct factorisation and solve, CG, p-multigrid set-up and solve.
  double direct_seconds = 0.0, cg_seconds = 0.0, pmg_seconds = 0.0;
  int cg_free_iterations = 0;  // matrix-free CG (matrix_free)
  bool cg_free_converged = false;
  double cg_free_seconds = 0.0, cg_free_difference = 0.0;  // ||x_free - x_cg|| / ||x_cg||
  int cg_iterations = 0;
  bool cg_converged = false;
  int pmg_cycles = 0;
  bool pmg_converged = false;
  // ||x - x_direct||_2 / ||x_direct||_2 (at most kappa times the relative residual)
  double pmg_error = 0.0;
  double cg_error = 0.0;
  double cg_bound = 0.0;  // iterations for 2 ((sqrt k - 1)/(sqrt k + 1))^n <= tolerance (eq. 4.57)
  // 004's values (NaN where it has none).
  double kappa_published = 0.0, cg_published = 0.0, pmg_published = 0.0;
};

// InputError for bad options.
std::vector<MassMatrixRow> massmatrix_study(const MassMatrixOptions& opt);
// The three tables (kappa, CG iterations, V-cycles), ours and 004's side by side.
void print_massmatrix(std::ostream& os, const MassMatrixOptions& opt,
                      const std::vector<MassMatrixRow>& rows);
void write_massmatrix_csv(const std::string& path, const std::vector<MassMatrixRow>& rows);

}  // namespace mpm
