#include "grid/body_mesh.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace mpm {

namespace {

// Dim! times the signed volume of the simplex (positive: counter-clockwise triangle,
// right-handed tetrahedron).
template <int Dim>
double scaled_volume(const std::array<Vec<Dim>, Dim + 1>& x) {
  Mat<Dim> J;
  for (int d = 0; d < Dim; ++d) J.col(d) = x[static_cast<std::size_t>(d) + 1] - x[0];
  return J.determinant();
}

template <int Dim>
std::string vertex_list(const typename BodyMesh<Dim>::Element& e) {
  std::string s;
  for (Index v : e) s += (s.empty() ? "" : ", ") + std::to_string(v);
  return s;
}

}  // namespace

template <int Dim>
BodyMesh<Dim>::BodyMesh(std::vector<Vec<Dim>> vertices, std::vector<Element> elements,
                        std::vector<std::size_t> tags, std::vector<int> group,
                        std::vector<std::string> group_names, std::string source)
    : vertices_(std::move(vertices)),
      elements_(std::move(elements)),
      tags_(std::move(tags)),
      group_(std::move(group)),
      group_names_(std::move(group_names)),
      source_(std::move(source)) {
  const char* kind = Dim == 2 ? "triangle" : "tetrahedron";
  if (vertices_.empty() || elements_.empty())
    throw InputError(fmt::format("{}: no {} ({} vertices, {} elements)", source_,
                                 Dim == 2 ? "triangles" : "tetrahedra", vertices_.size(),
                                 elements_.size()));
  if (tags_.size() != elements_.size() || group_.size() != elements_.size())
    throw std::logic_error("BodyMesh: one tag and one group per element");
  lo_ = hi_ = vertices_[0];
  for (const auto& v : vertices_) {
    if (!v.allFinite())
      throw InputError(fmt::format("{}: a vertex has a non-finite coordinate", source_));
    lo_ = lo_.cwiseMin(v);
    hi_ = hi_.cwiseMax(v);
  }
  if (!std::isfinite((hi_ - lo_).prod()) || !std::isfinite((hi_ - lo_).squaredNorm()))
    throw InputError(fmt::format(
        "{}: its coordinates span a box too large for volumes in double precision; give the "
        "mesh in units that keep coordinates below about 1e100",
        source_));
  const auto nv = static_cast<Index>(vertices_.size());
  volume_.resize(elements_.size());
  for (std::size_t e = 0; e < elements_.size(); ++e) {
    auto& el = elements_[e];
    for (Index v : el)
      if (v < 0 || v >= nv)
        throw InputError(fmt::format("{}: {} {} refers to vertex {}, outside 0..{}", source_, kind,
                                     tags_[e], v, nv - 1));
    if (group_[e] < -1 || group_[e] >= static_cast<int>(group_names_.size()))
      throw std::logic_error("BodyMesh: a group index out of range");
    std::array<Vec<Dim>, Dim + 1> x;
    double longest = 0.0;
    for (std::size_t a = 0; a <= Dim; ++a) {
      x[a] = vertex(el[a]);
      for (std::size_t b = 0; b < a; ++b) longest = std::max(longest, (x[a] - x[b]).norm());
    }
    double v = scaled_volume<Dim>(x);
    if (v < 0.0) {  // turned: the volume is positive from here on
      std::swap(el[0], el[1]);
      v = -v;
    }
    const double factorial = Dim == 2 ? 2.0 : 6.0;
    volume_[e] = v / factorial;
    if (!(volume_[e] > 1e-12 * std::pow(longest, Dim)))
      throw InputError(fmt::format(
          "{}: {} {} (vertices {}) has zero {} (below 1e-12 of its longest edge to the power "
          "{}): a body mesh's elements must enclose material",
          source_, kind, tags_[e], vertex_list<Dim>(el), Dim == 2 ? "area" : "volume", Dim));
    total_ += volume_[e];
  }
}

