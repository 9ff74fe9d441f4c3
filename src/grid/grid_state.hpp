#pragma once
// Per-DOF grid quantities of one time step (D Algorithm 2, steps 4-9). Sized by the basis; the
// quantities of a step are held over a window of the DOFs (core/dof_array.hpp): every DOF on one
// process, the DOFs of a process's slab in a distributed run.
#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/dof_array.hpp"
#include "core/types.hpp"

namespace mpm {

template <int Dim>
struct GridState {
  // Recomputed in every step from the particles, so a window can move between steps.
  DofArray<double> mass;          // lumped nodal mass m_i (row sums of M) [kg]
  DofArray<Vec<Dim>> momentum;    // q_i [kg m/s]
  DofArray<Vec<Dim>> force;       // f_i = f_ext - f_int [N]
  DofArray<Vec<Dim>> velocity;    // v_i [m/s]
  DofArray<Vec<Dim>> accel;       // a_i [m/s^2]
  DofArray<std::uint8_t> active;  // 1 where the DOF carries enough mass to be solved for
  // Bit d set: component d is prescribed zero (Dirichlet). Set up once for every DOF (one byte
  // each: not windowed).
  std::vector<std::uint8_t> fixed;
  // DOFs whose velocity is confined to a subspace that is not a set of components (a roller on
  // an inclined boundary: v . n = 0), with the orthogonal projector onto the velocities they may
  // take; sorted by DOF. Their `fixed` bits are folded into the projector and cleared, so a DOF
  // is constrained either by bits or by an entry here, never both (BasisState::fix_*).
  struct Projected {
    Index dof;
    Mat<Dim> free;
  };
  std::vector<Projected> projected;
  // DOFs whose velocity is prescribed (Problem::prescribed), with the velocity [m/s] their
  // `fixed` components take (the acceleration there is zero); sorted by DOF.
  std::vector<std::pair<Index, Vec<Dim>>> prescribed;

  // The basis's DOF count (not the window's).
  Index size() const { return dofs_; }
  // [first, end) of the DOFs the windowed arrays hold.
  std::array<Index, 2> window() const { return {mass.first(), mass.stop()}; }
  // Bytes per DOF of the windowed arrays above: a lower bound of a run's grid memory per DOF of
  // its window (the stages add per-thread scatter buffers, the basis its own arrays, `fixed` one
  // byte per DOF of the whole grid).
  static constexpr std::size_t bytes_per_dof() {
    return sizeof(double) + 4 * sizeof(Vec<Dim>) + sizeof(std::uint8_t);
  }
  // n DOFs, every one in the window (whole = false: none, for set_window to place), every
  // quantity zero.
  void resize(Index n, bool whole = true) {
    dofs_ = n;
    const Index count = whole ? n : 0;
    mass.assign(0, count, 0.0);
    for (auto* a : {&momentum, &force, &velocity, &accel}) a->assign(0, count, Vec<Dim>::Zero());
    active.assign(0, count, 0);
    fixed.resize(static_cast<std::size_t>(n), 0);
  }
  // Moves the window to [first, end) (within [0, size())), keeping the values of the DOFs in
  // both windows (the new ones zero).
  void set_window(Index first, Index end) {
    const Index count = end - first;
    mass.rewindow(first, count, 0.0);
    for (auto* a : {&momentum, &force, &velocity, &accel})
      a->rewindow(first, count, Vec<Dim>::Zero());
    active.rewindow(first, count, 0);
  }

 private:
  Index dofs_ = 0;
};

}  // namespace mpm
