#pragma once
// The initial stress of a custom body: the expressions of initial.stress (and, in 2D, the
// out-of-plane initial.stress_zz), or the geostatic stress of initial.geostatic = "k0": the
// vertical stress the weight of the body above a point makes, and K0 times it across.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "model/problem.hpp"
#include "setup/config.hpp"
#include "setup/expression.hpp"

namespace mpm {

// The mass above a point per unit area [kg/m^2] of a body mesh whose parts may differ in
// density: the integral of the density along the vertical above it (FileBody::integral_above).
template <int Dim>
using MassAbove = std::function<double(const Vec<Dim>& X)>;

// The geostatic stress under a constant body force g < 0 along the vertical, the last axis (y in
// 2D, z in 3D): sigma_v = g times the mass above the point per unit area (<= 0: compression;
// rho g (top - X_v) in a box body of density rho), and sigma_h = K0 sigma_v in every other
// direction, out of the plane of a 2D run included, with each material's K0; no shear.
template <int Dim>
struct Geostatic {
  std::function<double(const Vec<Dim>& X)> vertical;  // sigma_v [Pa]
  std::vector<double> k0;                             // sigma_h / sigma_v of each material [-]
  Mat<Dim> stress(const Vec<Dim>& X, std::size_t material) const {
    const double v = vertical(X);
    Mat<Dim> m = k0[material] * v * Mat<Dim>::Identity();
    m(Dim - 1, Dim - 1) = v;
    return m;
  }
  double out_of_plane(const Vec<Dim>& X, std::size_t material) const {
    return k0[material] * vertical(X);
  }
};

// initial.geostatic's stress for the box body [body_min, body_max] (of body.material's density),
// or, given `mass_above`, for a body mesh, under the body force of `body_force`
// (loading.body_force's expressions); none for initial.geostatic = "none". K0 is each material's
// material.k0, else initial.k0. InputError naming the key when the problem does not allow it:
// initial.stress given as well, a particle file or a mesh grid (grid.mesh), or a body force that
// is not constant and downwards along the last axis.
template <int Dim>
std::optional<Geostatic<Dim>> geostatic_from_config(const Config& cfg, const Problem<Dim>& pb,
                                                    const std::vector<Expression>& body_force,
                                                    const MassAbove<Dim>& mass_above = {});

// Sets the initial stress of pb's particles (Particles::stress and, in 2D, the out-of-plane
// stress of a law that carries it as state) and pb.initial_stress: K0's (each particle with its
// material's K0; `mass_above` for a body mesh, see geostatic_from_config), or that of
// `from_expressions` (initial.stress) and initial.stress_zz. InputError naming the key when a
// value is not finite, or a non-zero stress meets a law that computes its stress from F alone.
template <int Dim>
void set_initial_stress(const Config& cfg, Problem<Dim>& pb,
                        std::function<Mat<Dim>(const Vec<Dim>&)> from_expressions,
                        const std::vector<Expression>& body_force,
                        const MassAbove<Dim>& mass_above = {});

// InputError at initial.stress (or `key`) when `material` is not incremental: its stress follows
// from F, which is I at the start, so an initial stress cannot be given to it.
void refuse_initial_stress(const Config& cfg, const Material& material, int dim,
                           const char* key = "initial.stress");

}  // namespace mpm
