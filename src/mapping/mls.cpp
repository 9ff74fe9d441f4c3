// MLS (001 eq. 6-17) and IMLS (003 eq. 1-17) reconstruction in one and two dimensions.
#include "mapping/mls.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>

#include "core/bytes.hpp"

namespace mpm {

double mls_weight(MlsWeight kind, double distance, double cell, double dilation) {
  const double d = std::abs(distance);
  if (kind == MlsWeight::Linear) return d < cell ? 1.0 - d / cell : 0.0;
  const double r = d / (dilation * cell);  // 003 eq. 27, 001 eq. 16-17 (dilation 2)
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
    total.worst_y = step.worst_y;
    total.worst_z = step.worst_z;
  }
}

MlsReport over_ranks(const Comm& comm, const MlsReport& mine) {
  if (!comm.distributed()) return mine;
  const MlsReport& m = mine;
  const std::array<double, 10> v{static_cast<double>(m.points),
                                 static_cast<double>(m.empty),
                                 static_cast<double>(m.ill_conditioned),
                                 static_cast<double>(m.singular),
                                 static_cast<double>(m.reduced),
                                 static_cast<double>(m.widened),
                                 m.max_condition,
                                 m.worst_x,
                                 m.worst_y,
                                 m.worst_z};
  const std::vector<double> all = comm.allgather(std::span<const double>(v));
  MlsReport t;
  for (std::size_t r = 0; r < static_cast<std::size_t>(comm.size()); ++r) {
    const double* o = all.data() + r * v.size();
    MlsReport one;
    one.points = static_cast<Index>(o[0]);
    one.empty = static_cast<Index>(o[1]);
    one.ill_conditioned = static_cast<Index>(o[2]);
    one.singular = static_cast<Index>(o[3]);
    one.reduced = static_cast<Index>(o[4]);
    one.widened = static_cast<Index>(o[5]);
    one.max_condition = o[6];
    one.worst_x = o[7];
    one.worst_y = o[8];
    one.worst_z = o[9];
    accumulate(t, one);
  }
  return t;
}

template <int Dim>
MovingLeastSquares<Dim>::MovingLeastSquares(bool improved, int degree, double max_condition,
                                            double dilation)
    : improved_(improved), degree_(degree), max_condition_(max_condition), dilation_(dilation) {
  if (degree != 1 && degree != 2)
    throw InputError(fmt::format("method.mls_degree = {}: choose 1 or 2", degree));
  if (!(dilation > 0.0))
    throw InputError(fmt::format("method.mls_dilation = {}: must be > 0", dilation));
  terms_ = mls_terms(Dim, degree);
  scratch_.resize(1);
}

template <int Dim>
void MovingLeastSquares<Dim>::set_points(const Grid<Dim>& g, std::span<const Vec<Dim>> x) {
  x_.assign(x.begin(), x.end());
  bin(g);
}

template <int Dim>
void MovingLeastSquares<Dim>::bin(const Grid<Dim>& g) {
  grid_ = g;
  outside_ = bins_.build(g, std::span<const Vec<Dim>>(x_));
  // The positions in bin order: a row's candidates are then read contiguously (gather).
  xb_.resize(bins_.order.size());
  for (std::size_t k = 0; k < xb_.size(); ++k)
    xb_[k] = x_[static_cast<std::size_t>(bins_.order[k])];
  report_ = {};
}

