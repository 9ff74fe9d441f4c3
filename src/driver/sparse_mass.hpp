#pragma once
// The warning of set-up for consistent mass on bases that need many particles per triangle
// (Basis::kConsistentMassPoints: Powell-Sabin splines), shared by the MPM steppers
// (driver/stepper_impl.hpp) and the unified approach's (driver/otm_stepper.cpp).
#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "particles/particles.hpp"
#include "setup/run_settings.hpp"

namespace mpm::driver {

// Before the first step: a basis that declares how many particles per element its consistent
// mass needs (kConsistentMassPoints: Powell-Sabin) gets a warning when the median count over the
// elements holding particles is below it. A warning, not a refusal: below it some runs finish
// (docs/verification.md: the structured plate with 8 per triangle on 8 and 16 cells), and a
// body's partly filled elements at its free surface hold fewer by nature. The counts are summed
// over the processes, so that every process warns alike.
template <int Dim, class Basis>
void warn_sparse_consistent_mass(const MethodSettings& method, const Basis& basis,
                                 const Particles<Dim>& P, const Comm* comm,
                                 std::vector<std::string>& warnings) {
  if constexpr (requires { Basis::kConsistentMassPoints; }) {
    if (method.mass != MassType::Consistent) return;
    const auto& mesh = basis.mesh();
    std::vector<double> count(static_cast<std::size_t>(mesh.num_cells()), 0.0);
    for (const Vec<Dim>& x : P.x)
      if (const Index e = mesh.cell_index(x); e >= 0) count[static_cast<std::size_t>(e)] += 1.0;
    if (comm) comm->sum(count);
    std::vector<double> held;
    for (const double c : count)
      if (c > 0.0) held.push_back(c);
    if (held.empty()) return;
    const auto mid = held.begin() + static_cast<std::ptrdiff_t>(held.size() / 2);
    std::nth_element(held.begin(), mid, held.end());
    if (*mid < Basis::kConsistentMassPoints)
      warnings.push_back(fmt::format(
          "{}: method.mass = \"consistent\" with method.basis = \"{}\" and a median of {} "
          "particles per triangle: below {} such runs stop with a non-finite stress at a time "
          "that a smaller time step does not change, with or without method.partial_lumping "
          "(docs/verification.md, \"D Fig. 3.9 on unstructured meshes\"); seed {} or more "
          "(particles.per_triangle) or use method.mass = \"lumped\"",
          method.where_mass, Basis::kName, *mid, Basis::kConsistentMassPoints,
          Basis::kConsistentMassPoints));
  }
}

}  // namespace mpm::driver
