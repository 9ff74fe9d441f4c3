// Taylor least-squares reconstruction in 1D to 3D (D 5.2-5.3, 6.1-6.2, 000 sec. 2, 004 4.4.1):
// element systems, completion of deficient elements (D 5.2.3, 6.3.2) and the per-field fits.
#include "mapping/tls.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>

#include "core/parallel.hpp"

namespace mpm {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// The shifted Cholesky tests condition() spends on one element before it computes the
// eigenvalues: each halves the logarithmic width of a bracket, so 16 settle every element whose
// condition number is not within a few per cent of the limit.
constexpr int kConditionTests = 16;
// Two positions closer than this (in units of the element half-width) are one point: they add
// no new direction to D.
constexpr double kCoincident = 1e-10;

// f(std::integral_constant<int, n>{}) for n in 0..Max (larger n: Max), so that the small loops
// over the terms or fields of an element have their length at compile time and unroll.
template <int Max, int N = 0, class F>
void with_size(int n, F&& f) {
  if constexpr (N >= Max)
    f(std::integral_constant<int, Max>{});
  else if (n == N)
    f(std::integral_constant<int, N>{});
  else
    with_size<Max, N + 1>(n, f);
}

// cond_2 = lambda_max / lambda_min of the block of rows and columns first..t-1 of the symmetric
// positive semi-definite normal matrix D (D 5.2.3): the leading t x t block for plain fits
// (first = 0), the terms 2..t for conservative ones (first = 1); infinite when singular, 1 when
// nothing is fitted.
template <int K>
double condition_number(const Eigen::Matrix<double, K, K>& D, int first, int t) {
  double lo = 0.0, hi = 0.0;
  const int n = t - first;
  if (n == 0) return 1.0;
  if (n == 1) {
    lo = hi = D(first, first);
  } else {
    // One solver per K, of run-time size n <= K on the stack: a solver per size n (with_size)
    // made this unit compile in 167 s instead of 58 (g++ -O3). It runs for every fit in 1D
    // (TlsSettings::exact_condition) and in 2D and 3D only where the cheap bound of
    // condition() does not settle the test.
    using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, K, K>;
    const Eigen::SelfAdjointEigenSolver<Block> es(Block(D.block(first, first, n, n)),
                                                  Eigen::EigenvaluesOnly);
    lo = es.eigenvalues()[0];
    hi = es.eigenvalues()[n - 1];
  }
  if (!(lo > 0.0) || !std::isfinite(hi)) return kInf;
  return hi / lo;
}

// The inverse of the n x n block of the symmetric positive definite A at rows and columns first..
// first + n - 1, through its Cholesky factor A = R^T R (A^{-1} = R^{-1} R^{-T}), into the leading
// block of inv (zero elsewhere). A pivot that is not positive is left zero: its inverse is
// infinite, and so are the entries that depend on it. N = n at compile time, so that the loops
// unroll.
template <int N, class In, class Out>
void spd_inverse_n(const In& A, int first, Out& inv) {
  inv.setZero();
  if constexpr (N > 0 && N <= Out::RowsAtCompileTime) {
    Eigen::Matrix<double, N, N> R = Eigen::Matrix<double, N, N>::Zero(), Ri = R;
    for (int j = 0; j < N; ++j) {
      double d = A(first + j, first + j);
      for (int k = 0; k < j; ++k) d -= R(k, j) * R(k, j);
      R(j, j) = d > 0.0 ? std::sqrt(d) : 0.0;
      Ri(j, j) = 1.0 / R(j, j);  // multiplied by below: a division is 4-5x the latency
      for (int i = j + 1; i < N; ++i) {
        double v = A(first + j, first + i);
        for (int k = 0; k < j; ++k) v -= R(k, j) * R(k, i);
        R(j, i) = v * Ri(j, j);
      }
    }
    for (int j = 0; j < N; ++j)
      for (int i = j - 1; i >= 0; --i) {
        double v = 0.0;
        for (int k = i + 1; k <= j; ++k) v += R(i, k) * Ri(k, j);
        Ri(i, j) = -v * Ri(i, i);
      }
    for (int i = 0; i < N; ++i)
      for (int j = 0; j <= i; ++j) {
        double v = 0.0;
        for (int k = i; k < N; ++k) v += Ri(i, k) * Ri(j, k);
        inv(i, j) = inv(j, i) = v;
      }
  }
}

template <class In, class Out>
void spd_inverse(const In& A, int first, int n, Out& inv) {
  with_size<Out::RowsAtCompileTime>(
      n, [&]<int N>(std::integral_constant<int, N>) { spd_inverse_n<N>(A, first, inv); });
}

// ||M||_F of the n x n block at first..first + n - 1.
template <class M>
double frobenius(const M& A, int first, int n) {
  return A.block(first, first, n, n).norm();
}

// max_i sum_j |A_ij| over the n x n block at first..first + n - 1; infinite when an entry is
// not finite (an inverse whose pivot was not positive).
template <class M>
double norm_inf(const M& A, int first, int n) {
  double m = 0.0;
  for (int i = first; i < first + n; ++i) {
    double r = 0.0;
    for (int j = first; j < first + n; ++j) r += std::abs(A(i, j));
    if (!std::isfinite(r)) return kInf;
    m = std::max(m, r);
  }
  return m;
}

// Whether sign (M - sigma I) is positive definite, for the symmetric n x n block M of A at rows
// and columns first..first + n - 1: an LDL^T factorisation without square roots that stops at
// the first pivot that is not positive (or not finite). About n^3 / 3 multiplications, against
// about 6,600 instructions for Eigen's eigenvalues of a 6 x 6 block.
template <class M>
bool shifted_positive_definite(const M& A, int first, int n, double sigma, double sign) {
  constexpr int K = M::RowsAtCompileTime;
  std::array<double, K * K> l{};  // L (unit lower triangular, row-major) times D, column by column
  std::array<double, K> d_inv{};
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < j; ++i) {
      // w_ji = (L D)_ji = a_ji - sum_k w_jk w_ik / d_k; l holds w.
      double v = sign * A(first + j, first + i);
      for (int k = 0; k < i; ++k)
        v -= l[static_cast<std::size_t>(j * K + k)] * l[static_cast<std::size_t>(i * K + k)] *
             d_inv[static_cast<std::size_t>(k)];
      l[static_cast<std::size_t>(j * K + i)] = v;
    }
    double d = sign * (A(first + j, first + j) - sigma);
    for (int k = 0; k < j; ++k) {
      const double w = l[static_cast<std::size_t>(j * K + k)];
      d -= w * w * d_inv[static_cast<std::size_t>(k)];
    }
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    d_inv[static_cast<std::size_t>(j)] = 1.0 / d;
  }
  return true;
}

template <int K>
void add_outer(Eigen::Matrix<double, K, K>& D, const Eigen::Matrix<double, K, 1>& psi) {
  D.noalias() += psi * psi.transpose();
}

// Polynomial degree of n_b Taylor terms: 1D n_b - 1; 2D 0, 1, 2 for 1, 3, 6 terms; 3D for 1, 4,
// 10 terms.
int taylor_degree(int terms, int dim) {
  if (dim == 1) return terms - 1;
  return terms == 1 ? 0 : terms == dim + 1 ? 1 : 2;
}

