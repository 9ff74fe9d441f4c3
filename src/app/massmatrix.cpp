// `mpm massmatrix` (app/massmatrix.hpp; 004 Tables 4.2-4.4).
#include "app/massmatrix.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <chrono>
#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>

#include "io/output.hpp"
#include "solver/ldlt_pivots.hpp"
#include "solver/spline_matrices.hpp"

namespace mpm {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// 004 Table 4.2 (kappa, h^-1 = 8, 16, 32, 64), Table 4.3 (CG iterations, h^-1 = 16, 32, 64,
// 128) and Table 4.4 (V-cycles, h^-1 = 8, 16, 32, 64); rows p = 1..5.
constexpr Index kKappaCells[] = {8, 16, 32, 64};
constexpr double kKappa[5][4] = {{7.38, 8.55, 8.89, 8.97},
                                 {52.1, 55.1, 56.0, 56.2},
                                 {440, 424, 420, 422},
                                 {3770, 3360, 3290, 3300},
                                 {33000, 26100, 25200, 25200}};
constexpr Index kCgCells[] = {16, 32, 64, 128};
constexpr double kCg[5][4] = {{18, 18, 18, 17},
                              {34, 46, 46, 44},
                              {68, 93, 95, 91},
                              {93, 178, 196, 187},
                              {156, 242, 252, 227}};
constexpr Index kPmgCells[] = {8, 16, 32, 64};
constexpr double kPmg[5][4] = {
    {1, 1, 1, 1}, {4, 4, 4, 3}, {15, 12, 10, 9}, {22, 17, 13, 11}, {58, 38, 27, 20}};

double published(const double (&table)[5][4], const Index (&cells)[4], int p, Index n) {
  if (p < 1 || p > 5) return kNaN;
  for (int k = 0; k < 4; ++k)
    if (cells[k] == n) return table[p - 1][k];
  return kNaN;
}

// The kept functions: all, or all but those on the boundary (dirichlet).
template <int Dim>
std::vector<unsigned char> kept(const Grid<Dim>& g, int p, bool dirichlet) {
  std::vector<unsigned char> keep(static_cast<std::size_t>(spline_count(g, p)), 1);
  if (dirichlet)
    for (Index i : spline_boundary_functions(g, p)) keep[static_cast<std::size_t>(i)] = 0;
  return keep;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The quadrature points: p + 1 Gauss points per direction and cell (exact, 004), or N regular
// particles per direction and cell of mass rho h^d / N^d (rho = 1).
template <int Dim>
PointSet<Dim> points(const Grid<Dim>& g, int p, int particles) {
  return particles == 0 ? gauss_points(g, p + 1) : regular_points(g, particles);
}

// lambda_max / lambda_min of the 1D matrix (dense; at most a few hundred functions). The 2D
// matrix of the unit square with rho = 1 is the Kronecker product M_1D (x) M_1D (tensor-product
// functions, a tensor-product point set with product weights: Gauss points or the regular
// particles; tests/solver/test_iterative.cpp checks it on the assembled matrices), with the
// eliminated set the product of the 1D ones, so its eigenvalues are the products of the 1D ones
// and kappa_2D = kappa_1D^2. Infinity when lambda_min <= 1e-13 lambda_max (singular).
double kappa_1d(Index cells, int p, bool dirichlet, int particles) {
  const Grid<1> g(Vec<1>(0.0), Vec<1>(1.0), IVec<1>{cells});
  const auto keep = kept(g, p, dirichlet);
  const Eigen::MatrixXd M =
      Eigen::MatrixXd(kept_submatrix(spline_mass(g, p, p, points(g, p, particles)), keep, keep));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(M, Eigen::EigenvaluesOnly);
  const double lmax = es.eigenvalues().maxCoeff(), lmin = es.eigenvalues().minCoeff();
  return lmin <= 1e-13 * lmax ? std::numeric_limits<double>::infinity() : lmax / lmin;
}

template <int Dim>
MassMatrixRow one(const MassMatrixOptions& opt, int p, Index n) {
  MassMatrixRow row;
  row.degree = p;
  row.cells = n;
  const bool dirichlet = opt.boundary == "dirichlet";
  IVec<Dim> nc;
  nc.fill(n);
  const Grid<Dim> g(Vec<Dim>::Zero(), Vec<Dim>::Ones(), nc);
  const auto keep = kept(g, p, dirichlet);
  const PointSet<Dim> pts = points(g, p, opt.particles);
  const SparseMatrixD M = kept_submatrix(spline_mass(g, p, p, pts), keep, keep);
  const Eigen::VectorXd f_all = spline_load_exact(g, p, -9.81);
  Eigen::VectorXd f(M.rows());
  for (Index i = 0, k = 0; i < f_all.size(); ++i)
    if (keep[static_cast<std::size_t>(i)]) f[k++] = f_all[i];
  row.unknowns = M.rows();
  row.kappa = std::pow(kappa_1d(n, p, dirichlet, opt.particles), Dim);
  row.cg_bound = std::ceil(std::log(opt.tolerance / 2.0) /
                           std::log((std::sqrt(row.kappa) - 1.0) / (std::sqrt(row.kappa) + 1.0)));
  auto t0 = std::chrono::steady_clock::now();
  const Eigen::SimplicialLDLT<SparseMatrixD> direct(M);
  // As the consistent mass's direct solver (solver/ldlt_pivots.hpp): a pivot within round-off
  // of zero, whatever its sign, is a singular matrix.
  const bool factorised = ldlt_pivots_above_roundoff(direct, M);
  const Eigen::VectorXd exact =
      factorised ? Eigen::VectorXd(direct.solve(f)) : Eigen::VectorXd::Constant(M.rows(), kNaN);
  row.direct_seconds = seconds_since(t0);
  row.singular = !factorised || std::isinf(row.kappa);
  const double scale = exact.norm();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(M.rows());
  t0 = std::chrono::steady_clock::now();
  const IterationReport cg = conjugate_gradient(M, f, x, opt.tolerance, opt.max_iterations);
  row.cg_seconds = seconds_since(t0);
  row.cg_iterations = cg.iterations;
  row.cg_converged = cg.converged;
  row.cg_error = (x - exact).norm() / scale;
  if (opt.matrix_free) {
    t0 = std::chrono::steady_clock::now();
    const SplineMassOperator<Dim> op(g, p, pts, keep);
    Eigen::VectorXd z = Eigen::VectorXd::Zero(M.rows());
    const IterationReport cf =
        conjugate_gradient([&op](const Eigen::VectorXd& v, Eigen::VectorXd& w) { op.apply(v, w); },
                           f, z, opt.tolerance, opt.max_iterations);
    row.cg_free_seconds = seconds_since(t0);
    row.cg_free_iterations = cf.iterations;
    row.cg_free_converged = cf.converged;
    row.cg_free_difference = (z - x).norm() / x.norm();
  }
  std::vector<std::pair<int, int>> sides;
  if (dirichlet)
    for (int d = 0; d < Dim; ++d)
      for (int side = 0; side < 2; ++side) sides.emplace_back(d, side);
  t0 = std::chrono::steady_clock::now();
  const PMultigrid mg = spline_pmg(g, p, pts, keep, sides, opt.pmg);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(M.rows());
  const IterationReport v = mg.solve(f, y, opt.tolerance, opt.max_cycles);
  row.pmg_seconds = seconds_since(t0);
  row.pmg_cycles = v.iterations;
  row.pmg_converged = v.converged;
  row.pmg_error = (y - exact).norm() / scale;
  if (Dim == 2 && opt.particles == 0) {
    row.kappa_published = published(kKappa, kKappaCells, p, n);
    row.cg_published = published(kCg, kCgCells, p, n);
    row.pmg_published = published(kPmg, kPmgCells, p, n);
  } else {
    row.kappa_published = row.cg_published = row.pmg_published = kNaN;
  }
  return row;
}

std::string cell(double ours, bool converged, double pub, const char* fmt_ours) {
  std::string s = converged ? fmt::format(fmt::runtime(fmt_ours), ours) : "failed";
  if (!std::isnan(pub)) s += fmt::format(" ({:g})", pub);
  return s;
}

}  // namespace

std::vector<MassMatrixRow> massmatrix_study(const MassMatrixOptions& opt) {
  if (opt.dim != 1 && opt.dim != 2) throw InputError(fmt::format("--dim {}: 1 or 2", opt.dim));
  if (opt.boundary != "dirichlet" && opt.boundary != "free")
    throw InputError(fmt::format("--boundary \"{}\": \"dirichlet\" or \"free\"", opt.boundary));
  for (int p : opt.degrees)
    if (p < 1 || p > 5) throw InputError(fmt::format("--degrees: {} (the degrees are 1 to 5)", p));
  for (Index n : opt.cells)
    if (n < 1 || n > 4096) throw InputError(fmt::format("--cells: {} (1 to 4096)", n));
  if (opt.particles < 0 || opt.particles > 25)
    throw InputError(fmt::format("--particles {}: 0 (Gauss points) to 25 per direction and cell",
                                 opt.particles));
  if (!(opt.tolerance > 0.0 && opt.tolerance < 1.0))
    throw InputError(fmt::format("--tolerance {}: in (0, 1)", opt.tolerance));
  std::vector<MassMatrixRow> rows;
  for (int p : opt.degrees)
    for (Index n : opt.cells) rows.push_back(opt.dim == 1 ? one<1>(opt, p, n) : one<2>(opt, p, n));
  return rows;
}

void print_massmatrix(std::ostream& os, const MassMatrixOptions& opt,
                      const std::vector<MassMatrixRow>& rows) {
  os << fmt::format(
      "B-spline mass matrices on the unit {} (rho = 1, force 9.81 in -x{}), {} boundary, "
      "tolerance {:g} from zero (004 eq. 4.53); p-multigrid: nu1 = nu2 = {}, {} smoother, {}. "
      "{}\n",
      opt.dim == 2 ? "square" : "interval", opt.dim == 2 ? " and -y" : "", opt.boundary,
      opt.tolerance, opt.pmg.pre, name_of(opt.pmg.smoother),
      opt.pmg.coarse_correction
          ? fmt::format("{} restriction, CG to {:g} at p = 1", name_of(opt.pmg.restriction),
                        opt.pmg.coarse_tolerance)
          : std::string("no coarse correction (smoothing only)"),
      opt.particles > 0
          ? fmt::format("Matrices from {} regular particles per cell and direction (D eq. 2.34).",
                        opt.particles)
      : opt.dim == 2 ? "004's values in brackets (Gauss quadrature, as 004)."
                     : "Gauss quadrature (004 gives 2D values only).");
  auto table = [&](const char* title, auto value) {
    os << "\n" << title << "\n" << fmt::format("{:>3}", "p");
    for (Index n : opt.cells) os << fmt::format(" {:>18}", fmt::format("h^-1 = {}", n));
    os << "\n";
    for (int p : opt.degrees) {
      os << fmt::format("{:>3}", p);
      for (Index n : opt.cells)
        for (const auto& r : rows)
          if (r.degree == p && r.cells == n) os << fmt::format(" {:>18}", value(r));
      os << "\n";
    }
  };
  table("condition number kappa (004 Table 4.2)", [](const MassMatrixRow& r) {
    return r.singular ? std::string("singular") : cell(r.kappa, true, r.kappa_published, "{:.3g}");
  });
  table("CG iterations (004 Table 4.3)", [](const MassMatrixRow& r) {
    return cell(r.cg_iterations, r.cg_converged, r.cg_published, "{:.0f}");
  });
  table("p-multigrid V-cycles (004 Table 4.4)", [](const MassMatrixRow& r) {
    return cell(r.pmg_cycles, r.pmg_converged, r.pmg_published, "{:.0f}");
  });
  if (opt.matrix_free) {
    table("CG with the matrix-free application: iterations, ms (assembled CG's ms)",
          [](const MassMatrixRow& r) {
            return r.cg_free_converged ? fmt::format("{}, {:.3g} ({:.3g})", r.cg_free_iterations,
                                                     1e3 * r.cg_free_seconds, 1e3 * r.cg_seconds)
                                       : std::string("failed");
          });
  }
  table(
      "time to solution [ms]: direct (factorisation and solve) / CG / p-multigrid (set-up "
      "and cycles)",
      [](const MassMatrixRow& r) {
        return fmt::format("{:.3g}/{:.3g}/{:.3g}", 1e3 * r.direct_seconds, 1e3 * r.cg_seconds,
                           1e3 * r.pmg_seconds);
      });
}

void write_massmatrix_csv(const std::string& path, const std::vector<MassMatrixRow>& rows) {
  // Written whole and checked (io::write_file_atomic: never a half file, never over a device).
  std::ostringstream f;
  f << "degree,cells,unknowns,kappa,kappa_published,cg_iterations,cg_converged,cg_published,"
       "cg_bound,cg_error,pmg_cycles,pmg_converged,pmg_published,pmg_error,singular,"
       "direct_seconds,cg_seconds,pmg_seconds,cg_free_iterations,cg_free_seconds,"
       "cg_free_difference\n";
  auto v = [](double x) { return std::isnan(x) ? std::string() : fmt::format("{:.17g}", x); };
  for (const auto& r : rows)
    f << fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.degree,
                     r.cells, r.unknowns, v(r.kappa), v(r.kappa_published), r.cg_iterations,
                     r.cg_converged ? 1 : 0, v(r.cg_published), v(r.cg_bound), v(r.cg_error),
                     r.pmg_cycles, r.pmg_converged ? 1 : 0, v(r.pmg_published), v(r.pmg_error),
                     r.singular ? 1 : 0, v(r.direct_seconds), v(r.cg_seconds), v(r.pmg_seconds),
                     r.cg_free_iterations, v(r.cg_free_seconds), v(r.cg_free_difference));
  io::write_file_atomic(path, f.str());
}

}  // namespace mpm
