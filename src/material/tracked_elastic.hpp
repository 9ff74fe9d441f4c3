#pragma once
// Linear elastic in F with two internal variables per particle: a check that material state
// follows its particle (sorting, checkpoints, processes, outputs) and a cheap record of the
// deformation a particle went through.
#include <cmath>
#include <string_view>

#include "material/law.hpp"
#include "material/linear_elastic.hpp"

namespace mpm {

// The stress of LinearElastic (D eq. 2.13), bit for bit. State: "updates", the number of stress
// updates the particle has had (one per step), and "strain_path", the length of its strain path
// sum_steps |sym(dt L)| (Frobenius norm of the strain increment, D eq. 2.40) [-]; both start at 0.
struct TrackedElastic {
  static constexpr std::string_view kName = "tracked_elastic";
  static constexpr std::string_view kDescription =
      "linear_elastic that records per particle its stress updates and strain path length "
      "sum |sym(dt L)| (internal variables updates, strain_path)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr std::array<std::string_view, 2> kStateNames = {"updates", "strain_path"};
  static constexpr bool kIncremental = false;
  static constexpr NoParameters kParameters{};
  ElasticParameters p;
  explicit TrackedElastic(const ElasticParameters& params = {}) : p(params), elastic_(params) {}
  template <int Dim>
  bool update(Mat<Dim>& sigma, StateOf<TrackedElastic> state, const Mat<Dim>& F,
              const Mat<Dim>& dtL) const {
    sigma = elastic_.stress(F);
    state[0] += 1.0;
    state[1] += (0.5 * (dtL + dtL.transpose())).norm();
    return true;
  }
  template <int Dim>
  double energy(const Mat<Dim>& sigma, ConstStateOf<TrackedElastic> /*state*/, const Mat<Dim>& F,
                double V, double V0) const {
    return elastic_.energy(sigma, {}, F, V, V0);
  }
  double wave_speed() const { return elastic_.wave_speed(); }
  template <int Dim>
  double out_of_plane_stress(const Mat<Dim>& sigma, ConstStateOf<TrackedElastic> /*state*/,
                             const Mat<Dim>& F) const {
    return elastic_.out_of_plane_stress(sigma, {}, F);
  }

 private:
  LinearElastic elastic_;
};

}  // namespace mpm
