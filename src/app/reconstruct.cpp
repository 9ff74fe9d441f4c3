#include "app/reconstruct.hpp"

#include <fmt/format.h>
#include <array>
#include <cmath>
#include <functional>
#include <random>

#include "mapping/cubic_spline.hpp"
#include "mapping/mls.hpp"
#include "mapping/quadrature.hpp"
#include "mapping/tls.hpp"
#include "mapping/tls_triangle.hpp"
#include "setup/expression.hpp"
#include "setup/gmsh_mesh.hpp"

namespace mpm {
namespace {

double constant_expression(const std::string& text, const char* what) {
  const Expression e(text, {});
  if (!e.is_constant())
    throw InputError(
        fmt::format("{} = \"{}\" must be a number or a constant expression", what, text));
  return e(0.0);
}

// N of "kind:N" (leading digits); 0 when not a number.
int parse_count(const std::string& text) {
  try {
    return std::stoi(text);
  } catch (...) {
    return 0;
  }
}

std::vector<double> make_points(const ReconstructOptions& opt, const Grid<1>& g) {
  const auto colon = opt.points.find(':');
  const std::string kind = opt.points.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : opt.points.substr(colon + 1);
  std::vector<double> x;
  if (kind == "uniform" || kind == "random") {
    const int n = parse_count(arg);
    if (n < 1)
      throw InputError(fmt::format("--points {}: expected {}:N with N >= 1 points per element",
                                   opt.points, kind));
    std::mt19937 rng(opt.seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (Index e = 0; e < g.cells[0]; ++e)
      for (int k = 0; k < n; ++k) {
        const double s = kind == "uniform" ? (k + 0.5) / n : u(rng);
        x.push_back(g.origin[0] + (static_cast<double>(e) + s) * g.h[0]);
      }
    return x;
  }
  if (kind == "list") {
    std::size_t pos = 0;
    while (pos < arg.size()) {
      const auto comma = arg.find(',', pos);
      const std::string item =
          arg.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
      x.push_back(constant_expression(item, "--points list item"));
      if (comma == std::string::npos) break;
      pos = comma + 1;
    }
    if (x.empty()) throw InputError("--points list: give at least one point");
    return x;
  }
  throw InputError(fmt::format(
      "--points {}: choose uniform:N, random:N or list:X1,X2,... (N points per element)",
      opt.points));
}

// "N" or "NXxNY": points per element in x and y.
std::array<int, 2> parse_counts_2d(const std::string& text) {
  const auto x = text.find('x');
  if (x == std::string::npos) {
    const int n = parse_count(text);
    return {n, n};
  }
  return {parse_count(text.substr(0, x)), parse_count(text.substr(x + 1))};
}

// The data points of the 2D playground, element by element (x fastest, as Grid::cell_index).
std::vector<Vec<2>> make_points_2d(const ReconstructOptions& opt, const Grid<2>& g) {
  const auto colon = opt.points.find(':');
  const std::string kind = opt.points.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : opt.points.substr(colon + 1);
  std::vector<Vec<2>> x;
  if (kind == "uniform" || kind == "inner" || kind == "random") {
    const auto n =
        kind == "random" ? std::array<int, 2>{parse_count(arg), 1} : parse_counts_2d(arg);
    if (n[0] < 1 || n[1] < 1)
      throw InputError(fmt::format("--points {}: expected {}:N{} with N >= 1 points per element",
                                   opt.points, kind,
                                   kind == "random" ? "" : " or NXxNY (N x N or NX x NY)"));
    // Position k of n in [0, 1]: uniform (k + 1/2) / n; inner k / (n + 1), k = 1..n, which gives
    // D 6.2.1's x_min + 1/3, x_max - 1/3 (n = 2) and y_min + 1/4, mid, y_max - 1/4 (n = 3) in
    // unit elements.
    auto at = [&](int k, int m) {
      return kind == "uniform" ? (k + 0.5) / m : (k + 1.0) / (m + 1.0);
    };
    std::mt19937 rng(opt.seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (Index j = 0; j < g.cells[1]; ++j)
      for (Index i = 0; i < g.cells[0]; ++i) {
        const Vec<2> corner(g.origin[0] + static_cast<double>(i) * g.h[0],
                            g.origin[1] + static_cast<double>(j) * g.h[1]);
        if (kind == "random") {
          for (int k = 0; k < n[0]; ++k) {
            const double sx = u(rng), sy = u(rng);
            x.emplace_back(corner[0] + sx * g.h[0], corner[1] + sy * g.h[1]);
          }
          continue;
        }
        for (int ky = 0; ky < n[1]; ++ky)
          for (int kx = 0; kx < n[0]; ++kx)
            x.emplace_back(corner[0] + at(kx, n[0]) * g.h[0], corner[1] + at(ky, n[1]) * g.h[1]);
      }
    return x;
  }
  if (kind == "list") {
    std::size_t pos = 0;
    while (pos < arg.size()) {
      const auto comma = arg.find(',', pos);
      const std::string item =
          arg.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
      const auto semi = item.find(';');
      if (semi == std::string::npos)
        throw InputError(fmt::format("--points list: \"{}\" is not X;Y", item));
      x.emplace_back(constant_expression(item.substr(0, semi), "--points list item"),
                     constant_expression(item.substr(semi + 1), "--points list item"));
      if (comma == std::string::npos) break;
      pos = comma + 1;
    }
    if (x.empty()) throw InputError("--points list: give at least one point");
    return x;
  }
  throw InputError(fmt::format(
      "--points {}: choose uniform:N, uniform:NXxNY, inner:NXxNY, random:N or list:X1;Y1,... "
      "(points per element)",
      opt.points));
}

// f at the data points; InputError naming the function and the point where it is not finite.
std::vector<double> sample_2d(const Expression& f, const std::string& text,
                              const std::vector<Vec<2>>& points) {
  std::vector<double> fx;
  for (const Vec<2>& p : points) {
    fx.push_back(f(p[0], p[1]));
    if (!std::isfinite(fx.back()))
      throw InputError(fmt::format("--function \"{}\" is not finite at the point ({}, {}): {}",
                                   text, p[0], p[1], fx.back()));
  }
  return fx;
}

// Calls fn(x, w) at the n x n Gauss points of element e (weights include the Jacobian).
template <class Fn>
void for_each_gauss_point(const Grid<2>& g, Index e, const GaussRule& rule, Fn&& fn) {
  const auto [i, j] = g.cell_coords(e);
  const Vec<2> hw = 0.5 * g.h;
  const Vec<2> c(g.origin[0] + (static_cast<double>(i) + 0.5) * g.h[0],
                 g.origin[1] + (static_cast<double>(j) + 0.5) * g.h[1]);
  for (std::size_t ky = 0; ky < rule.xi.size(); ++ky)
    for (std::size_t kx = 0; kx < rule.xi.size(); ++kx)
      fn(Vec<2>(c[0] + hw[0] * rule.xi[kx], c[1] + hw[1] * rule.xi[ky]),
         hw[0] * rule.w[kx] * hw[1] * rule.w[ky]);
}

}  // namespace

Reconstruction2D::Reconstruction2D(const ReconstructOptions& opt, const Grid<2>& g,
                                   const std::vector<Vec<2>>& x, const std::vector<double>& f,
                                   const std::vector<double>& element_integrals) {
  if (opt.mapping != "tls")
    throw InputError(fmt::format(
        "--mapping {} is one-dimensional; --dim 2 reconstructs with tls (D 6.2)", opt.mapping));
  if (x.size() != f.size())
    throw InputError(fmt::format("{} points and {} values", x.size(), f.size()));
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (!g.inside(x[k]))
      throw InputError(fmt::format("point {} ({}, {}) lies outside [{}, {}] x [{}, {}]", k, x[k][0],
                                   x[k][1], g.origin[0], g.upper()[0], g.origin[1], g.upper()[1]));
    if (!std::isfinite(f[k]))
      throw InputError(fmt::format("the value at point {} ({}, {}) is not finite: {}", k, x[k][0],
                                   x[k][1], f[k]));
  }
  if (!element_integrals.empty() && static_cast<Index>(element_integrals.size()) != g.num_cells())
    throw InputError(fmt::format("{} element integrals for {} elements", element_integrals.size(),
                                 g.num_cells()));
  TlsSettings s;
  s.terms = opt.terms;
  s.completion = parse_tls_completion(opt.completion);
  s.max_condition = opt.max_condition;
  // Conservative fits only fit psi_2..psi_nb: judge the data on those (D 6.2.1's points make
  // the full normal matrix singular, see TlsSettings::conservative_only).
  s.conservative_only = !element_integrals.empty();
  validate(s, 2);
  tls_ = TlsReconstruction2D(s);
  tls_.set_points(g, x, opt.share_faces);
  if (tls_.report().failed > 0)
    throw InputError(fmt::format(
        "TLS cannot fit element {} ({} points, condition number {:.3g}) without completion; "
        "use --completion reduce, virtual or neighbour",
        tls_.describe(tls_.report().failed_element), tls_.report().failed_points,
        tls_.report().failed_condition));
  if (!element_integrals.empty())
    tls_.fit_conservative(f, element_integrals, coeffs_);
  else
    tls_.fit_plain(f, coeffs_);
  details_ += fmt::format("{:>8} {:>5} {:>5} {:>7} {:>8} {:>8} {:>6} {:>12}\n", "element", "i", "j",
                          "points", "virtual", "borrowed", "terms", "cond(D)");
  for (Index e = 0; e < g.num_cells(); ++e) {
    const auto& info = tls_.element(e);
    const IVec<2> c = tls_.cell(e);
    details_ +=
        fmt::format("{:>8} {:>5} {:>5} {:>7} {:>8} {:>8} {:>6} {:>12.4g}\n", e, c[0], c[1],
                    info.points, info.virtual_points, info.borrowed, info.terms, info.condition);
  }
}

double Reconstruction2D::value(Index e, const Vec<2>& x) const {
  return tls_.evaluate(coeffs_, e, x);
}

namespace {

// D 6.2.1: f(x, y) on the square [a, b]^2 with cells x cells rectangular elements, TLS only.
// The RMS error is taken over error_points x error_points Gauss points per element (D 6.2.1: 2 x
// 2, "four Gauss points per element"), the integral with integration_points x integration_points.
ReconstructResult reconstruct_2d(const ReconstructOptions& opt, double a, double b) {
  if (opt.mapping != "tls")
    throw InputError(fmt::format(
        "--mapping {} is one-dimensional; --dim 2 reconstructs with tls (D 6.2)", opt.mapping));
  const Expression f(opt.function, {});
  const Grid<2> g(Vec<2>(a, a), Vec<2>(b, b), IVec<2>{opt.cells, opt.cells});
  const Index ne = g.num_cells();

  ReconstructResult res;
  res.xy = make_points_2d(opt, g);
  for (const Vec<2>& p : res.xy)
    if (!g.inside(p))
      throw InputError(fmt::format("--points: ({}, {}) lies outside [{}, {}]^2", p[0], p[1], a, b));
  const std::vector<double> fx = sample_2d(f, opt.function, res.xy);

  // Exact element integrals (20 x 20 Gauss: far below any reconstruction error here).
  const GaussRule exact_rule = gauss_legendre(20);
  std::vector<double> element_integral(static_cast<std::size_t>(ne), 0.0);
  for (Index e = 0; e < ne; ++e)
    for_each_gauss_point(g, e, exact_rule, [&](const Vec<2>& x, double w) {
      element_integral[static_cast<std::size_t>(e)] += w * f(x[0], x[1]);
    });
  for (double c : element_integral) res.integral_exact += c;

  Reconstruction2D tls(opt, g, res.xy, fx,
                       opt.conservative ? element_integral : std::vector<double>{});
  res.details = tls.details();

  const GaussRule err_rule = gauss_legendre(opt.error_points);
  const GaussRule int_rule = gauss_legendre(opt.integration_points);
  double sq = 0.0;
  for (Index e = 0; e < ne; ++e) {
    for_each_gauss_point(g, e, err_rule, [&](const Vec<2>& x, double) {
      const double d = tls.value(e, x) - f(x[0], x[1]);
      sq += d * d;
    });
    for_each_gauss_point(g, e, int_rule, [&](const Vec<2>& x, double w) {
      res.integral_reconstructed += w * tls.value(e, x);
    });
  }
  res.rms_error = std::sqrt(sq / static_cast<double>(ne * opt.error_points * opt.error_points));
  res.relative_integral_error =
      std::abs(res.integral_reconstructed - res.integral_exact) / std::abs(res.integral_exact);
  return res;
}

// The degree-4 rule on a triangle with 6 points (Dunavant 1985): barycentric points and weights
// as fractions of the area.
struct TrianglePoint {
  double l0, l1, w;
};
constexpr std::array<TrianglePoint, 6> kDegree4 = {{
    {0.445948490915965, 0.445948490915965, 0.223381589678011},
    {0.445948490915965, 0.108103018168070, 0.223381589678011},
    {0.108103018168070, 0.445948490915965, 0.223381589678011},
    {0.091576213509771, 0.091576213509771, 0.109951743655322},
    {0.091576213509771, 0.816847572980459, 0.109951743655322},
    {0.816847572980459, 0.091576213509771, 0.109951743655322},
}};

// fn(x, w) at the degree-4 points of the k x k sub-triangles of triangle c (the uniform
// subdivision; weights include the area).
template <class Fn>
void for_each_triangle_point(const TriangleMesh& m, Index c, int k, Fn&& fn) {
  const auto& t = m.cell_vertices(c);
  const Vec<2> a = m.vertex(t[0]), e1 = (m.vertex(t[1]) - a) / k, e2 = (m.vertex(t[2]) - a) / k;
  const double w = m.cell_volume(c) / (k * k);
  for (int i = 0; i < k; ++i)
    for (int j = 0; i + j < k; ++j) {
      // The upright sub-triangle (i, j), (i + 1, j), (i, j + 1) and, unless at the edge, the
      // inverted one (i + 1, j), (i + 1, j + 1), (i, j + 1).
      const Vec<2> p = a + i * e1 + j * e2;
      for (const auto& q : kDegree4) fn(Vec<2>(p + q.l0 * e1 + q.l1 * e2), w * q.w);
      if (i + j + 1 < k) {
        const Vec<2> r = a + (i + 1) * e1 + (j + 1) * e2;
        for (const auto& q : kDegree4) fn(Vec<2>(r - q.l0 * e1 - q.l1 * e2), w * q.w);
      }
    }
}

// D 6.2.2: f(x, y) reconstructed by TLS on a triangular mesh.
ReconstructResult reconstruct_triangles(const ReconstructOptions& opt, double a, double b) {
  if (opt.mapping != "tls")
    throw InputError(
        fmt::format("--mesh reconstructs with tls (D 6.2.2), not --mapping {}", opt.mapping));
  const TriangleMesh mesh = [&] {
    if (opt.mesh == "right" || opt.mesh == "criss-cross")
      return structured_triangles(
          Vec<2>(a, a), Vec<2>(b, b), IVec<2>{opt.cells, opt.cells},
          opt.mesh == "right" ? TrianglePattern::right : TrianglePattern::criss_cross);
    return read_gmsh_mesh(opt.mesh);
  }();
  const Expression f(opt.function, {});
  ReconstructResult res;
  const auto colon = opt.points.find(':');
  const std::string kind = opt.points.substr(0, colon);
  const int n = parse_count(colon == std::string::npos ? "" : opt.points.substr(colon + 1));
  if ((kind != "random" && kind != "domain") || n < 1)
    throw InputError(
        fmt::format("--points {}: on triangles choose random:N (N per triangle) or "
                    "domain:N (N over the domain), N >= 1",
                    opt.points));
  std::mt19937 rng(opt.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  if (kind == "random") {
    for (Index c = 0; c < mesh.num_cells(); ++c) {
      const auto& t = mesh.cell_vertices(c);
      for (int k = 0; k < n; ++k) {
        double r1 = u(rng), r2 = u(rng);
        if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;  // uniform in the triangle
        res.xy.push_back(mesh.vertex(t[0]) + r1 * (mesh.vertex(t[1]) - mesh.vertex(t[0])) +
                         r2 * (mesh.vertex(t[2]) - mesh.vertex(t[0])));
      }
    }
  } else {
    const Vec<2> lo = mesh.lower(), span = mesh.upper() - mesh.lower();
    while (static_cast<int>(res.xy.size()) < n) {
      const Vec<2> p(lo[0] + u(rng) * span[0], lo[1] + u(rng) * span[1]);
      if (mesh.inside(p)) res.xy.push_back(p);
    }
  }
  const std::vector<double> fx = sample_2d(f, opt.function, res.xy);
  const auto ne = static_cast<std::size_t>(mesh.num_cells());
  // Element integrals with the degree-4 rule on 8 x 8 sub-triangles (far below any
  // reconstruction error here).
  std::vector<double> element_integral(ne, 0.0);
  for (Index c = 0; c < mesh.num_cells(); ++c)
    for_each_triangle_point(mesh, c, 8, [&](const Vec<2>& x, double w) {
      element_integral[static_cast<std::size_t>(c)] += w * f(x[0], x[1]);
    });
  for (double c : element_integral) res.integral_exact += c;

  TlsTriangleSettings s;
  s.terms = opt.terms;
  s.strategy = parse_tls_triangle_strategy(opt.strategy);
  s.max_condition = opt.max_condition;
  TlsTriangleReconstruction tls(mesh, s);  // validates the settings
  const auto& report = tls.set_points(res.xy);
  TlsTriangleCoefficients coeffs;
  const auto& fit = opt.conservative ? report.conservative : report.plain;
  if (fit.failed > 0)
    throw InputError(fmt::format(
        "TLS cannot fit triangle {} ({} points, condition number {:.3g}) with --strategy none; "
        "use reduce, min-norm or graded",
        fit.first_deficient, tls.element(fit.first_deficient).points,
        (opt.conservative ? tls.element(fit.first_deficient).conservative
                          : tls.element(fit.first_deficient).plain)
            .condition));
  if (opt.conservative)
    tls.fit_conservative(fx, element_integral, coeffs);
  else
    tls.fit_plain(fx, coeffs);
  res.details += fmt::format("{:>8} {:>7} {:>6} {:>5} {:>12}\n", "triangle", "points", "terms",
                             "rank", "cond(D)");
  for (Index c = 0; c < mesh.num_cells(); ++c) {
    const auto& info = tls.element(c);
    const auto& sys = opt.conservative ? info.conservative : info.plain;
    res.details += fmt::format("{:>8} {:>7} {:>6} {:>5} {:>12.4g}\n", c, info.points, sys.terms,
                               sys.rank, sys.condition);
  }
  double sq = 0.0, weight = 0.0;
  std::size_t count = 0;
  for (Index c = 0; c < mesh.num_cells(); ++c) {
    for_each_triangle_point(mesh, c, 1, [&](const Vec<2>& x, double w) {
      const double d = tls.evaluate(coeffs, c, x) - f(x[0], x[1]);
      sq += d * d;
      ++count;
      weight += w;
    });
    res.integral_reconstructed += tls.integral(coeffs, c);
  }
  res.rms_error = std::sqrt(sq / static_cast<double>(count));
  res.relative_integral_error =
      std::abs(res.integral_reconstructed - res.integral_exact) / std::abs(res.integral_exact);
  res.details += fmt::format("{} triangles, {} points, area {:.10g}\n", mesh.num_cells(),
                             res.xy.size(), weight);
  return res;
}

}  // namespace

Reconstruction1D::Reconstruction1D(const ReconstructOptions& opt, const Grid<1>& g,
                                   const std::vector<double>& x, const std::vector<double>& f,
                                   const std::vector<double>& element_integrals)
    : mapping_(opt.mapping),
      mls_degree_(opt.mls_degree),
      points_(x.size()),
      f_(f),
      mls_(opt.mapping == "imls",
           opt.mapping == "mls" || opt.mapping == "imls" ? opt.mls_degree : 1) {
  if (x.size() != f.size())
    throw InputError(fmt::format("{} points and {} values", x.size(), f.size()));
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (!g.inside(Vec<1>(x[k])))
      throw InputError(fmt::format("point {} (x = {}) lies outside [{}, {}]", k, x[k], g.origin[0],
                                   g.upper()[0]));
    if (!std::isfinite(f[k]))
      throw InputError(
          fmt::format("the value at point {} (x = {}) is not finite: {}", k, x[k], f[k]));
  }
  if (!element_integrals.empty() && static_cast<Index>(element_integrals.size()) != g.cells[0])
    throw InputError(
        fmt::format("{} element integrals for {} elements", element_integrals.size(), g.cells[0]));
  if (opt.mapping == "tls") {
    TlsSettings s;
    s.terms = opt.terms;
    s.completion = parse_tls_completion(opt.completion);
    s.max_condition = opt.max_condition;
    validate(s);
    tls_ = TlsReconstruction(s);
    tls_.set_points(g, x, opt.share_faces);
    if (!element_integrals.empty())
      tls_.fit_conservative(f, element_integrals, coeffs_);
    else
      tls_.fit_plain(f, coeffs_);
    if (tls_.report().failed > 0)
      throw InputError(fmt::format(
          "TLS cannot fit element {} ({} points, condition number {:.3g}) without completion; "
          "use --completion reduce, virtual or neighbour",
          tls_.report().failed_element, tls_.report().failed_points,
          tls_.report().failed_condition));
    details_ += fmt::format("{:>8} {:>7} {:>8} {:>8} {:>6} {:>12}\n", "element", "points",
                            "virtual", "borrowed", "terms", "cond(D)");
    for (Index e = 0; e < g.cells[0]; ++e) {
      const auto& info = tls_.element(e);
      details_ += fmt::format("{:>8} {:>7} {:>8} {:>8} {:>6} {:>12.4g}\n", e, info.points,
                              info.virtual_points, info.borrowed, info.terms, info.condition);
    }
  } else if (opt.mapping == "cubic_spline") {
    spline_.set_abscissae(x);
    spline_.fit(f);
    details_ =
        fmt::format("natural cubic spline through {} distinct points\n", spline_.num_knots());
  } else if (opt.mapping == "mls" || opt.mapping == "imls") {
    // Quadratic-spline weight of support 3 l (001 eq. 17, 003 eq. 27), l the cell size.
    mls_.set_points(g, x);
  } else {
    throw InputError(
        fmt::format("--mapping {}: choose tls, cubic_spline, mls or imls", opt.mapping));
  }
}

double Reconstruction1D::value(Index e, double x) {
  if (mapping_ == "tls") return tls_.evaluate(coeffs_, e, x);
  if (mapping_ == "cubic_spline") return spline_.value(x);
  return mls_.evaluate(x, MlsWeight::QuadraticSpline, f_);
}

std::string Reconstruction1D::details() const {
  if (mapping_ != "mls" && mapping_ != "imls") return details_;
  const MlsReport& r = mls_.report();
  return fmt::format(
      "{} degree {} through {} points: {} evaluations, {} without data, {} {}\n", mapping_,
      mls_degree_, points_, r.points, r.empty,
      mapping_ == "mls" ? r.ill_conditioned + r.singular : r.reduced,
      mapping_ == "mls"
          ? fmt::format("ill-conditioned or singular (max cond(A) {:.4g})", r.max_condition)
          : std::string("with dropped terms"));
}

ReconstructResult reconstruct(const ReconstructOptions& opt) {
  const double a = constant_expression(opt.lower, "--lower");
  const double b = constant_expression(opt.upper, "--upper");
  if (!(b > a)) throw InputError(fmt::format("--upper ({}) must exceed --lower ({})", b, a));
  if (opt.cells < 1) throw InputError("--cells must be at least 1");
  if (opt.error_points < 1 || opt.integration_points < 1)
    throw InputError("--error-points and --integration-points must be at least 1");
  if (!opt.mesh.empty()) {
    if (opt.dim != 2) throw InputError("--mesh needs --dim 2");
    return reconstruct_triangles(opt, a, b);
  }
  if (opt.dim == 2) return reconstruct_2d(opt, a, b);
  if (opt.dim != 1) throw InputError(fmt::format("--dim {}: choose 1 or 2", opt.dim));
  const Expression f(opt.function, {});
  const Grid<1> g(Vec<1>(a), Vec<1>(b), IVec<1>{opt.cells});

  ReconstructResult res;
  res.x = make_points(opt, g);
  for (double xp : res.x)
    if (!g.inside(Vec<1>(xp)))
      throw InputError(fmt::format("--points: {} lies outside [{}, {}]", xp, a, b));
  std::vector<double> fx;
  for (double xp : res.x) {
    fx.push_back(f(xp));
    if (!std::isfinite(fx.back()))
      throw InputError(fmt::format("--function \"{}\" is not finite at the point x = {}: {}",
                                   opt.function, xp, fx.back()));
  }

  // Exact element integrals (20-point Gauss: far below any reconstruction error here).
  const GaussRule exact_rule = gauss_legendre(20);
  std::vector<double> element_integral(static_cast<std::size_t>(opt.cells), 0.0);
  const double half = 0.5 * g.h[0];
  auto centre = [&](Index e) { return a + (static_cast<double>(e) + 0.5) * g.h[0]; };
  for (Index e = 0; e < opt.cells; ++e)
    for (std::size_t k = 0; k < exact_rule.xi.size(); ++k)
      element_integral[static_cast<std::size_t>(e)] +=
          half * exact_rule.w[k] * f(centre(e) + half * exact_rule.xi[k]);
  for (double c : element_integral) res.integral_exact += c;

  Reconstruction1D rec(opt, g, res.x, fx,
                       opt.conservative ? element_integral : std::vector<double>{});
  const auto value = [&](Index e, double x) { return rec.value(e, x); };
  res.details = rec.details();

  const GaussRule err_rule = gauss_legendre(opt.error_points);
  const GaussRule int_rule = gauss_legendre(opt.integration_points);
  double sq = 0.0;
  for (Index e = 0; e < opt.cells; ++e) {
    for (double xi : err_rule.xi) {
      const double x = centre(e) + half * xi;
      const double d = value(e, x) - f(x);
      sq += d * d;
    }
    for (std::size_t k = 0; k < int_rule.xi.size(); ++k)
      res.integral_reconstructed +=
          half * int_rule.w[k] * value(e, centre(e) + half * int_rule.xi[k]);
  }
  // (MLS reports the evaluations above.)
  if (opt.mapping == "mls" || opt.mapping == "imls") res.details = rec.details();
  res.rms_error = std::sqrt(sq / static_cast<double>(opt.cells * opt.error_points));
  res.relative_integral_error =
      std::abs(res.integral_reconstructed - res.integral_exact) / std::abs(res.integral_exact);
  return res;
}

}  // namespace mpm
