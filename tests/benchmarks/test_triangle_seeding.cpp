// Particles seeded per triangle (particles.per_triangle, model/problem.hpp
// seed_particles_in_triangles): the counts m k^2, every particle strictly inside its triangle,
// volumes that are exact equal shares of each triangle, and the first moment of each triangle's
// particles equal to the triangle's (equal-area parts); the configuration errors name the key.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "benchmarks/benchmarks.hpp"
#include "grid/triangle_mesh.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(TriangleSeeding, CountsAreMTimesKSquared) {
  struct Case {
    int n, m, k;
  };
  for (const Case c :
       {Case{1, 1, 1}, Case{3, 3, 1}, Case{4, 1, 2}, Case{6, 6, 1}, Case{9, 1, 3}, Case{12, 3, 2},
        Case{16, 1, 4}, Case{24, 6, 2}, Case{27, 3, 3}, Case{54, 6, 3}}) {
    const auto [m, k] = triangle_seed_pattern(c.n);
    EXPECT_EQ(m, c.m) << c.n;
    EXPECT_EQ(k, c.k) << c.n;
  }
  for (int n : {0, -3, 2, 5, 7, 8, 10, 11, 18, 20}) {
    EXPECT_EQ(triangle_seed_pattern(n).first, 0) << n;
  }
}

// A mesh with randomly moved interior vertices (every triangle a different shape).
TriangleMesh distorted_mesh() {
  const TriangleMesh base = structured_triangles(Vec<2>(0.0, 0.0), Vec<2>(2.0, 1.0), {6, 3},
                                                 TrianglePattern::criss_cross);
  std::vector<Vec<2>> v;
  for (Index i = 0; i < base.num_vertices(); ++i) v.push_back(base.vertex(i));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.06, 0.06);
  for (auto& x : v)
    if (x[0] > 1e-12 && x[0] < 2.0 - 1e-12 && x[1] > 1e-12 && x[1] < 1.0 - 1e-12)
      x += Vec<2>(u(rng), u(rng));
  std::vector<TriangleMesh::Triangle> t;
  for (Index c = 0; c < base.num_cells(); ++c) t.push_back(base.cell_vertices(c));
  return TriangleMesh(std::move(v), std::move(t), {}, "distorted");
}

TEST(TriangleSeeding, EqualSharesInsideEveryTriangleWithItsCentroid) {
  const TriangleMesh mesh = distorted_mesh();
  for (int n : {1, 3, 4, 6, 12, 16, 24, 27}) {
    SCOPED_TRACE(n);
    const Particles<2> P = seed_particles_in_triangles(mesh, n, 1000.0);
    ASSERT_EQ(P.size(), mesh.num_cells() * n);
    double volume = 0.0;
    for (Index c = 0; c < mesh.num_cells(); ++c) {
      const auto& t = mesh.cell_vertices(c);
      const Vec<2> centroid = (mesh.vertex(t[0]) + mesh.vertex(t[1]) + mesh.vertex(t[2])) / 3.0;
      Vec<2> first = Vec<2>::Zero();
      double vc = 0.0;
      for (Index a = 0; a < n; ++a) {
        const auto i = static_cast<std::size_t>(c * n + a);
        // Strictly inside: every barycentric coordinate positive, and located in this triangle.
        const auto l = mesh.barycentric(c, P.x[i]);
        for (double li : l) EXPECT_GT(li, 1e-3);
        EXPECT_EQ(mesh.cell_index(P.x[i]), c);
        EXPECT_EQ(P.x[i], P.x0[i]);
        EXPECT_NEAR(P.volume[i], mesh.cell_volume(c) / n, 1e-15);
        EXPECT_DOUBLE_EQ(P.mass[i], 1000.0 * P.volume[i]);
        first += P.volume[i] * P.x[i];
        vc += P.volume[i];
      }
      EXPECT_NEAR(vc, mesh.cell_volume(c), 1e-15);
      EXPECT_LT((first / vc - centroid).norm(), 1e-14) << c;
      volume += vc;
    }
    EXPECT_NEAR(volume, 2.0, 1e-13);
  }
  EXPECT_THROW(seed_particles_in_triangles(mesh, 5, 1.0), InputError);
}

std::string refusal(const std::vector<std::string>& sets, const std::string& example) {
  try {
    const Config cfg = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/" + example, sets);
    (void)make_problem(cfg);
  } catch (const InputError& e) {
    return e.what();
  }
  return {};
}

TEST(TriangleSeeding, ThePlateSeedsEveryTriangle) {
  const Config cfg = Config::load(std::string(MPM_SOURCE_DIR) + "/examples/plate_mms_2d.toml",
                                  {"method.basis=p1_triangles", "method.triangles=criss_cross",
                                   "grid.cells=3", "particles.per_triangle=12"});
  const auto pb = std::get<Problem<2>>(make_problem(cfg));
  EXPECT_EQ(pb.particles.size(), 3 * 3 * 4 * 12);
  double m = 0.0;
  for (double mp : pb.particles.mass) m += mp;
  EXPECT_NEAR(m, 1000.0, 1e-10);  // rho0 = 1000 kg/m^3 on the unit square
}

TEST(TriangleSeeding, BadInputNamesTheKey) {
  const auto basis = refusal({"particles.per_triangle=12"}, "plate_mms_2d.toml");
  EXPECT_NE(basis.find("particles.per_triangle"), std::string::npos) << basis;
  EXPECT_NE(basis.find("p1_triangles"), std::string::npos) << basis;
  const auto count =
      refusal({"method.basis=p1_triangles", "particles.per_triangle=5"}, "plate_mms_2d.toml");
  EXPECT_NE(count.find("m k^2"), std::string::npos) << count;
  EXPECT_NE(count.find("12, 16, 24"), std::string::npos) << count;
  const auto one_d = refusal({"particles.per_triangle=3"}, "vibrating_bar_small.toml");
  EXPECT_NE(one_d.find("1D"), std::string::npos) << one_d;
  const auto body =
      refusal({"method.basis=p1_triangles", "particles.per_triangle=3"}, "custom_plate_2d.toml");
  EXPECT_NE(body.find("body must be the grid"), std::string::npos) << body;
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
