#pragma once
// The initial stress of a custom body: the expressions of initial.stress (and, in 2D, the
// out-of-plane initial.stress_zz), or the geostatic stress of initial.geostatic = "k0": the
// vertical stress the weight of the body above a point makes, and K0 times it across.
#include <optional>
#include <vector>

#include "model/problem.hpp"
#include "setup/config.hpp"
#include "setup/expression.hpp"

namespace mpm {

// The geostatic stress of a box body whose top is `top` along the vertical, the last axis (y in
// 2D, z in 3D), under a constant body force g < 0 along it: sigma_v = rho g (top - X_v) (<= 0:
// compression) and sigma_h = K0 sigma_v in every other direction, out of the plane of a 2D run
// included; no shear.
template <int Dim>
struct K0Stress {
  double weight = 0.0;  // rho g [Pa/m]
  double top = 0.0;     // [m]
  double k0 = 0.0;      // sigma_h / sigma_v [-]
  double vertical(const Vec<Dim>& X) const { return weight * (top - X[Dim - 1]); }
  Mat<Dim> stress(const Vec<Dim>& X) const {
    Mat<Dim> m = k0 * vertical(X) * Mat<Dim>::Identity();
    m(Dim - 1, Dim - 1) = vertical(X);
    return m;
  }
  double out_of_plane(const Vec<Dim>& X) const { return k0 * vertical(X); }
};

// initial.geostatic's stress for the body [body_min, body_max] of density rho under the body
// force of `body_force` (loading.body_force's expressions), or none (initial.geostatic = "none").
// InputError naming the key when the problem does not allow it: initial.stress given as well, a
// body from a mesh file, or a body force that is not constant and downwards along the last axis.
template <int Dim>
std::optional<K0Stress<Dim>> k0_stress_from_config(const Config& cfg, const Problem<Dim>& pb,
                                                   const std::vector<Expression>& body_force,
                                                   double rho);

// Sets the initial stress of pb's particles (Particles::stress and, in 2D, the out-of-plane
// stress of a law that carries it as state) and pb.initial_stress: K0's, or that of
// `from_expressions` (initial.stress) and initial.stress_zz. InputError naming the key when a
// value is not finite, or a non-zero stress meets a law that computes its stress from F alone.
template <int Dim>
void set_initial_stress(const Config& cfg, Problem<Dim>& pb,
                        std::function<Mat<Dim>(const Vec<Dim>&)> from_expressions,
                        const std::vector<Expression>& body_force);

// InputError at initial.stress (or `key`) when `material` is not incremental: its stress follows
// from F, which is I at the start, so an initial stress cannot be given to it.
void refuse_initial_stress(const Config& cfg, const Material& material, int dim,
                           const char* key = "initial.stress");

}  // namespace mpm
