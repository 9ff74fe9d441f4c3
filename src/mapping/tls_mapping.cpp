// The TLS mapping's reconstructions (tls.hpp, TlsMapping): everything of map_mass, map_momentum
// and map_forces but the basis evaluation and assembly at the Gauss points, compiled once per
// dimension.
#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "basis/gimp.hpp"
#include "core/bytes.hpp"
#include "mapping/tls.hpp"
#include "parallel/distribution.hpp"

namespace mpm {

// TlsSettings::surface_volume: an active element with an inactive one among the 3^Dim - 1
// around it (inside the grid) is cut by a free surface.
// TlsSettings::positivity (Zhang and Shu 2010): with m = min_g rho^(x_g) < 0 over the element's
// Gauss points, rho^ = a_1 + theta (rho^ - a_1) with theta = a_1 / (a_1 - m) is zero there and
// non-negative at the others; a_1 = sum m_p / |Omega_e| > 0 is kept, so mass is conserved.
// st.surface is read only with surface_volume, st.theta only with positivity (apply_theta).
template <int Dim>
void TlsMapping::prepare_flags(TlsMappingState<Dim>& st) {
  const auto ne = static_cast<std::size_t>(st.recon.num_elements());
  if (settings_.surface_volume) st.surface.assign(ne, 0);
  if (settings_.positivity) st.theta.assign(ne, 1.0);
}

template <int Dim>
void TlsMapping::flag_element(TlsMappingState<Dim>& st, Index e) const {
  const auto& recon = st.recon;
  if (!recon.active(e)) return;
  if (settings_.surface_volume) {
    const auto& grid = recon.grid();
    int around = 1;
    for (int d = 0; d < Dim; ++d) around *= 3;
    const IVec<Dim> c = recon.cell(e);
    for (int k = 0; k < around; ++k) {
      IVec<Dim> n = c;
      for (int d = 0, r = k; d < Dim; ++d, r /= 3) n[d] += r % 3 - 1;
      if (grid.has_cell(n) && !recon.active(grid.cell_index(n))) {
        st.surface[static_cast<std::size_t>(e)] = 1;
        break;
      }
    }
  }
  if (settings_.positivity) {
    auto& a = st.coef[static_cast<std::size_t>(e)];
    double lowest = 0.0;
    for (const auto& psi : st.psi) lowest = std::min(lowest, a.dot(psi));
    if (lowest < 0.0) {
      const double theta = a[0] / (a[0] - lowest);
      st.theta[static_cast<std::size_t>(e)] = theta;
      a.tail(a.size() - 1) *= theta;
    }
  }
}

template <int Dim>
std::array<Index, 2> TlsMapping::count_flags(const TlsMappingState<Dim>& st,
                                             const CellBox<Dim>& own) const {
  std::array<Index, 2> flagged{0, 0};
  const std::array<Index, 2> span = own.span();
  for (Index e = span[0]; e < span[1]; ++e) {
    if (!own.holds(e)) continue;
    if (settings_.surface_volume) flagged[0] += st.surface[static_cast<std::size_t>(e)];
    if (settings_.positivity) flagged[1] += st.theta[static_cast<std::size_t>(e)] < 1.0;
  }
  return flagged;
}

template <int Dim>
double TlsMapping::reach(const RunState<Dim>& sim) const {
  if (!settings_.domain_integrals) return 1.0;
  // The reach of the step's first exchange (that of the mass sum, whose set_points bins the
  // particles with their ghosts) for all its exchanges: the later sums of the step (USF, USAVG:
  // the forces after the stress update, which stretches the boxes) and the adjoint rate read the
  // points as binned, so the ghosts must be the same particles in the same order.
  if (reach_step_ == sim.step) return reach_;
  const auto& g = sim.grid;
  double r = 0.0;  // the largest half-side in cells along any axis
  for (Index p = 0; p < sim.own_particles(); ++p)
    for (int d = 0; d < Dim; ++d) {
      const double half = 0.5 * cpgimp_side(g, sim.particles, p, d) / g.h[d];
      if (std::isfinite(half)) r = std::max(r, half);
    }
  reach_step_ = sim.step;
  reach_ = std::max(1.0, 2.0 * std::ceil(r));
  return reach_;
}

// The same theta on the terms beyond a_1 of a conservative field fitted in coef (every element,
// or those with only[e] != 0), so that (rho v)^ / rho^ stays what the fits give where theta = 1
// and the element's integral is kept.
template <int Dim>
void TlsMapping::apply_theta(const TlsMappingState<Dim>& st, BasicTlsCoefficients<Dim>& coef,
                             const unsigned char* only, Index e) const {
  if (!settings_.positivity) return;
  const auto i = static_cast<std::size_t>(e);
  if (st.theta[i] < 1.0 && (only == nullptr || only[i] != 0))
    coef[i].tail(coef[i].size() - 1) *= st.theta[i];
}

// TlsSettings::domain_integrals. A particle's domain is the cpGIMP box (basis/gimp.hpp): side
// l_d = F_dd l0_d with l0 = V_p^0 in 1D and h_d (V_p^0 / |cell|)^(1/Dim) otherwise, clipped to
// the grid. Its value is split among the active elements the box overlaps, in proportion to the
// overlap; overlap with inactive elements (no particle centre: no reconstruction) is given to
// the active ones, so each particle's fractions sum to one and sum_e c_e = sum_p value_p. A box
// that is empty or not finite (F_dd <= 0) leaves the whole value in the particle's own element,
// as D's sum does. The entries are then sorted by element, stably: in each element they follow
// the particles' bin order. The overlaps are computed in parallel over fixed chunks of the
// binned particles (each chunk's entries in bin order), the counting sort places each chunk's
// entries after those of the chunks before it: the same entries and order for any thread count,
// and serial work only per element of each chunk's band (the serial split was
// 10 % of a one-thread TLS step).
template <int Dim>
void TlsMapping::split_domains(const RunState<Dim>& sim, const BasicTlsReconstruction<Dim>& recon) {
  if (!settings_.domain_integrals) return;
  const auto& P = sim.particles;
  const auto& g = recon.grid();
  const Index ne = recon.num_elements();
  const auto& bins = recon.bins();
  const auto binned = static_cast<Index>(bins.order.size());
  const int nc = ParticleChunks::count(binned);
  Vec<Dim> inv_h;
  for (int d = 0; d < Dim; ++d) inv_h[d] = 1.0 / g.h[d];
  for_each_chunk(binned, [&](int c, Index first_k, Index end_k) {
    auto& ch = split_.chunks[static_cast<std::size_t>(c)];
    auto& list = ch.entries;
    list.clear();
    // The element holding bin position first_k: the last e with start[e] <= first_k (empty
    // elements before it share its start).
    Index e = static_cast<Index>(std::upper_bound(bins.start.begin(), bins.start.end(), first_k) -
                                 bins.start.begin()) -
              1;
    for (Index k = first_k; k < end_k; ++k) {
      while (bins.start[static_cast<std::size_t>(e + 1)] <= k) ++e;
      const Index pi = bins.order[static_cast<std::size_t>(k)];
      const auto p = static_cast<std::size_t>(pi);
      std::array<double, Dim> lo{}, hi{};
      IVec<Dim> c0{}, c1{};
      bool box = true;
      for (int d = 0; d < Dim; ++d) {
        const double r = 0.5 * cpgimp_side(g, P, pi, d) * inv_h[d];  // half side in cells
        const double s = (P.x[p][d] - g.origin[d]) * inv_h[d];
        const auto n = static_cast<double>(g.cells[d]);
        box = box && r > 0.0 && std::isfinite(r) && std::isfinite(s);
        if (!box) break;
        lo[d] = std::clamp(s - r, 0.0, n);
        hi[d] = std::clamp(s + r, 0.0, n);
        // floor and ceil of these non-negative values by conversion (the library calls were a
        // tenth of this function).
        const auto fl = static_cast<Index>(lo[d]), fh = static_cast<Index>(hi[d]);
        const Index cu = static_cast<double>(fh) == hi[d] ? fh : fh + 1;
        c0[d] = std::clamp(fl, Index{0}, g.cells[d] - 1);
        c1[d] = std::clamp(cu - 1, c0[d], g.cells[d] - 1);
      }
      const std::size_t first = list.size();
      double total = 0.0;
      if (box) {
        IVec<Dim> cell = c0;
        while (true) {
          double overlap = 1.0;
          for (int d = 0; d < Dim; ++d)
            overlap *= std::max(0.0, std::min(hi[d], static_cast<double>(cell[d] + 1)) -
                                         std::max(lo[d], static_cast<double>(cell[d])));
          const Index n = g.cell_index(cell);
          if (overlap > 0.0 && recon.active(n)) {
            list.push_back({n, pi, overlap});
            total += overlap;
          }
          int d = 0;
          while (d < Dim && cell[d] == c1[d]) cell[d] = c0[d], ++d;
          if (d == Dim) break;
          ++cell[d];
        }
      }
      if (!(total > 0.0)) {
        list.resize(first);
        list.push_back({e, pi, 1.0});
        total = 1.0;
      }
      for (std::size_t j = first; j < list.size(); ++j) list[j].fraction /= total;
    }
    // The chunk's band of elements and its entries per element of the band.
    ch.lo = ne;
    ch.hi = -1;
    for (const auto& t : list) {
      ch.lo = std::min(ch.lo, t.element);
      ch.hi = std::max(ch.hi, t.element);
    }
    ch.slot.assign(ch.lo <= ch.hi ? static_cast<std::size_t>(ch.hi - ch.lo + 1) : 0, 0);
    for (const auto& t : list) ++ch.slot[static_cast<std::size_t>(t.element - ch.lo)];
  });
  // Serial, per element of each band: the totals per element, then each chunk's first slot in
  // an element after the entries of the chunks before it.
  auto& start = split_.start;
  start.assign(static_cast<std::size_t>(ne) + 1, 0);
  for (int c = 0; c < nc; ++c) {
    const auto& ch = split_.chunks[static_cast<std::size_t>(c)];
    for (Index n = ch.lo; n <= ch.hi; ++n)
      start[static_cast<std::size_t>(n) + 1] += ch.slot[static_cast<std::size_t>(n - ch.lo)];
  }
  for (std::size_t n = 0; n < static_cast<std::size_t>(ne); ++n) start[n + 1] += start[n];
  auto& next = split_.next;
  next.assign(start.begin(), start.end() - 1);
  for (int c = 0; c < nc; ++c) {
    auto& ch = split_.chunks[static_cast<std::size_t>(c)];
    for (Index n = ch.lo; n <= ch.hi; ++n) {
      auto& s = ch.slot[static_cast<std::size_t>(n - ch.lo)];
      const std::size_t count = s;
      s = next[static_cast<std::size_t>(n)];
      next[static_cast<std::size_t>(n)] += count;
    }
  }
  split_.point.resize(start.back());
  split_.fraction.resize(start.back());
  for_each_chunk(binned, [&](int c, Index, Index) {
    auto& ch = split_.chunks[static_cast<std::size_t>(c)];
    for (const auto& t : ch.entries) {
      const std::size_t k = ch.slot[static_cast<std::size_t>(t.element - ch.lo)]++;
      split_.point[k] = t.point;
      split_.fraction[k] = t.fraction;
    }
  });
}

template <int Dim>
void TlsMapping::fit_mass(RunState<Dim>& sim, GaussPoints<Dim>& q) {
  auto& st = state<Dim>();
  const auto& P = sim.particles;
  // In a distributed run this process reconstructs with the ghost particles but integrates, and
  // reports, only its own elements; the reports of all processes are combined.
  const CellBox<Dim> own = sim.own_cells();
  st.recon.set_focus(own);
  TlsReport rep = st.recon.set_points(sim.grid, P);
  if (sim.comm) rep = over_ranks(*sim.comm, rep);
  accumulate(totals_, rep);
  if (rep.failed > 0)
    throw_fit_failure(sim.step, sim.time, rep, "element", st.recon.describe(rep.failed_element),
                      "reduce, virtual or neighbour");
  // D 6.3: the same Gauss rule in every element of the uniform grid, weights scaled by the
  // half-widths (the Jacobian of the map from [-1, 1]^Dim). The active elements' first points
  // by a serial count over the elements, then the points in parallel (in a serial loop they
  // were 1 % of a step).
  const Vec<Dim> hw = st.recon.half_width_vec();
  const std::size_t nk = st.xi.size();
  std::vector<Index>& first = st.gauss_first;
  const std::array<Index, 2> span = own.span();
  first.resize(static_cast<std::size_t>(span[1] - span[0]));
  std::size_t points = 0;
  for (Index e = span[0]; e < span[1]; ++e) {
    // No particles: no reconstruction, no mass; outside the box: another process's element.
    const bool integrated = own.holds(e) && st.recon.active(e);
    first[static_cast<std::size_t>(e - span[0])] = integrated ? static_cast<Index>(points) : -1;
    if (integrated) points += nk;
  }
  q.resize(points);
  st.gauss_range = span;
  parallel_for(static_cast<Index>(first.size()), [&](Index k0) {
    const Index e = span[0] + k0;
    if (first[static_cast<std::size_t>(k0)] < 0) return;
    const Vec<Dim> c = st.recon.centre_vec(e);
    const auto g0 = static_cast<std::size_t>(first[static_cast<std::size_t>(k0)]);
    for (std::size_t k = 0; k < nk; ++k) {
      Vec<Dim> x;
      double wg = 1.0;
      for (int d = 0; d < Dim; ++d) {
        x[d] = c[d] + hw[d] * st.xi[k][d];
        wg *= hw[d] * st.w[k][d];
      }
      q.x[g0 + k] = x;
      q.w[g0 + k] = wg;
      q.element[g0 + k] = e;
    }
  });
  split_domains(sim, st.recon);
  values_and_sums(
      st.recon, P.x.size(), 1, [&](std::size_t i, int) { return P.density(i); }, 1,
      [&](std::size_t i, int) { return P.mass[i]; });
  // Each element's flags, positivity limit and density at its Gauss points as soon as its fit
  // is done (fit_conservative's done).
  prepare_flags(st);
  st.rho.resize(q.size());
  st.recon.fit_conservative(values(), integrals_, st.coef, [&](Index e) {
    flag_element(st, e);
    const auto& a = st.coef[static_cast<std::size_t>(e)];
    gauss_points_of(st, e, [&](std::size_t g, std::size_t k) { st.rho[g] = a.dot(st.psi[k]); });
  });
  const std::array<Index, 2> flags = count_flags(st, own);
  std::array<double, 2> flagged{static_cast<double>(flags[0]), static_cast<double>(flags[1])};
  if (sim.comm) sim.comm->sum(std::span<double>(flagged));
  totals_.surface += static_cast<Index>(flagged[0]);
  totals_.limited += static_cast<Index>(flagged[1]);
}

// Both components in one fit (BasicTlsReconstruction::fit_fields).
template <int Dim>
void TlsMapping::fit_momentum(RunState<Dim>& sim, const GaussPoints<Dim>& q) {
  auto& st = state<Dim>();
  const auto& P = sim.particles;
  const Index ne = st.recon.num_elements();
  values_and_sums(
      st.recon, P.x.size(), Dim, [&](std::size_t i, int d) { return P.density(i) * P.v[i][d]; },
      Dim, [&](std::size_t i, int d) { return P.mass[i] * P.v[i][d]; });
  std::array<typename BasicTlsReconstruction<Dim>::Field, Dim> fields;
  for (int d = 0; d < Dim; ++d)
    fields[static_cast<std::size_t>(d)] = {integrals_of(d, ne), nullptr,
                                           &st.fields[static_cast<std::size_t>(d)]};
  st.rhov.resize(q.size());
  st.recon.fit_fields(values(), fields, [&](Index e) {
    for (int d = 0; d < Dim; ++d) {
      auto& a = st.fields[static_cast<std::size_t>(d)];
      apply_theta(st, a, nullptr, e);
      gauss_points_of(st, e, [&](std::size_t g, std::size_t k) {
        st.rhov[g][d] = a[static_cast<std::size_t>(e)].dot(st.psi[k]);
      });
    }
  });
}

// The stress and the body-force density in one fit. The Cauchy stress is symmetric (every law
// gives sigma_ij = sigma_ji to the bit), so its Dim (Dim + 1) / 2 independent components are
// fitted and sigma^ is symmetric too.
template <int Dim>
void TlsMapping::fit_forces(RunState<Dim>& sim, const GaussPoints<Dim>& q) {
  auto& st = state<Dim>();
  const auto& P = sim.particles;
  const Index ne = st.recon.num_elements();
  constexpr int ns = Dim * (Dim + 1) / 2, nf = ns + Dim;
  // Field j < ns: the stress component (r, c) = comp[j]; field ns + d: (rho b)_d.
  auto rc = [](int j) {
    if constexpr (Dim == 3) {
      constexpr std::array<std::array<int, 2>, 6> comp{
          {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}}};
      return comp[static_cast<std::size_t>(j)];
    } else {
      constexpr std::array<std::array<int, 2>, 3> comp{{{0, 0}, {0, 1}, {1, 1}}};
      return comp[static_cast<std::size_t>(j)];
    }
  };
  // Surface elements (surface_volume): the stress of their material, int_e sigma^ =
  // sum_p V_p sigma_p (fitted conservatively there, plain elsewhere). With the adjoint strain
  // rate every element fits the stress so, which makes each particle's weight in the fits its
  // volume (omega_p = V_p, adjoint_gradients).
  const bool surface = settings_.surface_volume, everywhere = settings_.adjoint_strain_rate;
  values_and_sums(
      st.recon, P.x.size(), nf,
      [&](std::size_t i, int j) {
        if (j < ns) {
          const auto [r, c] = rc(j);
          return P.stress[i](r, c);
        }
        return P.density(i) * P.body[i][j - ns];
      },
      nf,
      [&](std::size_t i, int j) {
        if (j < ns) {
          if (!surface && !everywhere) return 0.0;
          const auto [r, c] = rc(j);
          return P.volume[i] * P.stress[i](r, c);
        }
        return P.mass[i] * P.body[i][j - ns];
      });
  std::array<typename BasicTlsReconstruction<Dim>::Field, nf> fields;
  for (int j = 0; j < nf; ++j) {
    auto& f = fields[static_cast<std::size_t>(j)];
    f.a = &st.fields[static_cast<std::size_t>(j)];
    if (j >= ns || surface || everywhere) f.integrals = integrals_of(j, ne);
    if (j < ns && surface && !everywhere) f.conservative = st.surface.data();
  }
  st.sigma.resize(q.size());
  st.rhob.resize(q.size());
  st.recon.fit_fields(values(), fields, [&](Index e) {
    for (int j = 0; j < nf; ++j) {
      auto& a = st.fields[static_cast<std::size_t>(j)];
      if (j >= ns || surface) apply_theta(st, a, j < ns ? st.surface.data() : nullptr, e);
      gauss_points_of(st, e, [&](std::size_t g, std::size_t k) {
        const double v = a[static_cast<std::size_t>(e)].dot(st.psi[k]);
        if (j < ns) {
          const auto [r, c] = rc(j);
          st.sigma[g](r, c) = v;
          st.sigma[g](c, r) = v;
        } else {
          st.rhob[g][j - ns] = v;
        }
      });
    }
  });
}