namespace {

// The monomials of total degree <= degree in s, ordered by degree: [1, s_0 .. s_{D-1}] and then
// s_i s_j for i <= j ([1, x, y, x^2, xy, y^2] in 2D, 003 eq. 15; [1, x, x^2] in 1D).
template <int Dim>
inline void monomials(const Vec<Dim>& s, int degree, double* q) {
  q[0] = 1.0;
  for (int d = 0; d < Dim; ++d) q[1 + d] = s[d];
  if (degree < 2) return;
  int k = Dim + 1;
  for (int i = 0; i < Dim; ++i)
    for (int j = i; j < Dim; ++j) q[k++] = s[i] * s[j];
}

// MLS with M terms: phi_p = w_p q(s_p)^T A^{-1} e_1 (p(x) = e_1 at s = 0; 001 eq. 14). Returns
// cond(A); infinite when A is singular (phi untouched).
template <int M, int Dim>
double mls_shape(const Vec<Dim>* s, const double* w, std::size_t n, int degree, double singular,
                 double* phi) {
  using Mat = Eigen::Matrix<double, M, M>;
  using Vec = Eigen::Matrix<double, M, 1>;
  // 001 eq. 10, A = sum_p w_p q_p q_p^T: only the lower triangle, the part the symmetric
  // eigensolver reads. Each entry is summed as (w q_i) q_j in point order, the rounding of the
  // full outer-product update it replaces, so the bits are unchanged at half the work.
  Mat A = Mat::Zero();
  Vec q = Vec::Zero();
  // Degree 1 in 1D and 2D: q = (1, s_0 .. s_{D-1}) written out below; 3D takes the generic loop.
  constexpr bool kLinear = M == Dim + 1 && Dim <= 2;
  if constexpr (kLinear) {
    // Written out in scalars: the generic loop below kept A and q on the stack and reloaded
    // them as 16-byte pairs right after 8-byte stores (store-forwarding stalls, most of the
    // row's time). Entry (i, j) of the lower triangle is (w q_i) q_j summed in point order,
    // the rounding of the generic loop (1 * x = x exactly), so the bits are unchanged.
    double a[M * (M + 1) / 2] = {};  // (0,0), (1,0), .., (M-1,0), (1,1), (2,1), .., (M-1,M-1)
    for (std::size_t k = 0; k < n; ++k) {
      const double wk = w[k];
      if constexpr (Dim == 1) {
        const double ws = wk * s[k][0];
        a[0] += wk;
        a[1] += ws;
        a[2] += ws * s[k][0];
      } else {
        const double s0 = s[k][0], s1 = s[k][1];
        const double ws0 = wk * s0, ws1 = wk * s1;
        a[0] += wk;
        a[1] += ws0;
        a[2] += ws1;
        a[3] += ws0 * s0;
        a[4] += ws1 * s0;
        a[5] += ws1 * s1;
      }
    }
    for (int j = 0, l = 0; j < M; ++j)
      for (int i = j; i < M; ++i) A(i, j) = a[l++];
  } else {
    // 001 eq. 10, A = sum_p w_p q_p q_p^T: the lower triangle, the part the eigensolver reads.
    for (std::size_t k = 0; k < n; ++k) {
      monomials<Dim>(s[k], degree, q.data());
      const Vec wq = w[k] * q;
      for (int j = 0; j < M; ++j)
        for (int i = j; i < M; ++i) A(i, j) += wq[i] * q[j];
    }
  }
  Eigen::SelfAdjointEigenSolver<Mat> es;
  es.compute(A);                     // iterative: computeDirect loses ~1e-12 on 3x3 here
  const Vec lam = es.eigenvalues();  // ascending
  if (!(lam[0] > singular * lam[M - 1])) return std::numeric_limits<double>::infinity();
  const Mat& V = es.eigenvectors();
  // c = A^{-1} e_1 = V diag(1 / lambda) V^T e_1.
  Vec c = Vec::Zero();
  for (int j = 0; j < M; ++j) c += (V(0, j) / lam[j]) * V.col(j);
  if constexpr (kLinear) {
    // q.dot(c) in Eigen's order for these sizes, (q_0 c_0 + q_1 c_1) + q_2 c_2, with q_0 = 1.
    const double c0 = c[0], c1 = c[1], c2 = Dim == 2 ? c[M - 1] : 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      double v = c0 + s[k][0] * c1;
      if constexpr (Dim == 2) v += s[k][1] * c2;
      phi[k] = w[k] * v;
    }
  } else {
    for (std::size_t k = 0; k < n; ++k) {
      monomials<Dim>(s[k], degree, q.data());
      phi[k] = w[k] * q.dot(c);
    }
  }
  return lam[M - 1] / lam[0];
}

