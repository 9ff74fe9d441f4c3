#pragma once
// The 2D custom problem that the tests of bodies and materials vary:
// tests/benchmarks/test_custom_materials.cpp and tests/benchmarks/test_named_bodies.cpp.
#include <fmt/format.h>

#include <string>

namespace mpm::test {

// The law of the block's material: Mohr-Coulomb of little cohesion.
inline constexpr const char* kMohrCoulombLaw = R"toml(model = "mohr_coulomb"
density = 2000.0
youngs_modulus = 1e6
poisson_ratio = 0.3
cohesion = 50.0
friction_angle = 30.0)toml";

// The unit square (8 cells, quadratic B-splines, MUSL, dt = 1e-4 s to 1e-3 s) with a
// Mohr-Coulomb material of little cohesion (2000 kg/m^3, E = 1 MPa, nu = 0.3, c = 50 Pa,
// phi = 30 deg) under gravity on a fixed floor between free sides. `body`: the lines of the
// [body] table (body.material is on line 10 when `body` has three lines); `particles`: those of
// [particles]; `more`: further tables.
inline std::string mohr_coulomb_block(const std::string& body, const std::string& particles,
                                      const std::string& more = "") {
  return fmt::format(R"toml(benchmark = "custom"
[grid]
dimension = 2
cells = 8
min = [0.0, 0.0]
max = [1.0, 1.0]
[body]
{}
[particles]
{}
[time]
dt = 1e-4
end = 1e-3
[method]
scheme = "musl"
basis = "bspline"
degree = 2
[material]
{}
[loading]
body_force = ["0", "-10"]
[boundary]
left = "free"
right = "free"
bottom = "fixed"
top = "free"
{})toml",
                     body, particles, kMohrCoulombLaw, more);
}

// [material.copy]: a named material equal to mohr_coulomb_block's [material].
inline const std::string kMohrCoulombCopy =
    std::string("\n[material.copy]\n") + kMohrCoulombLaw + "\n";

}  // namespace mpm::test
