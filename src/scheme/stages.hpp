#pragma once
// The shared stages of every update scheme (D Algorithms 1-2, D 2.6.3). A scheme is an order of
// these calls; no stage knows which scheme calls it. Per-particle loops are plain loops over the
// struct-of-arrays with the basis and material resolved at compile time, run in parallel with
// OpenMP (core/parallel.hpp); every sum across particles has the same rounding for any
// thread count.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "basis/gauss_legendre.hpp"
#include "core/parallel.hpp"
#include "parallel/distribution.hpp"
#include "state/simulation.hpp"

namespace mpm {
class TriangleMesh;  // grid/triangle_mesh.hpp
}  // namespace mpm

namespace mpm::stages {

// The failures of the stages, formatted once per dimension (scheme/grid_stages.cpp): exit code,
// step, time and the particles (by id, with their positions; at most 8 listed) or points named.
// ids: particle indices.
template <int Dim>
[[noreturn]] void throw_unfit(const RunState<Dim>& sim, const std::vector<Index>& ids,
                              std::string_view basis);
// Every particle outside the grid (the grid's box named).
template <int Dim>
[[noreturn]] void throw_left_grid(const RunState<Dim>& sim);
// As throw_left_grid when a particle left the grid; otherwise the particles in no triangle of
// the mesh (a mesh from a file that does not fill its bounding box).
[[noreturn]] void throw_left_mesh(const RunState<2>& sim, const TriangleMesh& mesh);
// The face point x_face of particle index i's loaded face outside the grid (mesh: outside the
// triangles of the basis's mesh).
template <int Dim>
[[noreturn]] void throw_face_left_grid(const RunState<Dim>& sim, std::size_t i,
                                       const Vec<Dim>& x_face, bool mesh = false);
// Non-finite stress or F, else det F <= 0, at the particles where it holds.
template <int Dim>
[[noreturn]] void throw_particle_failure(const RunState<Dim>& sim);

// F, V, rho, the stress and the law's internal variables of the particles [b, e) from their
// velocity gradients L[0, e - b) over the increment dt (D eq. 2.40-2.43): F = (I + dt L) F,
// V = det F V0 (so rho = m / V), sigma by each particle's material's law. True when a particle
// failed (det F <= 0 or a non-finite stress). Compiled once per dimension (scheme/deform.cpp): the
// laws' return mappings are instantiated there, not once per basis in every stepper unit.
// Shared by the MPM stages and OTM (methods/otm.cpp).
template <int Dim>
bool deform_particles(Particles<Dim>& P, const Materials& materials, Index b, Index e,
                      const Mat<Dim>* L, double dt);

// The particles per block of update_particles' stress pass: their velocity gradients (a
// 3x3 matrix each, 9 KB in 3D) stay in the core's cache between the gather and the law.
inline constexpr Index kDeformBlock = 128;

// D Alg. 2 step 3: basis values and gradients at x_p^s. Stops the run (exit code 4) when a
// particle has left the grid, and counts grid crossings.
template <int Dim, class B>
void evaluate_basis(BasisState<Dim, B>& sim) {
  const StageTimer timer(sim.clock, Stage::kBasis);
  auto& P = sim.particles;
  auto& basis = sim.basis;
  // Bases built from the particle distribution (DDMPM node volumes, CPDI2 corners) refresh it
  // first.
  if constexpr (B::kPrepare) {
    // A node's sums (DDMPM) read the particles of the cells around it: in a distributed run the
    // other processes' particles within a cell are lent for them.
    if constexpr (B::kNodalSums)
      if (sim.comm) append_ghosts(sim, *sim.comm, 1.0);
    basis.prepare(P);
    remove_ghosts(sim);
  }
  const auto& g = sim.grid;
  // Per chunk: flags, crossings and the DOF range of the new stencils (recorded here, while
  // the stencils are in cache, for the scatters of DirectMapping).
  constexpr std::size_t K = ParticleChunks::kMax;
  std::array<std::uint8_t, K> chunk_outside{}, chunk_unfit{};
  std::array<Index, K> chunk_crossings{};
  auto& ranges = sim.scatter.ranges;
  // A distributed run: the box of DOF coordinates each chunk's stencils touch (RunState::
  // stencil_box, for the exchange of the grid sums).
  const bool boxes = sim.comm != nullptr;
  std::array<std::array<IVec<Dim>, 2>, K> chunk_box;
  for_each_chunk(P.size(), [&](int chunk, Index b, Index e) {
    const auto ck = static_cast<std::size_t>(chunk);
    Index lo = std::numeric_limits<Index>::max(), hi = -1;
    auto& [box_lo, box_hi] = chunk_box[ck];
    box_lo.fill(std::numeric_limits<Index>::max());
    box_hi.fill(-1);
    for (Index p = b; p < e; ++p) {
      const auto i = static_cast<std::size_t>(p);
      auto& s = sim.stencils[i];
      // Tensor-product bases take the position in cell units computed here for the checks (one
      // division per direction instead of three: inside, cell index, basis): inside iff s is in
      // [0, cells] in every direction (NaN fails), as Grid::inside.
      [[maybe_unused]] Vec<Dim> sx;
      bool in = true;
      if constexpr (B::kTensorProduct) {
        for (int d = 0; d < Dim; ++d) {
          sx[d] = (P.x[i][d] - g.origin[d]) / g.h[d];
          in = in && sx[d] >= 0.0 && sx[d] <= static_cast<double>(g.cells[d]);
        }
      } else {
        in = g.inside(P.x[i]);
      }
      if (!in) {
        chunk_outside[ck] = 1;
        continue;
      }
      if constexpr (B::kParticleDomain) {
        if (!basis.fits(P, p)) {
          chunk_unfit[ck] = 1;
          continue;
        }
      }
      Index c = 0;
      if constexpr (B::kTensorProduct) {
        // cell_of_scaled is Grid::cell_of on the scaled position.
        IVec<Dim> cx;
        Index stride = 1;
        for (int d = 0; d < Dim; ++d) {
          cx[d] = cell_of_scaled(sx[d], g.cells[d]);
          c += cx[d] * stride;
          stride *= g.cells[d];
        }
        basis.evaluate_scaled(sx, cx, s);
      } else if constexpr (B::kTriangleMesh) {
        // A mesh from a file need not fill the grid (its bounding box): a particle in no
        // triangle stops the run as one outside the grid does.
        c = g.cell_index(P.x[i]);
        if (!basis.evaluate(P, p, s)) {
          chunk_outside[ck] = 1;
          continue;
        }
      } else {
        c = g.cell_index(P.x[i]);
        basis.evaluate(P, p, s);
      }
      if (sim.cell[i] >= 0 && c != sim.cell[i]) ++chunk_crossings[ck];
      sim.cell[i] = static_cast<CompactIndex>(c);
      const auto [sl, sh] = dof_bounds(s, sim.dof_stride);
      lo = std::min(lo, sl);
      hi = std::max(hi, sh);
      if (boxes) extend_dof_box(s, sim.dof_stride, box_lo, box_hi);
    }
    ranges.lo[ck] = lo;
    ranges.hi[ck] = hi;
  });
  ranges.particles = P.size();
  if (boxes) {
    auto& [box_lo, box_hi] = sim.stencil_box;
    box_lo.fill(std::numeric_limits<Index>::max());
    box_hi.fill(-1);
    for (int c = 0; c < ParticleChunks::count(P.size()); ++c)
      for (int d = 0; d < Dim; ++d) {
        const auto& [l, h] = chunk_box[static_cast<std::size_t>(c)];
        box_lo[static_cast<std::size_t>(d)] =
            std::min(box_lo[static_cast<std::size_t>(d)], l[static_cast<std::size_t>(d)]);
        box_hi[static_cast<std::size_t>(d)] =
            std::max(box_hi[static_cast<std::size_t>(d)], h[static_cast<std::size_t>(d)]);
      }
    sim.stencil_box_particles = P.size();
  }
  bool outside = false, unfit = false;
  for (std::size_t c = 0; c < K; ++c) {
    outside = outside || chunk_outside[c];
    unfit = unfit || chunk_unfit[c];
    sim.diag.grid_crossings += chunk_crossings[c];
  }
  if constexpr (B::kParticleDomain) {
    if (unfit && !outside) {
      std::vector<Index> ids;
      for (Index p = 0; p < P.size(); ++p)
        if (!basis.fits(P, p)) ids.push_back(p);
      throw_unfit(sim, ids, B::kName);
    }
  }
  if (outside) {
    if constexpr (B::kTriangleMesh)
      throw_left_mesh(sim, basis.mesh());
    else
      throw_left_grid(sim);
  }
  if constexpr (B::kIterative) basis.throw_if_failed(sim.step, sim.time, "particles");
  if (sim.comm) sim.fit_dof_window();  // the grid arrays of this process's slab
}

// Body force b_p(x, t) for this step (constant forces were filled once at set-up).
template <int Dim>
void refresh_body_force(RunState<Dim>& sim) {
  if (sim.body_force.time_dependent || sim.body_force.position_dependent)
    sim.body_force.fill(sim.particles, sim.time, sim.particles.body);
}

// A distributed run (sim.comm): each rank's partial sums of What (grid_sum bits kMass, kMomentum,
// kForces) on the DOFs its particles touched are added to those of the ranks that share them,
// in rank order, so that every rank holds the same totals (scheme/grid_stages.cpp). Nothing on
// one process.
template <int Dim>
void share_grid_sums(RunState<Dim>& sim, unsigned what);

// The active set and the mass conservation check, and the consistent matrix if requested,
// from the nodal masses of the mapping (scheme/grid_stages.cpp).
template <int Dim>
void after_mass(RunState<Dim>& sim);

// The momentum conservation check from the nodal momenta of the mapping.
template <int Dim>
void after_momentum(RunState<Dim>& sim);

// Tractions through the particles next to the loaded faces (Traction: one face point per loaded
// particle, tau evaluated once per face), added to the forces of the mapping. kPatches (the
// mapping's kCellQuadrature): the load of a point with a patch (Traction::patch, a box face) is
// integrated over the patch by `gauss` Gauss-Legendre points per direction in the face, the
// mapping's count per direction of a cell, so that the load is integrated as exactly as the
// masses are (degree 2 gauss - 1 while the patch lies in one cell); at the face point alone a
// B-spline of degree >= 2 gets the midpoint sum of its integral across the face, and the rows of
// a uniform load would accelerate differently. Without it, the point alone: the particles' own
// quadrature, that of the direct mapping's masses.
template <bool kPatches, int Dim, class B>
void after_forces(BasisState<Dim, B>& sim, int gauss = 1) {
  const auto& P = sim.particles;
  const GaussRule rule = kPatches ? gauss_legendre(gauss) : GaussRule{};
  const int n = std::max(1, static_cast<int>(rule.xi.size()));
  for (const auto& tr : sim.tractions) {
    const Vec<Dim> tau = tr.value(sim.time);
    const double p = tr.pressure ? tr.pressure(sim.time) : 0.0;
    // The directions in the face that the patch spans, and its Gauss points.
    std::array<int, 2> along{};
    int spans = 0;
    if constexpr (kPatches && Dim > 1)
      for (int d = 0; d < Dim; ++d)
        if (tr.patch[d] > 0.0) along[static_cast<std::size_t>(spans++)] = d;
    int points = 1;
    for (int t = 0; t < spans; ++t) points *= n;
    for (std::size_t k = 0; k < tr.particles.size(); ++k) {
      const auto i = static_cast<std::size_t>(tr.particles[k]);
      Vec<Dim> centre = P.x[i];
      if constexpr (Dim == 1)
        centre[0] += 0.5 * tr.side * P.volume[i];  // V_p: the current length
      else
        centre += P.F[i] * tr.offset[k];
      // A_p = 1 in 1D: tau * 1.0 is exact, so the 1D forces are those of the end traction.
      const Vec<Dim> load = tr.point_force(k, tau, p);
      for (int q = 0; q < points; ++q) {
        Vec<Dim> x_face = centre;
        Vec<Dim> f = load;
        if (spans > 0) {
          Vec<Dim> local = Vec<Dim>::Zero();  // from the face point, in the reference patch
          double share = 1.0;
          for (int t = 0, r = q; t < spans; ++t, r /= n) {
            const auto j = static_cast<std::size_t>(r % n);
            const int d = along[static_cast<std::size_t>(t)];
            local[d] = 0.5 * rule.xi[j] * tr.patch[d];
            share *= 0.5 * rule.w[j];
          }
          x_face += P.F[i] * local;
          f *= share;
        }
        if (!sim.grid.inside(x_face)) throw_face_left_grid(sim, i, x_face);
        typename BasisState<Dim, B>::StencilT s;
        if constexpr (B::kTriangleMesh) {
          // A mesh need not fill its box: a point outside the triangles would lose its load.
          if (!sim.basis.evaluate_point(x_face, s)) throw_face_left_grid(sim, i, x_face, true);
        } else {
          sim.basis.evaluate_point(x_face, s);
        }
        if (sim.comm) {  // a DOF maybe beyond this process's sums: share_grid_sums places them
          for (int a = 0; a < s.kSize; ++a) sim.face_forces.emplace_back(s.dof[a], s.w[a] * f);
          continue;
        }
        for (int a = 0; a < s.kSize; ++a)
          sim.nodes.force[static_cast<std::size_t>(s.dof[a])] += s.w[a] * f;
      }
    }
  }
  if constexpr (B::kIterative)
    if (!sim.tractions.empty()) sim.basis.throw_if_failed(sim.step, sim.time, "traction faces");
}

// For the sums of a mapping that reads the particles of neighbouring cells (kGhostParticles:
// TLS's completions, free-surface test and domain integrals) in a distributed run: the other
// processes' particles within the mapping's reach (ghost_reach, in cells along every axis, the
// largest of any process) are appended to this process's while the object lives
// (parallel/distribution.hpp). Fresh copies for every sum: the particles' velocities and stresses
// change between them.
template <class Sim>
class GhostParticles {
 public:
  explicit GhostParticles(Sim& sim) : sim_(sim) {
    if constexpr (Sim::MappingT::kGhostParticles) {
      if (sim.comm == nullptr) return;
      append_ghosts(sim, *sim.comm, sim.mapping.ghost_reach(sim));
    }
  }
  ~GhostParticles() { remove_ghosts(sim_); }
  GhostParticles(const GhostParticles&) = delete;
  GhostParticles& operator=(const GhostParticles&) = delete;