// sum_k w_k a_k b_k for columns a, b, in four partial sums (k mod 4) added as (s0 + s1) +
// (s2 + s3). A single running sum makes the IMLS row latency-bound (one dependent add per point,
// ~4 cycles, for ~300 points and 9 sums per row); the grouping changes only the rounding.
inline double weighted_dot(const double* w, const double* a, const double* b, std::size_t n) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  std::size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    s0 += w[k] * a[k] * b[k];
    s1 += w[k + 1] * a[k + 1] * b[k + 1];
    s2 += w[k + 2] * a[k + 2] * b[k + 2];
    s3 += w[k + 3] * a[k + 3] * b[k + 3];
  }
  for (; k < n; ++k) s0 += w[k] * a[k] * b[k];
  return (s0 + s1) + (s2 + s3);
}

}  // namespace

template <int Dim>
void MovingLeastSquares<Dim>::gather(const Vec<Dim>& x, MlsWeight weight, Scratch& sc) const {
  // Per direction: the support radius R, 1 / l for the scaled offsets s and 1 / (a l) for the
  // weight's argument r (mls_weight), so that a candidate costs multiplications, no division.
  IVec<Dim> lo, hi;
  Vec<Dim> inv_h, inv_r;
  for (int d = 0; d < Dim; ++d) {
    const double R = mls_support(weight, grid_.h[d], dilation_);
    inv_h[d] = 1.0 / grid_.h[d];
    inv_r[d] = weight == MlsWeight::QuadraticSpline ? 1.0 / (dilation_ * grid_.h[d]) : inv_h[d];
    const double top = static_cast<double>(grid_.cells[d] - 1);
    const auto cell = [&](double y) {
      return static_cast<Index>(
          std::clamp(std::floor((y - grid_.origin[d]) / grid_.h[d]), 0.0, top));
    };
    // Cells overlapping the support box [x - R, x + R] (clamped to the grid).
    lo[d] = cell(x[d] - R);
    hi[d] = cell(x[d] + R);
  }
  // Rows of cells along x are contiguous in the bins (x fastest): one range of bin positions
  // [b, e) per row; f(b, e) for each row in order.
  const auto for_each_range = [&](auto&& f) {
    IVec<Dim> c = lo;
    while (true) {
      const Index first = grid_.cell_index(c);  // c[0] stays lo[0]
      const Index last = first + (hi[0] - lo[0]);
      f(static_cast<std::size_t>(bins_.start[static_cast<std::size_t>(first)]),
        static_cast<std::size_t>(bins_.start[static_cast<std::size_t>(last + 1)]));
      int d = 1;
      for (; d < Dim; ++d) {
        if (++c[d] <= hi[d]) break;
        c[d] = lo[d];
      }
      if (d >= Dim) break;
    }
  };
  std::size_t candidates = 0;
  for_each_range([&](std::size_t b, std::size_t e) { candidates += e - b; });
  if (sc.near.size() < candidates) {
    sc.near.resize(candidates);
    sc.s.resize(candidates);
    sc.w.resize(candidates);
  }
  // Every candidate is written and kept when its weight is positive (no branch on the weight:
  // the support's edge cells are partly inside, so such a branch is unpredictable). Raw
  // pointers: through the vectors every store could alias their data pointers, which were
  // then reloaded for each candidate.
  Index* near = sc.near.data();
  Vec<Dim>* s = sc.s.data();
  double* w = sc.w.data();
  const Vec<Dim>* xb = xb_.data();
  const Index* order = bins_.order.data();
  std::size_t n = 0;
  const auto scan = [&]<MlsWeight kWeight>(std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const Vec<Dim> dx = xb[k] - x;
      double wp = 1.0;  // 001 eq. 16: tensor product of the 1D weights
      for (int d = 0; d < Dim; ++d) {
        const double r = std::abs(dx[d]) * inv_r[d];
        if constexpr (kWeight == MlsWeight::Linear) {
          wp *= std::max(1.0 - r, 0.0);
        } else {  // 003 eq. 27 (mls_weight)
          const double t = std::max(1.5 - r, 0.0);
          wp *= r <= 0.5 ? 0.75 - r * r : 0.5 * t * t;
        }
      }
      near[n] = order[k];
      s[n] = dx.cwiseProduct(inv_h);
      w[n] = wp;
      n += wp > 0.0 ? 1 : 0;
    }
  };
  if (weight == MlsWeight::Linear)
    for_each_range(
        [&](std::size_t b, std::size_t e) { scan.template operator()<MlsWeight::Linear>(b, e); });
  else
    for_each_range([&](std::size_t b, std::size_t e) {
      scan.template operator()<MlsWeight::QuadraticSpline>(b, e);
    });
  sc.n = n;
}

