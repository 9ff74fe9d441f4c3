#include "basis/powell_sabin.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

namespace mpm {

namespace {

double cross(const Vec<2>& a, const Vec<2>& b) {
  return a[0] * b[1] - a[1] * b[0];
}

// The six domain points of mini-triangle m's Bezier net among the triangle's 19 (header), in
// the order A^2, B^2, C^2, AB, BC, CA of its vertices (A, B, C): (V_k, R_k, Z) for m = 2k,
// (R_k, V_k+1, Z) for m = 2k + 1.
constexpr std::array<std::array<int, 6>, 6> kNet = {{
    {0, 12, 18, 3, 15, 9},
    {12, 1, 18, 4, 10, 15},
    {1, 13, 18, 5, 16, 10},
    {13, 2, 18, 6, 11, 16},
    {2, 14, 18, 7, 17, 11},
    {14, 0, 18, 8, 9, 17},
}};

// The incenter's barycentric weights: the lengths of the opposite sides over the perimeter.
std::array<double, 3> incenter_weights(const std::array<Vec<2>, 3>& v) {
  const double l0 = (v[1] - v[2]).norm(), l1 = (v[2] - v[0]).norm(), l2 = (v[0] - v[1]).norm();
  const double p = l0 + l1 + l2;
  return {l0 / p, l1 / p, l2 / p};
}

// Counter-clockwise convex hull without collinear points (Andrew's monotone chain), starting at
// the leftmost, then lowest, point. Points within `tol` (twice an area) of a hull edge's line
// are dropped; ps_triangle_of places its lines against every point, so nothing is lost.
std::vector<Vec<2>> convex_hull(std::vector<Vec<2>> p, double tol) {
  std::sort(p.begin(), p.end(), [](const Vec<2>& a, const Vec<2>& b) {
    return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]);
  });
  std::vector<Vec<2>> h(2 * p.size());
  std::size_t k = 0;
  auto push = [&](const Vec<2>& q, std::size_t floor) {
    while (k >= floor && cross(h[k - 1] - h[k - 2], q - h[k - 2]) <= tol) --k;
    h[k++] = q;
  };
  for (const auto& q : p) push(q, 2);
  const std::size_t lower = k + 1;
  for (std::size_t i = p.size() - 1; i-- > 0;) push(p[i], lower);
  h.resize(k - 1);
  return h;
}

// The PS triangle of a vertex from its PS points (the choice in the header): the smallest
// triangle bounded by three supporting lines of the points' hull, along its edges or at its
// vertices along the bisectors of the edge normals.
std::array<Vec<2>, 3> ps_triangle_of(const std::vector<Vec<2>>& points) {
  Vec<2> lo = points[0], hi = points[0];
  for (const auto& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double extent = (hi - lo).norm();
  const auto hull = convex_hull(points, 1e-12 * extent * extent);
  const std::size_t n = hull.size();
  if (n < 3) throw InputError("Powell-Sabin basis: the PS points of a vertex are collinear");
  std::vector<Vec<2>> normal;  // outward unit normals of the candidate lines
  for (std::size_t k = 0; k < n; ++k) {
    const Vec<2> e = hull[(k + 1) % n] - hull[k];
    normal.emplace_back(Vec<2>(e[1], -e[0]).normalized());
  }
  for (std::size_t k = 0; k < n; ++k)
    normal.push_back((normal[(k + n - 1) % n] + normal[k]).normalized());
  // Each line at its supporting offset over all the points, so containment does not depend on
  // the hull's tolerance.
  std::vector<double> offset;
  for (const auto& nl : normal) {
    double h = -std::numeric_limits<double>::infinity();
    for (const auto& p : points) h = std::max(h, nl.dot(p));
    offset.push_back(h);
  }
  auto meet = [&](std::size_t a, std::size_t b) {
    const double det = cross(normal[a], normal[b]);
    return Vec<2>((offset[a] * normal[b][1] - offset[b] * normal[a][1]) / det,
                  (normal[a][0] * offset[b] - normal[b][0] * offset[a]) / det);
  };
  // Three lines bound a triangle when their outward normals positively span the plane: the
  // three turn the same way. Pairs of nearly parallel lines (sine below 1e-9) are skipped: their
  // triangle would be huge anyway.
  constexpr double kMinSine = 1e-9;
  const std::size_t m = normal.size();
  double best = std::numeric_limits<double>::infinity();
  std::array<Vec<2>, 3> tri{};
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = a + 1; b < m; ++b) {
      const double sab = cross(normal[a], normal[b]);
      if (std::abs(sab) < kMinSine) continue;
      for (std::size_t c = b + 1; c < m; ++c) {
        const double sbc = cross(normal[b], normal[c]), sca = cross(normal[c], normal[a]);
        const bool ccw = sab > 0.0 && sbc > kMinSine && sca > kMinSine;
        const bool cw = sab < 0.0 && sbc < -kMinSine && sca < -kMinSine;
        if (!ccw && !cw) continue;
        const Vec<2> p = meet(a, b), q = meet(b, c), r = meet(c, a);
        const double area = 0.5 * std::abs(cross(q - p, r - p));
        if (area < best) {
          best = area;
          tri = ccw ? std::array<Vec<2>, 3>{p, q, r} : std::array<Vec<2>, 3>{p, r, q};
        }
      }
    }
  if (!std::isfinite(best))
    throw InputError("Powell-Sabin basis: no PS triangle found for a vertex");
  return tri;
}

}  // namespace

