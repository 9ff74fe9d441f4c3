#include "grid/triangle_mesh.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace mpm {

namespace {
// Twice the signed area of (a, b, c): positive when counter-clockwise.
double twice_area(const Vec<2>& a, const Vec<2>& b, const Vec<2>& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
}
constexpr double kInsideTolerance = 1e-12;  // on barycentric coordinates (dimensionless)
}  // namespace

TriangleMesh::TriangleMesh(std::vector<Vec<2>> vertices, std::vector<Triangle> triangles,
                           std::map<std::string, std::vector<Edge>> boundaries, std::string source)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)), source_(std::move(source)) {
  if (vertices_.empty() || triangles_.empty())
    throw InputError(fmt::format("{}: no triangles ({} vertices, {} triangles)", source_,
                                 vertices_.size(), triangles_.size()));
  lo_ = hi_ = vertices_[0];
  for (const auto& v : vertices_) {
    if (!v.allFinite())
      throw InputError(fmt::format("{}: a vertex has a non-finite coordinate", source_));
    lo_ = lo_.cwiseMin(v);
    hi_ = hi_.cwiseMax(v);
  }
  const Index nv = num_vertices();
  // Areas, normals and the bucket grid are products of coordinate differences: a mesh whose
  // extent squared overflows has no area to speak of (refused, rather than called degenerate).
  if (!std::isfinite((hi_ - lo_).squaredNorm()) || !std::isfinite((hi_ - lo_).prod()))
    throw InputError(fmt::format(
        "{}: its coordinates span [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}], too large for areas in "
        "double precision; give the mesh in units that keep coordinates below about 1e150",
        source_, lo_[0], hi_[0], lo_[1], hi_[1]));
  // A triangle counts as degenerate below this area: 1e-12 of the bounding box's.
  const double min_area = 1e-12 * (hi_ - lo_).prod();
  area_.resize(triangles_.size());
  gradient_.resize(triangles_.size());
  for (std::size_t c = 0; c < triangles_.size(); ++c) {
    auto& t = triangles_[c];
    for (Index v : t)
      if (v < 0 || v >= nv)
        throw InputError(fmt::format("{}: triangle {} refers to vertex {}, outside 0..{}", source_,
                                     c, v, nv - 1));
    double a2 = twice_area(vertex(t[0]), vertex(t[1]), vertex(t[2]));
    if (a2 < 0.0) {
      std::swap(t[1], t[2]);
      a2 = -a2;
    }
    if (!(0.5 * a2 > min_area))
      throw InputError(fmt::format(
          "{}: triangle {} (vertices {}, {}, {}) has zero area (or below 1e-12 of the mesh's "
          "bounding box)",
          source_, c, t[0], t[1], t[2]));
    area_[c] = 0.5 * a2;
    // grad lambda_i = rot(x_k - x_j) / (2A) for (i, j, k) cyclic: the inward normal of the
    // opposite edge over twice the area.
    for (int i = 0; i < 3; ++i) {
      const Vec<2>& xj = vertex(t[static_cast<std::size_t>((i + 1) % 3)]);
      const Vec<2>& xk = vertex(t[static_cast<std::size_t>((i + 2) % 3)]);
      gradient_[c][static_cast<std::size_t>(i)] = Vec<2>(xj[1] - xk[1], xk[0] - xj[0]) / a2;
    }
  }
  // After the orientation fix every triangle is counter-clockwise, so two triangles sharing an
  // edge traverse it in opposite directions. The same directed edge twice means two triangles
  // on the same side of it: the mesh folds over itself (an inverted element), which the
  // orientation fix would otherwise hide.
  // Triangles per undirected edge: 1 on the mesh's outer boundary, 2 inside.
  std::map<std::pair<Index, Index>, int> edge_triangles;
  {
    std::map<std::pair<Index, Index>, std::size_t> directed;
    for (std::size_t c = 0; c < triangles_.size(); ++c)
      for (std::size_t i = 0; i < 3; ++i) {
        const auto key = std::make_pair(triangles_[c][i], triangles_[c][(i + 1) % 3]);
        const auto [it, fresh] = directed.emplace(key, c);
        if (!fresh)
          throw InputError(fmt::format(
              "{}: triangles {} and {} lie on the same side of their common edge ({}, {}): the "
              "mesh folds over itself (an inverted triangle) or holds a triangle twice",
              source_, it->second, c, key.first, key.second));
        ++edge_triangles[std::minmax(key.first, key.second)];
      }
  }
  for (auto& [name, edges] : boundaries) {
    Boundary b;
    for (const auto& e : edges) {
      for (Index v : e)
        if (v < 0 || v >= nv)
          throw InputError(
              fmt::format("{}: an edge of boundary \"{}\" refers to vertex {}, "
                          "outside 0..{}",
                          source_, name, v, nv - 1));
      // A named line that is no edge of the mesh would carry its conditions and loads nowhere.
      const auto found = edge_triangles.find(std::minmax(e[0], e[1]));
      if (found == edge_triangles.end())
        throw InputError(fmt::format(
            "{}: boundary \"{}\" has the edge ({}, {}) from ({:.6g}, {:.6g}) to ({:.6g}, {:.6g}), "
            "which is no edge of a triangle: a named boundary must follow the mesh's edges",
            source_, name, e[0], e[1], vertex(e[0])[0], vertex(e[0])[1], vertex(e[1])[0],
            vertex(e[1])[1]));
      if (found->second != 1) b.outer = false;
      b.vertices.push_back(e[0]);
      b.vertices.push_back(e[1]);
    }
    std::sort(b.vertices.begin(), b.vertices.end());
    b.vertices.erase(std::unique(b.vertices.begin(), b.vertices.end()), b.vertices.end());
    b.edges = std::move(edges);
    boundaries_.emplace(name, std::move(b));
  }
  build_buckets();
}

