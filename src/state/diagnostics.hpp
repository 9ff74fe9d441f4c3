#pragma once
#include <vector>

#include "core/types.hpp"

namespace mpm {

// Conservation and grid-crossing bookkeeping reported in summary.json (D 5.4).
struct Diagnostics {
  double max_rel_mass_error = 0.0;      // max over steps |sum M_ij - sum m_p| / sum m_p
  double max_rel_momentum_error = 0.0;  // max over steps |sum q_i - sum m_p v_p| / sum m_p|v_p|
  Index grid_crossings = 0;             // particle moves into another cell, summed over steps
  // The same relative errors of the latest mapping (history.csv); not checkpointed.
  double rel_mass_error = 0.0;
  double rel_momentum_error = 0.0;
  // Iterative mass solves (method.mass_solver = "cg" or "pmg"): CG iterations or V-cycles, in
  // all and the most of one solve; not checkpointed (a restart counts from there).
  Index mass_solver_iterations = 0;
  int max_mass_solver_iterations = 0;
  // Active DOFs with lumped rows (method.partial_lumping): in the latest step and the most in
  // any step; not checkpointed.
  Index lumped_dofs = 0;
  Index max_lumped_dofs = 0;
  // Problem::reactions: the reaction force [N; N/m in 2D, per unit thickness] on each
  // constrained boundary (RunState::reaction_dofs), Dim components per boundary, from the
  // latest step's grid forces (stages::solve_acceleration); empty before the first step; not
  // checkpointed.
  std::vector<double> reactions;
};

}  // namespace mpm