 private:
  Sim& sim_;
};

// The particle-to-grid sums of What (grid_sum bits: masses, D eq. 2.31 / 2.44; momenta,
// 2.32 / 2.48; forces, 2.33 / 2.45) with their checks, and the tractions after the forces.
// A mapping with map_fused computes them in one pass over the particles (the same bits as
// separate passes); the others map them one by one.
template <unsigned What, class Sim>
void map_to_grid(Sim& sim) {
  using namespace grid_sum;
  const StageTimer timer(sim.clock, Stage::kToGrid);
  if constexpr (Sim::MappingT::kFusedScatter) {
    sim.mapping.template map_fused<What>(sim);
  } else {
    const GhostParticles<Sim> ghosts(sim);
    if constexpr ((What & kMass) != 0) sim.mapping.map_mass(sim);
    if constexpr ((What & kMomentum) != 0) sim.mapping.map_momentum(sim);
    if constexpr ((What & kForces) != 0) sim.mapping.map_forces(sim);
  }
  // The tractions first, so that a distributed run shares the whole forces.
  if constexpr ((What & kForces) != 0) {
    if constexpr (Sim::MappingT::kCellQuadrature)
      after_forces<true>(sim, sim.mapping.gauss_points());
    else
      after_forces<false>(sim);
  }
  if (sim.comm) share_grid_sums(sim, What & (kMass | kMomentum | kForces));
  if constexpr ((What & kMass) != 0) after_mass(sim);
  if constexpr ((What & kMomentum) != 0) after_momentum(sim);
}

// Nodal (lumped) masses, the consistent matrix if requested, the active set, and the mass
// conservation check of the mapping.
template <class Sim>
void map_mass(Sim& sim) {
  map_to_grid<grid_sum::kMass>(sim);
}

template <class Sim>
void map_momentum(Sim& sim) {
  map_to_grid<grid_sum::kMomentum>(sim);
}

// Internal and body forces from the mapping, then the tractions.
template <class Sim>
void map_forces(Sim& sim) {
  map_to_grid<grid_sum::kForces>(sim);
}

// a_i = M^{-1} f_i with Dirichlet components zero (D eq. 2.46; scheme/grid_stages.cpp), with
// the frictional walls' contact and friction over the step's increment dt [s].
template <int Dim>
void solve_acceleration(RunState<Dim>& sim, double dt);

// v_i = M^{-1} q_i with Dirichlet components zero (D eq. 2.35 / 2.49); no velocity into a
// frictional wall.
template <int Dim>
void solve_velocity(RunState<Dim>& sim);

// Euler-Cromer on the grid: v_i^{s+1} = v_i^s + dt a_i^s (D eq. 2.36; USL, USF).
template <int Dim>
void advance_grid_velocity(RunState<Dim>& sim, double dt);

// The grid-to-particle updates of What (particle_update bits) in one pass over the particles
// and their stencils at x_p^s (each particle's updates are independent of the others', so the
// results are bitwise those of separate passes):
//   velocity: v_p^{s+1} = v_p^s + dt sum_i phi_i a_i^s (D eq. 2.39 / 2.47);
//   position: x_p^{s+1} = x_p^s + dt sum_i phi_i v_i^{s+1}, the same increment for u_p
//     (Euler-Cromer: positions use the new velocity; D eq. 2.38 / 2.51);
//   stress: the velocity gradient from the current grid velocity, then F, V, rho and the stress
//     (D eq. 2.52-2.55 and step 14) over the increment stress_dt (dt/2 in USAVG).
template <unsigned What, int Dim, class B>
void update_particles(BasisState<Dim, B>& sim, double dt, double stress_dt) {
  using namespace particle_update;
  const StageTimer timer(sim.clock, Stage::kToParticles);
  auto& P = sim.particles;
  const auto a = sim.nodes.accel.view();
  const auto v = sim.nodes.velocity.view();
  // The mapping's velocity gradients, where it gave them (RunState::mapped_gradient).
  const Mat<Dim>* mapped = nullptr;
  if constexpr ((What & kStress) != 0) {
    if (!sim.mapped_gradient.empty()) {
      if (static_cast<Index>(sim.mapped_gradient.size()) != P.size())
        throw std::logic_error("update_particles: mapped gradients of another particle set");
      mapped = sim.mapped_gradient.data();
    }
  }
  // One particle's grid sums; its velocity gradient L_ab = dv_a/dx_b into *out where the stress
  // is updated (not where the mapping gave it).
  const auto gather = [&](std::size_t i, [[maybe_unused]] Mat<Dim>* out) {
    Vec<Dim> acc = Vec<Dim>::Zero(), dx = Vec<Dim>::Zero();
    Mat<Dim> L = Mat<Dim>::Zero();
    for_each_entry(sim.stencils[i], sim.dof_stride, [&](Index dof, double w, const Vec<Dim>& grad) {
      const auto k = static_cast<std::size_t>(dof);
      if constexpr ((What & kVelocity) != 0) acc += w * a[k];
      if constexpr ((What & kPosition) != 0) dx += w * v[k];
      if constexpr ((What & kStress) != 0) L.noalias() += v[k] * grad.transpose();
    });
    if constexpr ((What & kVelocity) != 0) P.v[i] += dt * acc;
    if constexpr ((What & kPosition) != 0) {
      dx *= dt;
      P.x[i] += dx;
    }
    if constexpr ((What & kStress) != 0)
      if (out != nullptr) *out = L;
  };
  bool bad = false;  // any particle failed
  if constexpr ((What & kStress) != 0) {
    // Per block: the grid sums and velocity gradients, then the material's law over the block
    // (deform_particles, the law resolved once per block).
    bad = parallel_any_block(P.size(), kDeformBlock, [&](Index b, Index e) {
      std::array<Mat<Dim>, kDeformBlock> Ls;
      for (Index p = b; p < e; ++p)
        gather(static_cast<std::size_t>(p),
               mapped != nullptr ? nullptr : &Ls[static_cast<std::size_t>(p - b)]);
      const StageTimer material(sim.clock, Stage::kMaterial);  // one thread (StageClock)
      return deform_particles(P, sim.materials, b, e, mapped != nullptr ? mapped + b : Ls.data(),
                              stress_dt);
    });
  } else {
    parallel_for(P.size(), [&](Index p) { gather(static_cast<std::size_t>(p), nullptr); });
  }
  if constexpr ((What & kStress) != 0) sim.mapped_gradient.clear();
  // Bases that track particle-domain corners (CPDI2) move them with the same grid velocity.
  if constexpr ((What & kPosition) != 0) {
    if constexpr (B::kTrackedCorners) sim.basis.advect(sim, dt);
  }
  if (bad) throw_particle_failure(sim);
}

template <unsigned What, int Dim, class B>
void update_particles(BasisState<Dim, B>& sim, double dt) {
  update_particles<What>(sim, dt, dt);
}

// v_p^{s+1} = v_p^s + dt sum_i phi_i(x_p^s) a_i^s (D eq. 2.39 / 2.47).
template <int Dim, class B>
void update_particle_velocity(BasisState<Dim, B>& sim, double dt) {
  update_particles<particle_update::kVelocity>(sim, dt);
}

// x_p^{s+1} = x_p^s + dt sum_i phi_i(x_p^s) v_i^{s+1}, and the same increment for u_p.
template <int Dim, class B>
void update_particle_position(BasisState<Dim, B>& sim, double dt) {
  update_particles<particle_update::kPosition>(sim, dt);
}

// The velocity gradients that the next stress update reads, where the mapping defines its own
// (MappingFor's kStrainRates: TLS with method.tls_strain_rate = "adjoint", from the current grid
// velocity); nothing otherwise, and the update takes each particle's from its stencil.
template <class Sim>
void mapped_strain_rates(Sim& sim) {
  if constexpr (Sim::MappingT::kStrainRates) sim.mapping.strain_rates(sim);
}

// F, V, rho and the stress from the current grid velocity (D eq. 2.52-2.55). dt is the
// increment this update covers (dt/2 in USAVG).
template <int Dim, class B>
void update_stress(BasisState<Dim, B>& sim, double dt) {
  update_particles<particle_update::kStress>(sim, dt);
}

// v_p^{s+1} = v_p^s + dt sum_i phi_i(x_p^s) a_i^s (D eq. 2.47), then q_i from v_p^{s+1}
// (2.48) with its check: one pass over the particles with a mapping that fuses them
// (DirectMapping; the same bits as the two stages), else the two stages.
template <class Sim>
void update_velocity_map_momentum(Sim& sim, double dt) {
  using namespace grid_sum;
  if constexpr (Sim::MappingT::kFusedScatter) {
    // (The two stages of the other branch time themselves.)
    const StageTimer timer(sim.clock, Stage::kToGrid);
    sim.mapping.template map_fused<kMomentum | kVelocityFirst>(sim, dt);
    if (sim.comm) share_grid_sums(sim, kMomentum);
    after_momentum(sim);
  } else {
    update_particle_velocity(sim, dt);
    map_momentum(sim);
  }
}

}  // namespace mpm::stages
