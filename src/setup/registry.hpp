#pragma once
// The single list of every run-time choice (config values and `mpm list`). The configuration
// schema takes its allowed choices from here; the bases, mappings and schemes are generated from
// their classes (kName, kDescription), so a name exists in exactly one place.
#include <array>
#include <cstddef>
#include <span>
#include <string_view>
#include <utility>
#include <variant>

#include "material/materials.hpp"
#include "methods/kinds.hpp"

namespace mpm::registry {

struct Entry {
  std::string_view name;
  std::string_view description;
};

namespace detail {
template <class Variant, std::size_t... I>
constexpr auto all_entries(std::index_sequence<I...>) {
  return std::array<Entry, sizeof...(I)>{
      Entry{std::variant_alternative_t<I, Variant>::kName,
            std::variant_alternative_t<I, Variant>::kDescription}...};
}
template <class Variant>
constexpr auto all_entries() {
  return all_entries<Variant>(std::make_index_sequence<std::variant_size_v<Variant>>{});
}
template <class Variant>
constexpr std::size_t distinct_names() {
  const auto all = all_entries<Variant>();
  std::size_t n = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    bool seen = false;
    for (std::size_t j = 0; j < i; ++j) seen = seen || all[j].name == all[i].name;
    n += seen ? 0 : 1;
  }
  return n;
}
}  // namespace detail

// The entries of a method variant (bases, mappings, schemes), from each alternative's kName and
// kDescription: one entry per distinct name (the five B-spline kinds are one "bspline"), in
// variant order. The names are declared once, in the numerics.
template <class Variant>
constexpr auto entries_of() {
  const auto all = detail::all_entries<Variant>();
  std::array<Entry, detail::distinct_names<Variant>()> out{};
  std::size_t n = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    bool seen = false;
    for (std::size_t j = 0; j < n; ++j) seen = seen || out[j].name == all[i].name;
    if (!seen) out[n++] = all[i];
  }
  return out;
}

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
     "1D, 2D or 3D (grid.dimension) problem built from the config alone: extents, fields and "
     "forces by expression, side conditions, face tractions, optional exact solution"},
    {"plate_mms_2d",
     "2D axis-aligned vibration of a unit square, neo-Hookean manufactured solution (001, D "
     "3.4.1)"},
    {"cube_mms_3d",
     "3D axis-aligned vibration of a cube, neo-Hookean manufactured solution (001's "
     "plate in 3D), rollers on the six faces"},
    {"vortex_2d",
     "2D generalized vortex: an annulus turned by a radius-dependent angle, neo-Hookean "
     "manufactured solution with large shear and rotation (Kamojjala et al. 2015)"},
};

// vortex.seeding: where the particles of the vortex_2d annulus sit.
inline constexpr Entry kVortexSeedings[] = {
    {"polar",
     "rings of particles.per_cell per cell width across the annulus, each ring cut into equal "
     "sectors of about the same width; the sectors tile the annulus exactly"},
    {"cells",
     "the grid's particles (particles.per_cell or per_triangle) whose centre lies in the "
     "annulus: a staircase along both circles"},
};

inline constexpr auto kBases = entries_of<BasisKind>();

inline constexpr auto kMappings = entries_of<MappingKind>();

inline constexpr Entry kSolvers[] = {
    {"mpm", "material point method with the chosen basis, mapping and scheme"},
    {"ulfem", "1D updated-Lagrangian FEM, linear elements (reference solutions, D 5.4.1)"},
    {"otm",
     "optimal transportation meshfree method on nodes advected with the material: P1 (1D, 2D) "
     "or max-ent (1D, 2D) (D Algorithm 3)"},
    {"unified",
     "B-splines (1D, 2D) or Powell-Sabin splines (2D) on advected degrees of freedom, USL "
     "updates (D Algorithm 4, D 7.3)"},
};

inline constexpr Entry kTlsCompletions[] = {
    {"none", "stop the run when an element cannot support the Taylor basis"},
    {"reduce", "use fewer Taylor terms in that element (D 5.2.3)"},
    {"virtual", "add virtual points from the neighbouring elements' reconstructions (D 5.2.3)"},
    {"neighbour", "borrow the nearest particles of the neighbouring elements (D 5.2.3)"},
    {"min_norm", "triangles: truncated SVD, minimum-norm coefficients (mapping/tls_triangle.hpp)"},
    {"graded",
     "triangles: truncated SVD, undetermined directions resolved towards the lowest degree"},
    {"auto", "virtual in 1D (D 5.2.3), reduce in 2D (docs/verification.md)"},
};