template <int Dim>
void MovingLeastSquares<Dim>::add_row(const Vec<Dim>& x, MlsWeight weight, ShapeTable& t,
                                      bool widen) {
  row(x, weight, widen, scratch_[0], t, report_);
}

template <int Dim>
void MovingLeastSquares<Dim>::row(const Vec<Dim>& x, MlsWeight weight, bool widen, Scratch& sc,
                                  ShapeTable& t, MlsReport& rep) const {
  gather(x, weight, sc);
  if (sc.n == 0 && widen && weight == MlsWeight::Linear) {
    gather(x, MlsWeight::QuadraticSpline, sc);
    if (sc.n > 0) ++rep.widened;
  }
  ++rep.points;
  const std::size_t n = sc.n;
  const std::size_t row = t.point.size();
  if (n == 0) {
    ++rep.empty;
    t.start.push_back(row);
    return;
  }
  const auto nn = static_cast<std::ptrdiff_t>(n);
  if (sc.phi.size() < n) sc.phi.resize(n);
  if (improved_) {
    imls_row(sc, rep);
  } else {
    constexpr int M1 = mls_terms(Dim, 1), M2 = mls_terms(Dim, 2);
    const double cond =
        degree_ == 1
            ? mls_shape<M1, Dim>(sc.s.data(), sc.w.data(), n, degree_, kSingular, sc.phi.data())
            : mls_shape<M2, Dim>(sc.s.data(), sc.w.data(), n, degree_, kSingular, sc.phi.data());
    if (cond > rep.max_condition) {
      rep.max_condition = cond;
      rep.worst_x = x[0];
      rep.worst_y = Dim > 1 ? x[1] : 0.0;
      rep.worst_z = Dim > 2 ? x[Dim - 1] : 0.0;
    }
    if (!std::isfinite(cond)) {
      ++rep.singular;
      t.start.push_back(row);
      return;
    }
    if (cond > max_condition_) ++rep.ill_conditioned;
  }
  t.point.insert(t.point.end(), sc.near.begin(), sc.near.begin() + nn);
  t.phi.insert(t.phi.end(), sc.phi.begin(), sc.phi.begin() + nn);
  t.start.push_back(row + n);
}

