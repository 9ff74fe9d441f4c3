// Quadratic Powell-Sabin splines (basis/powell_sabin.hpp) on a criss-cross, a right-triangle, a
// randomly distorted criss-cross and a Gmsh mesh: the PS-6 refinement, PS triangles containing
// the PS points, the Hermite data that define the B-splines, partition of unity and
// nonnegativity, reproduction of quadratics, C1 continuity across every edge of the refinement
// and the local support. References are computed here from the geometry, never taken from the
// implementation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "basis/powell_sabin.hpp"
#include "setup/gmsh_mesh.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

using StencilT = PowellSabinBasis::StencilT;
using Tri = std::array<Vec<2>, 3>;

double cross(const Vec<2>& a, const Vec<2>& b) {
  return a[0] * b[1] - a[1] * b[0];
}

std::array<double, 3> bary(const Tri& t, const Vec<2>& x) {
  const double a = cross(t[1] - t[0], t[2] - t[0]);
  return {cross(t[1] - x, t[2] - x) / a, cross(t[2] - x, t[0] - x) / a,
          cross(t[0] - x, t[1] - x) / a};
}

// The gradient of the barycentric coordinate of t[j].
Vec<2> bary_gradient(const Tri& t, std::size_t j) {
  const Vec<2>& p = t[(j + 1) % 3];
  const Vec<2>& q = t[(j + 2) % 3];
  return Vec<2>(p[1] - q[1], q[0] - p[0]) / cross(t[1] - t[0], t[2] - t[0]);
}

Tri cell_triangle(const TriangleMesh& m, Index c) {
  const auto& t = m.cell_vertices(c);
  return {m.vertex(t[0]), m.vertex(t[1]), m.vertex(t[2])};
}

// Points of triangle t: its six quadratic domain points, its centroid and `random` random ones.
std::vector<Vec<2>> sample(const Tri& t, int random, std::mt19937& rng) {
  std::vector<Vec<2>> x = {t[0],
                           t[1],
                           t[2],
                           0.5 * (t[0] + t[1]),
                           0.5 * (t[1] + t[2]),
                           0.5 * (t[2] + t[0]),
                           (t[0] + t[1] + t[2]) / 3.0};
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < random; ++k) {
    double r1 = u(rng), r2 = u(rng);
    if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;
    x.push_back(t[0] + r1 * (t[1] - t[0]) + r2 * (t[2] - t[0]));
  }
  return x;
}

struct Case {
  std::string name;
  TriangleMesh mesh;
};

TriangleMesh distorted_criss_cross() {
  // Interior vertices (corners and centres) moved by up to 0.2 h in each direction.
  const auto base =
      structured_triangles({0.0, 0.0}, {2.0, 1.0}, {8, 4}, TrianglePattern::criss_cross);
  const double h = 0.25;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> shift(-0.2 * h, 0.2 * h);
  std::vector<Vec<2>> v;
  for (Index i = 0; i < base.num_vertices(); ++i) {
    Vec<2> x = base.vertex(i);
    const bool boundary = x[0] == 0.0 || x[0] == 2.0 || x[1] == 0.0 || x[1] == 1.0;
    if (!boundary) x += Vec<2>(shift(rng), shift(rng));
    v.push_back(x);
  }
  std::vector<TriangleMesh::Triangle> t;
  for (Index c = 0; c < base.num_cells(); ++c) t.push_back(base.cell_vertices(c));
  return TriangleMesh(v, t, {}, "distorted");
}

