#pragma once
// What a constitutive law is to the rest of the code (the ConstitutiveLaw concept) and what the
// laws share: the elastic parameters and the view of a particle's internal variables. Each law
// lives in its own header beside this one; material/materials.hpp lists them.
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <span>
#include <string_view>
#include <tuple>

#include "core/types.hpp"
#include "particles/material_state.hpp"

namespace mpm {

struct ElasticParameters {
  double density = 1.0;         // rho0 [kg/m^3]
  double youngs_modulus = 1.0;  // E [Pa]
  double poisson_ratio = 0.0;   // nu [-]
  double lambda() const {
    return youngs_modulus * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio));
  }
  double mu() const { return youngs_modulus / (2.0 * (1.0 + poisson_ratio)); }
};

// A law without internal variables declares `static constexpr NoState kStateNames{};`.
using NoState = std::array<std::string_view, 0>;

// A particle's internal variables as the law Law sees them: one double per name of its
// kStateNames, in that order (the particles store them: particles/material_state.hpp).
template <class Law>
using StateOf = std::span<double, std::tuple_size_v<decltype(Law::kStateNames)>>;
template <class Law>
using ConstStateOf = std::span<const double, std::tuple_size_v<decltype(Law::kStateNames)>>;
// Particle i's row of `state` (named by Law's kStateNames: Particles::state.set_names).
template <class Law>
StateOf<Law> state_row(MaterialState& state, std::size_t i) {
  return StateOf<Law>(state[i].data(), std::tuple_size_v<decltype(Law::kStateNames)>);
}
template <class Law>
ConstStateOf<Law> state_row(const MaterialState& state, std::size_t i) {
  return ConstStateOf<Law>(state[i].data(), std::tuple_size_v<decltype(Law::kStateNames)>);
}

// The constitutive-law concept, what the stages, outputs and set-up ask of a law:
// - kName, kDescription: its name in configurations (material.model) and `mpm list`'s line;
// - supports_dimension(d): the dimensions it exists in (make_material refuses the others; the
//   stages compile no update for them);
// - kStateNames: its internal variables per particle (a std::array of names, NoState for none),
//   which the particles carry through sorting, checkpoints, processes and outputs;
// - update(sigma, state, F, dtL): the per-particle stress update over a step (dtL = dt L, the
//   velocity gradient times the increment; F already updated), which also advances the state;
// - energy(sigma, state, F, V, V0): the strain energy of a particle [J] (history.csv);
// - wave_speed(): the elastic wave speed [m/s] of the stability limit;
// - out_of_plane_stress(sigma, state, F): the stress normal to the plane of a 2D run, which the
//   2D state omits (plane strain: outputs);
// - kIncremental: whether the stress is advanced from the previous one (then an initial stress
//   is meaningful), rather than computed from F alone.
template <class Law, int Dim>
concept ConstitutiveLaw = requires(const Law& law, Mat<Dim>& sigma, StateOf<Law> state,
                                   ConstStateOf<Law> cstate, const Mat<Dim>& F, const Mat<Dim>& dtL,
                                   double V, double V0, int dim) {
  { Law::kName } -> std::convertible_to<std::string_view>;
  { Law::kDescription } -> std::convertible_to<std::string_view>;
  { Law::supports_dimension(dim) } -> std::convertible_to<bool>;
  {std::span<const std::string_view>(Law::kStateNames)};
  { Law::kIncremental } -> std::convertible_to<bool>;
  law.update(sigma, state, F, dtL);
  { law.energy(sigma, cstate, F, V, V0) } -> std::convertible_to<double>;
  { law.wave_speed() } -> std::convertible_to<double>;
  { law.out_of_plane_stress(sigma, cstate, F) } -> std::convertible_to<double>;
};

}  // namespace mpm
