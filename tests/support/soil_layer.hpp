#pragma once
// A soil layer at rest that several tests step: tests/benchmarks/test_geostatic.cpp (it stays
// still) and tests/scheme/test_constraints.cpp (its reactions).

namespace mpm::test {

// A Mohr-Coulomb layer 1 m deep on a fixed base between rollers, its top on a grid line, under
// gravity, elastic at K0 = 0.5 (c = 10 kPa, phi = 30 deg).
inline constexpr const char* kK0Layer2D = R"toml(benchmark = "custom"
[grid]
dimension = 2
cells = 4
min = [0.0, 0.0]
max = [1.0, 1.5]
[body]
min = [0.0, 0.0]
max = [1.0, 1.0]
[particles]
per_cell = 2
[time]
dt = 1e-4
end = 2e-2
[material]
model = "mohr_coulomb"
density = 2000.0
youngs_modulus = 20e6
poisson_ratio = 0.3
cohesion = 10e3
friction_angle = 30.0
[boundary]
left = "roller"
right = "roller"
bottom = "fixed"
top = "free"
[loading]
body_force = ["0", "-9.81"]
[initial]
geostatic = "k0"
k0 = 0.5
)toml";

}  // namespace mpm::test