// The next smaller complete space (Reduce): 1D 3 -> 2 -> 1, 2D 6 -> 3 -> 1, 3D 10 -> 4 -> 1.
int fewer_terms(int terms, int dim) {
  if (dim == 1) return terms - 1;
  return terms > dim + 1 ? dim + 1 : 1;
}

}  // namespace

TlsCompletion parse_tls_completion(std::string_view name) {
  if (name == "none") return TlsCompletion::None;
  if (name == "reduce") return TlsCompletion::Reduce;
  if (name == "virtual") return TlsCompletion::Virtual;
  if (name == "neighbour") return TlsCompletion::Neighbour;
  if (name == "min_norm") return TlsCompletion::MinimumNorm;
  if (name == "graded") return TlsCompletion::Graded;
  throw InputError(
      fmt::format("TLS completion \"{}\" is not available; choose one of: none, reduce, virtual, "
                  "neighbour (rectangles), min_norm, graded (triangles)",
                  name));
}

std::string_view tls_completion_name(TlsCompletion c) {
  switch (c) {
    case TlsCompletion::None:
      return "none";
    case TlsCompletion::Reduce:
      return "reduce";
    case TlsCompletion::Virtual:
      return "virtual";
    case TlsCompletion::Neighbour:
      return "neighbour";
    case TlsCompletion::MinimumNorm:
      return "min_norm";
    case TlsCompletion::Graded:
      return "graded";
  }
  return "none";
}

void validate(const TlsSettings& s, int dim) {
  if (dim < 1 || dim > 3)
    throw InputError(
        fmt::format("the TLS reconstruction is available in 1D, 2D and 3D, not {}D", dim));
  if (dim == 1 && (s.terms < 0 || s.terms > 3))
    throw InputError(fmt::format(
        "method.tls_terms = {} must be 1, 2 or 3 in 1D (0: quadratic, 3 terms)", s.terms));
  if (dim == 2 && s.terms != 0 && s.terms != 1 && s.terms != 3 && s.terms != 6)
    throw InputError(fmt::format(
        "method.tls_terms = {} must be 1 (constant), 3 (linear) or 6 (quadratic) in 2D (0: 6)",
        s.terms));
  if (dim == 3 && s.terms != 0 && s.terms != 1 && s.terms != 4 && s.terms != 10)
    throw InputError(fmt::format(
        "method.tls_terms = {} must be 1 (constant), 4 (linear) or 10 (quadratic) in 3D (0: 10)",
        s.terms));
  if (!(s.max_condition > 1.0) || !(s.max_condition <= 1e14))
    throw InputError(fmt::format(
        "method.tls_max_condition = {} must lie in (1, 1e14] (0: the default of the dimension): "
        "the fits solve the normal equations, whose rounding error grows like the condition "
        "number times 2.2e-16",
        s.max_condition));
  if (s.gauss_points < 0 || s.gauss_points > 10)
    throw InputError(fmt::format("method.gauss_points = {} must lie in [0, 10]", s.gauss_points));
  if (s.max_borrowed < 0)
    throw InputError(
        fmt::format("TLS max_borrowed = {} must be positive (0: the default)", s.max_borrowed));
  // n Gauss points per direction integrate degree 2n - 1 exactly; psi_2.. must integrate to zero
  // (D 5.3.2: n_b <= 2 x Gauss points in 1D; in 2D the quadratic terms need 2 per direction).
  const int terms = s.terms_used(dim);
  if (2 * s.gauss_points_used() - 1 < taylor_degree(terms, dim))
    throw InputError(fmt::format(
        "method.gauss_points = {} does not integrate the Taylor basis of method.tls_terms = {} "
        "exactly, so mass and momentum would not be conserved (D 5.3.2: n Gauss points per "
        "direction integrate degree 2n - 1, the {}D basis has degree {}); use 2 or more Gauss "
        "points, or 0 for the default",
        s.gauss_points, terms, dim, taylor_degree(terms, dim)));
}

void throw_fit_failure(Index step, double time, const TlsReport& rep, std::string_view noun,
                       const std::string& which, std::string_view completions) {
  throw RunError(
      exit_code::kReconstruction,
      fmt::format(
          "step {}, t = {:.9g} s: TLS cannot fit {} {} ({} particles, condition "
          "number {:.3g}){}; set method.tls_completion = {}",
          step, time, noun, which, rep.failed_points, rep.failed_condition,
          rep.failed > 1 ? fmt::format(" and {} more {}(s)", rep.failed - 1, noun) : std::string(),
          completions));
}

void accumulate(TlsReport& total, const TlsReport& step) {
  total.elements += step.elements;
  total.active += step.active;
  total.full += step.full;
  total.reduced += step.reduced;
  total.with_virtual += step.with_virtual;
  total.with_neighbours += step.with_neighbours;
  total.outside += step.outside;
  if (step.min_terms > 0)
    total.min_terms =
        total.min_terms > 0 ? std::min(total.min_terms, step.min_terms) : step.min_terms;
  total.max_condition = std::max(total.max_condition, step.max_condition);
  if (step.failed > 0 && total.failed == 0) {
    total.failed_element = step.failed_element;
    total.failed_points = step.failed_points;
    total.failed_condition = step.failed_condition;
  }
  total.failed += step.failed;
  total.truncated += step.truncated;
  total.limited += step.limited;
  total.surface += step.surface;
  total.unweighted += step.unweighted;
}

TlsReport over_ranks(const Comm& comm, const TlsReport& mine) {
  if (!comm.distributed()) return mine;
  const TlsReport& m = mine;
  // As doubles (exact for counts below 2^53), one all-gather.
  const std::array<double, 15> v{static_cast<double>(m.active),
                                 static_cast<double>(m.full),
                                 static_cast<double>(m.reduced),
                                 static_cast<double>(m.with_virtual),
                                 static_cast<double>(m.with_neighbours),
                                 static_cast<double>(m.failed),
                                 static_cast<double>(m.truncated),
                                 static_cast<double>(m.limited),
                                 static_cast<double>(m.surface),
                                 static_cast<double>(m.outside),
                                 static_cast<double>(m.min_terms),
                                 m.max_condition,
                                 static_cast<double>(m.failed_element),
                                 static_cast<double>(m.failed_points),
                                 m.failed_condition};
  const std::vector<double> all = comm.allgather(std::span<const double>(v));
  TlsReport t;
  t.elements = m.elements;
  for (std::size_t r = 0; r < static_cast<std::size_t>(comm.size()); ++r) {
    const double* o = all.data() + r * v.size();
    const auto n = [&](int k) { return static_cast<Index>(o[k]); };
    t.active += n(0);
    t.full += n(1);
    t.reduced += n(2);
    t.with_virtual += n(3);
    t.with_neighbours += n(4);
    if (n(5) > 0 && (t.failed == 0 || n(12) < t.failed_element)) {
      t.failed_element = n(12);
      t.failed_points = n(13);
      t.failed_condition = o[14];
    }
    t.failed += n(5);
    t.truncated += n(6);
    t.limited += n(7);
    t.surface += n(8);
    t.outside += n(9);
    const int terms = static_cast<int>(o[10]);
    if (terms > 0) t.min_terms = t.min_terms > 0 ? std::min(t.min_terms, terms) : terms;
    t.max_condition = std::max(t.max_condition, o[11]);
  }
  return t;
}