void TriangleMesh::build_buckets() {
  // About one triangle per bin on a uniform mesh; the bins follow the box's aspect ratio.
  const Vec<2> extent = (hi_ - lo_).cwiseMax(1e-300);
  const double per_bin = extent.prod() / static_cast<double>(triangles_.size());
  const double side = std::sqrt(per_bin);
  for (int d = 0; d < 2; ++d) {
    bins_[static_cast<std::size_t>(d)] =
        std::clamp<Index>(static_cast<Index>(std::ceil(extent[d] / side)), 1, 4096);
    bin_size_[d] = extent[d] / static_cast<double>(bins_[static_cast<std::size_t>(d)]);
  }
  const auto nb = static_cast<std::size_t>(bins_[0] * bins_[1]);
  auto bin_range = [&](Index c) {
    const auto& t = triangles_[static_cast<std::size_t>(c)];
    Vec<2> a = vertex(t[0]), b = vertex(t[0]);
    for (Index v : t) a = a.cwiseMin(vertex(v)), b = b.cwiseMax(vertex(v));
    std::array<Index, 4> r{};  // i0, i1, j0, j1 (inclusive)
    for (int d = 0; d < 2; ++d) {
      const Index last = bins_[static_cast<std::size_t>(d)] - 1;
      r[static_cast<std::size_t>(2 * d)] = std::clamp<Index>(
          static_cast<Index>(std::floor((a[d] - lo_[d]) / bin_size_[d])), 0, last);
      r[static_cast<std::size_t>(2 * d + 1)] = std::clamp<Index>(
          static_cast<Index>(std::floor((b[d] - lo_[d]) / bin_size_[d])), 0, last);
    }
    return r;
  };
  std::vector<Index> count(nb + 1, 0);
  for (Index c = 0; c < num_cells(); ++c) {
    const auto r = bin_range(c);
    for (Index j = r[2]; j <= r[3]; ++j)
      for (Index i = r[0]; i <= r[1]; ++i) ++count[static_cast<std::size_t>(j * bins_[0] + i + 1)];
  }
  for (std::size_t k = 0; k < nb; ++k) count[k + 1] += count[k];
  bin_start_ = count;
  bin_cells_.assign(static_cast<std::size_t>(bin_start_[nb]), 0);
  for (Index c = 0; c < num_cells(); ++c) {  // ascending c: each bin's list is sorted
    const auto r = bin_range(c);
    for (Index j = r[2]; j <= r[3]; ++j)
      for (Index i = r[0]; i <= r[1]; ++i)
        bin_cells_[static_cast<std::size_t>(count[static_cast<std::size_t>(j * bins_[0] + i)]++)] =
            c;
  }
}