// method.tls_positivity and method.tls_surface_stress (mapping/tls.hpp, TlsSettings). "auto"
// keeps D's method in 1D, whose results the report reproduces, and takes the robust choice in
// 2D (the study "Robust TLS on the grid's cells" of docs/verification.md).
inline constexpr Entry kTlsPositivity[] = {
    {"auto", "on in 2D, off in 1D"},
    {"on",
     "scale the terms beyond the mean of density, momentum and body force where the density "
     "would be negative at a Gauss point (Zhang and Shu 2010; conservative)"},
    {"off", "the fits as they are (D 5.3, 6.3)"},
};
inline constexpr Entry kTlsCellIntegrals[] = {
    {"auto", "domains in 2D, centres (D's method) in 1D"},
    {"centres", "c_e = sum over the particles whose centre lies in the element (D eq. 5.9)"},
    {"domains",
     "c_e = each particle's value split among the active elements its domain (the cpGIMP box) "
     "overlaps, by the overlap"},
};
inline constexpr Entry kTlsStrainRates[] = {
    {"gradient", "each particle's velocity gradient at its position (D eq. 2.52)"},
    {"adjoint",
     "the adjoint of TLS's force: the grid's velocity gradients at the Gauss points through the "
     "transposed stress fit, divided by the particle's weight in it (a symmetric linearised "
     "step; docs/verification.md)"},
};
inline constexpr Entry kTlsSurfaceStress[] = {
    {"auto", "volume in 2D, element in 1D"},
    {"volume",
     "elements next to an empty one integrate their material's stress: conservative fit with "
     "the integral sum V_p sigma_p"},
    {"element", "plain least squares over the whole element (D 5.3.1, 6.3)"},
};

inline constexpr auto kSchemes = entries_of<Scheme>();

inline constexpr Entry kMassTypes[] = {
    {"lumped", "row-sum lumped (diagonal) mass matrix (D eq. 2.22-2.24)"},
    {"consistent", "consistent mass matrix, solved exactly each step (D eq. 2.31/2.44)"},
};

// method.mass_solver: how the consistent mass matrix is solved (solver/mass_matrix.hpp).
inline constexpr Entry kMassSolvers[] = {
    {"direct", "sparse LDL^T factorisation each step: exact to round-off"},
    {"cg", "conjugate gradients from zero to method.mass_solver_tolerance (004 eq. 4.53)"},
    {"pmg",
     "p-multigrid V-cycles over the B-spline degrees p .. 1 (004 4.7; method.basis = "
     "\"bspline\")"},
};

inline constexpr Entry kPmgSmoothers[] = {
    {"gauss-seidel", "forward sweeps before the coarse correction, backward after (004)"},
    {"jacobi", "damped Jacobi, omega = 1 / lambda_max(D^-1 M) (parallel)"},
};

// method.ddmpm_integrals, method.ddmpm_weight: the DDMPM basis (basis/ddmpm.hpp).
inline constexpr Entry kDdmpmIntegrals[] = {
    {"particles", "the particles as quadrature points, sum_p V_p (...)(x_p)"},
    {"quadrature", "exactly, by Gauss points over the grid cells holding particles"},
};
inline constexpr Entry kDdmpmWeights[] = {
    {"per_direction",
     "gradient component d blended by alpha_d = 2 xi_d (1 - xi_d): continuous, and a "
     "y-uniform field gives the 1D run's gradients"},
    {"product", "every component blended by alpha = prod_d 2 xi_d (1 - xi_d)"},
};

// output.vtk_format: how the .vtu frames hold their arrays (io/output.hpp).
inline constexpr Entry kVtkFormats[] = {
    {"binary", "raw little-endian bytes in an appended block (VTK XML 1.0; compact, fast)"},
    {"ascii", "text, 17 significant digits (readable, about 3x larger)"},
};

// method.sort: re-sorting the particles by cell between steps (state/sort.hpp).
inline constexpr Entry kTrianglePatterns[] = {
    {"right", "each cell split along its diagonal from the lower-left corner (2 triangles)"},
    {"criss_cross", "each cell split by both diagonals at a centre vertex (4 triangles)"},
};

// initial.geostatic: how a custom body's initial stress is given (benchmarks/initial_stress.hpp).
inline constexpr Entry kGeostaticModes[] = {
    {"none", "the initial stress is initial.stress (and initial.stress_zz in 2D)"},
    {"k0",
     "sigma_v = g times the mass above a point per unit area (rho g (top - depth) in a box "
     "body; a body mesh's parts with their materials' densities), sigma_h = K0 sigma_v across "
     "(out of the plane too; each material's material.k0, else initial.k0), under a constant "
     "body force along -y (2D) or -z (3D)"},
};

// prescribed.nodes: which degrees of freedom get a prescribed velocity (custom).
inline constexpr Entry kPrescribedModes[] = {
    {"none", "no prescribed velocity"},
    {"box",
     "the degrees of freedom whose positions lie in the box prescribed.min - prescribed.max move "
     "at prescribed.velocity"},
};
// prescribed.components: the prescribed velocity components.
inline constexpr Entry kPrescribedComponents[] = {
    {"all", "every component (a rough footing)"},
    {"x", "the x component alone"},
    {"y", "the y component alone (a smooth footing on a surface normal to y)"},
    {"z", "the z component alone (3D)"},
};

inline constexpr Entry kSortModes[] = {
    {"auto", "sort by cell when the order has degraded (chunk DOF spans twice the sorted ones)"},
    {"never", "keep the particles in their order (seeded, or as a checkpoint stored them)"},
};

// The constitutive laws, from each law's kName and kDescription (material/materials.hpp).
inline constexpr auto kMaterials = entries_of<Material>();

inline constexpr Entry kBoundaryTypes[] = {
    {"fixed", "all velocity components zero at the boundary degrees of freedom"},
    {"free", "traction-free (natural) boundary, or the traction.* of that side"},
    {"roller", "normal velocity component zero, tangential free (1D: as fixed)"},
    {"friction",
     "a rigid wall with Coulomb friction (coefficient boundary.friction): the body may leave "
     "it; pressed on it, it sticks or slips (MPM solver, lumped mass)"},
};

}  // namespace mpm::registry
