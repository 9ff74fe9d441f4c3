#pragma once
// Per-DOF grid quantities of one time step (D Algorithm 2, steps 4-9). Sized by the basis.
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace mpm {

template <int Dim>
struct GridState {
  std::vector<double> mass;          // lumped nodal mass m_i (row sums of M) [kg]
  std::vector<Vec<Dim>> momentum;    // q_i [kg m/s]
  std::vector<Vec<Dim>> force;       // f_i = f_ext - f_int [N]
  std::vector<Vec<Dim>> velocity;    // v_i [m/s]
  std::vector<Vec<Dim>> accel;       // a_i [m/s^2]
  std::vector<std::uint8_t> active;  // 1 where the DOF carries enough mass to be solved for
  std::vector<std::uint8_t> fixed;   // bit d set: component d is prescribed zero (Dirichlet)
  // DOFs whose velocity is confined to a subspace that is not a set of components (a roller on
  // an inclined boundary: v . n = 0), with the orthogonal projector onto the velocities they may
  // take; sorted by DOF. Their `fixed` bits are folded into the projector and cleared, so a DOF
  // is constrained either by bits or by an entry here, never both (BasisState::fix_*).
  struct Projected {
    Index dof;
    Mat<Dim> free;
  };
  std::vector<Projected> projected;

  Index size() const { return static_cast<Index>(mass.size()); }
  // Bytes per DOF of the arrays above: a lower bound of a run's grid memory (the stages add
  // per-thread scatter buffers and the basis's own arrays).
  static constexpr std::size_t bytes_per_dof() {
    return sizeof(double) + 4 * sizeof(Vec<Dim>) + 2 * sizeof(std::uint8_t);
  }
  void resize(Index n) {
    const auto s = static_cast<std::size_t>(n);
    mass.assign(s, 0.0);
    momentum.assign(s, Vec<Dim>::Zero());
    force.assign(s, Vec<Dim>::Zero());
    velocity.assign(s, Vec<Dim>::Zero());
    accel.assign(s, Vec<Dim>::Zero());
    active.assign(s, 0);
    fixed.resize(s, 0);
  }
};

}  // namespace mpm
