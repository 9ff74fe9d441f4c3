// Taylor least-squares reconstruction on triangles (D 6.1.2, 6.3): binning, the per-element
// least-squares operators with the strategies for deficient point sets, and the fits.
#include "mapping/tls_triangle.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/parallel.hpp"
#include "mapping/quadrature.hpp"

namespace mpm {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Graded: a truncated direction whose degree-d part has norm below this (the directions are unit
// vectors) counts as having none, so resolving it cannot amplify the data by more than 1e3.
constexpr double kGradedTolerance = 1e-3;

// Polynomial degree of Taylor term k (0-based): psi_1: 0; psi_2, psi_3: 1; psi_4..psi_6: 2.
constexpr int degree(Index k) {
  return k == 0 ? 0 : (k < 3 ? 1 : 2);
}

// The Gram matrix of the Taylor basis in the mean over the reference triangle,
// Gram_kl = 2 int psi_k psi_l d(xi, eta), exact: the collapsed product of 4-point Gauss rules
// integrates total degree 6 (the products have degree 4). Block diagonal: psi_2..psi_6 have
// zero mean (D eq. 5.7), so they are orthogonal to psi_1 = 1.
const Eigen::Matrix<double, 6, 6>& taylor_gram() {
  static const Eigen::Matrix<double, 6, 6> gram = [] {
    Eigen::Matrix<double, 6, 6> g = Eigen::Matrix<double, 6, 6>::Zero();
    const GaussRule rule = gauss_legendre(4);
    for (std::size_t i = 0; i < rule.xi.size(); ++i)
      for (std::size_t j = 0; j < rule.xi.size(); ++j) {
        const double u = 0.5 * (1.0 + rule.xi[i]), v = 0.5 * (1.0 + rule.xi[j]);
        const double w = 2.0 * 0.25 * rule.w[i] * rule.w[j] * (1.0 - u);
        const TriangleTaylor psi = triangle_taylor_basis(u, v * (1.0 - u));
        g += w * psi * psi.transpose();
      }
    return g;
  }();
  return gram;
}

// W = L^{-T} with L L^T the Cholesky factor of the Gram block of terms first..first+n-1: the
// basis phi = W^T psi is orthonormal in the mean over the triangle (L lower triangular, so phi_k
// combines psi_first..psi_k and the leading j columns of B W span the leading j terms).
Eigen::MatrixXd orthonormalising(int first, int n) {
  if (n == 0) return Eigen::MatrixXd(0, 0);
  const Eigen::MatrixXd g = taylor_gram().block(first, first, n, n);
  const Eigen::LLT<Eigen::MatrixXd> llt(g);
  const Eigen::MatrixXd L = llt.matrixL();
  return L.transpose().triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(n, n));
}

// cond_2(D) = (sigma_max / sigma_min)^2 from the singular values of B (descending); infinite when
// singular, 1 for no columns.
double condition_of(const Eigen::VectorXd& sigma) {
  if (sigma.size() == 0) return 1.0;
  const double hi = sigma[0], lo = sigma[sigma.size() - 1];
  if (!(lo > 0.0) || !std::isfinite(hi)) return kInf;
  const double r = hi / lo;
  return r * r;
}

// The least-squares operator G (n x m, zero rows beyond the columns fitted) of one element
// system: the data matrix B (m x n) holds the Taylor terms first..first+n-1 at the element's m
// points, and the coefficients of those terms are G f. `sizes`: the column counts of the
// complete polynomial spaces, descending (Reduce tries them in turn; the last is the fallback of
// None).
struct SystemResult {
  Eigen::MatrixXd G;
  TlsTriangleSystemInfo info;
};

//
// The system is solved, and its condition judged, in the orthonormal basis phi = W^T psi: data
// matrix B W, coefficients c, a = W c. Least-squares fits do not depend on the basis of the
// space, but cond(D) does: in psi it is about 1e3 for a uniform layout (psi_4..psi_6 are small
// on the triangle), in phi the normal matrix of m uniformly spread points is about m I, so
// cond(D) is 1 for ideal sampling and grows as some polynomial of the space is sampled worse
// than by uniform points: the measure of sampling quality of least squares on polynomial
// spaces (Cohen, Davenport and Leviatan 2013, Found. Comput. Math. 13: the empirical Gram
// matrix of an orthonormal basis). The Graded strategy minimises the coefficients c of phi by
// degree, i.e. the L2 norms of the degree-2 and degree-1 parts of the reconstruction.
SystemResult solve_system(const Eigen::MatrixXd& Bpsi, const Eigen::MatrixXd& W, int first,
                          std::span<const int> sizes, TlsTriangleStrategy strategy,
                          double max_condition) {
  using Eigen::MatrixXd;
  const MatrixXd B = Bpsi * W;
  const Index m = B.rows(), n = B.cols();
  SystemResult res;
  res.G = MatrixXd::Zero(n, m);
  TlsTriangleSystemInfo& info = res.info;
  // B = Q R with Q (m x n) orthonormal columns (zero columns where m < n) and R (n x n) upper
  // triangular (zero rows where m < n), so B[:, :j] = Q[:, :j] R[:j, :j] for every j: the
  // nested spaces of Reduce share one factorisation. Householder QR, then the SVD of the small
  // R: errors grow like cond(B) = cond(D)^(1/2), not like cond(D) as with D^{-1} (D eq. 5.1).
  MatrixXd Q = MatrixXd::Zero(m, n), R = MatrixXd::Zero(n, n);
  if (n > 0) {
    const Eigen::HouseholderQR<MatrixXd> qr(B);
    const Index k = std::min(m, n);
    Q.leftCols(k) = qr.householderQ() * MatrixXd::Identity(m, k);
    for (Index i = 0; i < k; ++i)
      for (Index j = i; j < n; ++j) R(i, j) = qr.matrixQR()(i, j);
  }
  using Svd = Eigen::JacobiSVD<MatrixXd>;
  auto svd = [&](Index j) {
    return Svd(R.topLeftCorner(j, j), Eigen::ComputeFullU | Eigen::ComputeFullV);
  };
  // The pseudo-inverse of B[:, :j] keeping the r largest singular values: V_r S_r^{-1} U_r^T Q^T.
  auto pinv = [&](const Svd& s, Index j, Index r) -> MatrixXd {
    return s.matrixV().leftCols(r) * s.singularValues().head(r).cwiseInverse().asDiagonal() *
           s.matrixU().leftCols(r).transpose() * Q.leftCols(j).transpose();
  };
  auto fit_block = [&](Index j) {  // all j leading columns (well posed, or the fallback)
    if (j > 0) {
      const Svd s = svd(j);
      res.G.topRows(j) = pinv(s, j, j);
      info.condition_solved = condition_of(s.singularValues());
    } else {
      info.condition_solved = 1.0;
    }
    info.terms = info.rank = first + static_cast<int>(j);
  };

  if (n == 0) {  // nothing fitted (the conservative system of one term)
    info.condition = 1.0;
    fit_block(0);
    return res;  // no columns: nothing to transform
  }
  const Svd full = svd(n);
  info.condition = condition_of(full.singularValues());
  info.deficient = !(info.condition <= max_condition);

  switch (strategy) {
    case TlsTriangleStrategy::None:
      info.failed = info.deficient;
      fit_block(info.deficient ? sizes.back() : n);
      break;
    case TlsTriangleStrategy::Reduce: {
      Index j = sizes.back();  // the constant fit (plain) or a_1 alone: always well posed
      if (!info.deficient) {
        j = n;
      } else {
        for (int c : sizes)
          if (c == 0 || condition_of(svd(c).singularValues()) <= max_condition) {
            j = c;
            break;
          }
      }
      fit_block(j);
      break;
    }
    case TlsTriangleStrategy::MinimumNorm:
    case TlsTriangleStrategy::Graded: {
      // Rank r: the singular values within sqrt(max_condition) of the largest.
      const Eigen::VectorXd& sigma = full.singularValues();
      const double cut = sigma[0] / std::sqrt(max_condition);
      Index r = 0;
      while (r < n && sigma[r] > 0.0 && sigma[r] >= cut) ++r;
      res.G = pinv(full, n, r);
      info.terms = first + static_cast<int>(n);
      info.rank = first + static_cast<int>(r);
      info.condition_solved = condition_of(sigma.head(r));
      if (strategy == TlsTriangleStrategy::MinimumNorm || r == n) break;
      // The truncated least-squares solutions are a_mn + V0 beta (V0: the dropped right singular
      // vectors). beta is chosen to minimise the quadratic coefficients, then (in what freedom is
      // left, the columns of N) the linear ones, then a_1. Each step is linear in a_mn, so the
      // whole is a matrix T with a = T a_mn.
      const MatrixXd V0 = full.matrixV().rightCols(n - r);
      MatrixXd T = MatrixXd::Identity(n, n);
      MatrixXd N = MatrixXd::Identity(n - r, n - r);
      for (int d = 2; d >= 0 && N.cols() > 0; --d) {
        MatrixXd P = MatrixXd::Zero(n, n);  // selects the coefficients of degree d
        Index rows = 0;
        for (Index i = 0; i < n; ++i)
          if (degree(first + i) == d) P(rows++, i) = 1.0;
        if (rows == 0) continue;
        const MatrixXd C = P.topRows(rows) * V0 * N;
        const Svd cs(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
        Index rc = 0;
        while (rc < cs.singularValues().size() && cs.singularValues()[rc] >= kGradedTolerance) ++rc;
        if (rc == 0) continue;
        const MatrixXd Cp = cs.matrixV().leftCols(rc) *
                            cs.singularValues().head(rc).cwiseInverse().asDiagonal() *
                            cs.matrixU().leftCols(rc).transpose();
        const MatrixXd step = V0 * N * Cp * P.topRows(rows) * T;
        T -= step;
        N = (N * cs.matrixV().rightCols(N.cols() - rc)).eval();
      }
      res.G = T * res.G;
      break;
    }
  }
  res.G = W * res.G;  // a = W c
  return res;
}

void add(TlsTriangleFitReport& r, const TlsTriangleSystemInfo& s, Index e, int requested) {
  if (s.deficient) {
    ++r.deficient;
    if (r.first_deficient < 0) r.first_deficient = e;
  } else {
    ++r.full;
  }
  if (s.failed) ++r.failed;
  if (!s.failed && s.terms < requested) ++r.reduced;
  if (s.rank < s.terms && !s.failed) ++r.truncated;
  r.min_rank = r.min_rank > 0 ? std::min(r.min_rank, s.rank) : s.rank;
  r.max_condition = std::max(r.max_condition, s.condition);
  r.max_condition_solved = std::max(r.max_condition_solved, s.condition_solved);
}

}  // namespace

TlsTriangleStrategy parse_tls_triangle_strategy(std::string_view name) {
  if (name == "none") return TlsTriangleStrategy::None;
  if (name == "reduce") return TlsTriangleStrategy::Reduce;
  if (name == "min-norm") return TlsTriangleStrategy::MinimumNorm;
  if (name == "graded") return TlsTriangleStrategy::Graded;
  throw InputError(fmt::format(
      "TLS triangle strategy \"{}\" is not available; choose one of: none, reduce, min-norm, "
      "graded",
      name));
}

std::string_view tls_triangle_strategy_name(TlsTriangleStrategy s) {
  switch (s) {
    case TlsTriangleStrategy::None:
      return "none";
    case TlsTriangleStrategy::Reduce:
      return "reduce";
    case TlsTriangleStrategy::MinimumNorm:
      return "min-norm";
    case TlsTriangleStrategy::Graded:
      return "graded";
  }
  return "none";
}

void validate(const TlsTriangleSettings& s) {
  if (s.terms != 0 && s.terms != 1 && s.terms != 3 && s.terms != 6)
    throw InputError(fmt::format(
        "TLS on triangles: terms = {} must be 1 (constant), 3 (linear) or 6 (quadratic) (0: 6)",
        s.terms));
  if (!(s.max_condition > 1.0) || !std::isfinite(s.max_condition))
    throw InputError(fmt::format(
        "TLS on triangles: max_condition = {} must be finite and greater than 1", s.max_condition));
  switch (s.strategy) {
    case TlsTriangleStrategy::None:
    case TlsTriangleStrategy::Reduce:
    case TlsTriangleStrategy::MinimumNorm:
    case TlsTriangleStrategy::Graded:
      return;
  }
  throw InputError(
      fmt::format("TLS on triangles: unknown strategy {}", static_cast<int>(s.strategy)));
}

TlsTriangleReconstruction::TlsTriangleReconstruction(const TriangleMesh& mesh,
                                                     const TlsTriangleSettings& s)
    : mesh_(&mesh), settings_(s) {
  validate(s);
  nb_ = s.terms_used();
  const auto ne = static_cast<std::size_t>(mesh.num_cells());
  origin_.resize(ne);
  inverse_.resize(ne);
  for (std::size_t e = 0; e < ne; ++e) {
    const auto& v = mesh.cell_vertices(static_cast<Index>(e));
    const Vec<2>& x0 = mesh.vertex(v[0]);
    Mat<2> A;  // x = x_0 + A (xi, eta)^T (D eq. 6.14-6.15 is its inverse)
    A.col(0) = mesh.vertex(v[1]) - x0;
    A.col(1) = mesh.vertex(v[2]) - x0;
    origin_[e] = x0;
    inverse_[e] = A.inverse();
  }
  start_.assign(ne + 1, 0);
  info_.assign(ne, TlsTriangleElementInfo{});
  report_.elements = mesh.num_cells();
}

const TlsTriangleReport& TlsTriangleReconstruction::set_points(std::span<const Vec<2>> x) {
  const Index ne = mesh_->num_cells();
  const auto ne_s = static_cast<std::size_t>(ne);
  report_ = TlsTriangleReport{};
  report_.elements = ne;
  num_points_ = x.size();

  // Counting sort by triangle (points in ascending order within an element).
  std::vector<Index> cell(x.size());
  parallel_for(static_cast<Index>(x.size()), [&](Index p) {
    cell[static_cast<std::size_t>(p)] = mesh_->cell_index(x[static_cast<std::size_t>(p)]);
  });
  start_.assign(ne_s + 1, 0);
  for (Index c : cell) {
    if (c < 0)
      ++report_.outside;
    else
      ++start_[static_cast<std::size_t>(c) + 1];
  }
  for (std::size_t e = 0; e < ne_s; ++e) start_[e + 1] += start_[e];
  order_.resize(static_cast<std::size_t>(start_[ne_s]));
  {
    std::vector<Index> fill(start_.begin(), start_.end() - 1);
    for (std::size_t p = 0; p < cell.size(); ++p)
      if (cell[p] >= 0)
        order_[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell[p])]++)] =
            static_cast<Index>(p);
  }
  q_.assign(order_.size(), TriangleTaylor::Zero());
  qc_.assign(order_.size(), TriangleTaylor::Zero());
  info_.assign(ne_s, TlsTriangleElementInfo{});

  // The complete polynomial spaces, descending: plain 6, 3, 1 columns; conservative (psi_1
  // left out) 5, 2, 0.
  constexpr std::array<int, 3> kPlain{6, 3, 1}, kConservative{5, 2, 0};
  const int skip = nb_ == 6 ? 0 : (nb_ == 3 ? 1 : 2);
  const std::span<const int> plain_sizes(kPlain.data() + skip, kPlain.size() - skip);
  const std::span<const int> cons_sizes(kConservative.data() + skip, kConservative.size() - skip);
  const double max_condition = settings_.max_condition;
  const TlsTriangleStrategy strategy = settings_.strategy;
  const Eigen::MatrixXd w_plain = orthonormalising(0, nb_), w_cons = orthonormalising(1, nb_ - 1);

  // Elements are independent: parallel, the same bits for any thread count.
  parallel_for(ne, [&](Index e) {
    const auto ei = static_cast<std::size_t>(e);
    const Index begin = start_[ei], m = start_[ei + 1] - begin;
    TlsTriangleElementInfo& info = info_[ei];
    info.points = m;
    if (m == 0) return;
    Eigen::MatrixXd B(m, nb_);
    for (Index k = 0; k < m; ++k) {
      const Vec<2>& xp = x[static_cast<std::size_t>(order_[static_cast<std::size_t>(begin + k)])];
      B.row(k) = basis(e, xp).head(nb_).transpose();
    }
    const SystemResult plain = solve_system(B, w_plain, 0, plain_sizes, strategy, max_condition);
    const SystemResult cons =
        solve_system(B.rightCols(nb_ - 1), w_cons, 1, cons_sizes, strategy, max_condition);
    for (Index k = 0; k < m; ++k) {
      const auto slot = static_cast<std::size_t>(begin + k);
      q_[slot].head(nb_) = plain.G.col(k);
      qc_[slot].segment(1, nb_ - 1) = cons.G.col(k);
    }
    info.plain = plain.info;
    info.conservative = cons.info;
  });

  for (Index e = 0; e < ne; ++e) {
    const TlsTriangleElementInfo& info = info_[static_cast<std::size_t>(e)];
    if (info.points == 0) continue;
    ++report_.active;
    add(report_.plain, info.plain, e, nb_);
    add(report_.conservative, info.conservative, e, nb_);
  }
  return report_;
}

