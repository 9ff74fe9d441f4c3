// The reconstruction playground (`mpm reconstruct`, D 5.2.3, Table 5.1).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "app/reconstruct.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(Reconstruct, TlsKeepsTheIntegralToRoundOff) {
  ReconstructOptions o;  // sin(x) + 2 on [0, 4 pi], 4 elements, quadratic TLS
  o.points = "random:3";
  o.seed = 7;
  const auto r = reconstruct(o);
  EXPECT_EQ(r.x.size(), 12u);
  EXPECT_LT(r.relative_integral_error, 1e-14);  // D Table 5.1: 2.79e-15
  EXPECT_LT(r.rms_error, 0.2);                  // D: 4.0e-2 for its (random) points
  EXPECT_NEAR(r.integral_exact, 8.0 * 3.14159265358979323846, 1e-12);
}

TEST(Reconstruct, TlsReproducesQuadraticsAndTheCubicSplineLines) {
  ReconstructOptions o;
  o.function = "3 - 2*x + 0.5*x^2";
  o.lower = "-1";
  o.upper = "2";
  o.cells = 5;
  o.points = "random:4";
  o.conservative = false;
  EXPECT_LT(reconstruct(o).rms_error, 1e-12);
  o.conservative = true;
  EXPECT_LT(reconstruct(o).rms_error, 1e-12);
  o.mapping = "cubic_spline";
  o.function = "3 - 2*x";
  EXPECT_LT(reconstruct(o).rms_error, 1e-12);
}

TEST(Reconstruct, DegenerateElementOfFigure55) {
  // [pi, 2 pi] holds only the shared face point pi and 5 pi / 3 (D Fig. 5.5): quadratic TLS is
  // singular there. Without completion: an error naming the element; the virtual point gives a
  // smaller error than reducing the basis (D Fig. 5.6 vs reduced basis).
  ReconstructOptions o;
  o.points = "list:0, pi/2, pi, 5*pi/3, 2.3*pi, 2.5*pi, 2.7*pi, 3.2*pi, 3.5*pi, 3.9*pi";
  o.share_faces = true;
  o.completion = "none";
  EXPECT_THROW(reconstruct(o), InputError);
  o.completion = "reduce";
  const double reduced = reconstruct(o).rms_error;
  o.completion = "virtual";
  const auto virt = reconstruct(o);
  EXPECT_LT(virt.rms_error, reduced);
  EXPECT_LT(virt.relative_integral_error, 1e-14);
}

TEST(Reconstruct, BadOptionsAreInputErrors) {
  ReconstructOptions o;
  o.mapping = "sph";
  EXPECT_THROW(reconstruct(o), InputError);
  o = {};
  o.points = "grid:3";
  EXPECT_THROW(reconstruct(o), InputError);
  o = {};
  o.upper = "-1";
  EXPECT_THROW(reconstruct(o), InputError);
  o = {};
  o.points = "list:100";
  EXPECT_THROW(reconstruct(o), InputError);
}

// A function with no finite value at a data point is refused with the point (issue 16, 12: "1/0"
// exited 0 and printed nan), in 1D and 2D.
TEST(Reconstruct, NonFiniteFunctionIsAnInputError) {
  for (int dim : {1, 2}) {
    ReconstructOptions o;
    o.dim = dim;
    o.function = "1/0";
    try {
      reconstruct(o);
      ADD_FAILURE() << dim << "D: accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--function \"1/0\" is not finite at the point"),
                std::string::npos)
          << e.what();
    }
  }
}

// TLS on triangles (D 6.2.2): a quadratic is reproduced to round-off by the plain and the
// conservative fit on every mesh kind, the integral is kept whatever the data, and the
// refusals name the option.
TEST(Reconstruct, TrianglesReproduceQuadraticsAndKeepTheIntegral) {
  ReconstructOptions o;
  o.dim = 2;
  o.function = "1 + x - 2*y + 0.5*x^2 - x*y + 0.25*y^2";
  o.lower = "0";
  o.upper = "1";
  o.cells = 3;
  o.points = "random:8";
  o.terms = 6;
  const std::vector<std::string> meshes{
      "right", "criss-cross", std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/square_v41.msh"};
  for (const auto& mesh : meshes) {
    o.mesh = mesh;
    for (bool conservative : {false, true}) {
      o.conservative = conservative;
      const auto r = reconstruct(o);
      EXPECT_LT(r.rms_error, 1e-12) << mesh << " " << conservative;
      EXPECT_LT(r.relative_integral_error, 1e-13) << mesh << " " << conservative;
    }
  }
  // sin(x) cos(y) over the domain with few points per triangle: the conservative fit keeps the
  // integral to round-off although the field is only approximated.
  o.mesh = "criss-cross";
  o.function = "sin(x)*cos(y)";
  o.upper = "5";
  o.cells = 4;
  o.points = "domain:300";
  o.conservative = true;
  const auto r = reconstruct(o);
  EXPECT_EQ(r.xy.size(), 300u);
  EXPECT_LT(r.relative_integral_error, 1e-13);
  EXPECT_NEAR(r.integral_exact, -0.68691371, 1e-7);  // D 6.2.1: -6.8691e-1
  o.points = "uniform:3";
  EXPECT_THROW(reconstruct(o), InputError);
  o.points = "random:4";
  o.strategy = "magic";
  EXPECT_THROW(reconstruct(o), InputError);
  o.strategy = "graded";
  o.mapping = "mls";
  EXPECT_THROW(reconstruct(o), InputError);
  o.mapping = "tls";
  o.dim = 1;
  EXPECT_THROW(reconstruct(o), InputError);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
