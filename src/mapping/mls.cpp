// MLS (001 eq. 6-17) and IMLS (003 eq. 1-17) reconstruction in one dimension.
#include "mapping/mls.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "io/config.hpp"

namespace mpm {

double mls_weight(MlsWeight kind, double distance, double cell) {
  const double d = std::abs(distance);
  if (kind == MlsWeight::Linear) return d < cell ? 1.0 - d / cell : 0.0;
  const double r = d / (2.0 * cell);  // 003 eq. 27, 001 eq. 17
  if (r <= 0.5) return 0.75 - r * r;
  if (r < 1.5) return 0.5 * (1.5 - r) * (1.5 - r);
  return 0.0;
}

void accumulate(MlsReport& total, const MlsReport& step) {
  total.points += step.points;
  total.empty += step.empty;
  total.widened += step.widened;
  total.ill_conditioned += step.ill_conditioned;
  total.singular += step.singular;
  total.reduced += step.reduced;
  if (step.max_condition > total.max_condition) {
    total.max_condition = step.max_condition;
    total.worst_x = step.worst_x;
  }
}

MovingLeastSquares::MovingLeastSquares(bool improved, int degree, double max_condition)
    : improved_(improved), degree_(degree), max_condition_(max_condition) {
  if (degree != 1 && degree != 2)
    throw InputError(fmt::format("method.mls_degree = {}: choose 1 or 2", degree));
}

void MovingLeastSquares::set_points(const Grid<1>& g, std::span<const double> x) {
  x_.assign(x.begin(), x.end());
  bin(g);
}

void MovingLeastSquares::set_points(const Grid<1>& g, const Particles<1>& P) {
  x_.resize(P.x.size());
  for (std::size_t p = 0; p < x_.size(); ++p) x_[p] = P.x[p][0];
  bin(g);
}

void MovingLeastSquares::bin(const Grid<1>& g) {
  grid_ = g;
  const Index nc = g.num_cells();
  start_.assign(static_cast<std::size_t>(nc + 1), 0);
  outside_ = 0;
  for (double xp : x_) {
    if (!g.inside(Vec<1>(xp))) {
      ++outside_;
      continue;
    }
    ++start_[static_cast<std::size_t>(g.cell_of(xp, 0) + 1)];
  }
  for (Index c = 0; c < nc; ++c)
    start_[static_cast<std::size_t>(c + 1)] += start_[static_cast<std::size_t>(c)];
  order_.resize(start_.back());
  fill_.assign(start_.begin(), start_.end() - 1);
  for (std::size_t p = 0; p < x_.size(); ++p) {
    if (!g.inside(Vec<1>(x_[p]))) continue;
    order_[fill_[static_cast<std::size_t>(g.cell_of(x_[p], 0))]++] = static_cast<Index>(p);
  }
  report_ = {};
}

namespace {

// MLS with M terms: phi_p = w_p q(s_p)^T A^{-1} e_1 (p(x) = e_1 at s = 0). Returns cond(A);
// infinite when A is singular (phi untouched).
template <int M>
double mls_shape(const std::vector<double>& s, const std::vector<double>& w, double singular,
                 std::vector<double>& phi) {
  using Mat = Eigen::Matrix<double, M, M>;
  using Vec = Eigen::Matrix<double, M, 1>;
  Mat A = Mat::Zero();
  auto basis = [](double sp) {
    Vec q;
    q[0] = 1.0;
    q[1] = sp;
    if constexpr (M == 3) q[2] = sp * sp;
    return q;
  };
  for (std::size_t k = 0; k < s.size(); ++k) {
    const Vec q = basis(s[k]);
    A.noalias() += w[k] * q * q.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Mat> es;
  es.compute(A);                     // iterative: computeDirect loses ~1e-12 on 3x3 here
  const Vec lam = es.eigenvalues();  // ascending
  if (!(lam[0] > singular * lam[M - 1])) return std::numeric_limits<double>::infinity();
  const Mat& V = es.eigenvectors();
  // c = A^{-1} e_1 = V diag(1 / lambda) V^T e_1.
  Vec c = Vec::Zero();
  for (int j = 0; j < M; ++j) c += (V(0, j) / lam[j]) * V.col(j);
  for (std::size_t k = 0; k < s.size(); ++k) phi[k] = w[k] * basis(s[k]).dot(c);
  return lam[M - 1] / lam[0];
}

}  // namespace

void MovingLeastSquares::gather(double x, MlsWeight weight) {
  const double h = grid_.h[0];
  const double R = mls_support(weight, h);
  const Index nc = grid_.num_cells();
  const auto cell = [&](double y) {
    const double c = std::floor((y - grid_.origin[0]) / h);
    return static_cast<Index>(std::clamp(c, 0.0, static_cast<double>(nc - 1)));
  };
  near_.clear();
  s_.clear();
  w_.clear();
  for (Index c = cell(x - R); c <= cell(x + R); ++c)
    for (std::size_t k = start_[static_cast<std::size_t>(c)];
         k < start_[static_cast<std::size_t>(c + 1)]; ++k) {
      const Index p = order_[k];
      const double d = x_[static_cast<std::size_t>(p)] - x;
      const double wp = mls_weight(weight, d, h);
      if (!(wp > 0.0)) continue;
      near_.push_back(p);
      s_.push_back(d / h);
      w_.push_back(wp);
    }
}

void MovingLeastSquares::add_row(double x, MlsWeight weight, ShapeTable& t, bool widen) {
  gather(x, weight);
  if (near_.empty() && widen && weight == MlsWeight::Linear) {
    gather(x, MlsWeight::QuadraticSpline);
    if (!near_.empty()) ++report_.widened;
  }
  ++report_.points;
  const std::size_t n = near_.size();
  const std::size_t row = t.point.size();
  if (n == 0) {
    ++report_.empty;
    t.start.push_back(row);
    return;
  }
  t.point.insert(t.point.end(), near_.begin(), near_.end());
  t.phi.resize(row + n);
  p_.resize(n);  // phi scratch for MLS, reused below
  const int m = degree_ + 1;

  if (!improved_) {
    const double cond =
        m == 2 ? mls_shape<2>(s_, w_, kSingular, p_) : mls_shape<3>(s_, w_, kSingular, p_);
    if (cond > report_.max_condition) {
      report_.max_condition = cond;
      report_.worst_x = x;
    }
    if (!std::isfinite(cond)) {
      ++report_.singular;
      t.point.resize(row);
      t.phi.resize(row);
      t.start.push_back(row);
      return;
    }
    if (cond > max_condition_) ++report_.ill_conditioned;
    std::copy(p_.begin(), p_.begin() + static_cast<std::ptrdiff_t>(n),
              t.phi.begin() + static_cast<std::ptrdiff_t>(row));
    t.start.push_back(row + n);
    return;
  }

  // IMLS: Gram-Schmidt (modified, two passes) of q_i = s^i under <f, g> = sum w f g
  // (003 eq. 16); p_[3 k + i] = p_i(s_k), px[i] = p_i(0), nrm[i] = <p_i, p_i>.
  p_.resize(3 * n);
  double px[3] = {0.0, 0.0, 0.0}, nrm[3] = {0.0, 0.0, 0.0};
  bool keep[3] = {false, false, false};
  int kept = 0;
  for (int i = 0; i < m; ++i) {
    for (std::size_t k = 0; k < n; ++k)
      p_[3 * k + static_cast<std::size_t>(i)] = std::pow(s_[k], i);
    px[i] = i == 0 ? 1.0 : 0.0;
    for (int pass = 0; pass < 2; ++pass)
      for (int j = 0; j < i; ++j) {
        if (!keep[j]) continue;
        double dot = 0.0;
        for (std::size_t k = 0; k < n; ++k)
          dot += w_[k] * p_[3 * k + static_cast<std::size_t>(i)] *
                 p_[3 * k + static_cast<std::size_t>(j)];
        const double c = dot / nrm[j];
        for (std::size_t k = 0; k < n; ++k)
          p_[3 * k + static_cast<std::size_t>(i)] -= c * p_[3 * k + static_cast<std::size_t>(j)];
        px[i] -= c * px[j];
      }
    double nn = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double v = p_[3 * k + static_cast<std::size_t>(i)];
      nn += w_[k] * v * v;
    }
    nrm[i] = nn;
    keep[i] = i == 0 ? nn > 0.0 : nn > kDropTolerance * nrm[0];
    if (keep[i]) ++kept;
  }
  if (kept < m) ++report_.reduced;
  // phi_p = w_p sum_i p_i(x) p_i(x_p) / <p_i, p_i> (003 eq. 14).
  for (std::size_t k = 0; k < n; ++k) {
    double a = 0.0;
    for (int i = 0; i < m; ++i)
      if (keep[i]) a += px[i] * p_[3 * k + static_cast<std::size_t>(i)] / nrm[i];
    t.phi[row + k] = w_[k] * a;
  }
  t.start.push_back(row + n);
}

double MovingLeastSquares::evaluate(double x, MlsWeight weight, std::span<const double> f) {
  scratch_.clear();
  add_row(x, weight, scratch_);
  return scratch_.apply(0, [&](std::size_t p) { return f[p]; });
}

MlsSettings mls_settings_from_config(const Config& cfg, bool improved) {
  MlsSettings s;
  s.degree = static_cast<int>(cfg.get_int("method.mls_degree"));
  s.gauss_points = static_cast<int>(cfg.get_int("method.gauss_points"));
  if (improved && cfg.get_string("method.mass") != "lumped")
    throw InputError("method.mapping = imls needs method.mass = lumped (003 eq. 32)");
  return s;
}

}  // namespace mpm
