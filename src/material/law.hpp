#pragma once
// What a constitutive law is to the rest of the code (the ConstitutiveLaw concept) and what the
// laws share: the elastic parameters and the view of a particle's internal variables. Each law
// lives in its own header beside this one; material/materials.hpp lists them.
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <limits>
#include <span>
#include <string>
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

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A parameter of a law beyond the elastic ones, read from the key material.<name>: a real number
// within [min, max] (a bound exclusive where said) or, where `choices` is not empty, one of those
// names, given to the law as its index. setup/keys.cpp declares the parameters of every law;
// setup/material_settings.cpp reads those of the chosen law and refuses the others'. Laws that
// share a parameter share its declaration (one object), so that the key means one thing.
struct MaterialParameter {
  std::string_view name = "";                                       // key material.<name>
  std::string_view unit = "";                                       // "Pa", "deg", "" ...
  double default_value = std::numeric_limits<double>::quiet_NaN();  // NaN: required
  double min = -kInfinity;
  double max = kInfinity;
  bool min_exclusive = false, max_exclusive = false;
  std::span<const std::string_view> choices = {};
  std::string_view description = "";
};
// A law's refusal of its parameter values (as a whole: e.g. a dilatancy above the friction
// angle), naming the key to blame (without "material."); set-up prefixes where it was given.
class InvalidParameter : public InputError {
 public:
  InvalidParameter(std::string_view parameter, const std::string& what)
      : InputError(what), parameter_(parameter) {}
  std::string_view parameter() const { return parameter_; }

 private:
  std::string_view parameter_;  // a MaterialParameter's name (static storage)
};

// A law with no parameters beyond ElasticParameters declares
// `static constexpr NoParameters kParameters{};` (it is built as Law{ElasticParameters}).
using NoParameters = std::array<MaterialParameter, 0>;
// The values of Law's kParameters, in that order (a choice as its index); a law with parameters
// is built as Law{ElasticParameters, ParametersOf<Law>}.
template <class Law>
using ParametersOf = std::array<double, std::tuple_size_v<decltype(Law::kParameters)>>;

// A law without internal variables declares `static constexpr NoState kStateNames{};`.
// A 2D law that carries the stress normal to the plane (plane strain) as a state variable names
// it so; set-up puts the initial out-of-plane stress there.
inline constexpr std::string_view kOutOfPlaneStressName = "stress_zz";
using NoState = std::array<std::string_view, 0>;

// A particle's internal variables as the law Law sees them: one double per name of its
// kStateNames, in that order (the particles store them: particles/material_state.hpp).
template <class Law>
using StateOf = std::span<double, std::tuple_size_v<decltype(Law::kStateNames)>>;
template <class Law>
using ConstStateOf = std::span<const double, std::tuple_size_v<decltype(Law::kStateNames)>>;
// Law's block of particle i's row of `state`, from column `offset` (the columns named by the
// laws' kStateNames: Particles::state.set_names; Materials::state_offset in a run of several).
template <class Law>
StateOf<Law> state_row(MaterialState& state, std::size_t i, std::size_t offset = 0) {
  return StateOf<Law>(state[i].data() + offset, std::tuple_size_v<decltype(Law::kStateNames)>);
}
template <class Law>
ConstStateOf<Law> state_row(const MaterialState& state, std::size_t i, std::size_t offset = 0) {
  return ConstStateOf<Law>(state[i].data() + offset, std::tuple_size_v<decltype(Law::kStateNames)>);
}

// The constitutive-law concept, what the stages, outputs and set-up ask of a law:
// - kName, kDescription: its name in configurations (material.model) and `mpm list`'s line;
// - supports_dimension(d): the dimensions it exists in (make_material refuses the others; the
//   stages compile no update for them);
// - kParameters: its parameters beyond the elastic ones (MaterialParameter, NoParameters for none);
// - kStateNames: its internal variables per particle (a std::array of names, NoState for none),
//   which the particles carry through sorting, checkpoints, processes and outputs;
// - update(sigma, state, F, dtL): the per-particle stress update over a step (dtL = dt L, the
//   velocity gradient times the increment; F already updated), which also advances the state;
//   false when the law has no stress for the increment (a return mapping that found no
//   admissible stress): the stage then stops the run (exit_code::kReturnMapping), and a law that
//   can fail says why with failed_return(sigma, state, F), a residual [Pa] that is NaN for a
//   particle whose update succeeded (material/materials.hpp, failed_update);
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
  {std::span<const MaterialParameter>(Law::kParameters)};
  { Law::kIncremental } -> std::convertible_to<bool>;
  { law.update(sigma, state, F, dtL) } -> std::same_as<bool>;
  { law.energy(sigma, cstate, F, V, V0) } -> std::convertible_to<double>;
  { law.wave_speed() } -> std::convertible_to<double>;
  { law.out_of_plane_stress(sigma, cstate, F) } -> std::convertible_to<double>;
};

}  // namespace mpm
