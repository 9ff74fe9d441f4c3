// Taylor least-squares reconstruction in 1D (D 5.2-5.3, 000 sec. 2, 004 4.4.1): element systems,
// completion of deficient elements (D 5.2.3) and the per-field fits.
#include "mapping/tls.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "io/config.hpp"

namespace mpm {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Two positions closer than this (in units of the element half-width) are one point: they add
// no new direction to D.
constexpr double kCoincident = 1e-10;

// cond_2(D_t) = lambda_max / lambda_min of the leading t x t block of the symmetric positive
// semi-definite normal matrix D (D 5.2.3); infinite when singular.
double condition_number(const Eigen::Matrix3d& D, int t) {
  double lo = 0.0, hi = 0.0;
  if (t == 1) {
    lo = hi = D(0, 0);
  } else if (t == 2) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(D.topLeftCorner<2, 2>(),
                                                            Eigen::EigenvaluesOnly);
    lo = es.eigenvalues()[0];
    hi = es.eigenvalues()[1];
  } else {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(D, Eigen::EigenvaluesOnly);
    lo = es.eigenvalues()[0];
    hi = es.eigenvalues()[2];
  }
  if (!(lo > 0.0) || !std::isfinite(hi)) return kInf;
  return hi / lo;
}

void add_outer(Eigen::Matrix3d& D, const Eigen::Vector3d& psi) {
  D.noalias() += psi * psi.transpose();
}

}  // namespace

