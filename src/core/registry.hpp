#pragma once
// The single list of every run-time choice (config values and `mpm list`). The configuration
// schema takes its allowed choices from here, so a name exists in exactly one place.
#include <span>
#include <string_view>

namespace mpm::registry {

struct Entry {
  std::string_view name;
  std::string_view description;
};

inline constexpr Entry kBenchmarks[] = {
    {"vibrating_bar",
     "1D bar with fixed ends, small deformation, exact solution (D 3.4.1, 5.4.1; Table 3.1)"},
    {"vibrating_bar_large",
     "1D bar with fixed ends, large deformation (D 5.4.1, Table 5.4); no exact solution"},
    {"column_compaction",
     "1D column under a ramped body force, quasi-static exact solution (D 5.4.2, Table 5.6)"},
    {"traction_bar",
     "1D neo-Hookean bar, fixed end, dynamic end traction, exact stress (D 4.6.2, eq. 4.93)"},
    {"mms_1d",
     "1D neo-Hookean manufactured solution, body force from the exact displacement (003)"},
    {"custom",
     "1D or 2D (grid.dimension) problem built from the config alone: extents, fields and "
     "forces by expression, side conditions, face tractions, optional exact solution"},
    {"plate_mms_2d",
     "2D axis-aligned vibration of a unit square, neo-Hookean manufactured solution (001, D "
     "3.4.1)"},
};

inline constexpr Entry kBases[] = {
    {"linear", "piecewise-linear (P1) nodal basis, tensor product (D 2.5)"},
    {"ugimp", "uniform GIMP: P1 averaged over the initial particle domain (D 2.6.4, eq. 2.61)"},
    {"cpgimp", "contiguous-particle GIMP: particle domain sized by the diagonal of F (D 2.6.4)"},
    {"cpdi", "CPDI: domain convected by F, P1 interpolated at its corners (D 2.6.4, eq. 2.64)"},
    {"cpdi2", "CPDI2: quadrilateral domains, corners moved with the grid velocity (D 2.6.4; 2D)"},
    {"bspline",
     "B-splines of degree method.degree (1-5) from one open uniform knot vector (D 3.1)"},
    {"ddmpm", "dual domain MPM: P1 values, smoothed gradients (D 2.6.4; 1D and 2D)"},
};

inline constexpr Entry kMappings[] = {
    {"direct", "standard MPM mapping: particles are the quadrature points (D 3.2, 004 4.4)"},
    {"cubic_spline",
     "global natural cubic spline through particle values, 2x2 Gauss points per element (D 3.2)"},
    {"tls",
     "Taylor least squares per element, mass and momentum conservative (D 5.3, 000, 004 4.4)"},
    {"mls", "moving least squares at Gauss points, quadratic-spline weight (001 eq. 6-37)"},
    {"imls",
     "improved MLS: Gram-Schmidt orthogonal basis, no moment-matrix inverse (003 eq. 1-40)"},
};

inline constexpr Entry kSolvers[] = {
    {"mpm", "material point method with the chosen basis, mapping and scheme"},
    {"ulfem", "1D updated-Lagrangian FEM, linear elements (reference solutions, D 5.4.1)"},
};

inline constexpr Entry kTlsCompletions[] = {
    {"none", "stop the run when an element cannot support the Taylor basis"},
    {"reduce", "use fewer Taylor terms in that element (D 5.2.3)"},
    {"virtual", "add virtual points from the neighbouring elements' reconstructions (D 5.2.3)"},
    {"neighbour", "borrow the nearest particles of the neighbouring elements (D 5.2.3)"},
};

inline constexpr Entry kSchemes[] = {
    {"usl", "update stress last: grid velocity advanced from grid acceleration (D Algorithm 1)"},
    {"usf", "update stress first: stress from the start-of-step grid velocity (D 2.6.3)"},
    {"musl", "modified USL: grid velocity remapped from updated particle velocity (D Alg. 2)"},
    {"usavg", "update stress averaged: half USF, half MUSL stress increment (D 2.6.3, Nairn)"},
};

inline constexpr Entry kMassTypes[] = {
    {"lumped", "row-sum lumped (diagonal) mass matrix (D eq. 2.22-2.24)"},
    {"consistent", "consistent mass matrix, solved exactly each step (D eq. 2.31/2.44)"},
};

// method.sort: re-sorting the particles by cell between steps (scheme/sort.hpp).
inline constexpr Entry kSortModes[] = {
    {"auto", "sort by cell when the order has degraded (chunk DOF spans twice the sorted ones)"},
    {"never", "keep the particles in their order (seeded, or as a checkpoint stored them)"},
};

inline constexpr Entry kMaterials[] = {
    {"elastic_1d_small", "1D linear elastic, small deformation: sigma += E d_eps (004 eq. 4.15)"},
    {"elastic_1d_large",
     "1D elastic, large deformation: sigma += (E - sigma) d_eps (004 eq. 4.16)"},
    {"linear_elastic", "linear elastic in F, any dimension (D eq. 2.13); 1D modulus lambda+2mu"},
    {"neo_hookean", "compressible neo-Hookean, any dimension (D eq. 2.14)"},
};

inline constexpr Entry kBoundaryTypes[] = {
    {"fixed", "all velocity components zero at the boundary degrees of freedom"},
    {"free", "traction-free (natural) boundary, or the traction.* of that side"},
    {"roller", "normal velocity component zero, tangential free (1D: as fixed)"},
};

}  // namespace mpm::registry
