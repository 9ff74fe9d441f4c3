#pragma once
// Direct MPM mapping: particles are the quadrature points of the grid integrals
// (D eq. 2.25, 2.44-2.45, 2.48; 004 eq. 4.5-4.7, 4.10).
#include <string_view>

#include "mapping/mapping.hpp"
#include "state/simulation.hpp"

namespace mpm {

struct DirectMapping {
  static constexpr std::string_view kName = "direct";
  static constexpr std::string_view kDescription =
      "standard MPM mapping: particles are the quadrature points (D 3.2, 004 4.4)";
  // Capabilities (mapping/mapping.hpp).
  static constexpr bool kFusedScatter = true, kRunTotals = false, kGhostParticles = false,
                        kStrainRates = false, kCellQuadrature = false;
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }

  // m_i = sum_p phi_i(x_p) m_p (lumped, D eq. 2.24); with consistent mass also
  // M_ij = sum_p phi_i m_p phi_j (D eq. 2.44). The sums run in parallel over fixed particle
  // chunks (core/parallel.hpp): the same bits for any thread count.
  template <class Sim>
  void map_mass(Sim& sim) const {
    map_fused<grid_sum::kMass>(sim);
  }

  // q_i = sum_p phi_i(x_p) m_p v_p (D eq. 2.32 / 2.48).
  template <class Sim>
  void map_momentum(Sim& sim) const {
    map_fused<grid_sum::kMomentum>(sim);
  }

  // f_i = sum_p ( -V_p sigma_p grad phi_i + phi_i m_p b_p ) (D eq. 2.45; rho_p V_p = m_p).
  template <class Sim>
  void map_forces(Sim& sim) const {
    map_fused<grid_sum::kForces>(sim);
  }

  // The sums of What (grid_sum bits) in one pass over the particles and their stencils
  // (stages::map_to_grid): each output is bitwise the one of its own pass. With kVelocityFirst
  // each particle's velocity is advanced by dt with the grid acceleration just before its
  // momentum is scattered (every particle is in exactly one chunk, and evaluate_basis has
  // stopped the run if any was outside the grid, so no chunk's range is empty).
  template <unsigned What, class Sim>
  void map_fused(Sim& sim, double dt = 0.0) const {
    using V = Vec<Sim::kDim>;
    using namespace grid_sum;
    constexpr bool M = What & kMass, Q = What & kMomentum, F = What & kForces;
    auto& sc = sim.scatter;
    const auto& r = ranges(sim);
    const ScatterTarget<double> mt{sc.scalar, sim.nodes.mass, 0.0};
    const ScatterTarget<V> qt{sc.vector, sim.nodes.momentum, V::Zero()};
    // Forces use a buffer of their own when momentum is summed in the same pass.
    const ScatterTarget<V> ft{Q ? sc.vector2 : sc.vector, sim.nodes.force, V::Zero()};
    const None no;
    // The particle sums of the conservation checks are taken in this pass (ChunkSums: the
    // bits of a pass of their own).
    if constexpr (M) sc.particle_mass.reset(0.0);
    if constexpr (Q) sc.particle_momentum.reset(ScatterBuffers<Sim::kDim>::MomentumSums::Zero());
    if constexpr (M && Q && F) {
      scatter_fused(
          r,
          [&](Index p, const auto& m, const auto& q, const auto& f) {
            add<What>(sim, dt, p, m, q, f);
          },
          mt, qt, ft);
    } else if constexpr (M && Q) {
      scatter_fused(
          r, [&](Index p, const auto& m, const auto& q) { add<What>(sim, dt, p, m, q, no); }, mt,
          qt);
    } else if constexpr (M && F) {
      scatter_fused(
          r, [&](Index p, const auto& m, const auto& f) { add<What>(sim, dt, p, m, no, f); }, mt,
          ft);
    } else if constexpr (Q && F) {
      scatter_fused(
          r, [&](Index p, const auto& q, const auto& f) { add<What>(sim, dt, p, no, q, f); }, qt,
          ft);
    } else if constexpr (M) {
      scatter_fused(
          r, [&](Index p, const auto& m) { add<What>(sim, dt, p, m, no, no); }, mt);
    } else if constexpr (Q) {
      scatter_fused(
          r, [&](Index p, const auto& q) { add<What>(sim, dt, p, no, q, no); }, qt);
    } else if constexpr (F) {
      scatter_fused(
          r, [&](Index p, const auto& f) { add<What>(sim, dt, p, no, no, f); }, ft);
    }
    if constexpr (M) sc.has_particle_mass = true;
    if constexpr (Q) sc.has_particle_momentum = true;
    if constexpr (M) {
      if (sim.mass_type == MassType::Consistent) consistent_mass(sim);
    }
  }