// IMLS: Gram-Schmidt (modified, two passes) of the monomials q_i under <f, g> = sum w f g
// (003 eq. 16); p[S k + i] = p_i(s_k), px[i] = p_i(0), nrm[i] = <p_i, p_i>. Terms whose norm
// vanishes relative to <p_1, p_1> (eq. 17) or that the data resolve too poorly at x
// (kMaxAmplification) are dropped, then phi_p = w_p sum_i p_i(x) p_i(x_p) / <p_i, p_i>
// (eq. 11, 14).
template <int Dim>
void MovingLeastSquares<Dim>::imls_row(Scratch& sc, MlsReport& rep) const {
  constexpr std::size_t S = kMaxTerms;
  const std::size_t n = sc.n;
  const int m = terms_;
  const double* w = sc.w.data();
  // Column i (p_i at the row's points) is contiguous, p[n i + k], so that the inner products
  // and the updates run over unit-stride data (vectorised); per point the operations are those
  // of the point-major layout, so the rounding is the same.
  if (sc.p.size() < S * n) sc.p.resize(S * n);
  double* p = sc.p.data();
  // The monomials (the order of monomials()), one column at a time.
  const Vec<Dim>* sk = sc.s.data();
  for (std::size_t k = 0; k < n; ++k) p[k] = 1.0;
  for (int d = 0; d < Dim; ++d)
    for (std::size_t k = 0; k < n; ++k) p[n * static_cast<std::size_t>(1 + d) + k] = sk[k][d];
  if (degree_ == 2) {
    std::size_t col = Dim + 1;
    for (int i = 0; i < Dim; ++i)
      for (int j = i; j < Dim; ++j, ++col)
        for (std::size_t k = 0; k < n; ++k) p[n * col + k] = sk[k][i] * sk[k][j];
  }
  double px[S] = {}, nrm[S] = {};
  bool keep[S] = {};
  int kept = 0;
  for (int i = 0; i < m; ++i) {
    const auto ii = static_cast<std::size_t>(i);
    double* pi = p + n * ii;
    px[ii] = i == 0 ? 1.0 : 0.0;
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t j = 0; j < ii; ++j) {
        if (!keep[j]) continue;
        const double* pj = p + n * j;
        const double c = weighted_dot(w, pi, pj, n) / nrm[j];
        for (std::size_t k = 0; k < n; ++k) pi[k] -= c * pj[k];
        px[ii] -= c * px[j];
      }
    const double nn = weighted_dot(w, pi, pi, n);
    nrm[ii] = nn;
    // Dropped when it vanishes (eq. 17) or when it would amplify the data at x too much:
    // |p_i(x)| > kMaxAmplification rms(p_i), rms(p_i)^2 = <p_i, p_i> / <p_1, p_1>.
    keep[ii] = i == 0 ? nn > 0.0
                      : nn > kDropTolerance * nrm[0] &&
                            px[ii] * px[ii] * nrm[0] <= kMaxAmplification * kMaxAmplification * nn;
    if (keep[ii]) ++kept;
  }
  if (kept < m) ++rep.reduced;
  // a_i = p_i(x) / <p_i, p_i> once per row, not per point (a division per term and point).
  double a[S] = {};
  for (std::size_t i = 0; i < static_cast<std::size_t>(m); ++i)
    if (keep[i]) a[i] = px[i] / nrm[i];
  // phi_k = w_k sum_i a_i p_i(s_k), the sum over i in order, one column at a time.
  double* phi = sc.phi.data();
  for (std::size_t k = 0; k < n; ++k) phi[k] = 0.0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(m); ++i) {
    const double ai = a[i];
    const double* pi = p + n * i;
    for (std::size_t k = 0; k < n; ++k) phi[k] += ai * pi[k];
  }
  for (std::size_t k = 0; k < n; ++k) phi[k] *= w[k];
}

template <int Dim>
double MovingLeastSquares<Dim>::evaluate(const Vec<Dim>& x, MlsWeight weight,
                                         std::span<const double> f) {
  scratch_table_.clear();
  add_row(x, weight, scratch_table_);
  return scratch_table_.apply(0, [&](std::size_t p) { return f[p]; });
}

template class MovingLeastSquares<1>;
template class MovingLeastSquares<2>;
template class MovingLeastSquares<3>;