template <int Dim>
double BodyMesh<Dim>::min_angle(Index e) const {
  const Element& el = element(e);
  double smallest = std::numbers::pi;  // [rad]
  if constexpr (Dim == 2) {
    for (std::size_t i = 0; i < 3; ++i) {
      const Vec<2> a = vertex(el[(i + 1) % 3]) - vertex(el[i]);
      const Vec<2> b = vertex(el[(i + 2) % 3]) - vertex(el[i]);
      smallest = std::min(smallest, std::atan2(std::abs(a[0] * b[1] - a[1] * b[0]), a.dot(b)));
    }
  } else {
    // The dihedral angle at edge (i, j) is the angle between the faces opposite k and l, pi
    // minus the angle between their outward normals.
    std::array<Vec<3>, 4> n;
    for (std::size_t k = 0; k < 4; ++k) {
      const Vec<3>& a = vertex(el[(k + 1) % 4]);
      const Vec<3>& b = vertex(el[(k + 2) % 4]);
      const Vec<3>& c = vertex(el[(k + 3) % 4]);
      Vec<3> m = (b - a).cross(c - a);
      if (m.dot(vertex(el[k]) - a) > 0.0) m = -m;  // outward: away from the opposite vertex
      n[k] = m.normalized();
    }
    for (std::size_t k = 0; k < 4; ++k)
      for (std::size_t l = k + 1; l < 4; ++l)
        smallest =
            std::min(smallest, std::numbers::pi - std::acos(std::clamp(n[k].dot(n[l]), -1.0, 1.0)));
  }
  return smallest * 180.0 / std::numbers::pi;
}

template <int Dim>
std::array<Index, Dim> BodyMesh<Dim>::bin_of(const Vec<Dim>& x) const {
  std::array<Index, Dim> b;
  for (int d = 0; d < Dim; ++d) {
    const auto D = static_cast<std::size_t>(d);
    const double s = (x[d] - lo_[d]) / (hi_[d] - lo_[d]) * static_cast<double>(bins_[D]);
    b[D] = std::clamp<Index>(static_cast<Index>(std::floor(s)), 0, bins_[D] - 1);
  }
  return b;
}

template <int Dim>
void BodyMesh<Dim>::build_buckets() const {
  // About one element per bin: bins per direction ~ elements^(1/Dim), in proportion to the box.
  const double per = std::pow(static_cast<double>(elements_.size()), 1.0 / Dim);
  for (int d = 0; d < Dim; ++d)
    bins_[static_cast<std::size_t>(d)] = std::max<Index>(1, std::llround(per));
  auto flat = [&](const std::array<Index, Dim>& b) {
    Index k = 0;
    for (int d = Dim - 1; d >= 0; --d)
      k = k * bins_[static_cast<std::size_t>(d)] + b[static_cast<std::size_t>(d)];
    return k;
  };
  Index total = 1;
  for (Index n : bins_) total *= n;
  std::vector<std::vector<Index>> lists(static_cast<std::size_t>(total));
  for (std::size_t e = 0; e < elements_.size(); ++e) {
    Vec<Dim> a = vertex(elements_[e][0]), b = a;
    for (Index v : elements_[e]) a = a.cwiseMin(vertex(v)), b = b.cwiseMax(vertex(v));
    const auto from = bin_of(a), to = bin_of(b);
    std::array<Index, Dim> i = from;
    while (true) {
      lists[static_cast<std::size_t>(flat(i))].push_back(static_cast<Index>(e));
      int d = 0;
      for (; d < Dim; ++d) {
        const auto D = static_cast<std::size_t>(d);
        if (++i[D] <= to[D]) break;
        i[D] = from[D];
      }
      if (d == Dim) break;
    }
  }
  bin_start_.assign(1, 0);
  for (const auto& l : lists) {
    bin_elements_.insert(bin_elements_.end(), l.begin(), l.end());
    bin_start_.push_back(static_cast<Index>(bin_elements_.size()));
  }
}

template <int Dim>
Index BodyMesh<Dim>::flat_bin(const std::array<Index, Dim>& b) const {
  Index k = 0;
  for (int d = Dim - 1; d >= 0; --d)
    k = k * bins_[static_cast<std::size_t>(d)] + b[static_cast<std::size_t>(d)];
  return k;
}

