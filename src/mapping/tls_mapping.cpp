// The TLS mapping's reconstructions (tls.hpp, TlsMapping): everything of map_mass, map_momentum
// and map_forces but the basis evaluation and assembly at the Gauss points, compiled once per
// dimension.
#include <fmt/format.h>

#include <string>

#include "core/bytes.hpp"
#include "mapping/tls.hpp"

namespace mpm {

template <int Dim>
void TlsMapping::fit_mass(RunState<Dim>& sim, GaussPoints<Dim>& q) {
  auto& st = state<Dim>();
  const auto& P = sim.particles;
  const TlsReport& rep = st.recon.set_points(sim.grid, P);
  accumulate(totals_, rep);
  if (rep.failed > 0)
    throw_fit_failure(sim.step, sim.time, rep, "element", st.recon.describe(rep.failed_element),
                      "reduce, virtual or neighbour");
  q.clear();
  // D 6.3: the same Gauss rule in every element of the uniform grid, weights scaled by the
  // half-widths (the Jacobian of the map from [-1, 1]^Dim).
  const Vec<Dim> hw = st.recon.half_width_vec();
  for (Index e = 0; e < st.recon.num_elements(); ++e) {
    if (!st.recon.active(e)) continue;  // no particles: no reconstruction, no mass
    const Vec<Dim> c = st.recon.centre_vec(e);
    for (std::size_t k = 0; k < st.xi.size(); ++k) {
      Vec<Dim> x;
      double wg = 1.0;
      for (int d = 0; d < Dim; ++d) {
        x[d] = c[d] + hw[d] * st.xi[k][d];
        wg *= hw[d] * st.w[k][d];
      }
      q.add(x, wg, e);
    }
  }
  element_sums(st.recon, [&](std::size_t i) { return P.mass[i]; });
  st.recon.fit_conservative(P.density, integrals_, st.coef);
  st.rho.resize(q.size());
  at_gauss(st, q, [&](std::size_t g, double v) { st.rho[g] = v; });
}

template <int Dim>
void TlsMapping::fit_momentum(RunState<Dim>& sim, const GaussPoints<Dim>& q) {
  auto& st = state<Dim>();
  const auto& P = sim.particles;
  st.rhov.resize(q.size());
  values_.resize(P.x.size());
  for (int d = 0; d < Dim; ++d) {
    fill_values([&](std::size_t i) { return P.density[i] * P.v[i][d]; });
    element_sums(st.recon, [&](std::size_t i) { return P.mass[i] * P.v[i][d]; });
    st.recon.fit_conservative(values_, integrals_, st.coef);
    at_gauss(st, q, [&](std::size_t g, double v) { st.rhov[g][d] = v; });
  }
}

template <int Dim>
void TlsMapping::fit_forces(RunState<Dim>& sim, const GaussPoints<Dim>& q) {
  auto& st = state<Dim>();
  const auto& P = sim.particles;
  values_.resize(P.x.size());
  st.sigma.resize(q.size());
  for (int r = 0; r < Dim; ++r)
    for (int c = 0; c < Dim; ++c) {
      fill_values([&](std::size_t i) { return P.stress[i](r, c); });
      st.recon.fit_plain(values_, st.coef);
      at_gauss(st, q, [&](std::size_t g, double v) { st.sigma[g](r, c) = v; });
    }

  st.rhob.resize(q.size());
  for (int d = 0; d < Dim; ++d) {
    fill_values([&](std::size_t i) { return P.density[i] * P.body[i][d]; });
    element_sums(st.recon, [&](std::size_t i) { return P.mass[i] * P.body[i][d]; });
    st.recon.fit_conservative(values_, integrals_, st.coef);
    at_gauss(st, q, [&](std::size_t g, double v) { st.rhob[g][d] = v; });
  }
}

template void TlsMapping::fit_mass<1>(RunState<1>&, GaussPoints<1>&);
template void TlsMapping::fit_mass<2>(RunState<2>&, GaussPoints<2>&);
template void TlsMapping::fit_momentum<1>(RunState<1>&, const GaussPoints<1>&);
template void TlsMapping::fit_momentum<2>(RunState<2>&, const GaussPoints<2>&);
template void TlsMapping::fit_forces<1>(RunState<1>&, const GaussPoints<1>&);
template void TlsMapping::fit_forces<2>(RunState<2>&, const GaussPoints<2>&);

// The run totals in a checkpoint: eleven counts, then the two condition numbers.
std::string TlsMapping::save_totals() const {
  const TlsReport& t = totals_;
  ByteWriter w;
  for (Index v :
       {t.elements, t.active, t.full, t.reduced, t.with_virtual, t.with_neighbours, t.failed,
        t.outside, static_cast<Index>(t.min_terms), t.failed_element, t.failed_points})
    w.i64(v);
  w.f64(t.max_condition);
  w.f64(t.failed_condition);
  w.i64(t.truncated);  // since the triangles (checkpoints before them end here)
  return std::move(w.bytes());
}

void TlsMapping::load_totals(std::string_view bytes, const std::string& what) {
  ByteReader r(bytes, what + " (TLS totals)");
  TlsReport t;
  for (Index* v : {&t.elements, &t.active, &t.full, &t.reduced, &t.with_virtual, &t.with_neighbours,
                   &t.failed, &t.outside})
    *v = r.i64();
  t.min_terms = static_cast<int>(r.i64());
  t.failed_element = r.i64();
  t.failed_points = r.i64();
  t.max_condition = r.f64();
  t.failed_condition = r.f64();
  if (!r.done()) t.truncated = r.i64();
  r.expect_done();
  totals_ = t;
}

}  // namespace mpm