template <int Dim>
BasicTlsReconstruction<Dim>::BasicTlsReconstruction(const TlsSettings& s)
    : settings_(s), nb_(s.terms_used(Dim)) {
  validate(s, Dim);
  // 2D virtual points (D 6.3.2 leaves their placement open): on each face, at the Gauss-Legendre
  // nodes of as many points as the face trace of a neighbour's reconstruction has coefficients
  // (2 for the linear basis, 3 for the quadratic one), so that the trace is passed on whole. The
  // nodes lie inside the face, so the faces share no virtual point at a corner. 3D: the tensor
  // product of these nodes on each face (9 for the quadratic basis, whose face trace is a
  // quadratic in two variables with 6 coefficients, unisolvent on the 3 x 3 nodes; 4 for the
  // linear one).
  if constexpr (Dim >= 2) face_xi_ = gauss_legendre(nb_ == kTaylorTerms<Dim> ? 3 : 2).xi;
}

template <int Dim>
std::string BasicTlsReconstruction<Dim>::describe(Index e) const {
  if constexpr (Dim == 1) {
    return fmt::format("{}", e);
  } else if constexpr (Dim == 2) {
    const IVec<Dim> c = cell(e);
    return fmt::format("{} at cell ({}, {})", e, c[0], c[1]);
  } else {
    const IVec<Dim> c = cell(e);
    return fmt::format("{} at cell ({}, {}, {})", e, c[0], c[1], c[2]);
  }
}

template <int Dim>
const TlsReport& BasicTlsReconstruction<Dim>::set_points(const Grid<Dim>& g,
                                                         std::span<const Point> x,
                                                         bool share_face_points) {
  grid_ = g;
  x_.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) x_[i] = as_vec(x[i]);
  key_.clear();
  report_ = TlsReport{};
  bin_points(share_face_points);
  build_systems();
  return report_;
}

template <int Dim>
const TlsReport& BasicTlsReconstruction<Dim>::set_points(const Grid<Dim>& g,
                                                         const Particles<Dim>& P) {
  grid_ = g;
  // Copied in the sort's parallel pass over the points (serial, these and the sort were 3 % of
  // a step).
  const auto n = static_cast<std::size_t>(P.size());
  x_.resize(n);
  key_.resize(n);
  report_ = TlsReport{};
  bins_.build(g, std::span(P.x), [&](std::size_t p) {
    x_[p] = P.x[p];
    key_[p] = P.id[p];
  });
  build_systems();
  return report_;
}

// Counting sort into the cells, as ElementBins, with the optional further owners of a point on
// interior faces (the lower neighbours across those faces, edges and corners).
template <int Dim>
void BasicTlsReconstruction<Dim>::bin_points(bool share_face_points) {
  const auto ne_s = static_cast<std::size_t>(grid_.num_cells());
  // Calls owner(e) for every element that holds x; false when x lies outside the grid.
  auto for_each_owner = [&](const Vec<Dim>& x, auto&& owner) {
    IVec<Dim> c{}, l{};
    for (int d = 0; d < Dim; ++d) {
      c[d] = grid_.cell_of(x[d], d);
      if (c[d] < 0 || c[d] >= grid_.cells[d]) return false;
      l[d] = -1;
      if (share_face_points && c[d] > 0 &&
          (x[d] - grid_.origin[d]) / grid_.h[d] == static_cast<double>(c[d]))
        l[d] = c[d] - 1;
    }
    for (int mask = 0; mask < (1 << Dim); ++mask) {
      IVec<Dim> o = c;
      for (int d = 0; d < Dim; ++d)
        if ((mask >> d) & 1) o[d] = l[d];
      if (grid_.has_cell(o)) owner(grid_.cell_index(o));
    }
    return true;
  };
  bins_.start.assign(ne_s + 1, 0);
  for (const auto& x : x_)
    if (!for_each_owner(x, [&](Index e) { ++bins_.start[static_cast<std::size_t>(e + 1)]; }))
      ++report_.outside;
  for (std::size_t e = 0; e < ne_s; ++e) bins_.start[e + 1] += bins_.start[e];
  bins_.order.resize(static_cast<std::size_t>(bins_.start[ne_s]));
  fill_.assign(bins_.start.begin(), bins_.start.end() - 1);
  for (std::size_t p = 0; p < x_.size(); ++p)
    for_each_owner(x_[p], [&](Index e) {
      bins_.order[static_cast<std::size_t>(fill_[static_cast<std::size_t>(e)]++)] =
          static_cast<Index>(p);
    });
}

template <int Dim>
bool BasicTlsReconstruction<Dim>::coincides(const System& sys, const Vec<Dim>& s) const {
  for (Index k = sys.begin; k < sys.end; ++k) {
    const Taylor& psi = data_[static_cast<std::size_t>(k)].psi;  // psi_2..psi_{1+Dim} = s
    bool same = true;
    for (int d = 0; d < Dim; ++d) same = same && std::abs(psi[1 + d] - s[d]) <= kCoincident;
    if (same) return true;
  }
  return false;
}

template <int Dim>
void BasicTlsReconstruction<Dim>::place(System& sys, const Vec<Dim>& s, Index point, Index source,
                                        const Vec<Dim>& s_source) {
  // The element's slot in data_ holds its own points and the most completion points it can
  // take (build_systems), so this never writes into the next element's slot.
  const auto k = static_cast<std::size_t>(sys.end++);
  data_[k] = {taylor_basis_at<Dim>(s), point};
  if (source >= 0) from_[k] = {source, s_source};
}

template <int Dim>
void BasicTlsReconstruction<Dim>::add_datum(System& sys, Matrix& D, const Vec<Dim>& s, Index point,
                                            Index source, const Vec<Dim>& s_source) {
  place(sys, s, point, source, s_source);
  add_outer(D, data_[static_cast<std::size_t>(sys.end - 1)].psi);
}

// In the orthonormal Taylor basis (TlsSettings::max_condition): phi = L psi, so the normal
// matrix is L D L with L the inverse root-mean-square norms of psi_1..psi_K over [-1, 1]^Dim.
template <int Dim>
const typename BasicTlsReconstruction<Dim>::Taylor& BasicTlsReconstruction<Dim>::scales() {
  static const Taylor l = [] {
    Taylor v;
    if constexpr (Dim == 1)
      v << 1.0, std::sqrt(3.0), std::sqrt(45.0);
    else if constexpr (Dim == 2)
      v << 1.0, std::sqrt(3.0), std::sqrt(3.0), std::sqrt(45.0), std::sqrt(45.0), 3.0;
    else
      v << 1.0, std::sqrt(3.0), std::sqrt(3.0), std::sqrt(3.0), std::sqrt(45.0), std::sqrt(45.0),
          std::sqrt(45.0), 3.0, 3.0, 3.0;
    return v;
  }();
  return l;
}