const std::vector<Case>& cases() {
  static const std::vector<Case> c = {
      {"criss-cross",
       structured_triangles({0.0, 0.0}, {1.0, 0.5}, {4, 3}, TrianglePattern::criss_cross)},
      {"right", structured_triangles({0.0, 0.0}, {1.0, 1.0}, {5, 4}, TrianglePattern::right)},
      {"distorted", distorted_criss_cross()},
      {"gmsh", read_gmsh_mesh(std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/square_v41.msh")},
  };
  return c;
}

// Interior edges: (cell, local edge) of both sides, found from the vertex pairs.
struct SharedEdge {
  Index c1, c2;
  int k1, k2;
};
std::vector<SharedEdge> shared_edges(const TriangleMesh& m, std::vector<std::array<int, 2>>* ends) {
  std::map<std::pair<Index, Index>, std::pair<Index, int>> first;
  std::vector<SharedEdge> out;
  for (Index c = 0; c < m.num_cells(); ++c)
    for (int k = 0; k < 3; ++k) {
      const auto& t = m.cell_vertices(c);
      const Index a = t[static_cast<std::size_t>(k)], b = t[static_cast<std::size_t>((k + 1) % 3)];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = first.find(key);
      if (it == first.end()) {
        first.emplace(key, std::make_pair(c, k));
      } else {
        out.push_back({it->second.first, c, it->second.second, k});
        first.erase(it);
      }
    }
  if (ends != nullptr) {
    ends->clear();
    for (const auto& [key, ck] : first) ends->push_back({static_cast<int>(ck.first), ck.second});
  }
  return out;
}

// Stencil entries by DOF.
std::map<Index, std::pair<double, Vec<2>>> by_dof(const StencilT& s) {
  std::map<Index, std::pair<double, Vec<2>>> out;
  for (std::size_t a = 0; a < 9; ++a) out[s.dof[a]] = {s.w[a], s.grad[a]};
  return out;
}

TEST(PowellSabin, RefinementSplitsEveryTriangleIntoSix) {
  for (const auto& [name, m] : cases()) {
    SCOPED_TRACE(name);
    const PowellSabinBasis basis(m);
    EXPECT_EQ(basis.num_dofs(), 3 * m.num_vertices());
    for (Index c = 0; c < m.num_cells(); ++c) {
      const Tri t = cell_triangle(m, c);
      const Vec<2>& z = basis.split_point(c);
      // Z is the incenter: inside, at the same distance from the three sides.
      std::array<double, 3> dist{};
      for (std::size_t k = 0; k < 3; ++k) {
        const Vec<2> e = t[(k + 1) % 3] - t[k];
        dist[k] = cross(e, z - t[k]) / e.norm();
      }
      EXPECT_GT(dist[0], 0.0);
      EXPECT_NEAR(dist[1], dist[0], 1e-14);
      EXPECT_NEAR(dist[2], dist[0], 1e-14);
      // R_k on edge k, strictly between its ends.
      for (int k = 0; k < 3; ++k) {
        const auto ku = static_cast<std::size_t>(k);
        const Vec<2> e = t[(ku + 1) % 3] - t[ku];
        const Vec<2> r = basis.edge_split_point(c, k) - t[ku];
        EXPECT_NEAR(cross(e, r) / e.squaredNorm(), 0.0, 1e-14);
        const double s = e.dot(r) / e.squaredNorm();
        EXPECT_GT(s, 0.01);
        EXPECT_LT(s, 0.99);
      }
      // Six counter-clockwise mini-triangles tiling the triangle.
      double area = 0.0;
      for (int mini = 0; mini < 6; ++mini) {
        const auto q = basis.mini_triangle(c, mini);
        const double a = 0.5 * cross(q[1] - q[0], q[2] - q[0]);
        EXPECT_GT(a, 0.0);
        area += a;
      }
      EXPECT_NEAR(area, m.cell_volume(c), 1e-14);
    }
    // Interior edges: the same R from both sides, on the segment between the two Z; boundary
    // edges: the midpoint.
    std::vector<std::array<int, 2>> boundary;
    const auto shared = shared_edges(m, &boundary);
    for (const auto& e : shared) {
      const Vec<2>& r1 = basis.edge_split_point(e.c1, e.k1);
      const Vec<2>& r2 = basis.edge_split_point(e.c2, e.k2);
      EXPECT_LT((r1 - r2).norm(), 1e-15);
      const Vec<2> z1 = basis.split_point(e.c1), z2 = basis.split_point(e.c2);
      const Vec<2> d = z2 - z1;
      EXPECT_NEAR(cross(d, r1 - z1) / d.squaredNorm(), 0.0, 1e-14);
      const double s = d.dot(r1 - z1) / d.squaredNorm();
      EXPECT_GT(s, 0.0);
      EXPECT_LT(s, 1.0);
    }
    for (const auto& [c, k] : boundary) {
      const Tri t = cell_triangle(m, c);
      const auto ku = static_cast<std::size_t>(k);
      EXPECT_LT((basis.edge_split_point(c, k) - 0.5 * (t[ku] + t[(ku + 1) % 3])).norm(), 1e-15);
    }
    EXPECT_EQ(static_cast<Index>(2 * shared.size() + boundary.size()), 3 * m.num_cells());
    // The PS points of each vertex: itself and the midpoints of the refinement's edges at it.
    std::vector<std::vector<Vec<2>>> expected(static_cast<std::size_t>(m.num_vertices()));
    for (Index v = 0; v < m.num_vertices(); ++v)
      expected[static_cast<std::size_t>(v)].push_back(m.vertex(v));
    // A reference to the structured binding: clang 14 (the sanitizer build) cannot capture one.
    const TriangleMesh& mesh = m;
    auto add_edge = [&](Index c, int k) {
      const auto& t = mesh.cell_vertices(c);
      const Vec<2>& r = basis.edge_split_point(c, k);
      for (int end = 0; end < 2; ++end) {
        const Index v = t[static_cast<std::size_t>((k + end) % 3)];
        expected[static_cast<std::size_t>(v)].push_back(0.5 * (mesh.vertex(v) + r));
      }
    };
    for (const auto& e : shared) add_edge(e.c1, e.k1);
    for (const auto& [c, k] : boundary) add_edge(c, k);
    for (Index c = 0; c < m.num_cells(); ++c)
      for (Index v : m.cell_vertices(c))
        expected[static_cast<std::size_t>(v)].push_back(0.5 * (m.vertex(v) + basis.split_point(c)));
    auto lex = [](const Vec<2>& a, const Vec<2>& b) {
      return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]);
    };
    for (Index v = 0; v < m.num_vertices(); ++v) {
      auto want = expected[static_cast<std::size_t>(v)];
      const auto got_span = basis.ps_points(v);
      std::vector<Vec<2>> got(got_span.begin(), got_span.end());
      ASSERT_EQ(got.size(), want.size());
      std::sort(want.begin(), want.end(), lex);
      std::sort(got.begin(), got.end(), lex);
      for (std::size_t p = 0; p < got.size(); ++p) EXPECT_LT((got[p] - want[p]).norm(), 1e-15);
    }
  }
}

