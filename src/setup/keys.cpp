// The configuration schema: every key `mpm` understands is declared here, once. Parsing,
// validation, `mpm keys`, the defaults and the written-back config.toml all read this table.
// Choices for String keys come from setup/registry.hpp, so a model/scheme name exists in one place.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "material/materials.hpp"
#include "setup/config.hpp"
#include "setup/registry.hpp"

namespace mpm {
namespace {

// Allowed numeric interval; unbounded sides are nullopt.
struct Range {
  std::optional<double> min, max;
  bool min_exclusive = false, max_exclusive = false;
};
Range any() {
  return {};
}
Range at_least(double lo) {
  return {lo, std::nullopt, false, false};
}
Range greater_than(double lo) {
  return {lo, std::nullopt, true, false};
}
Range closed(double lo, double hi) {
  return {lo, hi, false, false};
}
Range open(double lo, double hi) {
  return {lo, hi, true, true};
}
Range closed_open(double lo, double hi) {
  return {lo, hi, false, true};
}
Range open_closed(double lo, double hi) {
  return {lo, hi, true, false};
}

// Marks a key without default that the user must give.
constexpr std::nullopt_t kRequired = std::nullopt;

KeySpec numeric(std::string name, KeyType type, std::string unit, std::optional<Value> def,
                Range range, std::string description) {
  KeySpec k;
  k.name = std::move(name);
  k.type = type;
  k.unit = std::move(unit);
  k.default_value = std::move(def);
  k.min = range.min;
  k.max = range.max;
  k.min_exclusive = range.min_exclusive;
  k.max_exclusive = range.max_exclusive;
  k.description = std::move(description);
  return k;
}

// Integer keys are read in 64 bits and used as int (counts, degrees, frames) or as indices: a
// key without an upper bound gets the largest int, so that no value is narrowed silently
// (particles.per_cell = 4294967296 ran one particle per cell).
KeySpec integer(std::string name, std::optional<std::int64_t> def, Range range,
                std::string description) {
  if (!range.max) range.max = static_cast<double>(std::numeric_limits<int>::max());
  std::optional<Value> v;
  if (def) v = Value(*def);
  return numeric(std::move(name), KeyType::Integer, "", v, range, std::move(description));
}

KeySpec real(std::string name, std::string unit, std::optional<double> def, Range range,
             std::string description) {
  std::optional<Value> v;
  if (def) v = Value(*def);
  return numeric(std::move(name), KeyType::Real, std::move(unit), v, range, std::move(description));
}

KeySpec boolean(std::string name, bool def, std::string description) {
  return numeric(std::move(name), KeyType::Boolean, "", Value(def), any(), std::move(description));
}

KeySpec choice(std::string name, std::optional<std::string> def,
               std::span<const registry::Entry> entries, std::string description) {
  std::optional<Value> v;
  if (def) v = Value(*def);
  KeySpec k = numeric(std::move(name), KeyType::String, "", v, any(), std::move(description));
  for (const registry::Entry& e : entries) k.choices.emplace_back(e.name);
  return k;
}

KeySpec expression(std::string name, std::string unit, std::string def, std::string description) {
  return numeric(std::move(name), KeyType::Expression, std::move(unit), Value(std::move(def)),
                 any(), std::move(description));
}

// One value per direction (RealVector) or component (ExpressionVector); see KeyType.
KeySpec real_vector(std::string name, std::string unit, std::optional<double> def,
                    std::string description) {
  std::optional<Value> v;
  if (def) v = Value(*def);
  return numeric(std::move(name), KeyType::RealVector, std::move(unit), v, any(),
                 std::move(description));
}

KeySpec expression_vector(std::string name, std::string unit, std::string def,
                          std::string description) {
  return numeric(std::move(name), KeyType::ExpressionVector, std::move(unit), Value(std::move(def)),
                 any(), std::move(description));
}

// A required key that only some runs read (KeySpec::required_when_read).
KeySpec when_read(KeySpec k) {
  k.required_when_read = true;
  return k;
}

// The keys material.<name> of the laws' own parameters (material/law.hpp, MaterialParameter),
// each declared once by the laws that read it.
std::vector<KeySpec> material_parameter_keys() {
  std::vector<KeySpec> keys;
  for (const MaterialParameter& m : all_material_parameters()) {
    const std::string name = fmt::format("material.{}", m.name);
    std::string description(m.description);
    if (!m.choices.empty()) {
      std::optional<std::string> def;
      if (!std::isnan(m.default_value))
        def = std::string(m.choices[static_cast<std::size_t>(m.default_value)]);
      KeySpec k = numeric(name, KeyType::String, "",
                          def ? std::optional<Value>(*def) : std::nullopt, any(), description);
      for (const auto c : m.choices) k.choices.emplace_back(c);
      keys.push_back(std::move(k));
    } else {
      const Range range{m.min == -kInfinity ? std::nullopt : std::optional<double>(m.min),
                        m.max == kInfinity ? std::nullopt : std::optional<double>(m.max),
                        m.min_exclusive, m.max_exclusive};
      keys.push_back(
          real(name, std::string(m.unit),
               std::isnan(m.default_value) ? kRequired : std::optional<double>(m.default_value),
               range, description));
    }
    keys.back().required_when_read = true;  // by the laws that have it
  }
  return keys;
}

std::vector<KeySpec> declare() {
  using namespace registry;
  std::vector<KeySpec> keys = {
      choice("benchmark", kRequired, kBenchmarks, "benchmark problem to run"),

      integer("grid.cells", 20, at_least(1), "number of cells (knot spans) per direction"),
      integer("grid.dimension", 1, closed(1, 3),
              "spatial dimension of the custom benchmark (the other benchmarks fix their own)"),
      real_vector("grid.min", "m", 0.0,
                  "lower corner of the background grid, one value per direction (custom)"),
      real_vector("grid.max", "m", 1.0,
                  "upper corner of the background grid, one value per direction (custom)"),
      integer("grid.cells_y", 0, at_least(0),
              "cells in y of a 2D or 3D custom grid (0: round((max_y - min_y) / h_x), at least "
              "1, the cells closest to square)"),
      integer("grid.cells_z", 0, at_least(0),
              "cells in z of a 3D custom grid (0: round((max_z - min_z) / h_x), at least 1, the "
              "cells closest to cubic)"),

      choice("grid.mesh", "", {},
             "Gmsh mesh file (.msh 4.1 or 2.2, linear triangles) whose triangles carry "
             "method.basis = \"p1_triangles\" or \"powell_sabin\" instead of a structured "
             "triangulation (2D plate_mms_2d and custom); relative to the configuration file's "
             "directory. The grid stays the box of the particles' seeding and re-sorting and "
             "must be the mesh's bounding box; its sides are the mesh's boundary edges on them"),

      integer("particles.per_cell", 4, at_least(1),
              "material points per cell per direction, evenly spaced"),
      integer("particles.per_element", 0, at_least(0),
              "material points per element of body.mesh, equal volumes: per triangle m k^2 with "
              "m = 1, 3 or 6 (as particles.per_triangle: 1, 3, 4, 6, 9, 12, ...), per "
              "tetrahedron m 8^r with m = 1 (centroid) or 4 (the degree-2 rule) in each of the "
              "8^r tetrahedra of r red refinements (1, 4, 8, 32, 64, ...); 0: the degree-2 "
              "rules, 3 per triangle and 4 per tetrahedron"),
      integer("particles.per_triangle", 0, at_least(0),
              "material points per triangle of method.basis = \"p1_triangles\" or "
              "\"powell_sabin\", m k^2 with m = 1, 3 or 6 (k^2 similar sub-triangles, each split "
              "into m equal parts, one point at each part's centroid: 3, 4, 6, 9, 12, 16, 24, ...; "
              "D 6.3.1); 0: particles.per_cell per grid cell"),

      real("time.dt", "s", kRequired, greater_than(0), "time-step size"),
      real("time.end", "s", kRequired, greater_than(0), "end time of the simulation"),
      boolean("time.allow_unstable", false,
              "run even when time.dt exceeds the explicit stability limit"),

      choice("method.scheme", "musl", kSchemes, "update scheme"),
      choice("method.basis", "linear", kBases, "grid basis functions"),
      integer("method.degree", 2, closed(1, 5), "B-spline degree (method.basis = \"bspline\")"),
      choice("method.mapping", "direct", kMappings, "particle-to-grid mapping"),
      // The node window of the max-ent basis holds the nodes closer than 3 cells
      // (basis/maxent.hpp); at 1 or less a point between two nodes can see too few nodes to
      // reproduce affine fields.
      real("method.maxent_dmax", "", 2.0, open_closed(1, 3),
           "support radius d_max of the max-ent prior in nearest-node distances (D eq. 4.47; D "
           "uses 2 in 1D and 3 on the plate)"),
      real("method.maxent_tolerance", "", 1e-12, open(0, 1e-3),
           "the max-ent Newton iteration stops when |sum phi_i (x_i - x)| is below this times the "
           "cell size"),
      integer("method.maxent_max_iterations", 50, closed(1, 1000),
              "Newton iterations of the max-ent basis before the point is reported as failed "
              "(exit code 10)"),
      // D 2.6.4 gives neither how the integrals over Omega are evaluated nor alpha beyond 1D
      // (basis/ddmpm.hpp).
      choice("method.ddmpm_integrals", "particles", kDdmpmIntegrals,
             "how DDMPM's integrals over the material (node volumes and int phi_j grad phi_i) "
             "are evaluated (method.basis = \"ddmpm\")"),
      choice("method.ddmpm_weight", "per_direction", kDdmpmWeights,
             "DDMPM's blend of P1's gradient with the smoothed one in 2D and 3D (the same in 1D; "
             "method.basis = \"ddmpm\")"),
      choice("method.mass", "lumped", kMassTypes, "mass matrix"),
      // At 1 or above even the heaviest DOF would be inactive: nothing could move.
      real("method.mass_tolerance", "", 1e-10, closed_open(0, 1),
           "degrees of freedom with mass below this fraction of the largest nodal mass are "
           "inactive"),
      // D 7.2: partial lumping of the mass matrix for partially filled elements; what counts as
      // partially filled is this fraction of the element's volume held by its particles.
      real("method.partial_lumping", "", 0.0, closed(0, 1),
           "consistent mass: the DOFs whose functions reach an element (grid cell, or triangle of "
           "a basis on triangles) whose particles fill less than this fraction of its volume get "
           "lumped rows and columns (D 7.2); 0: none"),
      // B-spline TLS with consistent mass flutters under load
      // (docs/verification.md, "PS-MPM with partially filled elements").
      boolean("method.allow_unstable", false,
              "run B-spline TLS (degree >= 2) with consistent mass in 2D and 3D, refused otherwise "
              "as unstable under load (docs/verification.md)"),
      choice("method.mass_solver", "direct", kMassSolvers,
             "solver of the consistent mass matrix (method.mass = \"consistent\")"),
      real("method.mass_solver_tolerance", "", 1e-12, open(0, 1e-2),
           "relative residual at which cg and pmg stop (004 eq. 4.53)"),
      integer("method.mass_solver_max_iterations", 5000, closed(1, 1000000),
              "CG iterations or V-cycles of one solve before the run stops (exit code 11)"),
      choice("method.pmg_smoother", "gauss-seidel", kPmgSmoothers,
             "smoother of method.mass_solver = \"pmg\""),
      integer("method.pmg_smoothing_steps", 8, closed(1, 100),
              "pre- and post-smoothing steps nu_1 = nu_2 of a V-cycle (004: 8)"),
      // Direct mappings conserve mass and momentum to round-off; the reconstructions (MLS, IMLS,
      // TLS, cubic spline) to their approximation error, which falls with h. An error of order
      // one means the grid no longer holds the particles' mass (e.g. a support smaller than the
      // particle spacing): the run stops rather than report "ok".
      real("method.conservation_limit", "", 0.5, greater_than(0),
           "a step whose relative mass or momentum error on the grid (summary.json "
           "'conservation') exceeds this stops the run (exit code 9)"),
      real("method.local_damping", "", 0.0, closed_open(0, 1),
           "Cundall's local non-viscous damping alpha: each free component of a nodal force "
           "loses alpha |f| against the node's velocity, f - alpha |f| sign(v) (quasi-static "
           "problems; 0: none; 0.8 is usual for them; MPM solver)"),
      choice("method.solver", "mpm", kSolvers, "time-stepping method"),
      choice("method.triangles", "right", kTrianglePatterns,
             "triangulation of the grid cells for method.basis = \"p1_triangles\" and "
             "\"powell_sabin\""),
      choice("method.sort", "auto", kSortModes,
             "re-sorting of the particles by cell between steps (locality of the parallel "
             "scatters; changes results by round-off only)"),
      integer("method.tls_terms", 0, closed(0, 10),
              "Taylor basis functions per element of the TLS mapping (1D: 1-3; 2D: 1, 3 or 6; 3D: "
              "1, 4 or 10; 0: the quadratic basis, 3 in 1D, 6 in 2D, 10 in 3D)"),
      choice("method.tls_completion", "auto", kTlsCompletions,
             "what TLS does in an element with too few or badly placed particles (D 5.2.3)"),
      real("method.tls_max_condition", "", 0.0, at_least(0),
           "largest condition number of an element's least-squares matrix in the L2-orthonormal "
           "Taylor basis (1: as well sampled as by uniform points) before completion (the grid's "
           "cells; 0: 1e8 in 1D as D 5.2.3, 10 in 2D from the study of docs/verification.md and in "
           "3D)"),
      choice("method.tls_positivity", "auto", kTlsPositivity,
             "TLS: scale the higher Taylor terms of an element's conservative fields so that its "
             "density is non-negative at the Gauss points (the grid's cells)"),
      choice("method.tls_surface_stress", "auto", kTlsSurfaceStress,
             "TLS: the stress integrated in elements at a free surface (the grid's cells)"),
      choice("method.tls_cell_integrals", "auto", kTlsCellIntegrals,
             "TLS: the element integrals (mass, momentum, body force) of the conservative fits "
             "(the grid's cells)"),
      choice("method.tls_strain_rate", "gradient", kTlsStrainRates,
             "TLS: the particles' velocity gradients for the stress update (the grid's cells, "
             "one process)"),
      real("method.tls_triangle_max_condition", "", 10.0, greater_than(1),
           "largest condition number of a triangle's least-squares matrix in the L2-orthonormal "
           "Taylor basis (1: as well sampled as by uniform points) before completion "
           "(p1_triangles, powell_sabin; D 6.3.1, docs/verification.md)"),
      integer("method.gauss_points", 0, closed(0, 10),
              "Gauss points per element of a reconstruction mapping (0: the method's own: 2 "
              "for TLS, 2 per half element for the cubic spline)"),
      integer("method.mls_degree", 1, closed(1, 2),
              "polynomial degree of the MLS and IMLS reconstructions (1: [1, x], 2: [1, x, x^2])"),
      real("method.mls_dilation", "", 2.0, greater_than(0),
           "dilation a of the MLS/IMLS quadratic-spline weight, r = |x - x_p| / (a h) per "
           "direction, support 1.5 a h each side (001 eq. 16 and 003 eq. 27: a = 2)"),
      boolean("method.mls_conservative", false,
              "MLS/IMLS: scale the reconstructed density and add a common velocity and body "
              "force so that mass, momentum and external force are the particles' (conservative "
              "to round-off; src/mapping/mls.hpp); false: 001's and 003's definitions"),
      real("mms.amplitude", "m", 0.1, any(),
           "amplitude A of the manufactured displacement A sin(2 pi X/L) sin(c pi t/L) (mms_1d: "
           "003; plate_mms_2d: 001; cube_mms_3d)"),
      // Above an amplitude the plate's exact solution is itself unstable
      // (docs/verification.md, "The exact solution at A = 0.1 m is unstable").
      boolean("mms.allow_unstable", false,
              "plate_mms_2d: run over more than one period at an amplitude where the exact "
              "solution's perturbations grow (docs/verification.md), refused otherwise"),
      integer("reference.dofs", 120, at_least(2),
              "nodes of the updated-Lagrangian FEM reference of vibrating_bar_large (D: 120)"),

      choice("material.model", "elastic_1d_small", kMaterials, "constitutive law"),
      real("material.density", "kg/m^3", kRequired, greater_than(0), "initial density rho0"),
      real("material.youngs_modulus", "Pa", kRequired, greater_than(0), "Young's modulus E"),
      real("material.poisson_ratio", "", 0.0, open(-1, 0.5),
           "Poisson's ratio nu (multi-dimensional laws)"),
      real("material.k0", "", -1.0, at_least(-1),
           "coefficient of earth pressure at rest K0 = sigma_h / sigma_v of this material under "
           "initial.geostatic = \"k0\" (a layer's own, e.g. 1 - sin(phi); -1: initial.k0)"),

      real("bar.length", "m", 1.0, greater_than(0), "length L of the vibrating bar"),
      real("bar.v0", "m/s", 0.1, any(), "amplitude v0 of the initial velocity v0 sin(pi x/L)"),
      real("plate.length", "m", 1.0, greater_than(0),
           "side L of the square plate of plate_mms_2d (001: 1 m)"),
      real("cube.length", "m", 1.0, greater_than(0), "side L of the cube of cube_mms_3d"),
      real("vortex.amplitude", "rad", 1.0, any(),
           "largest turn A of the vortex_2d annulus, alpha = A sin(2 pi t / period) h(R) (at "
           "the mid radius)"),
      real("vortex.period", "s", 2.0, greater_than(0),
           "period of the vortex_2d rotation g(t) = A sin(2 pi t / period) (2: the sin(pi t) of "
           "Kamojjala et al. 2015)"),
      real("vortex.inner_radius", "m", 0.75, greater_than(0),
           "inner radius R_i of the vortex_2d annulus"),
      real("vortex.outer_radius", "m", 1.25, greater_than(0),
           "outer radius R_o of the vortex_2d annulus"),
      real("vortex.half_width", "m", 1.5, greater_than(0),
           "half side of the square grid [-w, w]^2 of vortex_2d, centred on the annulus (at "
           "least vortex.outer_radius)"),
      choice("vortex.seeding", "polar", kVortexSeedings,
             "particle layout of the vortex_2d annulus"),
      real("column.height", "m", 50.0, greater_than(0),
           "initial height H of the compacted column (D 5.4.2)"),
      real("column.body_force", "m/s^2", -200.0, any(),
           "body force per unit mass reached at the end of the ramp (D Table 5.6)"),
      real("column.ramp_time", "s", 0.5, greater_than(0),
           "time over which the body force grows linearly from zero"),
      real("traction.amplitude", "Pa", 1.0, any(),
           "amplitude A of the end traction -A sin(pi c t / L) of the traction bar (D 4.6.2)"),

      real_vector("body.min", "m", 0.0,
                  "lower corner of the material body, one value per direction (custom)"),
      real_vector("body.max", "m", 1.0,
                  "upper corner of the material body, one value per direction (custom)"),
      choice("body.mesh", "", {},
             "Gmsh mesh file (.msh 4.1 or 2.2; linear triangles in the plane z = 0 in 2D, "
             "linear tetrahedra in 3D) whose elements are the body instead of the box body.min, "
             "body.max, on the run's own grid, which it need not fill; seeded per element by "
             "particles.per_element (2D and 3D custom; relative to the configuration file's "
             "directory; `mpm mesh FILE` reports it)"),
      choice("body.material", "material", {},
             "the body's material: \"material\" (the [material] table) or the NAME of a "
             "[material.NAME] table (custom)"),
      choice("body.part_materials", "", {},
             "parts of body.mesh (its physical groups) that have their own material, as "
             "\"PART: NAME, ...\" with NAME as in body.material; the other parts take "
             "body.material (2D and 3D custom)"),
      choice("body.particles", "", {},
             "CSV file of the body's particles instead of the box body.min, body.max: a header, "
             "then one row per particle with columns x_1, x_2[, x_3] (or x, y, z) [m], volume "
             "[m^3 per m of thickness in 2D], optionally v_1... (or vx...) [m/s], stress_11, "
             "stress_12, ... [Pa] (incremental laws) and in 2D stress_zz; lines starting with # "
             "are comments (2D and 3D custom; relative to the configuration file's directory)"),

      expression_vector("initial.velocity", "m/s", "0",
                        "initial velocity, one expression of the position x, y, z per "
                        "component (custom; a single \"0\": all zero)"),
      expression_vector("initial.stress", "Pa", "0",
                        "initial Cauchy stress as an expression of x (custom; incremental laws "
                        "only: the others compute the stress from F and refuse a non-zero one)"),
      expression("initial.stress_zz", "Pa", "0",
                 "initial stress normal to the plane of a 2D (plane-strain) custom run, an "
                 "expression of x, y (laws that carry it: von_mises, drucker_prager, "
                 "mohr_coulomb)"),
      choice("initial.geostatic", "none", kGeostaticModes,
             "geostatic initial stress of the custom body"),
      when_read(real("initial.k0", "", kRequired, at_least(0),
                     "coefficient of earth pressure at rest K0 = sigma_h / sigma_v of "
                     "initial.geostatic = \"k0\" (e.g. 1 - sin(phi), Jaky; nu / (1 - nu) for "
                     "an elastic layer), for the materials without their own material.k0")),
      expression_vector("loading.body_force", "m/s^2", "0",
                        "body force per unit mass, one expression of the current position x, y, "
                        "z and t per component (custom)"),

      choice("boundary.left", "fixed", kBoundaryTypes,
             "condition on the grid side x = grid.min (custom)"),
      choice("boundary.right", "fixed", kBoundaryTypes,
             "condition on the grid side x = grid.max (custom)"),
      choice("boundary.bottom", "fixed", kBoundaryTypes,
             "condition on the grid side y = grid.min (2D and 3D custom)"),
      choice("boundary.top", "fixed", kBoundaryTypes,
             "condition on the grid side y = grid.max (2D and 3D custom)"),
      choice("boundary.back", "fixed", kBoundaryTypes,
             "condition on the grid side z = grid.min (3D custom)"),
      choice("boundary.front", "fixed", kBoundaryTypes,
             "condition on the grid side z = grid.max (3D custom)"),
      when_read(real("boundary.friction", "", kRequired, at_least(0),
                     "Coulomb friction coefficient mu = tan(delta) of the grid sides whose "
                     "boundary.* is \"friction\" (0: a smooth wall the body may leave)")),
      choice("prescribed.nodes", "none", kPrescribedModes,
             "degrees of freedom with a prescribed velocity: a rigid footing or plate pushed at "
             "constant speed (2D and 3D custom; MPM, lumped mass)"),
      when_read(real_vector("prescribed.min", "m", std::nullopt,
                            "lower corner of the box of prescribed.nodes = \"box\": the degrees "
                            "of freedom whose positions lie in it (grid nodes; B-splines: "
                            "Greville abscissae; mesh vertices)")),
      when_read(real_vector("prescribed.max", "m", std::nullopt,
                            "upper corner of the box of prescribed.nodes = \"box\"")),
      when_read(real_vector("prescribed.velocity", "m/s", std::nullopt,
                            "the constant velocity of the box's degrees of freedom, per "
                            "component")),
      choice("prescribed.components", "all", kPrescribedComponents,
             "the velocity components prescribed in the box (all: a rough footing; the normal "
             "one: a smooth footing)"),
      choice("boundary.fixed", "", {},
             "named boundaries of grid.mesh (its physical groups of lines; `mpm mesh FILE` "
             "lists them) whose velocity is zero, separated by commas, e.g. \"inlet, base\" "
             "(2D custom)"),
      choice("boundary.roller", "", {},
             "named boundaries of grid.mesh whose normal velocity is zero, separated by commas; "
             "each must lie on one straight line, which may be inclined (v . n = 0 couples the "
             "velocity components), or with method.basis = \"p1_triangles\" may bend (a normal "
             "per vertex; corners turning by more than 45 degrees are fixed) (2D custom)"),
      choice("boundary.frictional", "", {},
             "named boundaries of grid.mesh that are rigid walls with Coulomb friction "
             "boundary.friction (as boundary.* = \"friction\" on a grid side), separated by "
             "commas; each must lie on one straight line on the mesh's outer boundary, which may "
             "be inclined (2D custom, method.basis = \"p1_triangles\", MPM, lumped mass)"),
      choice("boundary.loaded", "", {},
             "named boundaries of grid.mesh loaded by traction.loaded and pressure.loaded, "
             "separated by commas; the body must lie along them (2D custom)"),
      expression_vector("traction.loaded", "Pa", "0",
                        "traction on the boundaries of boundary.loaded, one expression of t per "
                        "component, per unit reference length (2D custom with grid.mesh)"),
      expression("pressure.loaded", "Pa", "0",
                 "normal pressure p(t) on the boundaries of boundary.loaded, positive in "
                 "compression: adds -p n (each edge's reference outward normal n) to "
                 "traction.loaded (2D custom with grid.mesh)"),
      expression_vector("traction.left", "Pa", "0",
                        "traction on the body face x = body.min, one expression of t per "
                        "component, per unit reference area (custom; \"0\": traction-free)"),
      expression_vector("traction.right", "Pa", "0",
                        "traction on the body face x = body.max, as traction.left (custom)"),
      expression_vector("traction.bottom", "Pa", "0",
                        "traction on the body face y = body.min, as traction.left (2D and 3D "
                        "custom)"),
      expression_vector("traction.top", "Pa", "0",
                        "traction on the body face y = body.max, as traction.left (2D and 3D "
                        "custom)"),
      expression_vector("traction.back", "Pa", "0",
                        "traction on the body face z = body.min, as traction.left (3D custom)"),
      expression_vector("traction.front", "Pa", "0",
                        "traction on the body face z = body.max, as traction.left (3D custom)"),
      expression("pressure.left", "Pa", "0",
                 "normal pressure p(t) on the body face x = body.min, positive in compression: "
                 "adds -p n (reference outward normal n) to traction.left (custom)"),
      expression("pressure.right", "Pa", "0",
                 "normal pressure on the body face x = body.max, as pressure.left (custom)"),
      expression("pressure.bottom", "Pa", "0",
                 "normal pressure on the body face y = body.min, as pressure.left (2D and 3D "
                 "custom)"),
      expression("pressure.top", "Pa", "0",
                 "normal pressure on the body face y = body.max, as pressure.left (2D and 3D "
                 "custom)"),
      expression("pressure.back", "Pa", "0",
                 "normal pressure on the body face z = body.min, as pressure.left (3D custom)"),
      expression("pressure.front", "Pa", "0",
                 "normal pressure on the body face z = body.max, as pressure.left (3D custom)"),
      expression_vector("exact.displacement", "m", "0",
                        "exact displacement u(X, t) for error norms, one expression of the "
                        "material position x, y, z and t per component (custom; all exact.* "
                        "\"0\": none)"),
      expression_vector("exact.velocity", "m/s", "0",
                        "exact velocity v(X, t), as exact.displacement (\"0\": zero)"),
      expression_vector("exact.stress", "Pa", "0",
                        "exact Cauchy stress sigma(X, t) (1D: one; 2D: [xx, yy, xy]; 3D: [xx, "
                        "yy, zz, yz, xz, xy]; \"0\": zero)"),

      integer("output.frames", 10, at_least(0),
              "frames evenly spaced in time after the initial one, the final state always "
              "written (0: initial and final only)"),
      boolean("output.csv", true, "write particle frames as CSV"),
      boolean("output.reactions", false,
              "history.csv gets the reaction force on each constrained boundary (grid sides, "
              "named mesh boundaries, the prescribed box), reaction_<name>_<x|y|z> [N; N/m in "
              "2D] (MPM, lumped mass)"),
      boolean("output.vtk", true, "write particle and grid frames as VTK XML (.vtu + .pvd)"),
      choice("output.vtk_format", "binary", kVtkFormats, "encoding of the .vtu arrays"),
      integer("output.history_every", 1, at_least(1), "write a history.csv row every N steps"),
      integer("output.checkpoint_every", 0, at_least(0),
              "write the complete state to checkpoint.bin every N steps, replacing the previous "
              "one, for `mpm run --restart` (0: never)"),
      // Distributed runs (mpirun; parallel/distribution.hpp).
      choice("parallel.blocks", "slabs", {},
             "how several processes cut the grid: \"slabs\" (cell layers along the last axis), "
             "\"auto\" (blocks shaped from the particles) or processes per axis (\"2x2\")"),
      real("parallel.rebalance", "", 0.25, at_least(0),
           "a run on several processes moves its cuts when the most loaded process holds this "
           "fraction more particles than the mean (0: never)"),
  };
  // The laws' parameters after the elastic ones.
  const auto after = std::find_if(keys.begin(), keys.end(),
                                  [](const KeySpec& k) { return k.name == "material.k0"; });
  const std::vector<KeySpec> parameters = material_parameter_keys();
  keys.insert(after + 1, parameters.begin(), parameters.end());
  return keys;
}

}  // namespace

const std::vector<KeySpec>& schema() {
  static const std::vector<KeySpec> keys = declare();
  return keys;
}

}  // namespace mpm