template <int Dim>
double BasicTlsReconstruction<Dim>::condition(const Matrix& D, int t, Matrix* s_inv,
                                              bool* has_s_inv) const {
  const Taylor& l = scales();
  if (has_s_inv != nullptr) *has_s_inv = false;
  const Matrix S = l.asDiagonal() * D * l.asDiagonal();
  const int first = settings_.conservative_only ? 1 : 0, n = t - first;
  if (!settings_.exact_condition && n > 1) {
    // cond_2(S) <= ||S||_inf ||S^{-1}||_inf (||A||_2 <= ||A||_inf for symmetric A): when this
    // bound already meets the limit, the eigenvalues are not needed. Its rounding error is about
    // n cond eps relative, hence the margin and the ceiling (a failed or non-finite inverse fails
    // the test; it is rejected below).
    Matrix inv;
    spd_inverse(S, first, n, inv);
    const double bound = norm_inf(S, first, n) * norm_inf(inv, 0, n);
    if (bound <= 1e10 && bound * (1.0 + 1e-4) <= settings_.max_condition) {
      if (s_inv != nullptr && has_s_inv != nullptr) {
        *s_inv = inv;
        *has_s_inv = true;
      }
      return bound;
    }
    // Above the ceiling rounding could reach the limit: only the eigenvalues decide there.
    if (settings_.max_condition > 1e10) return condition_number(S, first, t);
    // A pivot of the Cholesky factorisation that is not positive (the inverse then has entries
    // that are not finite) proves cond(S) above any limit the bounds serve: in floating point the
    // factorisation of a symmetric positive definite matrix runs to completion when n^2 (n + 1)
    // u cond(S) < 1 roughly (Demmel; Higham, Accuracy and Stability of Numerical Algorithms, 2nd
    // ed., Thm. 10.7 with van der Sluis's bound for the diagonal scaling), i.e. for cond(S) below
    // 8e12 when n <= 10, far above the ceiling 1e10. Elements with fewer distinct points than
    // terms are of this kind; the eigenvalues would say the same (infinite or above 1e12).
    if (!std::isfinite(bound)) return kInf;
    // Otherwise bracket the two factors of cond(S) = lambda_max(S) lambda_max(S^{-1}) and narrow
    // the brackets until they settle the test (in deformed layouts about half the elements reached
    // the eigenvalues here, each an Eigen solve of about 6,600 instructions). For
    // symmetric positive definite M with eigenvalues mu_i, max_i M_ii <= lambda_max(M),
    // ||M||_F / sqrt(n) <= lambda_max(M) <= min(||M||_F, ||M||_inf). A shifted Cholesky test
    // narrows a bracket at its geometric mean: sigma I - S positive definite <=> lambda_max(S) <
    // sigma, and S - I / sigma positive definite <=> lambda_max(S^{-1}) < sigma. Only where
    // rounding cannot reach the limit (the test's backward error is about n eps ||S||, i.e. n eps
    // cond(S) relative to lambda_min: far inside the margin below the ceiling 1e10; 16 tests that
    // do not settle it go to the eigenvalues). Both decisions are those of the eigenvalues
    // outside the margin; the value returned is the bracket's end that decided (a lower bound
    // when rejected: the elements rejected here are reported only through their completion, and
    // `none` recomputes the condition for its message). The inverse is not handed on where the
    // brackets accept (factorise forms its own, as after the eigenvalues), so the fits are those
    // of the eigenvalue test, bit for bit. With a finite bound S is numerically positive
    // definite, so both brackets are finite and positive.
    double lo_s = 0.0, lo_i = 0.0;
    for (int i = 0; i < n; ++i) {
      lo_s = std::max(lo_s, S(first + i, first + i));
      lo_i = std::max(lo_i, inv(i, i));
    }
    const double root_n = std::sqrt(static_cast<double>(n));
    const double f_s = frobenius(S, first, n), f_i = frobenius(inv, 0, n);
    lo_s = std::max(lo_s, f_s / root_n);
    lo_i = std::max(lo_i, f_i / root_n);
    double hi_s = std::min(f_s, norm_inf(S, first, n)), hi_i = std::min(f_i, norm_inf(inv, 0, n));
    for (int test = 0;; ++test) {
      const double lower = lo_s * lo_i, upper = hi_s * hi_i;
      if (lower * (1.0 - 1e-4) > settings_.max_condition) return lower;
      if (upper <= 1e10 && upper * (1.0 + 1e-4) <= settings_.max_condition) return upper;
      if (test == kConditionTests) break;
      if (hi_s * lo_i >= hi_i * lo_s) {  // the wider bracket (hi / lo) first
        const double sigma = std::sqrt(lo_s * hi_s);
        (shifted_positive_definite(S, first, n, sigma, -1.0) ? hi_s : lo_s) = sigma;
      } else {
        const double sigma = std::sqrt(lo_i * hi_i);
        (shifted_positive_definite(S, first, n, 1.0 / sigma, 1.0) ? hi_i : lo_i) = sigma;
      }
    }
  }
  return condition_number(S, first, t);
}

// Enough distinct positions for the unknowns (t, or t - 1 when a_1 is always given) and
// cond(D) within the limit.
template <int Dim>
bool BasicTlsReconstruction<Dim>::well_posed(const Matrix& D, int distinct, int t, double& cond,
                                             Matrix* s_inv, bool* has_s_inv) const {
  // Too few distinct points fail whatever the condition number; the value is then not used
  // (a failed element's condition is recomputed where it is reported, system_pass).
  if (distinct < t - (settings_.conservative_only ? 1 : 0)) {
    cond = kInf;
    if (has_s_inv != nullptr) *has_s_inv = false;
    return false;
  }
  cond = condition(D, t, s_inv, has_s_inv);
  return cond <= settings_.max_condition;
}

// D 5.2.3: virtual points on each face whose neighbour fits all n_b terms from its own points,
// valued by that neighbour's reconstruction there (at fit time). 1D: one point, the face itself;
// 2D: the face nodes face_xi_; 3D: their tensor product on the face (see the constructor). A
// virtual point coinciding with a point of the element adds nothing and is skipped.
template <int Dim>
void BasicTlsReconstruction<Dim>::add_virtual_points(Index e, System& sys, Matrix& D,
                                                     int& distinct) {
  const IVec<Dim> c = cell(e);
  const std::size_t nxi = face_xi_.size();
  const std::size_t per_face = Dim == 1 ? 1 : Dim == 2 ? nxi : nxi * nxi;
  Index stride = 1;
  for (int d = 0; d < Dim; stride *= grid_.cells[d], ++d) {
    for (int side : {-1, +1}) {
      if (c[d] + side < 0 || c[d] + side >= grid_.cells[d]) continue;
      const Index n = e + side * stride;
      if (!own_[static_cast<std::size_t>(n)].ok) continue;
      for (std::size_t k = 0; k < per_face; ++k) {
        Vec<Dim> s;
        s[d] = static_cast<double>(side);
        // The other directions of the face, in increasing order: node k % nxi, then k / nxi.
        for (int o = 0, r = static_cast<int>(k); o < Dim; ++o)
          if (o != d) {
            s[o] = face_xi_[static_cast<std::size_t>(r) % nxi];
            r /= static_cast<int>(nxi);
          }
        Vec<Dim> s_source = s;  // the same point in the neighbour's coordinates
        s_source[d] = -s[d];
        if (coincides(sys, s)) continue;
        add_datum(sys, D, s, -1, n, s_source);
        sys.has_virtual = true;
        ++distinct;
        ++info_[static_cast<std::size_t>(e)].virtual_points;
      }
    }
  }
}