TEST(PowellSabin, PsTrianglesContainThePsPoints) {
  for (const auto& [name, m] : cases()) {
    SCOPED_TRACE(name);
    const PowellSabinBasis basis(m);
    for (Index v = 0; v < m.num_vertices(); ++v) {
      const Tri& q = basis.ps_triangle(v);
      EXPECT_GT(cross(q[1] - q[0], q[2] - q[0]), 0.0);
      // Every PS point inside, and every side touching one (the sides support their hull).
      std::array<double, 3> closest = {1.0, 1.0, 1.0};
      for (const auto& p : basis.ps_points(v)) {
        const auto l = bary(q, p);
        for (std::size_t j = 0; j < 3; ++j) {
          EXPECT_GE(l[j], -1e-12) << "vertex " << v;
          closest[j] = std::min(closest[j], l[j]);
        }
      }
      for (double l : closest) EXPECT_LT(l, 1e-12) << "vertex " << v;
      for (int j = 0; j < 3; ++j)
        EXPECT_TRUE(basis.dof_position(3 * v + j) == q[static_cast<std::size_t>(j)]);
    }
  }
}

TEST(PowellSabin, HermiteDataAtTheVertices) {
  // N_ij has the value and gradient at V_i of L_ij, the barycentric coordinate of Q_ij in the
  // PS triangle, and value and gradient 0 at the other vertices (Dierckx 1997); from every
  // mini-triangle at the vertex.
  for (const auto& [name, m] : cases()) {
    SCOPED_TRACE(name);
    const PowellSabinBasis basis(m);
    StencilT s;
    for (Index c = 0; c < m.num_cells(); ++c) {
      const auto& t = m.cell_vertices(c);
      const double scale = 1.0 / std::sqrt(m.cell_volume(c));
      for (std::size_t a = 0; a < 3; ++a)
        for (int mini : {static_cast<int>(2 * a), static_cast<int>((2 * a + 5) % 6)}) {
          const Vec<2>& x = m.vertex(t[a]);
          basis.evaluate_piece(c, mini, x, s);
          for (std::size_t f = 0; f < 9; ++f) {
            const std::size_t b = f / 3, j = f % 3;
            ASSERT_EQ(s.dof[f], 3 * t[b] + static_cast<Index>(j));
            double w = 0.0;
            Vec<2> g = Vec<2>::Zero();
            if (b == a) {
              const Tri& q = basis.ps_triangle(t[a]);
              w = bary(q, x)[j];
              g = bary_gradient(q, j);
            }
            EXPECT_NEAR(s.w[f], w, 1e-14);
            EXPECT_LT((s.grad[f] - g).norm(), 1e-12 * scale);
          }
        }
    }
  }
}