// The mapping's reconstructions (mls.hpp, MlsFamilyMapping): everything of map_mass,
// map_momentum and map_forces but the basis evaluation and assembly at the Gauss points.
template <int Dim>
void MlsFamilyMapping::fit_mass(RunState<Dim>& sim, GaussPoints<Dim>& q) {
  if (improved_ && sim.mass_type == MassType::Consistent)
    throw InputError("method.mapping = imls needs method.mass = lumped (003 eq. 32)");
  dim_ = Dim;
  auto& mls = std::get<Dim - 1>(work_).mls;
  const auto& P = sim.particles;
  const auto& grid = sim.grid;
  mls.set_points(grid, P);
  q.clear();
  // Tensor-product Gauss rule on each element holding a particle: point k has index
  // k_d = (k / n^d) % n in direction d (x fastest), weight prod_d (h_d / 2) w_{k_d}.
  const int n = static_cast<int>(rule_.xi.size());
  const int per_element = ipow(n, Dim);
  const Vec<Dim> half = 0.5 * grid.h;
  // A process of a distributed run integrates its own elements (the fits read the ghosts too).
  const CellBox<Dim> own = sim.own_cells();
  const std::array<Index, 2> span = own.span();
  for (Index e = span[0]; e < span[1]; ++e) {
    if (mls.bins().count(e) == 0 || !own.holds(e)) continue;
    const IVec<Dim> cell = grid.cell_coords(e);
    Vec<Dim> centre;
    for (int d = 0; d < Dim; ++d)
      centre[d] = grid.origin[d] + (static_cast<double>(cell[d]) + 0.5) * grid.h[d];
    for (int k = 0; k < per_element; ++k) {
      Vec<Dim> xg;
      double wg = 1.0;
      for (int d = 0, r = k; d < Dim; ++d, r /= n) {
        const auto j = static_cast<std::size_t>(r % n);
        xg[d] = centre[d] + half[d] * rule_.xi[j];
        wg *= half[d] * rule_.w[j];
      }
      q.add(xg, wg, e);
    }
  }
  // The shape functions at the Gauss points (the bulk of the step), rows in parallel.
  const auto ng = static_cast<Index>(q.size());
  mls.add_rows(
      ng, [&](Index g) -> const Vec<Dim>& { return q.x[static_cast<std::size_t>(g)]; },
      MlsWeight::QuadraticSpline, gauss_);
  rho_.resize(q.size());
  gauss_.for_each_row([&](std::size_t g, const ShapeTable& t, std::size_t r) {
    rho_[g] = t.apply(r, [&](std::size_t p) { return P.density(p); });
  });
  if (settings_.conservative) {
    // rho~ = rho^ M / sum_g w_g rho^_g (mls.hpp).
    std::array<double, 2> sums{};  // sum_g w_g rho^_g, sum_p m_p
    for (std::size_t g = 0; g < q.size(); ++g) sums[0] += q.w[g] * rho_[g];
    for (Index p = 0; p < sim.own_particles(); ++p) sums[1] += P.mass[static_cast<std::size_t>(p)];
    if (sim.comm) sim.comm->sum(std::span<double>(sums));
    const double integral = sums[0], mass = sums[1];
    if (integral > 0.0)
      for (double& r : rho_) r *= mass / integral;
  }
}

template <int Dim, class V>
void MlsFamilyMapping::conserve_with_density(const GaussPoints<Dim>& q, std::vector<V>& f,
                                             const V& total, const Comm* comm) const {
  // f~_g = f_g + rho~_g delta with sum_g w_g f~_g = total (mls.hpp); serial sums in point order,
  // then over the processes in rank order.
  V integral = V::Zero();
  double mass = 0.0;
  for (std::size_t g = 0; g < q.size(); ++g) {
    integral += q.w[g] * f[g];
    mass += q.w[g] * rho_[g];
  }
  if (comm) {
    std::array<double, Dim + 1> sums;
    for (int d = 0; d < Dim; ++d) sums[static_cast<std::size_t>(d)] = integral[d];
    sums[Dim] = mass;
    comm->sum(std::span<double>(sums));
    for (int d = 0; d < Dim; ++d) integral[d] = sums[static_cast<std::size_t>(d)];
    mass = sums[Dim];
  }
  if (!(mass > 0.0)) return;
  const V delta = (total - integral) / mass;
  for (std::size_t g = 0; g < q.size(); ++g) f[g] += rho_[g] * delta;
}