// D 5.2.3, 6.3.2: the nearest points of the adjacent elements (Euclidean distance to this
// element, ties by index), one at a time until n_b terms are well posed or max_borrowed points
// were taken. The elements across the faces are searched first, then (2D, 3D) those across the
// edges (3D) and the corners, each group only when the nearer ones have nothing left. Points
// coinciding with the element's data are passed over. No allocation: each search scans the
// neighbours for the next candidate after the last one taken in (distance, index) order.
template <int Dim>
void BasicTlsReconstruction<Dim>::borrow_points(Index e, System& sys, Matrix& D, int& distinct) {
  const int nb = nb_;
  const int max_taken = settings_.max_borrowed_used(Dim);
  const Vec<Dim> xc = centre_vec(e), dx = half_width_vec();
  Vec<Dim> lo, hi;
  for (int d = 0; d < Dim; ++d) {
    lo[d] = xc[d] - dx[d];
    hi[d] = xc[d] + dx[d];
  }
  const IVec<Dim> c = cell(e);
  int taken = 0;
  double cond = 0.0;
  // Whether D as it stands is known to fail the test: pass 1's D did, and so does D until a point
  // is added (the test repeated on the same D would only repeat its eigenvalues).
  bool known_failed = true;
  auto failing = [&] {
    if (!known_failed) known_failed = !well_posed(D, distinct, nb, cond);
    return known_failed;
  };
  for (int corners = 0; corners < Dim; ++corners) {
    // The neighbours of this round: those 1 + corners steps away (across a face, an edge, a
    // corner), in the order of the offsets (x fastest).
    std::array<Index, 12> nbrs{};  // at most 12: the edges of a hexahedron
    int count = 0;
    int around = 1;
    for (int d = 0; d < Dim; ++d) around *= 3;
    for (int k = 0; k < around; ++k) {
      IVec<Dim> nc = c;
      int offsets = 0;
      for (int d = 0, r = k; d < Dim; ++d, r /= 3) {
        nc[d] += r % 3 - 1;
        offsets += r % 3 != 1;
      }
      if (offsets != 1 + corners) continue;
      if (grid_.has_cell(nc)) nbrs[static_cast<std::size_t>(count++)] = grid_.cell_index(nc);
    }
    double last_d = -1.0;
    Index last_key = -1;
    while (taken < max_taken && failing()) {
      double best_d = kInf;
      Index best_p = -1, best_key = -1;
      for (int k = 0; k < count; ++k) {
        const Index n = nbrs[static_cast<std::size_t>(k)];
        for (const Index* it = bins_.begin(n); it != bins_.end(n); ++it) {
          const Vec<Dim>& xp = x_[static_cast<std::size_t>(*it)];
          double d = 0.0;
          if constexpr (Dim == 1) {
            d = std::max(0.0, std::max(lo[0] - xp[0], xp[0] - hi[0]));
          } else {
            double sq = 0.0;
            for (int j = 0; j < Dim; ++j) {
              const double gap = std::max(0.0, std::max(lo[j] - xp[j], xp[j] - hi[j]));
              sq += gap * gap;
            }
            d = std::sqrt(sq);
          }
          const Index k =
              key_.empty() ? *it : static_cast<Index>(key_[static_cast<std::size_t>(*it)]);
          const bool after = d > last_d || (d == last_d && k > last_key);
          const bool better = d < best_d || (d == best_d && (best_p < 0 || k < best_key));
          if (after && better) {
            best_d = d;
            best_p = *it;
            best_key = k;
          }
        }
      }
      if (best_p < 0) break;  // these neighbours have nothing left
      last_d = best_d;
      last_key = best_key;
      const Vec<Dim> s = local(e, x_[static_cast<std::size_t>(best_p)]);
      if (coincides(sys, s)) continue;
      add_datum(sys, D, s, best_p);
      known_failed = false;
      ++distinct;
      ++taken;
      ++info_[static_cast<std::size_t>(e)].borrowed;
    }
  }
}

// The inverses of the normal matrix (System) from its Cholesky factor D = R^T R, D^{-1} =
// R^{-1} R^{-T}: of terms 1..t (plain fits) and of terms 2..t (conservative, psi_1 left out as in
// D 5.3.1). well_posed bounded cond(D) of the fitted terms by max_condition, so D is positive
// definite to working precision (the block of terms 2..t too: its eigenvalues lie between D's);
// a pivot that is not positive all the same is left zero, its inverse is infinite and the fits
// give the non-finite values the run stops on.
template <int Dim>
void BasicTlsReconstruction<Dim>::factorise(System& sys, const Matrix& D,
                                            const Matrix* s_inv) const {
  // S = L D L on the orthonormal basis (L = diag(scales())), so D^{-1} = L S^{-1} L.
  const Taylor& l = scales();
  if (settings_.conservative_only) {
    if (s_inv != nullptr) {
      const Taylor1 lc = l.template tail<K - 1>();
      sys.inv_c = lc.asDiagonal() * s_inv->template topLeftCorner<K - 1, K - 1>() * lc.asDiagonal();
    } else {
      spd_inverse(D, 1, sys.terms - 1, sys.inv_c);
    }
    return;
  }
  if (s_inv == nullptr) {
    spd_inverse(D, 0, sys.terms, sys.inv);
    spd_inverse(D, 1, sys.terms - 1, sys.inv_c);
    return;
  }
  const Matrix& Si = *s_inv;
  sys.inv = l.asDiagonal() * Si * l.asDiagonal();
  // The block of terms 2..t from the same inverse: for S = [a b^T; b C], C^{-1} = Z - z z^T / w
  // where S^{-1} = [w z^T; z Z] (the Schur complement of w in S^{-1}), in place of a second
  // Cholesky factorisation. The subtraction loses at most about cond(S) eps, and s_inv is only
  // given where the bound ||S||_inf ||S^{-1}||_inf (>= cond_2(S)) is within max_condition.
  sys.inv_c.setZero();
  const int tc = sys.terms - 1;
  for (int i = 0; i < tc; ++i)
    for (int j = 0; j <= i; ++j) {
      const double v = (Si(i + 1, j + 1) - Si(i + 1, 0) * Si(0, j + 1) / Si(0, 0)) * l[i + 1];
      sys.inv_c(i, j) = sys.inv_c(j, i) = v * l[j + 1];
    }
}