TEST(PowellSabin, PartitionOfUnityAndNonnegative) {
  for (const auto& [name, m] : cases()) {
    SCOPED_TRACE(name);
    const PowellSabinBasis basis(m);
    std::mt19937 rng(5);
    StencilT s, piece;
    double worst_sum = 0.0, worst_grad = 0.0, lowest = 0.0;
    for (Index c = 0; c < m.num_cells(); ++c) {
      const auto& t = m.cell_vertices(c);
      const double scale = 1.0 / std::sqrt(m.cell_volume(c));
      for (int mini = 0; mini < 6; ++mini) {
        const auto q = basis.mini_triangle(c, mini);
        const auto points = sample(q, 8, rng);
        for (std::size_t p = 0; p < points.size(); ++p) {
          const Vec<2>& x = points[p];
          basis.evaluate_in(c, x, s);
          basis.evaluate_piece(c, mini, x, piece);
          for (const StencilT* st : {&s, &piece}) {
            double sum = 0.0;
            Vec<2> gsum = Vec<2>::Zero();
            for (std::size_t f = 0; f < 9; ++f) {
              EXPECT_EQ(st->dof[f], 3 * t[f / 3] + static_cast<Index>(f % 3));
              EXPECT_GE(st->w[f], -1e-14);
              lowest = std::min(lowest, st->w[f]);
              sum += st->w[f];
              gsum += st->grad[f];
            }
            EXPECT_NEAR(sum, 1.0, 1e-13);
            EXPECT_LT(gsum.norm(), 1e-12 * scale);
            worst_sum = std::max(worst_sum, std::abs(sum - 1.0));
            worst_grad = std::max(worst_grad, gsum.norm() / scale);
          }
          // Inside the mini-triangle (the random points) evaluate_in takes its piece.
          if (p >= 7)
            for (std::size_t f = 0; f < 9; ++f) {
              EXPECT_NEAR(s.w[f], piece.w[f], 1e-15);
              EXPECT_LT((s.grad[f] - piece.grad[f]).norm(), 1e-13 * scale);
            }
        }
      }
    }
    // The Bezier ordinates: in [0, 1] and summing to 1 at every domain point, so that the
    // nonnegativity and the partition of unity hold everywhere, not only where sampled.
    for (Index c = 0; c < m.num_cells(); ++c)
      for (std::size_t p = 0; p < PowellSabinBasis::kDomainPoints; ++p) {
        double sum = 0.0;
        for (int f = 0; f < 9; ++f) {
          const double o = basis.bezier_ordinates(c, f)[p];
          EXPECT_GE(o, -1e-14);
          EXPECT_LE(o, 1.0 + 1e-14);
          sum += o;
        }
        EXPECT_NEAR(sum, 1.0, 1e-14);
      }
    EXPECT_FALSE(basis.evaluate_point(m.upper() + Vec<2>(1.0, 1.0), s));
    std::cout << "[ info ] " << name << ": |sum N - 1| <= " << worst_sum
              << ", |sum grad N| * sqrt(area) <= " << worst_grad << ", min N = " << lowest << "\n";
  }
}

