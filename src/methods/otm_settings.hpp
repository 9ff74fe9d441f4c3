#pragma once
// What the OTM solver and the unified approach (methods/otm.hpp) are set up with: the basis on
// the advected nodes, which the basis kinds declare (methods/kinds.hpp: configure_otm), and the
// mass. Apart from otm.hpp so that the kinds can name it without the solver.
#include <memory>

#include "basis/maxent_settings.hpp"
#include "grid/triangle_mesh.hpp"
#include "solver/mass_matrix.hpp"
#include "state/run_state.hpp"

namespace mpm {

enum class OtmBasis { Linear, MaxEnt, BSpline, PowellSabin };

struct OtmSettings {
  bool unified = false;  // D Algorithm 4 (B-splines, USL particle velocity) instead of OTM
  OtmBasis basis = OtmBasis::Linear;
  int degree = 0;         // OtmBasis::BSpline: 1-5
  MaxEntSettings maxent;  // with OtmBasis::MaxEnt: d_i = d_max times node i's nearest distance
  // OtmBasis::PowellSabin: the body's triangles, a structured triangulation of the body's part
  // of the grid (method.triangles), or `mesh` (grid.mesh: the mesh is the body).
  TrianglePattern triangles = TrianglePattern::right;
  std::shared_ptr<const TriangleMesh> mesh;
  MassType mass = MassType::Consistent;
  double mass_tolerance = 1e-10;
  MassSolverSettings mass_solver;  // direct or cg (pmg needs a B-spline basis on the grid)
  double conservation_limit = 0.5;
};

}  // namespace mpm