template <int Dim>
void BasicTlsReconstruction<Dim>::build_systems() {
  if (settings_.completion == TlsCompletion::MinimumNorm ||
      settings_.completion == TlsCompletion::Graded)
    throw InputError(fmt::format(
        "TLS completion \"{}\" works on triangles (mapping/tls_triangle.hpp); on the grid's "
        "cells choose none, reduce, virtual or neighbour",
        tls_completion_name(settings_.completion)));
  const Index ne = grid_.num_cells();
  const auto ne_s = static_cast<std::size_t>(ne);
  const int nb = nb_;
  const Vec<Dim> dx = half_width_vec();
  report_.elements = ne;
  own_.resize(ne_s);
  systems_.resize(ne_s);
  info_.assign(ne_s, TlsElementInfo{});
  // Every element gets a slot in data_ for its own points and the most completion points it can
  // add, at a fixed offset, so that pass 2 can fill the slots in parallel (unused entries stay
  // unused; sys.begin .. sys.end is what an element filled).
  const std::size_t nxi = face_xi_.size();
  const std::size_t virtual_max = 2 * Dim * (Dim == 1 ? 1 : Dim == 2 ? nxi : nxi * nxi);
  const Index extra = settings_.completion == TlsCompletion::Virtual
                          ? static_cast<Index>(virtual_max)
                      : settings_.completion == TlsCompletion::Neighbour
                          ? static_cast<Index>(settings_.max_borrowed_used(Dim))
                          : 0;
  slots_.resize(ne_s + 1);

  // Reduce and None complete no element from its neighbours: each element's slot holds its own
  // points (the bins' offsets), and an element's pass 2 can follow its pass 1 in one loop (a
  // parallel region and a second sweep over the elements saved per step; the same systems).
  const bool local =
      settings_.completion == TlsCompletion::Reduce || settings_.completion == TlsCompletion::None;
  // Pass 1: each element from its own points (also decides which neighbours can lend virtual
  // points). Elements are independent: parallel, and the same bits for any thread count.
  auto own_pass = [&](Index e) {
    Own& o = own_[static_cast<std::size_t>(e)];
    o.D.setZero();
    o.distinct = 0;
    std::array<Vec<Dim>, K> seen{};
    const Vec<Dim> xc = centre_vec(e);
    for (const Index* it = bins_.begin(e); it != bins_.end(e); ++it) {
      const Vec<Dim>& x = x_[static_cast<std::size_t>(*it)];
      Vec<Dim> s;
      for (int d = 0; d < Dim; ++d) s[d] = (x[d] - xc[d]) / dx[d];
      // The upper triangle only (D is symmetric; mirrored below): the same sums, 21 of 36
      // products in 2D.
      const Taylor psi = taylor_basis_at<Dim>(s);
      for (int j = 0; j < K; ++j)
        for (int i = 0; i <= j; ++i) o.D(i, j) += psi[i] * psi[j];
      if (o.distinct < nb) {
        bool fresh = true;
        for (int k = 0; k < o.distinct; ++k) {
          bool same = true;
          for (int d = 0; d < Dim; ++d)
            same = same && std::abs(seen[static_cast<std::size_t>(k)][d] - s[d]) <= kCoincident;
          fresh = fresh && !same;
        }
        if (fresh) seen[static_cast<std::size_t>(o.distinct++)] = s;
      }
    }
    o.D.template triangularView<Eigen::StrictlyLower>() = o.D.transpose();
    const Index count = bins_.count(e);
    info_[static_cast<std::size_t>(e)].points = count;
    o.ok = count > 0 && well_posed(o.D, o.distinct, nb, o.condition, &o.s_inv, &o.has_s_inv);
    if (count == 0) o.condition = 0.0;
    if (!local)
      slots_[static_cast<std::size_t>(e) + 1] = count > 0 ? count + (o.ok ? 0 : extra) : 0;
  };

  // Pass 2: data, completion, number of terms and factorisations; independent per element (a
  // completion reads only the pass-1 results of its neighbours).
  auto system_pass = [&](Index e) {
    const Own& o = own_[static_cast<std::size_t>(e)];
    System& sys = systems_[static_cast<std::size_t>(e)];
    TlsElementInfo& info = info_[static_cast<std::size_t>(e)];
    sys.begin = slots_[static_cast<std::size_t>(e)];
    sys.end = sys.begin;
    sys.terms = 0;
    sys.has_virtual = false;
    if (info.points == 0) return;  // inactive: no reconstruction
    const Vec<Dim> xc = centre_vec(e);
    for (const Index* it = bins_.begin(e); it != bins_.end(e); ++it) {
      const Vec<Dim>& x = x_[static_cast<std::size_t>(*it)];
      Vec<Dim> s;
      for (int d = 0; d < Dim; ++d) s[d] = (x[d] - xc[d]) / dx[d];
      place(sys, s, *it);
    }
    Matrix D = o.D;
    int distinct = o.distinct;
    if (!o.ok) {
      switch (settings_.completion) {
        case TlsCompletion::None:
          info.failed = true;
          // The value for the failure's message: pass 1's may be a lower bound (condition()).
          info.condition =
              condition_number(Matrix(scales().asDiagonal() * D * scales().asDiagonal()),
                               settings_.conservative_only ? 1 : 0, nb);
          return;
        case TlsCompletion::Reduce:
          break;
        case TlsCompletion::Virtual:
          add_virtual_points(e, sys, D, distinct);
          break;
        case TlsCompletion::Neighbour:
          borrow_points(e, sys, D, distinct);
          break;
        case TlsCompletion::MinimumNorm:  // refused by build_systems
        case TlsCompletion::Graded:
          break;
      }
    }
    // Reduce (also the fallback of the completions): drop terms until well posed, 1D 3 -> 2 -> 1,
    // 2D 6 -> 3 -> 1, 3D 10 -> 4 -> 1 (complete polynomial spaces). One term is always well posed
    // in an active element (D = number of data > 0). An element that was well posed from its own
    // points keeps D, so its pass-1 condition number stands (the same eigenvalues, not recomputed).
    int t = nb;
    double cond = o.condition;
    if (!o.ok) {
      // With no completion point added (`reduce`, or none found) D is pass 1's, which already
      // failed with n_b terms: the same test again would only repeat its eigenvalues.
      if (sys.end - sys.begin == info.points) t = fewer_terms(t, Dim);
      while (!well_posed(D, distinct, t, cond) && t > 1) t = fewer_terms(t, Dim);
    }
    sys.terms = t;
    // An element well posed from its own points has D = o.D and t = n_b: its inverse from the
    // condition bound serves.
    factorise(sys, D, o.ok && o.has_s_inv ? &o.s_inv : nullptr);
    info.terms = t;
    info.condition = cond;
  };
  if (local) {
    slots_.assign(bins_.start.begin(), bins_.start.end());
    data_.resize(static_cast<std::size_t>(slots_[ne_s]));
    from_.resize(static_cast<std::size_t>(slots_[ne_s]));
    parallel_for(ne, [&](Index e) {
      own_pass(e);
      system_pass(e);
    });
  } else {
    parallel_for(ne, own_pass);
    // The slots' offsets: a prefix sum over this compact array (a serial pass that read the
    // elements' systems instead, a cache line each, was 1 % of a step).
    slots_[0] = 0;
    for (std::size_t e = 0; e < ne_s; ++e) slots_[e + 1] += slots_[e];
    data_.resize(static_cast<std::size_t>(slots_[ne_s]));
    from_.resize(static_cast<std::size_t>(slots_[ne_s]));
    parallel_for(ne, system_pass);
  }

  // The report over the elements of set_focus: partial reports of fixed chunks of elements in
  // parallel, combined in chunk order by accumulate (counts, extremes and the first failed element,
  // the lowest index: the same for any thread count; a serial pass was 1 % of a step).
  const std::array<Index, 2> range = focus_ ? focus_->span() : std::array<Index, 2>{0, ne};
  const Index lo = range[0], span = range[1] - range[0];
  std::array<TlsReport, ParticleChunks::kMax> part;
  for_each_chunk(span, [&](int c, Index b, Index end) {
    TlsReport& r = part[static_cast<std::size_t>(c)];
    r = TlsReport{};
    for (Index e = lo + b; e < lo + end; ++e) {
      const TlsElementInfo& info = info_[static_cast<std::size_t>(e)];
      if (info.points == 0 || (focus_ && !focus_->holds(e))) continue;
      ++r.active;
      if (info.failed) {
        if (r.failed++ == 0) {
          r.failed_element = e;
          r.failed_points = info.points;
          r.failed_condition = info.condition;
        }
        continue;
      }
      const int t = info.terms;
      if (own_[static_cast<std::size_t>(e)].ok) ++r.full;
      if (t < nb) ++r.reduced;
      if (info.virtual_points > 0) ++r.with_virtual;
      if (info.borrowed > 0) ++r.with_neighbours;
      r.min_terms = r.min_terms > 0 ? std::min(r.min_terms, t) : t;
      r.max_condition = std::max(r.max_condition, info.condition);
    }
  });
  for (int c = 0; c < ParticleChunks::count(span); ++c)
    accumulate(report_, part[static_cast<std::size_t>(c)]);
}