// TlsSettings::adjoint_strain_rate. The force's stress part, -sum_g w_g sigma^_g grad phi_i(x_g),
// is linear in the particle stresses through the stress fit (fit_forces: conservative in every
// element with c_e = sum_p V_p sigma_p, split by the domains; in surface elements positivity
// scales the terms beyond a_1 by theta_e): its power sum_g w_g sigma^_g : L_g is sum_p
// sigma_p : Z_p, Z_p the transpose of that fit applied to the element data abar_e =
// sum_{g in e} psi_g w_g L_g. The same transpose of w_g alone (abar_e = |Omega_e| e_1) gives
// omega_p: V_p, since every element's fit integrates to its particles' sum (a plain fit's
// weights are not the volumes and can be negative: -0.8 to 1.5 V_p on a stretched layout of the
// plate, where the particles without a positive one broke the symmetry). L_p = Z_p / omega_p.
template <int Dim>
const std::vector<Index>& TlsMapping::adjoint_gradients(RunState<Dim>& sim,
                                                        const GaussPoints<Dim>& q) {
  auto& st = state<Dim>();
  const auto& recon = st.recon;
  const Index ne = recon.num_elements();
  const auto E = static_cast<std::size_t>(ne);
  constexpr int nL = Dim * Dim, nf = nL + 1;  // L's components (row-major), then the weight
  st.abar.resize(nf);
  for (auto& a : st.abar) a.assign(E, TaylorVector<Dim>::Zero());
  // The Gauss points of an element are consecutive (fit_mass places n^Dim per active element).
  const std::size_t n = st.psi.size();
  parallel_for(static_cast<Index>(q.size() / n), [&](Index group) {
    const std::size_t g0 = static_cast<std::size_t>(group) * n;
    const auto e = static_cast<std::size_t>(q.element[g0]);
    for (std::size_t k = 0; k < n; ++k) {
      const Mat<Dim>& wl = st.wgrad[g0 + k];
      for (int r = 0; r < Dim; ++r)
        for (int c = 0; c < Dim; ++c)
          st.abar[static_cast<std::size_t>(r * Dim + c)][e] += st.psi[k] * wl(r, c);
      st.abar[nL][e] += st.psi[k] * q.w[g0 + k];
    }
  });
  if (settings_.surface_volume && settings_.positivity)  // apply_theta's transpose (fit_forces)
    for (std::size_t e = 0; e < E; ++e)
      if (st.surface[e] != 0 && st.theta[e] < 1.0)
        for (auto& a : st.abar) a[e].tail(a[e].size() - 1) *= st.theta[e];
  st.conservative.assign(E, 1);
  const auto np = static_cast<std::size_t>(recon.num_points());
  st.zbar.resize(np * nf);
  st.ibar.resize(E * nf);
  recon.fit_transpose(st.abar, st.conservative.data(), st.zbar, st.ibar);
  // In a distributed run the step's fits read the ghost particles: the same ones again (no
  // particle has moved since the mass sum's exchange, and reach() keeps the step's reach), with
  // their current volumes; each process transposes the fits of all the elements it holds, from
  // the Gauss points of its own (abar is zero in the others), and the parts at the ghosts go
  // back to their processes (sums of linear parts, so the whole transpose, to round-off).
  if (sim.comm) {
    append_ghosts(sim, *sim.comm, reach<Dim>(sim));
    if (static_cast<std::size_t>(sim.particles.size()) != np)
      throw std::logic_error(fmt::format(
          "TLS adjoint rate: {} particles with ghosts, the fits had {}", sim.particles.size(), np));
  }
  const auto& P = sim.particles;
  {
    // c_e = sum_p V_p sigma_p (times the overlap fraction with the domains): Z_p += V_p frac
    // ibar_e.
    auto add = [&](std::size_t e, std::size_t p, double fraction) {
      const double f = P.volume[p] * fraction;
      for (int j = 0; j < nf; ++j)
        st.zbar[p * nf + static_cast<std::size_t>(j)] +=
            f * st.ibar[static_cast<std::size_t>(j) * E + e];
    };
    // In parallel over the particles: the split's entries of a particle are all in the chunk
    // of binned particles that holds it (split_domains), a bin's particles in that bin alone.
    const auto& bins = recon.bins();
    if (settings_.domain_integrals) {
      for_each_chunk(static_cast<Index>(bins.order.size()), [&](int c, Index, Index) {
        for (const auto& t : split_.chunks[static_cast<std::size_t>(c)].entries)
          add(static_cast<std::size_t>(t.element), static_cast<std::size_t>(t.point), t.fraction);
      });
    } else {
      parallel_for(ne, [&](Index e) {
        for (const Index* p = bins.begin(e); p != bins.end(e); ++p)
          add(static_cast<std::size_t>(e), static_cast<std::size_t>(*p), 1.0);
      });
    }
  }
  if (sim.comm) {
    add_ghost_values_to_owners(sim, *sim.comm, std::span<double>(st.zbar), nf);
    remove_ghosts(sim);
  }
  const auto N = static_cast<std::size_t>(P.size());
  sim.mapped_gradient.resize(N);
  st.omega.resize(N);
  parallel_for(static_cast<Index>(N), [&](Index i) {
    const auto p = static_cast<std::size_t>(i);
    const double* z = st.zbar.data() + p * nf;
    const double omega = z[nL];
    st.omega[p] = omega;
    if (!(omega > 0.0)) return;
    Mat<Dim>& L = sim.mapped_gradient[p];
    for (int r = 0; r < Dim; ++r)
      for (int c = 0; c < Dim; ++c) L(r, c) = z[r * Dim + c] / omega;
  });
  no_weight_.clear();
  for (std::size_t p = 0; p < N; ++p)
    if (!(st.omega[p] > 0.0)) no_weight_.push_back(static_cast<Index>(p));
  double unweighted = static_cast<double>(no_weight_.size());
  if (sim.comm) sim.comm->sum(std::span<double>(&unweighted, 1));
  totals_.unweighted += static_cast<Index>(unweighted);
  return no_weight_;
}