template <int Dim>
double BodyMesh<Dim>::chord_above(Index e, const Vec<Dim>& x) const {
  // The element is the intersection of the half-spaces n_f . (y - p_f) <= 0 of its faces f
  // (outward normals n_f, p_f a vertex of f); on the line y(s) = (x lateral, s) each bounds s
  // from above (n_v > 0) or below (n_v < 0), or holds everywhere or nowhere (n_v = 0).
  constexpr int V = Dim - 1;  // the vertical axis
  const Element& el = element(e);
  double lo = x[V], hi = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f <= Dim; ++f) {
    // The face opposite vertex f.
    const Vec<Dim>& p = vertex(el[(f + 1) % (Dim + 1)]);
    Vec<Dim> n;
    if constexpr (Dim == 2) {
      const Vec<2> t = vertex(el[(f + 2) % 3]) - p;
      n = Vec<2>(t[1], -t[0]);
    } else {
      n = (vertex(el[(f + 2) % 4]) - p).cross(vertex(el[(f + 3) % 4]) - p);
    }
    if (n.dot(vertex(el[f]) - p) > 0.0) n = -n;  // outward
    double lateral = 0.0;
    for (int d = 0; d < V; ++d) lateral += n[d] * (x[d] - p[d]);
    if (n[V] > 0.0) {
      hi = std::min(hi, p[V] - lateral / n[V]);
    } else if (n[V] < 0.0) {
      lo = std::max(lo, p[V] - lateral / n[V]);
    } else {
      // A vertical face: the line is outside, or on it (then it counts for the element on the
      // face's far side only: outward normal's first non-zero component negative).
      if (lateral > 0.0) return 0.0;
      if (lateral == 0.0) {
        int d = 0;
        while (d < V && n[d] == 0.0) ++d;
        if (d == V || n[d] > 0.0) return 0.0;
      }
    }
  }
  return std::max(0.0, hi - lo);
}

template <int Dim>
double BodyMesh<Dim>::integral_above(const Vec<Dim>& x,
                                     const std::function<double(Index)>& weight) const {
  if (bin_start_.empty()) build_buckets();
  constexpr auto V = static_cast<std::size_t>(Dim - 1);
  auto b = bin_of(x);
  const Index first = b[V];
  double sum = 0.0;
  for (Index j = first; j < bins_[V]; ++j) {
    b[V] = j;
    const auto k = static_cast<std::size_t>(flat_bin(b));
    for (Index i = bin_start_[k]; i < bin_start_[k + 1]; ++i) {
      const Index e = bin_elements_[static_cast<std::size_t>(i)];
      // Each element once: in the lowest of its bins at or above x's.
      Vec<Dim> low = x;
      low[Dim - 1] = vertex(element(e)[0])[Dim - 1];
      for (Index v : element(e)) low[Dim - 1] = std::min(low[Dim - 1], vertex(v)[Dim - 1]);
      if (std::max(bin_of(low)[V], first) != j) continue;
      const double c = chord_above(e, x);
      if (c > 0.0) sum += weight(e) * c;
    }
  }
  return sum;
}

template <int Dim>
Index BodyMesh<Dim>::other_element_holding(const Vec<Dim>& x, Index except) const {
  if (bin_start_.empty()) build_buckets();
  const auto k = flat_bin(bin_of(x));
  for (Index j = bin_start_[static_cast<std::size_t>(k)];
       j < bin_start_[static_cast<std::size_t>(k) + 1]; ++j) {
    const Index e = bin_elements_[static_cast<std::size_t>(j)];
    if (e == except) continue;
    const Element& el = element(e);
    Mat<Dim> J;
    for (int d = 0; d < Dim; ++d)
      J.col(d) = vertex(el[static_cast<std::size_t>(d) + 1]) - vertex(el[0]);
    const Vec<Dim> lambda = J.partialPivLu().solve(x - vertex(el[0]));
    if (lambda.minCoeff() > 1e-10 && 1.0 - lambda.sum() > 1e-10) return e;
  }
  return -1;
}

template class BodyMesh<2>;
template class BodyMesh<3>;

}  // namespace mpm