TEST(PowellSabin, ReproducesQuadratics) {
  // f = sum_ij c_ij N_ij with c_ij = f(V_i) + grad f(V_i) . (Q_ij - V_i): the spline with f's
  // value and gradient at every vertex, which is f itself since quadratics are PS splines.
  struct Quadratic {
    double c0, cx, cy, cxx, cxy, cyy;
    double value(const Vec<2>& x) const {
      return c0 + cx * x[0] + cy * x[1] + cxx * x[0] * x[0] + cxy * x[0] * x[1] + cyy * x[1] * x[1];
    }
    Vec<2> gradient(const Vec<2>& x) const {
      return {cx + 2.0 * cxx * x[0] + cxy * x[1], cy + cxy * x[0] + 2.0 * cyy * x[1]};
    }
  };
  std::mt19937 coef(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::vector<Quadratic> fs = {{1, 0, 0, 0, 0, 0},
                                     {0, 1, 0, 0, 0, 0},
                                     {0, 0, 1, 0, 0, 0},
                                     {0, 0, 0, 1, 0, 0},
                                     {0, 0, 0, 0, 1, 0},
                                     {0, 0, 0, 0, 0, 1},
                                     {u(coef), u(coef), u(coef), u(coef), u(coef), u(coef)}};
  for (const auto& [name, m] : cases()) {
    SCOPED_TRACE(name);
    const PowellSabinBasis basis(m);
    std::mt19937 rng(9);
    StencilT s;
    double worst_value = 0.0, worst_gradient = 0.0;
    for (std::size_t n = 0; n < fs.size(); ++n) {
      SCOPED_TRACE(n);
      const Quadratic& f = fs[n];
      std::vector<double> coefficient(static_cast<std::size_t>(basis.num_dofs()));
      for (Index v = 0; v < m.num_vertices(); ++v) {
        const Vec<2>& x = m.vertex(v);
        for (std::size_t j = 0; j < 3; ++j)
          coefficient[static_cast<std::size_t>(3 * v) + j] =
              f.value(x) + f.gradient(x).dot(basis.ps_triangle(v)[j] - x);
      }
      for (Index c = 0; c < m.num_cells(); ++c) {
        const double scale = 1.0 / std::sqrt(m.cell_volume(c));
        for (int mini = 0; mini < 6; ++mini)
          for (const auto& x : sample(basis.mini_triangle(c, mini), 3, rng)) {
            basis.evaluate_in(c, x, s);
            double value = 0.0;
            Vec<2> gradient = Vec<2>::Zero();
            for (std::size_t a = 0; a < 9; ++a) {
              const double ca = coefficient[static_cast<std::size_t>(s.dof[a])];
              value += ca * s.w[a];
              gradient += ca * s.grad[a];
            }
            const double dv = std::abs(value - f.value(x));
            const double dg = (gradient - f.gradient(x)).norm() / scale;
            EXPECT_LT(dv, 1e-13);
            EXPECT_LT(dg, 1e-13);
            worst_value = std::max(worst_value, dv);
            worst_gradient = std::max(worst_gradient, dg);
          }
      }
    }
    std::cout << "[ info ] " << name << ": quadratic reproduction, value error <= " << worst_value
              << ", gradient error * sqrt(area) <= " << worst_gradient << "\n";
  }
}

// The largest differences of value and gradient (times sqrt(area)) between two evaluations at
// the same point, over the union of their DOFs (a DOF missing from one counts as 0 there).
std::pair<double, double> difference(const StencilT& s1, const StencilT& s2, double scale) {
  auto e1 = by_dof(s1), e2 = by_dof(s2);
  for (const auto& [dof, wg] : e1) e2.try_emplace(dof, 0.0, Vec<2>::Zero());
  for (const auto& [dof, wg] : e2) e1.try_emplace(dof, 0.0, Vec<2>::Zero());
  double dw = 0.0, dg = 0.0;
  for (const auto& [dof, wg] : e1) {
    const auto& other = e2.at(dof);
    dw = std::max(dw, std::abs(wg.first - other.first));
    dg = std::max(dg, (wg.second - other.second).norm() / scale);
  }
  return {dw, dg};
}

TEST(PowellSabin, C1AcrossEveryEdgeOfTheRefinement) {
  const std::vector<double> along = {0.0, 0.1, 0.25, 0.5, 0.6180339887, 0.9, 1.0};
  for (const auto& [name, m] : cases()) {
    SCOPED_TRACE(name);
    const PowellSabinBasis basis(m);
    StencilT s1, s2;
    double worst_w = 0.0, worst_g = 0.0;
    auto check = [&](double scale) {
      const auto [dw, dg] = difference(s1, s2, scale);
      EXPECT_LT(dw, 1e-14);
      EXPECT_LT(dg, 1e-12);
      worst_w = std::max(worst_w, dw);
      worst_g = std::max(worst_g, dg);
    };
    // Inside each triangle: V_k Z between mini-triangles 2k - 1 and 2k, R_k Z between 2k and
    // 2k + 1 (the pieces extrapolated to the common edge).
    for (Index c = 0; c < m.num_cells(); ++c) {
      const double scale = 1.0 / std::sqrt(m.cell_volume(c));
      for (int k = 0; k < 3; ++k) {
        const Vec<2>& z = basis.split_point(c);
        const Vec<2>& v = m.vertex(m.cell_vertices(c)[static_cast<std::size_t>(k)]);
        const Vec<2>& r = basis.edge_split_point(c, k);
        for (double t : along) {
          const Vec<2> xv = v + t * (z - v), xr = r + t * (z - r);
          basis.evaluate_piece(c, (2 * k + 5) % 6, xv, s1);
          basis.evaluate_piece(c, 2 * k, xv, s2);
          check(scale);
          basis.evaluate_piece(c, 2 * k, xr, s1);
          basis.evaluate_piece(c, 2 * k + 1, xr, s2);
          check(scale);
        }
      }
    }
    // Across each interior mesh edge, both halves (V_a R and R V_b), from each triangle.
    for (const auto& e : shared_edges(m, nullptr)) {
      const auto& t = m.cell_vertices(e.c1);
      const Vec<2>& va = m.vertex(t[static_cast<std::size_t>(e.k1)]);
      const Vec<2>& vb = m.vertex(t[static_cast<std::size_t>((e.k1 + 1) % 3)]);
      const Vec<2>& r = basis.edge_split_point(e.c1, e.k1);
      const double scale = 1.0 / std::sqrt(std::min(m.cell_volume(e.c1), m.cell_volume(e.c2)));
      for (double u : along)
        for (const Vec<2>& x : {Vec<2>(va + u * (r - va)), Vec<2>(r + u * (vb - r))}) {
          basis.evaluate_in(e.c1, x, s1);
          basis.evaluate_in(e.c2, x, s2);
          check(scale);
          ASSERT_TRUE(basis.evaluate_point(x, s2));
          check(scale);
        }
    }
    std::cout << "[ info ] " << name << ": C1 jumps, value <= " << worst_w
              << ", gradient * sqrt(area) <= " << worst_g << "\n";
  }
}

TEST(PowellSabin, LocalSupport) {
  // N_ij vanishes outside the triangles at V_i: in each of them its value and gradient tend to 0
  // on the side opposite V_i (C1 against the zero outside), and the triangles without V_i do
  // not list it.
  const std::vector<double> along = {0.0, 0.2, 0.5, 0.7, 1.0};
  for (const auto& [name, m] : cases()) {
    SCOPED_TRACE(name);
    const PowellSabinBasis basis(m);
    StencilT s;
    for (Index c = 0; c < m.num_cells(); ++c) {
      const auto& t = m.cell_vertices(c);
      const double scale = 1.0 / std::sqrt(m.cell_volume(c));
      for (std::size_t a = 0; a < 3; ++a) {
        // The opposite side is edge k = a + 1, split at R_k into mini-triangles 2k and 2k + 1.
        const int k = static_cast<int>((a + 1) % 3);
        const Vec<2>& p = m.vertex(t[(a + 1) % 3]);
        const Vec<2>& q = m.vertex(t[(a + 2) % 3]);
        const Vec<2>& r = basis.edge_split_point(c, k);
        for (double u : along)
          for (int half = 0; half < 2; ++half) {
            const Vec<2> x = half == 0 ? Vec<2>(p + u * (r - p)) : Vec<2>(r + u * (q - r));
            basis.evaluate_piece(c, 2 * k + half, x, s);
            for (std::size_t j = 0; j < 3; ++j) {
              EXPECT_NEAR(s.w[3 * a + j], 0.0, 1e-15);
              EXPECT_LT(s.grad[3 * a + j].norm(), 1e-12 * scale);
            }
          }
      }
      // And nonzero inside: the sum of V_a's functions is 1 at V_a.
      StencilT sv;
      for (std::size_t a = 0; a < 3; ++a) {
        basis.evaluate_in(c, m.vertex(t[a]), sv);
        EXPECT_NEAR(sv.w[3 * a] + sv.w[3 * a + 1] + sv.w[3 * a + 2], 1.0, 1e-14);
      }
    }
    // The stencil of a point lists the functions of its triangle's vertices only.
    std::mt19937 rng(4);
    for (Index c = 0; c < m.num_cells(); ++c)
      for (const auto& x : sample(cell_triangle(m, c), 2, rng)) {
        ASSERT_TRUE(basis.evaluate_point(x, s));
        const Index cx = m.cell_index(x);
        const auto& t = m.cell_vertices(cx);
        for (std::size_t f = 0; f < 9; ++f) EXPECT_EQ(s.dof[f] / 3, t[f / 3]);
      }
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