void TlsTriangleReconstruction::fit_conservative(std::span<const double> f,
                                                 std::span<const double> integrals,
                                                 Coefficients& a) const {
  if (f.size() < num_points_)
    throw std::invalid_argument("TlsTriangleReconstruction: one value per point of set_points");
  const Index ne = mesh_->num_cells();
  if (integrals.size() < static_cast<std::size_t>(ne))
    throw std::invalid_argument(
        "TlsTriangleReconstruction::fit_conservative: one integral per "
        "element");
  a.resize(static_cast<std::size_t>(ne));
  parallel_for(ne, [&](Index e) {
    const auto ei = static_cast<std::size_t>(e);
    // D eq. 5.9: a_1 fixed by the element integral; a_2.. = G_c (f - a_1).
    const double a1 = integrals[ei] / mesh_->cell_volume(e);
    TriangleTaylor coef = TriangleTaylor::Zero();
    for (Index k = start_[ei]; k < start_[ei + 1]; ++k) {
      const auto slot = static_cast<std::size_t>(k);
      coef += qc_[slot] * (f[static_cast<std::size_t>(order_[slot])] - a1);
    }
    coef[0] = a1;
    a[ei] = coef;
  });
}

void TlsTriangleReconstruction::fit_plain(std::span<const double> f, Coefficients& a) const {
  if (f.size() < num_points_)
    throw std::invalid_argument("TlsTriangleReconstruction: one value per point of set_points");
  const Index ne = mesh_->num_cells();
  a.resize(static_cast<std::size_t>(ne));
  parallel_for(ne, [&](Index e) {
    const auto ei = static_cast<std::size_t>(e);
    TriangleTaylor coef = TriangleTaylor::Zero();  // D eq. 5.1: a = G f
    for (Index k = start_[ei]; k < start_[ei + 1]; ++k) {
      const auto slot = static_cast<std::size_t>(k);
      coef += q_[slot] * f[static_cast<std::size_t>(order_[slot])];
    }
    a[ei] = coef;
  });
}

double TlsTriangleReconstruction::evaluate(const Coefficients& a, const Vec<2>& x) const {
  const Index e = mesh_->cell_index(x);
  return e < 0 ? 0.0 : evaluate(a, e, x);
}

}  // namespace mpm