std::array<double, 3> TriangleMesh::barycentric(Index c, const Vec<2>& x) const {
  const auto& t = triangles_[static_cast<std::size_t>(c)];
  const auto& g = gradient_[static_cast<std::size_t>(c)];
  // lambda_i is affine, 1 at vertex i and 0 at the others: lambda_i(x) = g_i . (x - x_j) for
  // any other vertex j; lambda_0 = 1 - lambda_1 - lambda_2 keeps the partition of unity exact.
  const Vec<2> d = x - vertex(t[0]);
  const double l1 = g[1].dot(d), l2 = g[2].dot(d);
  return {1.0 - l1 - l2, l1, l2};
}

Index TriangleMesh::cell_index(const Vec<2>& x) const {
  if (!x.allFinite()) return -1;
  std::array<Index, 2> b{};
  for (int d = 0; d < 2; ++d) {
    const double s = (x[d] - lo_[d]) / bin_size_[d];
    const auto n = bins_[static_cast<std::size_t>(d)];
    // A point on the box's upper side belongs to the last bin; farther out is outside (with the
    // tolerance of the barycentric test, measured in bins).
    if (s < -1e-9 || s > static_cast<double>(n) * (1.0 + 1e-9)) return -1;
    b[static_cast<std::size_t>(d)] = std::clamp<Index>(static_cast<Index>(std::floor(s)), 0, n - 1);
  }
  const auto k = static_cast<std::size_t>(b[1] * bins_[0] + b[0]);
  for (Index q = bin_start_[k]; q < bin_start_[k + 1]; ++q) {
    const Index c = bin_cells_[static_cast<std::size_t>(q)];
    const auto l = barycentric(c, x);
    if (l[0] >= -kInsideTolerance && l[1] >= -kInsideTolerance && l[2] >= -kInsideTolerance)
      return c;
  }
  return -1;
}

std::vector<std::string> TriangleMesh::boundary_names() const {
  std::vector<std::string> names;
  for (const auto& [name, b] : boundaries_) names.push_back(name);
  return names;
}

const TriangleMesh::Boundary& TriangleMesh::boundary(std::string_view name) const {
  const auto it = boundaries_.find(name);
  if (it == boundaries_.end()) {
    std::string valid;
    for (const auto& [n, b] : boundaries_)
      valid += fmt::format("{}\"{}\"", valid.empty() ? "" : ", ", n);
    throw InputError(fmt::format(
        "{}: no boundary named \"{}\"; {}", source_, name,
        valid.empty() ? std::string("it has no named boundaries") : "its boundaries are " + valid));
  }
  return it->second;
}

TriangleMesh structured_triangles(const Vec<2>& lo, const Vec<2>& hi, const IVec<2>& n,
                                  TrianglePattern pattern) {
  if (n[0] < 1 || n[1] < 1 || !(hi[0] > lo[0]) || !(hi[1] > lo[1]))
    throw InputError(
        fmt::format("structured triangles: need at least one cell per direction and "
                    "hi > lo (got {} x {} cells on [{}, {}] x [{}, {}])",
                    n[0], n[1], lo[0], hi[0], lo[1], hi[1]));
  const Index nx = n[0], ny = n[1];
  const Vec<2> h((hi[0] - lo[0]) / static_cast<double>(nx),
                 (hi[1] - lo[1]) / static_cast<double>(ny));
  std::vector<Vec<2>> v;
  // Corners: the same coordinates as Grid<2>::vertex (origin + h i).
  for (Index j = 0; j <= ny; ++j)
    for (Index i = 0; i <= nx; ++i)
      v.emplace_back(lo[0] + h[0] * static_cast<double>(i), lo[1] + h[1] * static_cast<double>(j));
  auto corner = [&](Index i, Index j) { return j * (nx + 1) + i; };
  std::vector<TriangleMesh::Triangle> t;
  for (Index j = 0; j < ny; ++j)
    for (Index i = 0; i < nx; ++i) {
      const Index a = corner(i, j), b = corner(i + 1, j), c = corner(i + 1, j + 1),
                  d = corner(i, j + 1);
      if (pattern == TrianglePattern::right) {
        t.push_back({a, b, c});
        t.push_back({a, c, d});
      } else {
        const auto m = static_cast<Index>(v.size());
        v.emplace_back(lo[0] + h[0] * (static_cast<double>(i) + 0.5),
                       lo[1] + h[1] * (static_cast<double>(j) + 0.5));
        t.push_back({a, b, m});
        t.push_back({b, c, m});
        t.push_back({c, d, m});
        t.push_back({d, a, m});
      }
    }
  std::map<std::string, std::vector<TriangleMesh::Edge>> bnd;
  for (Index i = 0; i < nx; ++i) {
    bnd["y-"].push_back({corner(i, 0), corner(i + 1, 0)});
    bnd["y+"].push_back({corner(i, ny), corner(i + 1, ny)});
  }
  for (Index j = 0; j < ny; ++j) {
    bnd["x-"].push_back({corner(0, j), corner(0, j + 1)});
    bnd["x+"].push_back({corner(nx, j), corner(nx, j + 1)});
  }
  return TriangleMesh(std::move(v), std::move(t), std::move(bnd), "the generated triangle mesh");
}