 private:
  struct None {};  // the slice of a sum not computed in this pass

  // M_ij = sum_p phi_i m_p phi_j (D eq. 2.44). The triplet list is one shared structure and the
  // consistent mass is rarely used: serial. Entries of weight zero are left out (as the
  // quadrature mappings do): max-ent's window holds 36 entries in 2D of which about 13 are
  // nonzero at d_max = 2, and its 36^2 triplets per particle made the assembly 8x the rest of
  // the step. The matrix is the same; its stored pattern loses the
  // explicit zeros, which can change the factorisation's ordering and so the last bits.
  template <int Dim, class B>
  static void consistent_mass(BasisState<Dim, B>& sim) {
    const auto& P = sim.particles;
    sim.consistent.begin(sim.nodes.size());
    for (Index p = 0; p < P.size(); ++p) {
      const auto& s = sim.stencils[static_cast<std::size_t>(p)];
      const double mp = P.mass[static_cast<std::size_t>(p)];
      for_each_entry(s, sim.dof_stride, [&](Index da, double wa, const auto&) {
        if (wa == 0.0) return;
        for_each_entry(s, sim.dof_stride, [&](Index db, double wb, const auto&) {
          if (wb != 0.0) sim.consistent.add(da, db, wa * mp * wb);
        });
      });
    }
  }

  // Particle p's contributions to the sums of What into the slices m (mass), q (momentum) and
  // f (forces), one pass over its stencil (two with kVelocityFirst).
  template <unsigned What, class Sim, class SM, class SQ, class SF>
  static void add(Sim& sim, double dt, Index p, const SM& m, const SQ& q, const SF& f) {
    using V = Vec<Sim::kDim>;
    using namespace grid_sum;
    auto& P = sim.particles;
    const auto i = static_cast<std::size_t>(p);
    if constexpr ((What & kVelocityFirst) != 0) {  // as stages::update_particles<kVelocity>
      const auto a = sim.nodes.accel.view();
      V acc = V::Zero();
      for_each_entry(sim.stencils[i], sim.dof_stride,
                     [&](Index dof, double w, const auto&) { acc += w * a[dof]; });
      P.v[i] += dt * acc;
    }
    const double mp = P.mass[i];
    [[maybe_unused]] V mv, mb;
    [[maybe_unused]] const Mat<Sim::kDim>* sigma = nullptr;
    [[maybe_unused]] double Vp = 0.0;
    if constexpr ((What & kMomentum) != 0) mv = P.mass[i] * P.v[i];
    if constexpr ((What & kForces) != 0) {
      mb = P.mass[i] * P.body[i];
      sigma = &P.stress[i];
      Vp = P.volume[i];
    }
    if constexpr ((What & kMass) != 0) sim.scatter.particle_mass[m.chunk] += mp;
    if constexpr ((What & kMomentum) != 0) {  // as stages::after_momentum
      typename ScatterBuffers<Sim::kDim>::MomentumSums r;
      r.template head<Sim::kDim>() = mv;
      r[Sim::kDim] = P.mass[i] * P.v[i].norm();
      sim.scatter.particle_momentum[q.chunk] += r;
    }
    // kBody: the body-force term phi_i m_p b_p. A particle with b_p = 0 skips it: f + (0 - t)
    // and f - t are the same bits (a grid sum starts at +0 and never becomes -0), and the term
    // costs 2 x Dim flops per entry (problems without a body force: the yardstick's).
    const auto entries = [&]<bool kBody>() {
      for_each_entry(sim.stencils[i], sim.dof_stride, [&](Index dof, double w, const V& grad) {
        if constexpr ((What & kMass) != 0) m[dof] += w * mp;
        if constexpr ((What & kMomentum) != 0) q[dof] += w * mv;
        if constexpr ((What & kForces) != 0) {
          if constexpr (kBody)
            f[dof] += w * mb - Vp * (*sigma * grad);
          else
            f[dof] -= Vp * (*sigma * grad);
        }
      });
    };
    if constexpr ((What & kForces) != 0) {
      if ((mb.array() != 0.0).any()) {
        entries.template operator()<true>();
        return;
      }
    }
    entries.template operator()<false>();
  }

  // The DOF range of each particle chunk, recorded by evaluate_basis (scanned here if a caller
  // filled the stencils some other way).
  template <class Sim>
  static const ChunkDofRanges& ranges(Sim& sim) {
    auto& r = sim.scatter.ranges;
    if (r.particles != sim.particles.size()) r.scan(sim.stencils, sim.dof_stride);
    return r;
  }
};

}  // namespace mpm