// Elements with virtual points need their neighbours' coefficients, and their neighbours never
// have virtual points (they fit all terms from their own points), so two passes suffice.
template <int Dim>
void BasicTlsReconstruction<Dim>::fit(std::span<const double> f, std::span<const Field> fields,
                                      const ElementDone& done) const {
  const std::size_t nf = fields.size();
  if (nf == 0 || nf > static_cast<std::size_t>(kMaxFields))
    throw std::invalid_argument("TlsReconstruction: 1 to kMaxFields fields per fit");
  if (f.size() < x_.size() * nf)
    throw std::invalid_argument("TlsReconstruction: one value per point and field of set_points");
  const Index ne = grid_.num_cells();
  for (const Field& fd : fields) fd.a->resize(static_cast<std::size_t>(ne));
  const double volume = grid_.cell_volume();  // |Omega_e| (D eq. 6.7)
  // Elements are independent within a pass (pass 1 reads only pass-0 coefficients): parallel,
  // the same bits for any thread count.
  // Only the virtual completion adds virtual points: the other completions need no second pass
  // (a parallel loop over the elements, three per step, saved).
  const int passes = settings_.completion == TlsCompletion::Virtual ? 2 : 1;
  for (int pass = 0; pass < passes; ++pass) {
    auto element = [&](Index e) {
      const auto ei = static_cast<std::size_t>(e);
      const System& sys = systems_[ei];
      if (pass == 0) {
        if (info_[ei].points == 0) {
          for (const Field& fd : fields) (*fd.a)[ei].setZero();
          return;
        }
        if (info_[ei].failed) {
          for (const Field& fd : fields)
            (*fd.a)[ei].setConstant(std::numeric_limits<double>::quiet_NaN());
          return;
        }
      }
      if (sys.terms == 0 || sys.has_virtual != (pass == 1)) return;
      // Per field: D eq. 5.9 (conservative: a_1 fixed by the element integral, the rest fit
      // f - a_1 without psi_1, a_2..t = D_c^{-1} B_c^T (U - a_1)) or D eq. 5.1 (plain:
      // a = D^{-1} B U). The sums over the data for all fields in one pass; the entries beyond t
      // of the sums meet the zero rows and columns of the inverses.
      // Plain fields take a_1 = 0 here, so that one sum serves both: psi (f - a_1), of which a
      // conservative fit uses the entries 2..t.
      std::array<bool, kMaxFields> cons{};
      std::array<double, kMaxFields> a1{};
      for (std::size_t j = 0; j < nf; ++j) {
        const Field& fd = fields[j];
        cons[j] =
            fd.integrals != nullptr && (fd.conservative == nullptr || fd.conservative[ei] != 0);
        a1[j] = cons[j] ? fd.integrals[ei] / volume : 0.0;
      }
      std::array<Taylor, kMaxFields> rhs;
      // The number of fields at compile time, so that the sums stay in registers.
      auto accumulate = [&]<int NF>(std::integral_constant<int, NF>) {
        std::array<Taylor, NF> b;
        for (auto& v : b) v.setZero();
        for (Index k = sys.begin; k < sys.end; ++k) {
          const Datum& d = data_[static_cast<std::size_t>(k)];
          if (d.point >= 0) {
            const double* v = f.data() + static_cast<std::size_t>(d.point) * NF;
            for (int j = 0; j < NF; ++j) b[j] += d.psi * (v[j] - a1[j]);
          } else {
            const DatumSource& src = from_[static_cast<std::size_t>(k)];
            const Taylor psi_source = taylor_basis_at<Dim>(src.s_source);
            for (int j = 0; j < NF; ++j)
              b[j] +=
                  d.psi *
                  ((*fields[j].a)[static_cast<std::size_t>(src.source)].dot(psi_source) - a1[j]);
          }
        }
        for (int j = 0; j < NF; ++j) rhs[j] = b[j];
      };
      with_size<kMaxFields>(static_cast<int>(nf), accumulate);
      for (std::size_t j = 0; j < nf; ++j) {
        Taylor coef;
        if (cons[j]) {
          coef[0] = a1[j];
          coef.template tail<K - 1>().noalias() = sys.inv_c * rhs[j].template tail<K - 1>();
        } else {
          coef.noalias() = sys.inv * rhs[j];
        }
        (*fields[j].a)[ei] = coef;
      }
    };
    if (done && passes == 1) {
      parallel_for(ne, [&](Index e) {
        element(e);
        done(e);
      });
    } else {
      parallel_for(ne, element);
    }
  }
  if (done && passes > 1) parallel_for(ne, done);
}

template <int Dim>
void BasicTlsReconstruction<Dim>::fit_fields(std::span<const double> f,
                                             std::span<const Field> fields,
                                             const ElementDone& done) const {
  for (const Field& fd : fields) {
    if (fd.a == nullptr) throw std::invalid_argument("TlsReconstruction::fit_fields: no output");
    if (fd.integrals == nullptr && settings_.conservative_only)
      throw std::logic_error("TlsReconstruction::fit_fields: a plain field with conservative_only");
  }
  fit(f, fields, done);
}

