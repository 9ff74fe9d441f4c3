#include <fmt/format.h>
#include <cmath>
#include <numbers>

#include "benchmarks/benchmarks.hpp"
#include "setup/config.hpp"
#include "setup/material_settings.hpp"

namespace mpm {

double Mms1DExact::deformation_gradient(double X, double t) const {
  using std::numbers::pi;
  const double k = 2.0 * pi / length, w = wave_speed * pi / length;
  return 1.0 + amplitude * k * std::cos(k * X) * std::sin(w * t);  // 003 eq. 46
}

double Mms1DExact::piola_stress(double F) const {
  // 1D neo-Hookean (003 eq. 42-43 with J = F): P = J sigma F^-T = sigma.
  return lambda * std::log(F) / F + mu * (F * F - 1.0) / F;
}

double Mms1DExact::body_force(double X, double t) const {
  using std::numbers::pi;
  // b = u_tt - (1/rho0) dP/dX with u = A sin(kX) sin(wt), k = 2 pi/L, w = c pi/L:
  //   u_tt = -w^2 u,  dF/dX = -k^2 u,
  //   dP/dF = lambda (1 - ln F)/F^2 + mu (1 + 1/F^2),
  //   b = u [k^2/rho0 (mu + (lambda (1 - ln F) + mu)/F^2) - w^2]
  //     = pi^2 u / L^2 [4 mu/rho0 - c^2 - 4 (lambda (ln F - 1) - mu)/(rho0 F^2)].
  // This is 003 eq. 47 with its prefactor pi u / L^2 corrected to pi^2 u / L^2 (METHODS.md
  // errata; the bracket agrees term by term).
  const double k = 2.0 * pi / length, w = wave_speed * pi / length;
  const double u = amplitude * std::sin(k * X) * std::sin(w * t);
  const double F = deformation_gradient(X, t);
  const double dPdF = lambda * (1.0 - std::log(F)) / (F * F) + mu * (1.0 + 1.0 / (F * F));
  return u * (k * k * dPdF / density - w * w);
}

ExactState<1> Mms1DExact::operator()(const Vec<1>& X, double t) const {
  using std::numbers::pi;
  const double k = 2.0 * pi / length, w = wave_speed * pi / length;
  ExactState<1> s;
  s.u[0] = amplitude * std::sin(k * X[0]) * std::sin(w * t);  // 003 eq. 44
  // 003 eq. 45 writes A c pi (L = 1 there); du/dt carries the factor 1/L.
  s.v[0] = amplitude * w * std::sin(k * X[0]) * std::cos(w * t);
  s.stress(0, 0) = piola_stress(deformation_gradient(X[0], t));  // Cauchy = P in 1D
  return s;
}

Problem<1> make_mms_1d(const Config& cfg, const SeedScope& scope) {
  Problem<1> pb;
  pb.benchmark = "mms_1d";
  pb.materials = material_from_config(cfg, 1);
  const auto* law = &require_neo_hookean(cfg, pb.materials.single(), pb.benchmark, "003 eq. 42");
  const double L = cfg.get_real("bar.length");
  const double rho = cfg.get_real("material.density");
  // 003: c = sqrt(E / rho0), not the 1D neo-Hookean modulus sqrt((lambda + 2 mu) / rho0).
  const Mms1DExact ex{L,
                      rho,
                      law->p.lambda(),
                      law->p.mu(),
                      std::sqrt(cfg.get_real("material.youngs_modulus") / rho),
                      cfg.get_real("mms.amplitude")};
  // u(X, 0) = 0, F = 1, zero stress; v(X, 0) = A c pi / L sin(2 pi X / L); u = 0 at X = 0 and
  // X = L for all t (fixed ends).
  fill_fixed_bar(pb, cfg, L, rho, scope, [ex](const Vec<1>& X) { return Vec<1>(ex(X, 0.0).v[0]); });
  // b depends on the material position X (P.x0, fixed), so only time-dependence is flagged.
  pb.body_force.time_dependent = true;
  pb.body_force.fill = [ex](const Particles<1>& P, double t, std::vector<Vec<1>>& b) {
    for (std::size_t i = 0; i < b.size(); ++i) b[i][0] = ex.body_force(P.x0[i][0], t);
  };
  pb.exact = ex;
  return pb;
}

}  // namespace mpm
