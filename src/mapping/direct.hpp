#pragma once
// Direct MPM mapping: particles are the quadrature points of the grid integrals
// (D eq. 2.25, 2.44-2.45, 2.48; 004 eq. 4.5-4.7, 4.10).
#include <string_view>

#include "core/simulation.hpp"

namespace mpm {

struct DirectMapping {
  static constexpr std::string_view kName = "direct";

  // m_i = sum_p phi_i(x_p) m_p (lumped, D eq. 2.24); with consistent mass also
  // M_ij = sum_p phi_i m_p phi_j (D eq. 2.44). The sums run in parallel over fixed particle
  // chunks (scheme/parallel.hpp): the same bits for any thread count.
  template <class Sim>
  void map_mass(Sim& sim) const {
    const auto& P = sim.particles;
    sim.scatter.scalar.scatter(sim.nodes.mass, 0.0, ranges(sim), [&](Index p, const auto& m) {
      const auto& s = sim.stencils[static_cast<std::size_t>(p)];
      const double mp = P.mass[static_cast<std::size_t>(p)];
      for (int a = 0; a < s.kSize; ++a) m[s.dof[a]] += s.w[a] * mp;
    });
    if (sim.mass_type != MassType::Consistent) return;
    // The triplet list is one shared structure and the consistent mass is rarely used: serial.
    sim.consistent.begin(sim.nodes.size());
    for (Index p = 0; p < P.size(); ++p) {
      const auto& s = sim.stencils[static_cast<std::size_t>(p)];
      const double mp = P.mass[static_cast<std::size_t>(p)];
      for (int a = 0; a < s.kSize; ++a)
        for (int b = 0; b < s.kSize; ++b)
          sim.consistent.add(s.dof[a], s.dof[b], s.w[a] * mp * s.w[b]);
    }
  }

  // q_i = sum_p phi_i(x_p) m_p v_p (D eq. 2.32 / 2.48).
  template <class Sim>
  void map_momentum(Sim& sim) const {
    using V = Vec<Sim::kDim>;
    const auto& P = sim.particles;
    sim.scatter.vector.scatter(sim.nodes.momentum, V::Zero(), ranges(sim),
                               [&](Index p, const auto& q) {
                                 const auto i = static_cast<std::size_t>(p);
                                 const auto& s = sim.stencils[i];
                                 const V mv = P.mass[i] * P.v[i];
                                 for (int a = 0; a < s.kSize; ++a) q[s.dof[a]] += s.w[a] * mv;
                               });
  }

  // f_i = sum_p ( -V_p sigma_p grad phi_i + phi_i m_p b_p ) (D eq. 2.45; rho_p V_p = m_p).
  template <class Sim>
  void map_forces(Sim& sim) const {
    using V = Vec<Sim::kDim>;
    const auto& P = sim.particles;
    sim.scatter.vector.scatter(sim.nodes.force, V::Zero(), ranges(sim),
                               [&](Index p, const auto& f) {
                                 const auto i = static_cast<std::size_t>(p);
                                 const auto& s = sim.stencils[i];
                                 const auto& sigma = P.stress[i];
                                 const double Vp = P.volume[i];
                                 const V mb = P.mass[i] * P.body[i];
                                 for (int a = 0; a < s.kSize; ++a)
                                   f[s.dof[a]] += s.w[a] * mb - Vp * (sigma * s.grad[a]);
                               });
  }

 private:
  // The DOF range of each particle chunk, recorded by evaluate_basis (scanned here if a caller
  // filled the stencils some other way).
  template <class Sim>
  static const ChunkDofRanges& ranges(Sim& sim) {
    auto& r = sim.scatter.ranges;
    if (r.particles != sim.particles.size()) r.scan(sim.stencils);
    return r;
  }
};

}  // namespace mpm
