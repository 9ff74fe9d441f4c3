#pragma once
// The basis concept. Every basis provides the interface below, and declares its optional
// capabilities as constants; the stages (scheme/stages.hpp, state/sort.hpp) branch on those
// constants, never on whether a member happens to exist, and the concept checks that a declared
// capability has its members. A misspelt member is then a compile error at the basis's
// static_assert instead of a feature silently switched off.
//
// Capabilities:
//   kTensorProduct   compact per-particle stencils (CachedStencilT: 1D factors and the first
//                    DOF) evaluated from the position in cell units: evaluate_scaled(s, c, st);
//                    otherwise the full StencilT from the particle: evaluate(P, p, st)
//   kParticleDomain  the particle's domain must fit the stencil window: fits(P, p) is checked
//                    before every evaluation (GIMP, CPDI)
//   kPrepare         prepare(P) runs before each evaluation pass (DDMPM node volumes, CPDI2
//                    corners)
//   kNodalSums       prepare(P) sums over the particles to the nodes (DDMPM node volumes): a
//                    node's sums need the particles of the cells around it, so a distributed
//                    run lends prepare the other processes' particles of the next cell layer
//                    (stages::evaluate_basis)
//   kTrackedCorners  per-particle state between steps (CPDI2 corners): corners() and
//                    set_corners() (checkpoints), permute(perm) (re-sorting) and advect(sim, dt)
//                    (after the position update)
//   kIterative       the evaluation is an iteration that can fail at a point (max-ent): the
//                    point's weights are NaN and recorded, and every stage that evaluated the
//                    basis calls throw_if_failed(step, time, where) after its loop
//   kTriangleMesh    the functions live on a triangular mesh, mesh() (P1 and Powell-Sabin
//                    splines): element-wise mappings (TLS) fit and integrate over its triangles
//                    instead of the grid's rectangles. Each triangle is the union of pieces()
//                    triangles piece(c, k) on which the functions are polynomials (P1: 1, the
//                    triangle; PS: 6, its Powell-Sabin split), where Gauss rules apply
#include <array>
#include <concepts>
#include <string_view>
#include <vector>

#include "basis/stencil.hpp"
#include "core/types.hpp"
#include "particles/particles.hpp"
#include "particles/permutation.hpp"

namespace mpm {

class TriangleMesh;  // grid/triangle_mesh.hpp

template <class B, int Dim>
concept Basis = requires(const B& b, const Vec<Dim>& x, typename B::StencilT& s, int d, int side,
                         Index i) {
  { B::kName } -> std::convertible_to<std::string_view>;
  { B::kTensorProduct } -> std::convertible_to<bool>;
  { B::kParticleDomain } -> std::convertible_to<bool>;
  { B::kPrepare } -> std::convertible_to<bool>;
  { B::kNodalSums } -> std::convertible_to<bool>;
  { B::kTrackedCorners } -> std::convertible_to<bool>;
  { B::kIterative } -> std::convertible_to<bool>;
  { B::kTriangleMesh } -> std::convertible_to<bool>;
  { b.num_dofs() } -> std::convertible_to<Index>;
  { b.dofs_per_dim() } -> std::convertible_to<IVec<Dim>>;
  { b.dof_position(i) } -> std::convertible_to<Vec<Dim>>;
  { b.boundary_dofs(d, side) } -> std::convertible_to<std::vector<Index>>;
  b.evaluate_point(x, s);  // weights and gradients at any point (tractions, Gauss points)
}
&&(!B::kTensorProduct ||
   requires(const B& b, const Vec<Dim>& s, const IVec<Dim>& c, typename B::CachedStencilT& st) {
     b.evaluate_scaled(s, c, st);
   }) &&
    (B::kTensorProduct || requires(const B& b, const Particles<Dim>& P, Index p,
                                   typename B::StencilT& st) { b.evaluate(P, p, st); }) &&
    (!B::kParticleDomain ||
     requires(const B& b, const Particles<Dim>& P, Index p) {
       { b.fits(P, p) } -> std::convertible_to<bool>;
     }) &&
    (!B::kPrepare || requires(B & b, const Particles<Dim>& P) { b.prepare(P); }) &&
    (!B::kNodalSums || B::kPrepare) &&
    (!B::kTrackedCorners ||
     requires(B & b, const B& cb, Permutation& perm) {
       b.set_corners(cb.corners());
       b.permute(perm);
     }) &&
    (!B::kIterative ||
     requires(const B& b, Index step, double time, std::string_view where) {
       b.throw_if_failed(step, time, where);
     }) &&
    (!B::kTriangleMesh || requires(const B& b, Index c, int k) {
      { b.mesh() } -> std::same_as<const TriangleMesh&>;
      { b.pieces() } -> std::convertible_to<int>;
      { b.piece(c, k) } -> std::convertible_to<std::array<Vec<2>, 3>>;
    });

}  // namespace mpm