PowellSabinBasis::PowellSabinBasis(const TriangleMesh& mesh) : mesh_(&mesh) {
  const Index nc = mesh.num_cells(), nv = mesh.num_vertices();
  cells_.resize(static_cast<std::size_t>(nc));
  // mu[c][k]: R_k = mu V_k + (1 - mu) V_k+1, the edge's split ratio seen from cell c.
  std::vector<std::array<double, 3>> mu(static_cast<std::size_t>(nc));
  std::vector<std::array<double, 3>> zw(static_cast<std::size_t>(nc));
  auto corners = [&](Index c) {
    const auto& t = mesh.cell_vertices(c);
    return std::array<Vec<2>, 3>{mesh.vertex(t[0]), mesh.vertex(t[1]), mesh.vertex(t[2])};
  };
  for (Index c = 0; c < nc; ++c) {
    const auto v = corners(c);
    const auto w = incenter_weights(v);
    zw[static_cast<std::size_t>(c)] = w;
    cells_[static_cast<std::size_t>(c)].z = w[0] * v[0] + w[1] * v[1] + w[2] * v[2];
  }

  // Edges: (low vertex, high vertex, cell, local edge k), sorted, so the (at most two, as the
  // mesh checks) triangles of an edge are adjacent.
  struct Side {
    Index lo, hi, cell;
    int k;
  };
  std::vector<Side> sides;
  sides.reserve(static_cast<std::size_t>(3 * nc));
  for (Index c = 0; c < nc; ++c) {
    const auto& t = mesh.cell_vertices(c);
    for (int k = 0; k < 3; ++k) {
      const Index a = t[static_cast<std::size_t>(k)], b = t[static_cast<std::size_t>((k + 1) % 3)];
      sides.push_back({std::min(a, b), std::max(a, b), c, k});
    }
  }
  std::sort(sides.begin(), sides.end(), [](const Side& x, const Side& y) {
    return std::tie(x.lo, x.hi, x.cell) < std::tie(y.lo, y.hi, y.cell);
  });
  struct EdgeSplit {
    Index a, b;
    Vec<2> r;
  };
  std::vector<EdgeSplit> edges;
  for (std::size_t s = 0; s < sides.size();) {
    const Side& s1 = sides[s];
    const auto c1 = static_cast<std::size_t>(s1.cell);
    const auto k1 = static_cast<std::size_t>(s1.k);
    const auto& t1 = mesh.cell_vertices(s1.cell);
    const Vec<2>& va = mesh.vertex(t1[k1]);
    const Vec<2>& vb = mesh.vertex(t1[(k1 + 1) % 3]);
    const bool shared =
        s + 1 < sides.size() && sides[s + 1].lo == s1.lo && sides[s + 1].hi == s1.hi;
    if (!shared) {
      const Vec<2> r = 0.5 * (va + vb);
      cells_[c1].r[k1] = r;
      mu[c1][k1] = 0.5;
      edges.push_back({s1.lo, s1.hi, r});
      s += 1;
      continue;
    }
    // The rule of the PS-6 split (Powell and Sabin 1977): R on the segment Z_1 Z_2, without
    // which the vertex data alone cannot make the spline C1 across the edge. With incenters
    // Z_1 R : R Z_2 = r_1 : r_2, so R lies between the incircles' points of contact.
    const Side& s2 = sides[s + 1];
    const auto c2 = static_cast<std::size_t>(s2.cell);
    const auto k2 = static_cast<std::size_t>(s2.k);
    const Vec<2>& z1 = cells_[c1].z;
    const Vec<2> d = cells_[c2].z - z1;
    const double t = cross(z1 - va, d) / cross(vb - va, d);  // R = va + t (vb - va)
    if (!(t > 1e-9 && t < 1.0 - 1e-9))
      throw InputError(fmt::format(
          "Powell-Sabin basis: the incenters of triangles {} and {} of {} are not on either side "
          "of their common edge ({}, {})",
          s1.cell, s2.cell, mesh.source(), s1.lo, s1.hi));
    const Vec<2> r = va + t * (vb - va);
    cells_[c1].r[k1] = r;
    cells_[c2].r[k2] = r;
    mu[c1][k1] = 1.0 - t;
    mu[c2][k2] = t;  // the second triangle runs along the edge from vb to va
    edges.push_back({s1.lo, s1.hi, r});
    s += 2;
  }

  // PS points: V_i, then (V_i + R_e) / 2 per edge, then (V_i + Z_c) / 2 per triangle.
  std::vector<Index> count(static_cast<std::size_t>(nv), 1);
  for (const auto& e : edges)
    ++count[static_cast<std::size_t>(e.a)], ++count[static_cast<std::size_t>(e.b)];
  for (Index c = 0; c < nc; ++c)
    for (Index v : mesh.cell_vertices(c)) ++count[static_cast<std::size_t>(v)];
  ps_start_.assign(static_cast<std::size_t>(nv) + 1, 0);
  for (std::size_t v = 0; v < static_cast<std::size_t>(nv); ++v)
    ps_start_[v + 1] = ps_start_[v] + count[v];
  ps_points_.resize(static_cast<std::size_t>(ps_start_.back()));
  std::vector<Index> next(ps_start_.begin(), ps_start_.end() - 1);
  auto add = [&](Index v, const Vec<2>& p) {
    ps_points_[static_cast<std::size_t>(next[static_cast<std::size_t>(v)]++)] = p;
  };
  for (Index v = 0; v < nv; ++v) add(v, mesh.vertex(v));
  for (const auto& e : edges) {
    add(e.a, 0.5 * (mesh.vertex(e.a) + e.r));
    add(e.b, 0.5 * (mesh.vertex(e.b) + e.r));
  }
  for (Index c = 0; c < nc; ++c)
    for (Index v : mesh.cell_vertices(c)) add(v, 0.5 * (mesh.vertex(v) + split_point(c)));

  ps_triangle_.resize(static_cast<std::size_t>(nv));
  for (Index v = 0; v < nv; ++v) {
    const auto p = ps_points(v);
    ps_triangle_[static_cast<std::size_t>(v)] =
        ps_triangle_of(std::vector<Vec<2>>(p.begin(), p.end()));
  }

  for (Index c = 0; c < nc; ++c) {
    Cell& cell = cells_[static_cast<std::size_t>(c)];
    const auto v = corners(c);
    const auto& t = mesh.cell_vertices(c);
    const auto& m = mu[static_cast<std::size_t>(c)];
    const auto& w = zw[static_cast<std::size_t>(c)];
    for (int mini = 0; mini < 6; ++mini) {
      const auto q = mini_triangle(c, mini);
      const double a2 = cross(q[1] - q[0], q[2] - q[0]);
      auto& g = cell.gradient[static_cast<std::size_t>(mini)];
      g[1] = Vec<2>(q[2][1] - q[0][1], q[0][0] - q[2][0]) / a2;
      g[2] = Vec<2>(q[0][1] - q[1][1], q[1][0] - q[0][0]) / a2;
      g[0] = -(g[1] + g[2]);
      cell.origin[static_cast<std::size_t>(mini)] = q[0];
    }
    // The domain points of the vertices' tangent planes (0-11, header order).
    std::array<Vec<2>, 12> own;
    for (std::size_t k = 0; k < 3; ++k) {
      own[k] = v[k];
      own[3 + 2 * k] = 0.5 * (v[k] + cell.r[k]);
      own[4 + 2 * k] = 0.5 * (v[(k + 1) % 3] + cell.r[k]);
      own[9 + k] = 0.5 * (v[k] + cell.z);
    }
    for (std::size_t a = 0; a < 3; ++a) {
      const auto& Q = ps_triangle(t[a]);
      const double q2 = cross(Q[1] - Q[0], Q[2] - Q[0]);
      const std::array<std::size_t, 4> mine = {a, 3 + 2 * a, 4 + 2 * ((a + 2) % 3), 9 + a};
      for (std::size_t j = 0; j < 3; ++j) {
        auto& o = cell.ordinate[3 * a + j];
        o.fill(0.0);
        // At V_a and its PS points the ordinates are those of N_ij's tangent plane at V_a, the
        // barycentric coordinate L_ij of Q_ij in the PS triangle (Dierckx 1997): nonnegative
        // because the PS triangle contains the PS points. The other vertices' ones are 0.
        const Vec<2>& q1 = Q[(j + 1) % 3];
        const Vec<2> e = Q[(j + 2) % 3] - q1;
        for (std::size_t p : mine) o[p] = cross(e, own[p] - q1) / q2;
        // C1 along the edges and across the split lines R_k Z: each remaining ordinate is the
        // combination of its neighbours with the weights of its domain point on their segment
        // (R_k = mu V_k + (1 - mu) V_k+1 between the two edge PS points, the midpoint of R_k Z
        // between those of V_k Z and V_k+1 Z); at Z, C1 across V_a Z makes the seven ordinates
        // around Z coplanar, and Z = sum_a z_a (V_a + Z) / 2 (Dierckx 1997; Speleers et al.
        // 2012).
        for (std::size_t k = 0; k < 3; ++k) {
          const std::size_t k1 = (k + 1) % 3;
          o[12 + k] = m[k] * o[3 + 2 * k] + (1.0 - m[k]) * o[4 + 2 * k];
          o[15 + k] = m[k] * o[9 + k] + (1.0 - m[k]) * o[9 + k1];
        }
        o[18] = w[0] * o[9] + w[1] * o[10] + w[2] * o[11];
      }
    }
  }
}

