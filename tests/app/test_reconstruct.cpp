// The reconstruction playground (`mpm reconstruct`, D 5.2.3, Table 5.1).
#include <gtest/gtest.h>

#include <string>

#include "app/reconstruct.hpp"

namespace mpm {
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

}  // namespace
}  // namespace mpm
