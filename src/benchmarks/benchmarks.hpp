#pragma once
// Constructors of the built-in benchmarks (one file each).
#include "benchmarks/problem.hpp"

namespace mpm {

// Vibrating bar with fixed ends (D 3.4.1, 5.4.1; 004 4.5). Small deformation: exact solution
// u = v0/omega sin(omega t) sin(pi X/L), v = v0 cos(omega t) sin(pi X/L),
// sigma = v0 rho c sin(omega t) cos(pi X/L), omega = pi c / L (MEHODS.md closed forms; D 3.4.1
// writes the stress amplitude as v0 sqrt(E/rho), an erratum: it is v0 sqrt(E rho)).
// large = true: the same set-up without an exact solution (D Table 5.4).
Problem<1> make_vibrating_bar(const Config& cfg, bool large);

struct VibratingBarExact {
  double length, v0, density, wave_speed;
  ExactState<1> operator()(const Vec<1>& X, double t) const;
};

// 1D problem from the configuration alone: grid and body extents, initial velocity and stress
// as expressions of x, body force as an expression of x and t, fixed or free ends.
Problem<1> make_custom_1d(const Config& cfg);

// Material from the [material] keys for a problem in `dim` dimensions.
Material material_from_config(const Config& cfg, int dim);

}  // namespace mpm
