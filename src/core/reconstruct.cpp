#include "core/reconstruct.hpp"

#include <fmt/format.h>
#include <cmath>
#include <functional>
#include <random>

#include "io/expression.hpp"
#include "mapping/cubic_spline.hpp"
#include "mapping/mls.hpp"
#include "mapping/quadrature.hpp"
#include "mapping/tls.hpp"

namespace mpm {
namespace {

double constant_expression(const std::string& text, const char* what) {
  const Expression e(text, {});
  if (!e.is_constant())
    throw InputError(
        fmt::format("{} = \"{}\" must be a number or a constant expression", what, text));
  return e(0.0);
}

std::vector<double> make_points(const ReconstructOptions& opt, const Grid<1>& g) {
  const auto colon = opt.points.find(':');
  const std::string kind = opt.points.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : opt.points.substr(colon + 1);
  std::vector<double> x;
  if (kind == "uniform" || kind == "random") {
    int n = 0;
    try {
      n = std::stoi(arg);
    } catch (...) {
      n = 0;
    }
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

}  // namespace

ReconstructResult reconstruct(const ReconstructOptions& opt) {
  const double a = constant_expression(opt.lower, "--lower");
  const double b = constant_expression(opt.upper, "--upper");
  if (!(b > a)) throw InputError(fmt::format("--upper ({}) must exceed --lower ({})", b, a));
  if (opt.cells < 1) throw InputError("--cells must be at least 1");
  if (opt.error_points < 1 || opt.integration_points < 1)
    throw InputError("--error-points and --integration-points must be at least 1");
  const Expression f(opt.function, {});
  const Grid<1> g(Vec<1>(a), Vec<1>(b), IVec<1>{opt.cells});

  ReconstructResult res;
  res.x = make_points(opt, g);
  for (double xp : res.x)
    if (!g.inside(Vec<1>(xp)))
      throw InputError(fmt::format("--points: {} lies outside [{}, {}]", xp, a, b));
  std::vector<double> fx;
  for (double xp : res.x) fx.push_back(f(xp));

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

  std::function<double(Index, double)> value;  // reconstruction in element e at x
  TlsReconstruction tls;
  TlsCoefficients coeffs;
  NaturalCubicSpline spline;
  MovingLeastSquares mls(opt.mapping == "imls",
                         opt.mapping == "mls" || opt.mapping == "imls" ? opt.mls_degree : 1);
  if (opt.mapping == "tls") {
    TlsSettings s;
    s.terms = opt.terms;
    s.completion = parse_tls_completion(opt.completion);
    s.max_condition = opt.max_condition;
    validate(s);
    tls = TlsReconstruction(s);
    tls.set_points(g, res.x, opt.share_faces);
    if (opt.conservative)
      tls.fit_conservative(fx, element_integral, coeffs);
    else
      tls.fit_plain(fx, coeffs);
    if (tls.report().failed > 0)
      throw InputError(fmt::format(
          "TLS cannot fit element {} ({} points, condition number {:.3g}) without completion; "
          "use --completion reduce, virtual or neighbour",
          tls.report().failed_element, tls.report().failed_points, tls.report().failed_condition));
    value = [&](Index e, double x) { return tls.evaluate(coeffs, e, x); };
    res.details += fmt::format("{:>8} {:>7} {:>8} {:>8} {:>6} {:>12}\n", "element", "points",
                               "virtual", "borrowed", "terms", "cond(D)");
    for (Index e = 0; e < opt.cells; ++e) {
      const auto& info = tls.element(e);
      res.details += fmt::format("{:>8} {:>7} {:>8} {:>8} {:>6} {:>12.4g}\n", e, info.points,
                                 info.virtual_points, info.borrowed, info.terms, info.condition);
    }
  } else if (opt.mapping == "cubic_spline") {
    spline.set_abscissae(res.x);
    spline.fit(fx);
    value = [&](Index, double x) { return spline.value(x); };
    res.details =
        fmt::format("natural cubic spline through {} distinct points\n", spline.num_knots());
  } else if (opt.mapping == "mls" || opt.mapping == "imls") {
    // Quadratic-spline weight of support 3 l (001 eq. 17, 003 eq. 27), l the cell size.
    mls.set_points(g, res.x);
    value = [&](Index, double x) { return mls.evaluate(x, MlsWeight::QuadraticSpline, fx); };
    // The report covers the RMS and integration points evaluated below; filled in afterwards.
  } else {
    throw InputError(
        fmt::format("--mapping {}: choose tls, cubic_spline, mls or imls", opt.mapping));
  }

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
  if (opt.mapping == "mls" || opt.mapping == "imls") {
    const MlsReport& r = mls.report();
    res.details = fmt::format(
        "{} degree {} through {} points: {} evaluations, {} without data, {} {}\n", opt.mapping,
        opt.mls_degree, res.x.size(), r.points, r.empty,
        opt.mapping == "mls" ? r.ill_conditioned + r.singular : r.reduced,
        opt.mapping == "mls"
            ? fmt::format("ill-conditioned or singular (max cond(A) {:.4g})", r.max_condition)
            : std::string("with dropped terms"));
  }
  res.rms_error = std::sqrt(sq / static_cast<double>(opt.cells * opt.error_points));
  res.relative_integral_error =
      std::abs(res.integral_reconstructed - res.integral_exact) / std::abs(res.integral_exact);
  return res;
}

}  // namespace mpm
