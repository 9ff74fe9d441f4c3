#pragma once
// Partial lumping of the consistent mass matrix (method.partial_lumping): D 7.2 reports that
// lumping the mass matrix partially gave PS-MPM "a stable and relatively accurate solution" with
// partially filled elements, where the consistent matrix of a DOF reached only through the few
// particles of a partly filled element is singular or nearly so (docs/verification.md, "PS-MPM
// with partially filled elements", and TLS with consistent mass on the vortex). The rule here:
// in each step the DOFs whose functions the particles cover to less than a fraction of their
// integrals (each element's fill, its particles' volumes over its own, weighted by the
// function's integral over it: mark_lumped_rows in scheme/grid_stages.cpp) get lumped rows and
// columns (ConsistentMass::set_lumped, which keeps every row sum and so the conserved totals); the
// DOFs inside the body keep their consistent rows. This header sets up the elements with the
// integrals of the functions over each, once per run.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "mapping/quadrature.hpp"
#include "state/simulation.hpp"

namespace mpm {

// The elements of sim's basis, the DOFs whose functions do not vanish in each and the integrals
// of those functions over it, by Gauss rules exact for the basis's pieces: 3 Gauss-Legendre
// points per direction on a grid cell (degree 5 per direction: the B-splines up to quintic, the
// hats of linear, GIMP and CPDI), and on each piece of a triangle (P1: the triangle; PS: its six
// Powell-Sabin triangles, on which the functions are quadratics) the three-point rule at
// barycentric (2/3, 1/6, 1/6), exact for quadratics. `below`: method.partial_lumping (> 0).
template <int Dim, class B>
void setup_partial_lumping(BasisState<Dim, B>& sim, double below) {
  if constexpr (B::kIterative) {
    // Max-ent's functions are not polynomials on elements: no rule integrates them.
    throw InputError(std::string("method.partial_lumping needs a basis whose functions are "
                                 "piecewise polynomials on the grid's cells or triangles; the ") +
                     std::string(B::kName) + " basis is not");
  } else {
    auto& L = sim.lumping;
    L.below = below;
    L.first.assign(1, 0);
    L.dofs.clear();
    L.share.clear();
    L.volume.clear();
    L.integral.assign(static_cast<std::size_t>(sim.basis.num_dofs()), 0.0);
    typename B::StencilT s;
    std::vector<std::pair<Index, double>> seen;  // (DOF, weight x N_i) of the element's points
    const auto sample = [&](const Vec<Dim>& x, double weight) {
      sim.basis.evaluate_point(x, s);
      for (int a = 0; a < s.kSize; ++a)
        if (s.w[a] != 0.0) seen.emplace_back(s.dof[a], weight * s.w[a]);
    };
    const auto close = [&](double volume) {
      std::sort(seen.begin(), seen.end(),
                [](const auto& a, const auto& b) { return a.first < b.first; });
      for (std::size_t k = 0; k < seen.size();) {
        const Index dof = seen[k].first;
        double integral = 0.0;
        for (; k < seen.size() && seen[k].first == dof; ++k) integral += seen[k].second;
        L.dofs.push_back(dof);
        L.share.push_back(integral);
        L.integral[static_cast<std::size_t>(dof)] += integral;
      }
      L.first.push_back(static_cast<Index>(L.dofs.size()));
      L.volume.push_back(volume);
      seen.clear();
    };
    if constexpr (B::kTriangleMesh) {
      const auto& mesh = sim.basis.mesh();
      for (Index c = 0; c < mesh.num_cells(); ++c) {
        for (int k = 0; k < sim.basis.pieces(); ++k) {
          const std::array<Vec<2>, 3> t = sim.basis.piece(c, k);
          const double area = 0.5 * std::abs((t[1] - t[0])[0] * (t[2] - t[0])[1] -
                                             (t[1] - t[0])[1] * (t[2] - t[0])[0]);
          for (int q = 0; q < 3; ++q) {
            const auto a = static_cast<std::size_t>(q);
            sample((2.0 * t[a] + 0.5 * (t[(a + 1) % 3] + t[(a + 2) % 3])) / 3.0, area / 3.0);
          }
        }
        close(mesh.cell_volume(c));
      }
      L.element_of = [&mesh](const Vec<2>& x) { return mesh.cell_index(x); };
    } else {
      const auto& g = sim.grid;
      double volume = 1.0;
      for (int d = 0; d < Dim; ++d) volume *= g.h[d];
      // The 3-point Gauss-Legendre rule moved from [-1, 1] to [0, 1].
      const GaussRule rule = gauss_legendre(3);
      std::array<double, 3> at{}, wt{};
      for (std::size_t j = 0; j < 3; ++j) {
        at[j] = 0.5 * (rule.xi[j] + 1.0);
        wt[j] = 0.5 * rule.w[j];
      }
      int points = 1;
      for (int d = 0; d < Dim; ++d) points *= 3;
      for (Index c = 0; c < g.num_cells(); ++c) {
        const IVec<Dim> cx = g.cell_coords(c);
        for (int q = 0; q < points; ++q) {
          Vec<Dim> x;
          double w = volume;
          int rq = q;
          for (int d = 0; d < Dim; ++d, rq /= 3) {
            const auto j = static_cast<std::size_t>(rq % 3);
            x[d] = g.origin[d] + (static_cast<double>(cx[d]) + at[j]) * g.h[d];
            w *= wt[j];
          }
          sample(x, w);
        }
        close(volume);
      }
      L.element_of = nullptr;  // the particle's grid cell (RunState::cell)
    }
  }
}

}  // namespace mpm
