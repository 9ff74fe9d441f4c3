#pragma once
// Constructors of the built-in benchmarks (one file each).
#include <array>
#include <memory>
#include <numbers>

#include "core/parallel.hpp"
#include "model/problem.hpp"

namespace mpm {

class Config;

// Builds the problem selected by `benchmark` (registry::kBenchmarks). Throws InputError.
// `scope`: which of its particles this process stores (SeedScope; every one by default). Each
// constructor below passes its scope to its seeder.
AnyProblem make_problem(const Config& cfg, const SeedScope& scope = {});

// Vibrating bar with fixed ends (D 3.4.1, 5.4.1; 004 4.5). Small deformation: exact solution
// u = v0/omega sin(omega t) sin(pi X/L), v = v0 cos(omega t) sin(pi X/L),
// sigma = v0 rho c sin(omega t) cos(pi X/L), omega = pi c / L (MEHODS.md closed forms; D 3.4.1
// writes the stress amplitude as v0 sqrt(E/rho), an erratum: it is v0 sqrt(E rho)).
// large = true: the same set-up without an exact solution (D Table 5.4).
Problem<1> make_vibrating_bar(const Config& cfg, bool large, const SeedScope& scope = {});

struct VibratingBarExact {
  double length, v0, density, wave_speed;
  ExactState<1> operator()(const Vec<1>& X, double t) const;
};

// Column compaction (D 5.4.2, after Bardenhagen & Kober): a column of height H, fixed at the
// bottom, free at the top, under a body force b(t) = b_max min(t / T_ramp, 1). The grid has one
// empty cell above the column (h = H / grid.cells). Quasi-static exact solution of the 1D
// large-deformation law at the current load: sigma(X) = rho0 b (H - X), F = 1/(1 - sigma/E),
// u(X) = int_0^X (F - 1) dX' = (1/k) ln((1 - k (H - X)) / (1 - k H)) - X with k = rho0 b / E.
Problem<1> make_column_compaction(const Config& cfg, const SeedScope& scope = {});

struct ColumnExact {
  double height, density, youngs_modulus, body_force_max, ramp_time;
  double body_force(double t) const;
  ExactState<1> operator()(const Vec<1>& X, double t) const;
};

// Bar with a dynamic traction at its free end (D 4.6.2, Steffen et al.): neo-Hookean, fixed at
// X = 0, traction tau(t) = -A sin(omega c t) at X = L, omega = pi / L, c = sqrt(E / rho0). The
// exact stress is D eq. 4.93 (written there for c = 1 and A = 1; here t -> c t, amplitude A),
// the linear-wave (d'Alembert) solution, valid for c t <= 4 L; velocity and displacement follow
// from the same travelling waves (v = +-sigma / (rho0 c) for left/right-going waves).
Problem<1> make_traction_bar(const Config& cfg, const SeedScope& scope = {});

struct TractionBarExact {
  double length, density, wave_speed, amplitude;
  ExactState<1> operator()(const Vec<1>& X, double t) const;
};

// 1D neo-Hookean manufactured solution (003 eq. 41-47): u = A sin(2 pi X/L) sin(c pi t/L),
// c = sqrt(E / rho0), fixed ends, body force b(X, t) = u_tt - (1/rho0) dP/dX evaluated at each
// particle's material position (closed form; 003 eq. 47 with pi^2 u / L^2, METHODS.md errata).
Problem<1> make_mms_1d(const Config& cfg, const SeedScope& scope = {});

struct Mms1DExact {
  double length, density, lambda, mu, wave_speed, amplitude;
  double deformation_gradient(double X, double t) const;  // F = 1 + du/dX
  double piola_stress(double F) const;                    // P(F) = sigma(F) in 1D
  double body_force(double X, double t) const;            // b(X, t) [m/s^2]
  ExactState<1> operator()(const Vec<1>& X, double t) const;
};

// 2D axis-aligned vibration of a unit square, manufactured solution (001 eq. 38-42, D 3.4.1,
// after Sadeghirad et al. 2011), plane-strain neo-Hookean:
//   u = (A sin(2 pi X/L) sin(omega t), -A sin(2 pi Y/L) sin(omega t)), omega = c pi / L,
// c = sqrt(E / rho0); rollers on all four sides; body force b = u_tt - Div P / rho0.
Problem<2> make_plate_mms_2d(const Config& cfg, const SeedScope& scope = {});

struct PlateMms2DExact {
  double length, density, lambda, mu, wave_speed, amplitude;
  double omega() const { return wave_speed * std::numbers::pi / length; }
  Mat<2> deformation_gradient(const Vec<2>& X, double t) const;  // F = I + Grad u (diagonal)
  Mat<2> cauchy_stress(const Mat<2>& F) const;                   // sigma(F) [Pa]
  Mat<2> piola_stress(const Mat<2>& F) const;                    // P(F) [Pa]
  Vec<2> body_force(const Vec<2>& X, double t) const;            // b(X, t) [m/s^2]
  ExactState<2> operator()(const Vec<2>& X, double t) const;
};

// 3D axis-aligned vibration of the cube [0, L]^3, manufactured solution (001's plate
// extended to 3D), neo-Hookean:
//   u_i = A sin(2 pi X_i/L) sin(omega t),   omega = c pi / L,   c = sqrt(E / rho0),
// rollers on all six faces; body force b = u_tt - Div P / rho0 (scripts/cube_mms.py derives it).
Problem<3> make_cube_mms_3d(const Config& cfg, const SeedScope& scope = {});

struct CubeMms3DExact {
  double length, density, lambda, mu, wave_speed, amplitude;
  double omega() const { return wave_speed * std::numbers::pi / length; }
  Mat<3> deformation_gradient(const Vec<3>& X, double t) const;  // F = I + Grad u (diagonal)
  Mat<3> cauchy_stress(const Mat<3>& F) const;                   // sigma(F) [Pa]
  Mat<3> piola_stress(const Mat<3>& F) const;                    // P(F) [Pa]
  Vec<3> body_force(const Vec<3>& X, double t) const;            // b(X, t) [m/s^2]
  ExactState<3> operator()(const Vec<3>& X, double t) const;
};

// The generalized vortex (Kamojjala, Brannon, Sadeghirad & Guilkey, Eng. Comput. 2015), a
// rotation test: the material of the annulus R_i <= R <= R_o turns about its centre by
// alpha(R, t) = g(t) h(R), g = A sin(2 pi t / period), h = (1 - 4 xi^2)^2 with
// xi = (R - (R_i + R_o)/2) / (R_o - R_i) (R_i = 0.75, R_o = 1.25: the paper's
// 1 - 32 (R - 1)^2 + 256 (R - 1)^4), so x = Q(alpha) X, J = 1, and F = I with zero traction on
// both circles. Plane-strain neo-Hookean; body force b = x_tt - Div P / rho0 derived in
// scripts/vortex_mms.py. The grid is [-half_width, half_width]^2, the body its particles whose
// centre lies in the annulus (vortex.seeding = "cells") or rings of particles that tile it
// (seed_annulus, "polar", the default); no boundary condition.
Problem<2> make_vortex_2d(const Config& cfg, const SeedScope& scope = {});

// Particles tiling the annulus inner <= R <= outer (centred at the origin) in rings of annular
// sectors about h / per_cell wide in both directions (h: the grid's cell size), each carrying
// its sector's area; mass = rho0 V, F = I.
Particles<2> seed_annulus(const Grid<2>& g, double inner, double outer, int per_cell, double rho0,
                          const SeedScope& scope = {});

struct Vortex2DExact {
  double inner_radius, outer_radius, amplitude, period, density, lambda, mu;
  double g(double t) const;                 // rotation amplitude g(t) [rad]
  double g_t(double t) const;               // dg/dt [rad/s]
  double g_tt(double t) const;              // d2g/dt2 [rad/s^2]
  std::array<double, 3> h(double R) const;  // h, dh/dR [1/m], d2h/dR2 [1/m^2]; 0 outside
  Mat<2> deformation_gradient(const Vec<2>& X, double t) const;
  Mat<2> cauchy_stress(const Mat<2>& F) const;         // sigma(F) [Pa]
  Vec<2> body_force(const Vec<2>& X, double t) const;  // b(X, t) [m/s^2]
  ExactState<2> operator()(const Vec<2>& X, double t) const;
};

// 1D problem from the configuration alone: grid and body extents, initial velocity and stress
// as expressions of x, body force as an expression of x and t, fixed or free ends, tractions on
// the body ends (traction.left/right, expressions of t), an exact solution by expressions.
// The keys that only the custom problem reads (boundary.*, traction.* but the traction bar's
// traction.amplitude, pressure.*, body.*, initial.*, loading.*, exact.*): another benchmark
// refuses them when they are not at their default (make_problem), rather than ignore them.
bool read_by_custom_alone(std::string_view key);

// InputError naming `key` (the feature it enables, `what` it does) unless the run uses the MPM
// solver with lumped mass (`why_lumped`: why consistent mass cannot have it).
void require_mpm_lumped(const Config& cfg, const char* key, std::string_view what,
                        std::string_view why_lumped);

Problem<1> make_custom_1d(const Config& cfg, const SeedScope& scope = {});

// The same in 2D (grid.dimension = 2): a box body in a box grid, vector keys as arrays
// (body_force = ["0", "-9.81"]), per-side conditions fixed / roller / free, tractions on the
// four body faces through the particles next to them (Traction), exact.* by expressions.
Problem<2> make_custom_2d(const Config& cfg, const SeedScope& scope = {});

// The same in 3D (grid.dimension = 3): vector keys with three values or expressions of x, y, z
// (and t), initial.stress and exact.stress as [xx, yy, zz, yz, xz, xy], per-side conditions on
// the six sides (boundary.back: z = grid.min, boundary.front: z = grid.max), tractions and
// pressures on the six body faces; no mesh file, so no named boundaries.
Problem<3> make_custom_3d(const Config& cfg, const SeedScope& scope = {});

// A bar on [0, L] filling a grid of grid.cells cells with particles.per_cell particles per
// cell, density rho, fixed at both ends, released with velocity v(X) (vibrating bar, mms_1d).
void fill_fixed_bar(Problem<1>& pb, const Config& cfg, double L, double rho, const SeedScope& scope,
                    std::function<Vec<1>(const Vec<1>&)> velocity);

// The triangles of grid.mesh (a Gmsh file; a relative path is taken from the configuration
// file's directory) with the sides of its bounding box named as the grid's (with_box_sides);
// null when grid.mesh is "". InputError naming the key when the basis is not on triangles
// (p1_triangles, powell_sabin), method.triangles is also given, or the file cannot be read.
std::shared_ptr<const TriangleMesh> mesh_from_config(const Config& cfg);
// InputError naming grid.mesh unless the mesh's bounding box is the grid's (to 1e-9 of the
// grid's diagonal): the grid's sides are where the conditions on sides act.
void check_mesh_box(const Config& cfg, const TriangleMesh& m, const Grid<2>& g);

// The particles of a 2D body [lo, hi] in grid g: particles.per_cell per cell and direction, or
// with particles.per_triangle > 0 that many in every triangle of the grid's triangulation
// (method.basis p1_triangles or powell_sabin, method.triangles; the body must be the grid), or
// of `mesh` when the triangles come from a file (then particles.per_cell's particles must all
// lie in the mesh). InputError naming the key otherwise. `scope`: the particles this process
// stores (SeedScope); `body` (optional): only the points X with body(X) belong to the body,
// numbered among themselves (the vortex's annulus cut out of the grid's cells).
Particles<2> seed_body_2d(const Config& cfg, const Grid<2>& g, const Vec<2>& lo, const Vec<2>& hi,
                          double rho0, const TriangleMesh* mesh = nullptr,
                          const SeedScope& scope = {},
                          const std::function<bool(const Vec<2>& X)>& body = {});
// The points of seed_body_2d's body in its order, f(X, volume), after its checks, storing none;
// begin(total) first with the number of points to come (when given). For what needs the
// whole body's particles but not their state (the loaded points of a mesh's named boundaries).
void for_each_body_seed_2d(const Config& cfg, const Grid<2>& g, const Vec<2>& lo, const Vec<2>& hi,
                           const TriangleMesh* mesh, double machine_share,
                           const std::function<void(const Vec<2>& X, double volume)>& f,
                           const std::function<void(Index total)>& begin = {});

// A manufactured solution `ex` (plate_mms_2d, vortex_2d, cube_mms_3d) on pb's particles: their
// initial velocity ex(X, 0).v, the body force ex.body_force(X, t) at their material positions
// X = x0 refilled every step in parallel (sines, cosines per particle), and ex as the exact
// solution.
template <int Dim, class Exact>
void use_manufactured_solution(Problem<Dim>& pb, const Exact& ex) {
  pb.initial_velocity = [ex](const Vec<Dim>& X) { return ex(X, 0.0).v; };
  for (std::size_t i = 0; i < pb.particles.x.size(); ++i)
    pb.particles.v[i] = pb.initial_velocity(pb.particles.x0[i]);
  // b depends on the material position X (P.x0, fixed), so only time dependence is flagged.
  pb.body_force.time_dependent = true;
  pb.body_force.fill = [ex](const Particles<Dim>& P, double t, std::vector<Vec<Dim>>& b) {
    parallel_for(static_cast<Index>(b.size()), [&](Index p) {
      const auto i = static_cast<std::size_t>(p);
      b[i] = ex.body_force(P.x0[i], t);
    });
  };
  pb.exact = ex;
}

// The neo-Hookean law of a manufactured-solution benchmark, whose body force is derived for that
// law (`source` names the derivation); InputError naming material.model otherwise.
const NeoHookean& require_neo_hookean(const Config& cfg, const Material& m,
                                      std::string_view benchmark, std::string_view source);

}  // namespace mpm