template <int Dim>
void MlsFamilyMapping::finish_mass(RunState<Dim>& sim) {
  auto& mls = std::get<Dim - 1>(work_).mls;
  if (improved_) {
    const auto& xn = std::get<Dim - 1>(work_).node_x;
    mls.add_rows(
        static_cast<Index>(xn.size()),
        [&](Index r) -> const Vec<Dim>& { return xn[static_cast<std::size_t>(r)]; },
        MlsWeight::Linear, nodes_, true);
  }
  const MlsReport rep = sim.comm ? over_ranks(*sim.comm, mls.report()) : mls.report();
  accumulate(totals_, rep);
  if (rep.singular > 0)
    throw RunError(
        exit_code::kReconstruction,
        fmt::format("step {}, t = {:.9g} s: the MLS moment matrix is singular at {} "
                    "point(s) (first near x = {:.6g}{}): too few distinct particles "
                    "for method.mls_degree = {}; use method.mapping = imls",
                    sim.step, sim.time, rep.singular, rep.worst_x,
                    Dim == 1   ? std::string()
                    : Dim == 2 ? fmt::format(", y = {:.6g}", rep.worst_y)
                               : fmt::format(", y = {:.6g}, z = {:.6g}", rep.worst_y, rep.worst_z),
                    settings_.degree));
}

template <int Dim>
void MlsFamilyMapping::fit_momentum(RunState<Dim>& sim, const GaussPoints<Dim>& q) {
  using V = Vec<Dim>;
  const auto& P = sim.particles;
  if (improved_) {
    auto& out = sim.nodes.momentum;
    std::fill(out.begin(), out.end(), V::Zero());
    nodes_.for_each_row([&](std::size_t r, const ShapeTable& t, std::size_t k) {
      const auto i = static_cast<std::size_t>(node_dof_[r]);
      out[i] = node_mass_[r] * t.apply<V>(k, [&](std::size_t p) -> const V& { return P.v[p]; });
    });
    if (settings_.conservative) {
      // The common velocity shift (mls.hpp): sums in DOF and particle order, serial.
      // In a distributed run each process's nodal masses and momenta are its partial sums
      // (m_i^r v_i: the exchange adds them), so the totals are sums over the processes.
      V nodal = V::Zero(), particles = V::Zero();
      double mass = 0.0;
      for (std::size_t r = 0; r < node_dof_.size(); ++r) {
        nodal += out[static_cast<std::size_t>(node_dof_[r])];
        mass += node_mass_[r];
      }
      for (std::size_t p = 0; p < static_cast<std::size_t>(sim.own_particles()); ++p)
        particles += P.mass[p] * P.v[p];
      if (sim.comm) {
        std::array<double, 2 * Dim + 1> sums;
        for (int d = 0; d < Dim; ++d) {
          sums[static_cast<std::size_t>(d)] = nodal[d];
          sums[static_cast<std::size_t>(Dim + d)] = particles[d];
        }
        sums[2 * Dim] = mass;
        sim.comm->sum(std::span<double>(sums));
        for (int d = 0; d < Dim; ++d) {
          nodal[d] = sums[static_cast<std::size_t>(d)];
          particles[d] = sums[static_cast<std::size_t>(Dim + d)];
        }
        mass = sums[2 * Dim];
      }
      if (mass > 0.0) {
        const V shift = (particles - nodal) / mass;
        for (std::size_t r = 0; r < node_dof_.size(); ++r)
          out[static_cast<std::size_t>(node_dof_[r])] += node_mass_[r] * shift;
      }
    }
  } else {
    auto& vec = std::get<Dim - 1>(work_).vec;
    vec.resize(q.size());
    gauss_.for_each_row([&](std::size_t g, const ShapeTable& t, std::size_t r) {
      vec[g] = t.apply<V>(r, [&](std::size_t p) -> V { return P.density(p) * P.v[p]; });
    });
    if (settings_.conservative) {
      V total = V::Zero();
      for (std::size_t p = 0; p < static_cast<std::size_t>(sim.own_particles()); ++p)
        total += P.mass[p] * P.v[p];
      if (sim.comm) sim.comm->sum(std::span<double>(total.data(), Dim));
      conserve_with_density(q, vec, total, sim.comm);
    }
  }
}