template void TlsMapping::prepare_flags<1>(TlsMappingState<1>&);
template void TlsMapping::prepare_flags<2>(TlsMappingState<2>&);
template void TlsMapping::prepare_flags<3>(TlsMappingState<3>&);
template void TlsMapping::flag_element<1>(TlsMappingState<1>&, Index) const;
template void TlsMapping::flag_element<2>(TlsMappingState<2>&, Index) const;
template void TlsMapping::flag_element<3>(TlsMappingState<3>&, Index) const;
template std::array<Index, 2> TlsMapping::count_flags<1>(const TlsMappingState<1>&,
                                                         const CellBox<1>&) const;
template std::array<Index, 2> TlsMapping::count_flags<2>(const TlsMappingState<2>&,
                                                         const CellBox<2>&) const;
template std::array<Index, 2> TlsMapping::count_flags<3>(const TlsMappingState<3>&,
                                                         const CellBox<3>&) const;
template double TlsMapping::reach<1>(const RunState<1>&) const;
template double TlsMapping::reach<2>(const RunState<2>&) const;
template double TlsMapping::reach<3>(const RunState<3>&) const;
template void TlsMapping::split_domains<1>(const RunState<1>&, const BasicTlsReconstruction<1>&);
template void TlsMapping::split_domains<2>(const RunState<2>&, const BasicTlsReconstruction<2>&);
template void TlsMapping::split_domains<3>(const RunState<3>&, const BasicTlsReconstruction<3>&);
template void TlsMapping::fit_mass<1>(RunState<1>&, GaussPoints<1>&);
template void TlsMapping::fit_mass<2>(RunState<2>&, GaussPoints<2>&);
template void TlsMapping::fit_mass<3>(RunState<3>&, GaussPoints<3>&);
template void TlsMapping::fit_momentum<1>(RunState<1>&, const GaussPoints<1>&);
template void TlsMapping::fit_momentum<2>(RunState<2>&, const GaussPoints<2>&);
template void TlsMapping::fit_momentum<3>(RunState<3>&, const GaussPoints<3>&);
template void TlsMapping::fit_forces<1>(RunState<1>&, const GaussPoints<1>&);
template void TlsMapping::fit_forces<2>(RunState<2>&, const GaussPoints<2>&);
template void TlsMapping::fit_forces<3>(RunState<3>&, const GaussPoints<3>&);
template const std::vector<Index>& TlsMapping::adjoint_gradients<1>(RunState<1>&,
                                                                    const GaussPoints<1>&);
template const std::vector<Index>& TlsMapping::adjoint_gradients<2>(RunState<2>&,
                                                                    const GaussPoints<2>&);
template const std::vector<Index>& TlsMapping::adjoint_gradients<3>(RunState<3>&,
                                                                    const GaussPoints<3>&);

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
  w.i64(t.limited);    // since positivity and surface stress (earlier checkpoints end above)
  w.i64(t.surface);
  w.i64(t.unweighted);  // since the adjoint strain rate (earlier checkpoints end above)
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
  if (!r.done()) {
    t.limited = r.i64();
    t.surface = r.i64();
  }
  if (!r.done()) t.unweighted = r.i64();
  r.expect_done();
  totals_ = t;
}

}  // namespace mpm