std::array<Vec<2>, 3> PowellSabinBasis::mini_triangle(Index cell, int mini) const {
  const auto& t = mesh_->cell_vertices(cell);
  const Cell& c = cells_[static_cast<std::size_t>(cell)];
  const auto k = static_cast<std::size_t>(mini / 2);
  if (mini % 2 == 0) return {mesh_->vertex(t[k]), c.r[k], c.z};
  return {c.r[k], mesh_->vertex(t[(k + 1) % 3]), c.z};
}

void PowellSabinBasis::evaluate_piece(Index cell, int mini, const Vec<2>& x, StencilT& s) const {
  const Cell& c = cells_[static_cast<std::size_t>(cell)];
  const auto mi = static_cast<std::size_t>(mini);
  const auto& g = c.gradient[mi];
  const Vec<2> d = x - c.origin[mi];
  const double l1 = g[1].dot(d), l2 = g[2].dot(d), l0 = 1.0 - l1 - l2;
  // Quadratic Bernstein polynomials in kNet order, and their gradients.
  const std::array<double, 6> b = {l0 * l0,       l1 * l1,       l2 * l2,
                                   2.0 * l0 * l1, 2.0 * l1 * l2, 2.0 * l2 * l0};
  const std::array<Vec<2>, 6> db = {2.0 * l0 * g[0],
                                    2.0 * l1 * g[1],
                                    2.0 * l2 * g[2],
                                    2.0 * (l1 * g[0] + l0 * g[1]),
                                    2.0 * (l2 * g[1] + l1 * g[2]),
                                    2.0 * (l0 * g[2] + l2 * g[0])};
  const auto& net = kNet[mi];
  const auto& t = mesh_->cell_vertices(cell);
  for (std::size_t f = 0; f < 9; ++f) {
    const auto& o = c.ordinate[f];
    double w = 0.0;
    Vec<2> gr = Vec<2>::Zero();
    for (std::size_t q = 0; q < 6; ++q) {
      const double oq = o[static_cast<std::size_t>(net[q])];
      w += oq * b[q];
      gr += oq * db[q];
    }
    s.dof[f] = 3 * t[f / 3] + static_cast<Index>(f % 3);
    s.w[f] = w;
    s.grad[f] = gr;
  }
}

void PowellSabinBasis::evaluate_in(Index cell, const Vec<2>& x, StencilT& s) const {
  const Cell& c = cells_[static_cast<std::size_t>(cell)];
  // The first mini-triangle containing x, else the one x is least outside of.
  int best = 0;
  double best_min = -std::numeric_limits<double>::infinity();
  for (std::size_t m = 0; m < 6; ++m) {
    const Vec<2> d = x - c.origin[m];
    const double l1 = c.gradient[m][1].dot(d), l2 = c.gradient[m][2].dot(d);
    const double lmin = std::min({1.0 - l1 - l2, l1, l2});
    if (lmin > best_min) best_min = lmin, best = static_cast<int>(m);
    if (lmin >= 0.0) break;
  }
  evaluate_piece(cell, best, x, s);
}

}  // namespace mpm