TlsCompletion parse_tls_completion(std::string_view name) {
  if (name == "none") return TlsCompletion::None;
  if (name == "reduce") return TlsCompletion::Reduce;
  if (name == "virtual") return TlsCompletion::Virtual;
  if (name == "neighbour") return TlsCompletion::Neighbour;
  throw InputError(fmt::format(
      "TLS completion \"{}\" is not available; choose one of: none, reduce, virtual, neighbour",
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
  }
  return "none";
}

void validate(const TlsSettings& s) {
  if (s.terms < 1 || s.terms > 3)
    throw InputError(fmt::format("method.tls_terms = {} must be 1, 2 or 3", s.terms));
  if (!(s.max_condition > 1.0))
    throw InputError(
        fmt::format("method.tls_max_condition = {} must be greater than 1", s.max_condition));
  if (s.gauss_points < 0 || s.gauss_points > 10)
    throw InputError(fmt::format("method.gauss_points = {} must lie in [0, 10]", s.gauss_points));
  if (s.max_borrowed < 1)
    throw InputError(fmt::format("TLS max_borrowed = {} must be at least 1", s.max_borrowed));
  // n Gauss points integrate degree 2n - 1 exactly; psi_3 is quadratic (D 5.3.2).
  if (2 * s.gauss_points_used() < s.terms)
    throw InputError(fmt::format(
        "method.gauss_points = {} does not integrate the Taylor basis of method.tls_terms = {} "
        "exactly, so mass and momentum would not be conserved (D 5.3.2 needs tls_terms <= 2 x "
        "gauss_points); use 2 or more Gauss points, or 0 for the default",
        s.gauss_points, s.terms));
}

TlsSettings tls_settings_from_config(const Config& cfg) {
  TlsSettings s;
  s.terms = static_cast<int>(cfg.get_int("method.tls_terms"));
  s.completion = parse_tls_completion(cfg.get_string("method.tls_completion"));
  s.max_condition = cfg.get_real("method.tls_max_condition");
  s.gauss_points = static_cast<int>(cfg.get_int("method.gauss_points"));
  validate(s);
  return s;
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
}

TlsReconstruction::TlsReconstruction(const TlsSettings& s) : settings_(s) {
  validate(s);
}

const TlsReport& TlsReconstruction::set_points(const Grid<1>& g, std::span<const double> x,
                                               bool share_face_points) {
  grid_ = g;
  x_.assign(x.begin(), x.end());
  const Index ne = g.num_cells();
  const auto ne_s = static_cast<std::size_t>(ne);
  report_ = TlsReport{};
  // Counting sort into the cells, as ElementBins, with the optional second owner of a point on
  // an interior face (its lower neighbour).
  auto lower_owner = [&](double xp, Index c) -> Index {
    if (!share_face_points || c <= 0) return -1;
    const double s = (xp - g.origin[0]) / g.h[0];
    return s == static_cast<double>(c) ? c - 1 : -1;
  };
  bins_.start.assign(ne_s + 1, 0);
  for (double xp : x_) {
    const Index c = g.cell_of(xp, 0);
    if (c < 0 || c >= ne) {
      ++report_.outside;
      continue;
    }
    ++bins_.start[static_cast<std::size_t>(c + 1)];
    const Index l = lower_owner(xp, c);
    if (l >= 0) ++bins_.start[static_cast<std::size_t>(l + 1)];
  }
  for (std::size_t e = 0; e < ne_s; ++e) bins_.start[e + 1] += bins_.start[e];
  bins_.order.resize(static_cast<std::size_t>(bins_.start[ne_s]));
  std::vector<Index> fill(bins_.start.begin(), bins_.start.end() - 1);
  for (std::size_t p = 0; p < x_.size(); ++p) {
    const Index c = g.cell_of(x_[p], 0);
    if (c < 0 || c >= ne) continue;
    bins_.order[static_cast<std::size_t>(fill[static_cast<std::size_t>(c)]++)] =
        static_cast<Index>(p);
    const Index l = lower_owner(x_[p], c);
    if (l >= 0)
      bins_.order[static_cast<std::size_t>(fill[static_cast<std::size_t>(l)]++)] =
          static_cast<Index>(p);
  }
  build_systems();
  return report_;
}

const TlsReport& TlsReconstruction::set_points(const Grid<1>& g, const Particles<1>& P) {
  grid_ = g;
  x_.resize(P.x.size());
  for (std::size_t i = 0; i < x_.size(); ++i) x_[i] = P.x[i][0];
  report_ = TlsReport{};
  bins_.build(g, P);
  build_systems();
  return report_;
}

bool TlsReconstruction::coincides(const System& sys, double s) const {
  for (Index k = sys.begin; k < sys.end; ++k)
    if (std::abs(data_[static_cast<std::size_t>(k)].psi[1] - s) <= kCoincident) return true;
  return false;
}

void TlsReconstruction::add_datum(System& sys, Eigen::Matrix3d& D, const Datum& d) {
  data_.push_back(d);
  sys.end = static_cast<Index>(data_.size());
  add_outer(D, d.psi);
}

// D 5.2.3: a virtual point on each face whose neighbour fits all n_b terms from its own points,
// valued by that neighbour's reconstruction at the face (at fit time). A face already holding a
// point of the element adds nothing and is skipped.
void TlsReconstruction::add_virtual_points(Index e, System& sys, Eigen::Matrix3d& D,
                                           int& distinct) {
  const Index ne = grid_.num_cells();
  for (int side : {-1, +1}) {
    const Index n = e + side;
    if (n < 0 || n >= ne || !own_[static_cast<std::size_t>(n)].ok) continue;
    const double s = static_cast<double>(side);
    if (coincides(sys, s)) continue;
    add_datum(sys, D, Datum::virtual_point(s, n, -s));
    sys.has_virtual = true;
    ++distinct;
    ++info_[static_cast<std::size_t>(e)].virtual_points;
  }
}

// D 5.2.3: the nearest points of the two adjacent elements (distance to this element, ties by
// index), one at a time until n_b terms are well posed or max_borrowed points were taken.
// Points coinciding with the element's data are passed over. No allocation: each search scans
// the neighbours for the next candidate after the last one taken in (distance, index) order.
void TlsReconstruction::borrow_points(Index e, System& sys, Eigen::Matrix3d& D, int& distinct) {
  const Index ne = grid_.num_cells();
  const int nb = settings_.terms;
  const double xc = centre(e), dx = half_width();
  const double lo = xc - dx, hi = xc + dx;
  double last_d = -1.0;
  Index last_p = -1;
  int taken = 0;
  while (taken < settings_.max_borrowed &&
         !(distinct >= nb && condition_number(D, nb) <= settings_.max_condition)) {
    double best_d = kInf;
    Index best_p = -1;
    for (int side : {-1, +1}) {
      const Index n = e + side;
      if (n < 0 || n >= ne) continue;
      for (const Index* it = bins_.begin(n); it != bins_.end(n); ++it) {
        const double xp = x_[static_cast<std::size_t>(*it)];
        const double d = std::max(0.0, side < 0 ? lo - xp : xp - hi);
        const bool after = d > last_d || (d == last_d && *it > last_p);
        const bool better = d < best_d || (d == best_d && *it < best_p);
        if (after && better) {
          best_d = d;
          best_p = *it;
        }
      }
    }
    if (best_p < 0) break;  // the neighbours have nothing left
    last_d = best_d;
    last_p = best_p;
    const double s = (x_[static_cast<std::size_t>(best_p)] - xc) / dx;
    if (coincides(sys, s)) continue;
    add_datum(sys, D, Datum::real(s, best_p));
    ++distinct;
    ++taken;
    ++info_[static_cast<std::size_t>(e)].borrowed;
  }
}

// Thin QR of the element's data matrix by modified Gram-Schmidt applied twice ("twice is
// enough": orthogonal to working precision for cond(B) well below 1/eps, which max_condition
// guarantees), once for terms 1..t (plain) and once for terms 2..t (conservative, psi_1 left
// out as in D 5.3.1). Q is stored in the data, so no allocation.
void TlsReconstruction::factorise(System& sys) {
  const int t = sys.terms;
  auto orthonormalise = [&](auto column, auto& R, int first, int n) {
    R.setZero();
    for (int j = 0; j < n; ++j) {
      for (Index k = sys.begin; k < sys.end; ++k) {
        Datum& d = data_[static_cast<std::size_t>(k)];
        column(d)[j] = d.psi[first + j];
      }
      for (int pass = 0; pass < 2; ++pass) {
        for (int i = 0; i < j; ++i) {
          double r = 0.0;
          for (Index k = sys.begin; k < sys.end; ++k) {
            Datum& d = data_[static_cast<std::size_t>(k)];
            r += column(d)[i] * column(d)[j];
          }
          for (Index k = sys.begin; k < sys.end; ++k) {
            Datum& d = data_[static_cast<std::size_t>(k)];
            column(d)[j] -= r * column(d)[i];
          }
          R(i, j) += r;
        }
      }
      double norm2 = 0.0;
      for (Index k = sys.begin; k < sys.end; ++k) {
        const double v = column(data_[static_cast<std::size_t>(k)])[j];
        norm2 += v * v;
      }
      R(j, j) = std::sqrt(norm2);
      const double inv = R(j, j) > 0.0 ? 1.0 / R(j, j) : 0.0;
      for (Index k = sys.begin; k < sys.end; ++k)
        column(data_[static_cast<std::size_t>(k)])[j] *= inv;
    }
  };
  orthonormalise([](Datum& d) -> Eigen::Vector3d& { return d.q; }, sys.R, 0, t);
  orthonormalise([](Datum& d) -> Eigen::Vector2d& { return d.qc; }, sys.Rc, 1, t - 1);
}

void TlsReconstruction::build_systems() {
  const Index ne = grid_.num_cells();
  const auto ne_s = static_cast<std::size_t>(ne);
  const int nb = settings_.terms;
  const double dx = half_width(), max_cond = settings_.max_condition;
  report_.elements = ne;
  own_.resize(ne_s);
  systems_.resize(ne_s);
  info_.assign(ne_s, TlsElementInfo{});
  data_.clear();
  data_.reserve(bins_.order.size() +
                ne_s * static_cast<std::size_t>(2 + std::max(0, settings_.max_borrowed)));

  // Pass 1: each element from its own points (also decides which neighbours can lend virtual
  // points).
  for (Index e = 0; e < ne; ++e) {
    Own& o = own_[static_cast<std::size_t>(e)];
    o.D.setZero();
    o.distinct = 0;
    std::array<double, 3> seen{};
    const double xc = centre(e);
    for (const Index* it = bins_.begin(e); it != bins_.end(e); ++it) {
      const double s = (x_[static_cast<std::size_t>(*it)] - xc) / dx;
      add_outer(o.D, taylor_basis(s));
      if (o.distinct < nb) {
        bool fresh = true;
        for (int k = 0; k < o.distinct; ++k)
          fresh = fresh && std::abs(seen[static_cast<std::size_t>(k)] - s) > kCoincident;
        if (fresh) seen[static_cast<std::size_t>(o.distinct++)] = s;
      }
    }
    const Index count = bins_.count(e);
    info_[static_cast<std::size_t>(e)].points = count;
    o.condition = count > 0 ? condition_number(o.D, nb) : 0.0;
    o.ok = count > 0 && o.distinct >= nb && o.condition <= max_cond;
  }

  // Pass 2: data, completion, number of terms and factorisations.
  for (Index e = 0; e < ne; ++e) {
    const Own& o = own_[static_cast<std::size_t>(e)];
    System& sys = systems_[static_cast<std::size_t>(e)];
    TlsElementInfo& info = info_[static_cast<std::size_t>(e)];
    sys.begin = sys.end = static_cast<Index>(data_.size());
    sys.terms = 0;
    sys.has_virtual = false;
    if (info.points == 0) continue;  // inactive: no reconstruction
    ++report_.active;
    const double xc = centre(e);
    for (const Index* it = bins_.begin(e); it != bins_.end(e); ++it) {
      data_.push_back(Datum::real((x_[static_cast<std::size_t>(*it)] - xc) / dx, *it));
    }
    sys.end = static_cast<Index>(data_.size());
    Eigen::Matrix3d D = o.D;
    int distinct = o.distinct;
    if (!o.ok) {
      switch (settings_.completion) {
        case TlsCompletion::None:
          info.failed = true;
          info.condition = o.condition;
          if (report_.failed++ == 0) {
            report_.failed_element = e;
            report_.failed_points = info.points;
            report_.failed_condition = o.condition;
          }
          continue;
        case TlsCompletion::Reduce:
          break;
        case TlsCompletion::Virtual:
          add_virtual_points(e, sys, D, distinct);
          break;
        case TlsCompletion::Neighbour:
          borrow_points(e, sys, D, distinct);
          break;
      }
    }
    // Reduce (also the fallback of the completions): drop terms until well posed. One term is
    // always well posed in an active element (D = number of data > 0).
    int t = nb;
    double cond = condition_number(D, t);
    while (t > 1 && (distinct < t || cond > max_cond)) cond = condition_number(D, --t);
    sys.terms = t;
    factorise(sys);
    info.terms = t;
    info.condition = cond;
    if (o.ok) ++report_.full;
    if (t < nb) ++report_.reduced;
    if (info.virtual_points > 0) ++report_.with_virtual;
    if (info.borrowed > 0) ++report_.with_neighbours;
    report_.min_terms = report_.min_terms > 0 ? std::min(report_.min_terms, t) : t;
    report_.max_condition = std::max(report_.max_condition, cond);
  }
}

// Elements with virtual points need their neighbours' coefficients, and their neighbours never
// have virtual points (they fit all terms from their own points), so two passes suffice.
void TlsReconstruction::fit(std::span<const double> f, const double* integrals,
                            TlsCoefficients& a) const {
  if (f.size() < x_.size())
    throw std::invalid_argument("TlsReconstruction: one value per point of set_points");
  const Index ne = grid_.num_cells();
  a.resize(static_cast<std::size_t>(ne));
  const double h = grid_.h[0];
  for (int pass = 0; pass < 2; ++pass) {
    for (Index e = 0; e < ne; ++e) {
      const auto ei = static_cast<std::size_t>(e);
      const System& sys = systems_[ei];
      if (pass == 0) {
        if (info_[ei].points == 0) {
          a[ei].setZero();
          continue;
        }
        if (info_[ei].failed) {
          a[ei].setConstant(std::numeric_limits<double>::quiet_NaN());
          continue;
        }
      }
      if (sys.terms == 0 || sys.has_virtual != (pass == 1)) continue;
      const int t = sys.terms;
      auto value = [&](const Datum& d) {
        if (d.point >= 0) return f[static_cast<std::size_t>(d.point)];
        return a[static_cast<std::size_t>(d.source)].dot(taylor_basis(d.s_source));
      };
      Eigen::Vector3d coef = Eigen::Vector3d::Zero();
      if (integrals != nullptr) {
        // D eq. 5.9: a_1 fixed by the element integral; the rest fit f - a_1 without psi_1:
        // a_2..t = R_c^{-1} Q_c^T (U - a_1).
        const double a1 = integrals[ei] / h;
        coef[0] = a1;
        if (t > 1) {
          Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
          for (Index k = sys.begin; k < sys.end; ++k) {
            const Datum& d = data_[static_cast<std::size_t>(k)];
            rhs += d.qc * (value(d) - a1);  // q_c is zero beyond t - 1 columns
          }
          for (int i = t - 2; i >= 0; --i) {  // back substitution
            double v = rhs[i];
            for (int j = i + 1; j < t - 1; ++j) v -= sys.Rc(i, j) * coef[1 + j];
            coef[1 + i] = v / sys.Rc(i, i);
          }
        }
      } else {
        // D eq. 5.1: a = D^{-1} B U = R^{-1} Q^T U.
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        for (Index k = sys.begin; k < sys.end; ++k) {
          const Datum& d = data_[static_cast<std::size_t>(k)];
          rhs += d.q * value(d);  // q is zero beyond t columns
        }
        for (int i = t - 1; i >= 0; --i) {
          double v = rhs[i];
          for (int j = i + 1; j < t; ++j) v -= sys.R(i, j) * coef[j];
          coef[i] = v / sys.R(i, i);
        }
      }
      a[ei] = coef;
    }
  }
}

void TlsReconstruction::fit_conservative(std::span<const double> f,
                                         std::span<const double> integrals,
                                         TlsCoefficients& a) const {
  if (integrals.size() < static_cast<std::size_t>(grid_.num_cells()))
    throw std::invalid_argument("TlsReconstruction::fit_conservative: one integral per element");
  fit(f, integrals.data(), a);
}

void TlsReconstruction::fit_plain(std::span<const double> f, TlsCoefficients& a) const {
  fit(f, nullptr, a);
}

double TlsReconstruction::evaluate(const TlsCoefficients& a, double x) const {
  const Index e = grid_.cell_of(x, 0);
  if (e < 0 || e >= grid_.num_cells()) return 0.0;
  return evaluate(a, e, x);
}

}  // namespace mpm