double TriangleMesh::min_altitude() const {
  double h = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < triangles_.size(); ++c) {
    const auto& t = triangles_[c];
    double longest = 0.0;
    for (std::size_t i = 0; i < 3; ++i)
      longest = std::max(longest, (vertex(t[(i + 1) % 3]) - vertex(t[i])).norm());
    h = std::min(h, 2.0 * area_[c] / longest);
  }
  return h;
}

TriangleMesh with_box_sides(const TriangleMesh& m) {
  // Boundary edges: an edge of one triangle only (counted without direction).
  std::map<std::pair<Index, Index>, int> count;
  for (Index c = 0; c < m.num_cells(); ++c) {
    const auto& t = m.cell_vertices(c);
    for (std::size_t i = 0; i < 3; ++i) ++count[std::minmax(t[i], t[(i + 1) % 3])];
  }
  std::map<std::string, std::vector<TriangleMesh::Edge>> boundaries;
  for (const auto& name : m.boundary_names()) boundaries[name] = m.boundary(name).edges;
  // The sides' names belong to the sides: a group of the file named so would silently take the
  // place of its side in boundary.left, ... and grid-side conditions.
  for (int d = 0; d < 2; ++d)
    for (int side = 0; side < 2; ++side)
      if (boundaries.contains(side_name(d, side)))
        throw InputError(fmt::format(
            "{}: its physical group \"{}\" has the name mpm gives the side {} = {:.9g} of the "
            "mesh's bounding box (boundary.{}); rename the group",
            m.source(), side_name(d, side), "xy"[d], side == 0 ? m.lower()[d] : m.upper()[d],
            d == 0 ? (side == 0 ? "left" : "right") : (side == 0 ? "bottom" : "top")));
  const double tol = 1e-10 * (m.upper() - m.lower()).norm();
  for (int d = 0; d < 2; ++d)
    for (int side = 0; side < 2; ++side) {
      const std::string name = side_name(d, side);
      const double line = side == 0 ? m.lower()[d] : m.upper()[d];
      std::vector<TriangleMesh::Edge> edges;
      for (const auto& [e, n] : count)
        if (n == 1 && std::abs(m.vertex(e.first)[d] - line) <= tol &&
            std::abs(m.vertex(e.second)[d] - line) <= tol)
          edges.push_back({e.first, e.second});
      if (!edges.empty()) boundaries[name] = std::move(edges);
    }
  std::vector<Vec<2>> vertices(static_cast<std::size_t>(m.num_vertices()));
  for (Index v = 0; v < m.num_vertices(); ++v) vertices[static_cast<std::size_t>(v)] = m.vertex(v);
  std::vector<TriangleMesh::Triangle> triangles(static_cast<std::size_t>(m.num_cells()));
  for (Index c = 0; c < m.num_cells(); ++c)
    triangles[static_cast<std::size_t>(c)] = m.cell_vertices(c);
  return TriangleMesh(std::move(vertices), std::move(triangles), std::move(boundaries), m.source());
}

std::optional<BoundaryLine> straight_boundary(const TriangleMesh& m, std::string_view name) {
  const auto& b = m.boundary(name);
  if (b.edges.empty()) return std::nullopt;
  const Vec<2> a = m.vertex(b.edges[0][0]);
  const Vec<2> t = m.vertex(b.edges[0][1]) - a;
  const Vec<2> n = Vec<2>(-t[1], t[0]) / t.norm();
  const double tol = 1e-10 * (m.upper() - m.lower()).norm();
  for (Index v : b.vertices)
    if (std::abs((m.vertex(v) - a).dot(n)) > tol) return std::nullopt;
  return BoundaryLine{a, n};
}

double triangle_stability_factor(TrianglePattern pattern) {
  return pattern == TrianglePattern::right ? 1.0 / std::sqrt(2.0) : 0.5;
}

}  // namespace mpm