template <int Dim>
void BasicTlsReconstruction<Dim>::fit_conservative(std::span<const double> f,
                                                   std::span<const double> integrals,
                                                   Coefficients& a, const ElementDone& done) const {
  if (integrals.size() < static_cast<std::size_t>(grid_.num_cells()))
    throw std::invalid_argument("TlsReconstruction::fit_conservative: one integral per element");
  const Field fd{integrals.data(), nullptr, &a};
  fit(f, std::span<const Field>(&fd, 1), done);
}

template <int Dim>
void BasicTlsReconstruction<Dim>::fit_plain(std::span<const double> f, Coefficients& a) const {
  if (settings_.conservative_only)
    throw std::logic_error("TlsReconstruction::fit_plain: the settings are conservative_only");
  const Field fd{nullptr, nullptr, &a};
  fit(f, std::span<const Field>(&fd, 1));
}

template <int Dim>
void BasicTlsReconstruction<Dim>::fit_mixed(std::span<const double> f,
                                            std::span<const double> integrals,
                                            std::span<const unsigned char> conservative,
                                            Coefficients& a) const {
  const auto ne = static_cast<std::size_t>(grid_.num_cells());
  if (integrals.size() < ne || conservative.size() < ne)
    throw std::invalid_argument("TlsReconstruction::fit_mixed: one integral and flag per element");
  if (settings_.conservative_only)
    throw std::logic_error("TlsReconstruction::fit_mixed: the settings are conservative_only");
  const Field fd{integrals.data(), conservative.data(), &a};
  fit(f, std::span<const Field>(&fd, 1));
}

// fit() in reverse: the elements with virtual points first (they push their part to the
// elements that value those points, which have none), then the others. Per element and field,
// plain: a = D^{-1} sum_k psi_k u_k, so u_k gets psi_k . D^{-1} abar; conservative: a_1 = c_e /
// |Omega_e| and a_2..t = D_c^{-1} sum_k psi_k' (u_k - a_1), so u_k gets psi_k' . D_c^{-1}
// abar', and c_e gets (abar_1 - sum_k of those) / |Omega_e|. A point can be a datum of several
// elements (borrowed, or on a shared face), so only the parts of own points are written in
// parallel.
template <int Dim>
void BasicTlsReconstruction<Dim>::fit_transpose(std::span<Coefficients> abar,
                                                const unsigned char* conservative,
                                                std::span<double> z, std::span<double> ibar) const {
  const std::size_t nf = abar.size();
  constexpr std::size_t kMaxNf = 16;  // a stack array per element (before the parallel loop)
  if (nf > kMaxNf) throw std::invalid_argument("TlsReconstruction::fit_transpose: too many fields");
  const Index ne = grid_.num_cells();
  const auto E = static_cast<std::size_t>(ne);
  if (z.size() < x_.size() * nf || ibar.size() < E * nf)
    throw std::invalid_argument("TlsReconstruction::fit_transpose: output too small");
  for (const Coefficients& a : abar)
    if (a.size() < E)
      throw std::invalid_argument("TlsReconstruction::fit_transpose: one vector per element");
  std::fill(z.begin(), z.end(), 0.0);
  std::fill(ibar.begin(), ibar.end(), 0.0);
  const double volume = grid_.cell_volume();
  // Element e: c_j = D^{-1} abar_j (conservative: of terms 2..t) into c[0..nf), the parts of its
  // own points (the first info.points data) if `own`, of its borrowed points if `borrowed`, of
  // its virtual points (to their sources' abar), and ibar from all of them.
  auto element = [&](Index e, bool own, bool borrowed, Taylor* c) {
    const auto ei = static_cast<std::size_t>(e);
    const System& sys = systems_[ei];
    const bool cons = conservative != nullptr && conservative[ei] != 0;
    for (std::size_t j = 0; j < nf; ++j) {
      const Taylor& ab = abar[j][ei];
      if (cons) {
        c[j].setZero();
        c[j].template tail<K - 1>().noalias() = sys.inv_c * ab.template tail<K - 1>();
      } else {
        c[j].noalias() = sys.inv * ab;
      }
    }
    std::array<double, kMaxNf> sum{};  // sum_k of u_k's parts (conservative a_1)
    const Index own_end = sys.begin + info_[ei].points;
    for (Index k = sys.begin; k < sys.end; ++k) {
      const Datum& d = data_[static_cast<std::size_t>(k)];
      const bool write = d.point < 0 || (k < own_end ? own : borrowed);
      for (std::size_t j = 0; j < nf; ++j) {
        const double u = d.psi.dot(c[j]);
        sum[j] += u;
        if (!write) continue;
        if (d.point >= 0) {
          z[static_cast<std::size_t>(d.point) * nf + j] += u;
        } else {
          const DatumSource& src = from_[static_cast<std::size_t>(k)];
          abar[j][static_cast<std::size_t>(src.source)] += taylor_basis_at<Dim>(src.s_source) * u;
        }
      }
    }
    if (cons)
      for (std::size_t j = 0; j < nf; ++j) ibar[j * E + ei] = (abar[j][ei][0] - sum[j]) / volume;
  };
  auto fitted = [&](Index e, bool with_virtual) {
    const auto ei = static_cast<std::size_t>(e);
    return info_[ei].points > 0 && !info_[ei].failed && systems_[ei].terms > 0 &&
           systems_[ei].has_virtual == with_virtual;
  };
  // The elements with virtual points first, serially: they push parts to their sources.
  std::vector<Taylor> c(E * nf);
  for (Index e = 0; e < ne; ++e)
    if (fitted(e, true)) element(e, true, true, c.data() + static_cast<std::size_t>(e) * nf);
  // Then the others. Each point is the own datum of one element unless face points were shared
  // (standalone set_points): then they write their own points' parts in parallel, and the parts
  // of the points borrowed from other elements follow in element order (the same bits for any
  // thread count).
  const bool exclusive =
      bins_.order.size() + static_cast<std::size_t>(report_.outside) == x_.size();
  if (!exclusive) {
    for (Index e = 0; e < ne; ++e)
      if (fitted(e, false)) element(e, true, true, c.data() + static_cast<std::size_t>(e) * nf);
    return;
  }
  parallel_for(ne, [&](Index e) {
    if (fitted(e, false)) element(e, true, false, c.data() + static_cast<std::size_t>(e) * nf);
  });
  for (Index e = 0; e < ne; ++e) {
    const auto ei = static_cast<std::size_t>(e);
    if (!fitted(e, false)) continue;
    const System& sys = systems_[ei];
    for (Index k = sys.begin + info_[ei].points; k < sys.end; ++k) {
      const Datum& d = data_[static_cast<std::size_t>(k)];
      for (std::size_t j = 0; j < nf; ++j)
        z[static_cast<std::size_t>(d.point) * nf + j] += d.psi.dot(c[ei * nf + j]);
    }
  }
}

template <int Dim>
double BasicTlsReconstruction<Dim>::evaluate(const Coefficients& a, const Point& x) const {
  const Vec<Dim> v = as_vec(x);
  if (!grid_.inside(v)) return 0.0;
  return evaluate(a, grid_.cell_index(v), x);
}

template class BasicTlsReconstruction<1>;
template class BasicTlsReconstruction<2>;
template class BasicTlsReconstruction<3>;

}  // namespace mpm