template <int Dim>
void MlsFamilyMapping::fit_forces(RunState<Dim>& sim, const GaussPoints<Dim>& q) {
  using V = Vec<Dim>;
  using M = Mat<Dim>;
  const auto& P = sim.particles;
  auto& sig = std::get<Dim - 1>(work_).sig;
  auto& vec = std::get<Dim - 1>(work_).vec;
  sig.resize(q.size());
  vec.resize(q.size());
  // Stress and body force in one pass over each row: every sum runs over the row in the same
  // order as separate applications, so the bits are theirs.
  gauss_.for_each_row([&](std::size_t g, const ShapeTable& t, std::size_t r) {
    M s = M::Zero();
    V b = V::Zero();
    for (std::size_t k = t.start[r]; k < t.start[r + 1]; ++k) {
      const auto p = static_cast<std::size_t>(t.point[k]);
      s += t.phi[k] * P.stress[p];
      b += t.phi[k] * P.body[p];
    }
    sig[g] = s;
    vec[g] = rho_[g] * b;
  });
  if (settings_.conservative) {
    V total = V::Zero();
    for (std::size_t p = 0; p < static_cast<std::size_t>(sim.own_particles()); ++p)
      total += P.mass[p] * P.body[p];
    if (sim.comm) sim.comm->sum(std::span<double>(total.data(), Dim));
    conserve_with_density(q, vec, total, sim.comm);
  }
}

#define MPM_MLS_MAPPING_DIM(D)                                                          \
  template void MlsFamilyMapping::fit_mass<D>(RunState<D>&, GaussPoints<D>&);           \
  template void MlsFamilyMapping::finish_mass<D>(RunState<D>&);                         \
  template void MlsFamilyMapping::fit_momentum<D>(RunState<D>&, const GaussPoints<D>&); \
  template void MlsFamilyMapping::fit_forces<D>(RunState<D>&, const GaussPoints<D>&);
MPM_MLS_MAPPING_DIM(1)
MPM_MLS_MAPPING_DIM(2)
MPM_MLS_MAPPING_DIM(3)
#undef MPM_MLS_MAPPING_DIM

// The run totals in a checkpoint: six counters, then the largest condition number and where.
std::string MlsFamilyMapping::save_totals() const {
  const MlsReport& t = totals_;
  ByteWriter w;
  for (Index v : {t.points, t.empty, t.ill_conditioned, t.singular, t.reduced, t.widened}) w.i64(v);
  w.f64(t.max_condition);
  w.f64(t.worst_x);
  w.f64(t.worst_y);
  w.f64(t.worst_z);  // since 3D (earlier checkpoints end above)
  return std::move(w.bytes());
}

void MlsFamilyMapping::load_totals(std::string_view bytes, const std::string& what) {
  ByteReader r(bytes, what + " (MLS totals)");
  MlsReport t;
  for (Index* v : {&t.points, &t.empty, &t.ill_conditioned, &t.singular, &t.reduced, &t.widened})
    *v = r.i64();
  t.max_condition = r.f64();
  t.worst_x = r.f64();
  t.worst_y = r.f64();
  if (!r.done()) t.worst_z = r.f64();
  r.expect_done();
  totals_ = t;
}

}  // namespace mpm
