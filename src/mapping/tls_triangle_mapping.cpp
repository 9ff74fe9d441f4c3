// The TLS mapping on triangular meshes (tls.hpp, TlsMapping with a kTriangleMesh basis; D 6.1.2,
// 6.3): the reconstructions of map_mass, map_momentum and map_forces per triangle, compiled
// once. The basis evaluation and the assembly at the Gauss points are the rectangles'
// (quadrature.hpp, once per basis).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "mapping/tls.hpp"

namespace mpm {

TlsTriangleSettings tls_triangle_settings(const TlsSettings& s) {
  TlsTriangleSettings t;
  t.terms = s.terms;
  t.max_condition = s.max_condition;
  switch (s.completion) {
    case TlsCompletion::None:
      t.strategy = TlsTriangleStrategy::None;
      break;
    case TlsCompletion::Reduce:
      t.strategy = TlsTriangleStrategy::Reduce;
      break;
    case TlsCompletion::MinimumNorm:
      t.strategy = TlsTriangleStrategy::MinimumNorm;
      break;
    case TlsCompletion::Graded:
      t.strategy = TlsTriangleStrategy::Graded;
      break;
    case TlsCompletion::Virtual:
    case TlsCompletion::Neighbour:
      throw InputError(fmt::format(
          "method.tls_completion = \"{}\" completes the grid's rectangles; on triangles choose "
          "one of: none, reduce, min_norm, graded (or auto: reduce)",
          tls_completion_name(s.completion)));
  }
  // The collapsed n x n rule is exact for total degree 2n - 2: linear and quadratic Taylor
  // terms need n >= 2, or the Gauss points lose mass (D 5.3.2).
  if (s.gauss_points_used() < 2 && t.terms_used() > 1)
    throw InputError(fmt::format(
        "method.gauss_points = {} integrates only constants exactly on a triangle (the collapsed "
        "rule of n x n points is exact to degree 2n - 2); {} Taylor terms need at least 2",
        s.gauss_points_used(), t.terms_used()));
  validate(t);
  return t;
}

TlsTriangleMappingState::TlsTriangleMappingState(const TriangleMesh& mesh, const TlsSettings& s,
                                                 int per_cell_,
                                                 std::vector<std::array<Vec<2>, 3>> pieces_)
    : recon(mesh, tls_triangle_settings(s)), per_cell(per_cell_), pieces(std::move(pieces_)) {
  const GaussRule rule = gauss_legendre(s.gauss_points_used());
  for (std::size_t i = 0; i < rule.xi.size(); ++i)
    for (std::size_t j = 0; j < rule.xi.size(); ++j) {
      const double u = 0.5 * (1.0 + rule.xi[i]), v = 0.5 * (1.0 + rule.xi[j]);
      ref.emplace_back(u, v * (1.0 - u));
      ref_w.push_back(0.25 * rule.w[i] * rule.w[j] * (1.0 - u));
    }
}

namespace {
// st.integrated (TlsTriangleMappingState): the triangles this process integrates. In a
// distributed run a triangle's points are all here, own particles or ghosts (the ghost reach of
// one cell layer covers the triangles of a cell's neighbours, where a particle on a shared edge
// may be counted), and every process holding one of them sees the same lowest id: the triangle
// goes to the process that owns that particle. (Not the process of the triangle's cell layer, as
// the grid's elements go: a particle on a horizontal cell edge belongs to the layer above by
// Grid::cell_of but to the lower triangle by TriangleMesh::cell_index, and that layer may hold
// no particle of any process.)
void mark_integrated(const RunState<2>& sim, TlsTriangleMappingState& st) {
  const auto& recon = st.recon;
  const Index ne = recon.num_elements();
  st.integrated.assign(static_cast<std::size_t>(ne), 0);
  const Index own = sim.own_particles();
  const auto& id = sim.particles.id;
  parallel_for(ne, [&](Index e) {
    const auto pts = recon.points(e);
    if (pts.empty()) return;
    Index lowest = pts.front();
    if (sim.comm)
      for (const Index p : pts)
        if (id[static_cast<std::size_t>(p)] < id[static_cast<std::size_t>(lowest)]) lowest = p;
    st.integrated[static_cast<std::size_t>(e)] = lowest < own ? 1 : 0;
  });
}

// The mapping's summary of one step's fits over the triangles this process integrates: an
// element counts once, by the worse of its two systems (plain: stress; conservative: density,
// momentum, body force).
TlsReport summarise(const RunState<2>& sim, const TlsTriangleMappingState& st) {
  const TlsTriangleReconstruction& recon = st.recon;
  const TlsTriangleReport& rep = recon.report();
  TlsReport r;
  r.elements = rep.elements;
  r.outside = rep.outside;
  if (sim.comm != nullptr && rep.outside > 0) {  // this process's own particles only
    r.outside = 0;
    for (Index p = 0; p < sim.own_particles(); ++p)
      if (recon.mesh().cell_index(sim.particles.x[static_cast<std::size_t>(p)]) < 0) ++r.outside;
  }
  const int nb = recon.terms();
  for (Index e = 0; e < recon.num_elements(); ++e) {
    if (st.integrated[static_cast<std::size_t>(e)] == 0) continue;
    ++r.active;
    const TlsTriangleElementInfo& info = recon.element(e);
    const auto& a = info.plain;
    const auto& b = info.conservative;
    if (a.failed || b.failed) {
      if (r.failed++ == 0) {
        r.failed_element = e;
        r.failed_points = info.points;
        r.failed_condition = std::max(a.condition, b.condition);
      }
      continue;
    }
    if (!a.deficient && !b.deficient) ++r.full;
    if (a.terms < nb || b.terms < nb) ++r.reduced;
    if (a.rank < a.terms || b.rank < b.terms) ++r.truncated;
    const int rank = std::min(a.rank, b.rank);
    r.min_terms = r.min_terms > 0 ? std::min(r.min_terms, rank) : rank;
    r.max_condition = std::max({r.max_condition, a.condition_solved, b.condition_solved});
  }
  return r;
}

// st.integrals[e] = the sum of value(p) over the particles of triangle e.
template <class Value>
void triangle_sums(TlsTriangleMappingState& st, Value&& value) {
  const Index ne = st.recon.num_elements();
  st.integrals.resize(static_cast<std::size_t>(ne));
  parallel_for(ne, [&](Index e) {
    double c = 0.0;
    for (const Index p : st.recon.points(e)) c += value(static_cast<std::size_t>(p));
    st.integrals[static_cast<std::size_t>(e)] = c;
  });
}

// st.values[i] = value(i) for every particle (sized by the caller).
template <class Value>
void triangle_values(TlsTriangleMappingState& st, Value&& value) {
  parallel_for(static_cast<Index>(st.values.size()), [&](Index i) {
    st.values[static_cast<std::size_t>(i)] = value(static_cast<std::size_t>(i));
  });
}

// The reconstruction st.coef at every Gauss point (of triangle q.element[g]).
template <class Store>
void triangle_at_gauss(const TlsTriangleMappingState& st, const GaussPoints<2>& q, Store&& store) {
  parallel_for(static_cast<Index>(q.size()), [&](Index gi) {
    const auto g = static_cast<std::size_t>(gi);
    store(g, st.coef[static_cast<std::size_t>(q.element[g])].dot(st.psi[g]));
  });
}
}  // namespace

// A particle in a triangle lies in a cell (Grid::cell_of) between those of the triangle's corners
// along each axis, so a process whose particle is in it reaches every other particle of it
// within that many cells: the ghost reach that gives it every particle of the triangles its own
// are in (1 on the grid's triangles, whose corners lie on the next grid lines; a mesh from a
// file may have triangles across more cells).
double TlsMapping::triangle_reach(const TriangleMesh& mesh, const Grid<2>& grid) const {
  if (triangle_reach_mesh_ == &mesh) return triangle_reach_;
  Index layers = 1;
  for (Index c = 0; c < mesh.num_cells(); ++c)
    for (int d = 0; d < 2; ++d) {
      Index lo = std::numeric_limits<Index>::max(), hi = std::numeric_limits<Index>::min();
      for (const Index v : mesh.cell_vertices(c)) {
        const Index layer = grid.cell_of(mesh.vertex(v)[d], d);
        lo = std::min(lo, layer);
        hi = std::max(hi, layer);
      }
      layers = std::max(layers, hi - lo);
    }
  triangle_reach_mesh_ = &mesh;
  triangle_reach_ = static_cast<double>(layers);
  return triangle_reach_;
}

void TlsMapping::fit_mass_triangles(RunState<2>& sim, GaussPoints<2>& q) {
  dim_ = 2;
  auto& st = *triangles_;
  const auto& P = sim.particles;
  st.recon.set_points(P.x);
  mark_integrated(sim, st);
  triangle_report_ = summarise(sim, st);
  if (sim.comm) triangle_report_ = over_ranks(*sim.comm, triangle_report_);
  const TlsReport& rep = triangle_report_;
  accumulate(totals_, rep);
  if (rep.failed > 0)
    throw_fit_failure(sim.step, sim.time, rep, "triangle", std::to_string(rep.failed_element),
                      "reduce, min_norm or graded");
  q.clear();
  st.psi.clear();
  for (Index e = 0; e < st.recon.num_elements(); ++e) {
    // No particles: no reconstruction, no mass; another process's triangle: its Gauss points.
    if (st.integrated[static_cast<std::size_t>(e)] == 0) continue;
    for (int k = 0; k < st.per_cell; ++k) {
      const auto& v = st.pieces[static_cast<std::size_t>(e * st.per_cell + k)];
      const Vec<2> e1 = v[1] - v[0], e2 = v[2] - v[0];
      const double jacobian = std::abs(e1[0] * e2[1] - e1[1] * e2[0]);  // 2 |piece|
      for (std::size_t g = 0; g < st.ref.size(); ++g) {
        const Vec<2> x = v[0] + st.ref[g][0] * e1 + st.ref[g][1] * e2;
        q.add(x, jacobian * st.ref_w[g], e);
        st.psi.push_back(st.recon.basis(e, x));
      }
    }
  }
  triangle_sums(st, [&](std::size_t i) { return P.mass[i]; });
  st.values.resize(P.x.size());
  triangle_values(st, [&](std::size_t i) { return P.density(i); });
  st.recon.fit_conservative(st.values, st.integrals, st.coef);
  st.rho.resize(q.size());
  triangle_at_gauss(st, q, [&](std::size_t g, double v) { st.rho[g] = v; });
}

void TlsMapping::fit_momentum_triangles(RunState<2>& sim, const GaussPoints<2>& q) {
  auto& st = *triangles_;
  const auto& P = sim.particles;
  st.rhov.resize(q.size());
  st.values.resize(P.x.size());
  for (int d = 0; d < 2; ++d) {
    triangle_values(st, [&](std::size_t i) { return P.density(i) * P.v[i][d]; });
    triangle_sums(st, [&](std::size_t i) { return P.mass[i] * P.v[i][d]; });
    st.recon.fit_conservative(st.values, st.integrals, st.coef);
    triangle_at_gauss(st, q, [&](std::size_t g, double v) { st.rhov[g][d] = v; });
  }
}

void TlsMapping::fit_forces_triangles(RunState<2>& sim, const GaussPoints<2>& q) {
  auto& st = *triangles_;
  const auto& P = sim.particles;
  st.values.resize(P.x.size());
  st.sigma.resize(q.size());
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) {
      triangle_values(st, [&](std::size_t i) { return P.stress[i](r, c); });
      st.recon.fit_plain(st.values, st.coef);
      triangle_at_gauss(st, q, [&](std::size_t g, double v) { st.sigma[g](r, c) = v; });
    }
  st.rhob.resize(q.size());
  for (int d = 0; d < 2; ++d) {
    triangle_values(st, [&](std::size_t i) { return P.density(i) * P.body[i][d]; });
    triangle_sums(st, [&](std::size_t i) { return P.mass[i] * P.body[i][d]; });
    st.recon.fit_conservative(st.values, st.integrals, st.coef);
    triangle_at_gauss(st, q, [&](std::size_t g, double v) { st.rhob[g][d] = v; });
  }
}

}  // namespace mpm
