#pragma once
// Per-step bookkeeping shared by the reconstruction mappings
// (D 3.2.2: Gauss quadrature; 5.3.1: element-wise integration of the reconstructions).
#include <Eigen/Core>
#include <algorithm>
#include <any>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <vector>

#include "basis/gauss_legendre.hpp"
#include "core/parallel.hpp"
#include "state/simulation.hpp"

namespace mpm {

// Particles grouped by the grid cell (element, knot span) containing them: a counting sort,
// O(particles + cells) per step, no allocation after the first step. The cell of each point
// (a division and a rounding per direction) is found in parallel; the counting and the placing
// are serial passes over those cells, so the order is the points' order for any thread count
// (the serial sort was 2-3 % of a TLS step).
template <int Dim>
struct ElementBins {
  std::vector<Index> start;  // particles of cell e: order[start[e] .. start[e + 1])
  std::vector<Index> order;

  void build(const Grid<Dim>& g, const Particles<Dim>& P) { build(g, std::span(P.x)); }
  // Any point set; points outside the grid are left out of every cell. Returns their number.
  Index build(const Grid<Dim>& g, std::span<const Vec<Dim>> x) {
    return build(g, x, [](std::size_t) {});
  }
  // The same, calling each(i) for every point i in the parallel pass (a caller's own work per
  // point, in the same parallel region).
  template <class Each>
  Index build(const Grid<Dim>& g, std::span<const Vec<Dim>> x, Each&& each) {
    const Index ne = g.num_cells();
    cell_.resize(x.size());
    parallel_for(static_cast<Index>(x.size()), [&](Index i) {
      const auto p = static_cast<std::size_t>(i);
      cell_[p] = g.inside(x[p]) ? g.cell_index(x[p]) : -1;
      each(p);
    });
    start.assign(static_cast<std::size_t>(ne + 1), 0);
    Index outside = 0;
    for (const Index e : cell_) {
      if (e < 0)
        ++outside;
      else
        ++start[static_cast<std::size_t>(e + 1)];
    }
    for (Index e = 0; e < ne; ++e)
      start[static_cast<std::size_t>(e + 1)] += start[static_cast<std::size_t>(e)];
    order.resize(static_cast<std::size_t>(start.back()));
    fill_.assign(start.begin(), start.end() - 1);
    for (std::size_t p = 0; p < x.size(); ++p) {
      const Index e = cell_[p];
      if (e >= 0)
        order[static_cast<std::size_t>(fill_[static_cast<std::size_t>(e)]++)] =
            static_cast<Index>(p);
    }
    return outside;
  }
  Index count(Index e) const {
    return start[static_cast<std::size_t>(e + 1)] - start[static_cast<std::size_t>(e)];
  }
  const Index* begin(Index e) const { return order.data() + start[static_cast<std::size_t>(e)]; }
  const Index* end(Index e) const { return order.data() + start[static_cast<std::size_t>(e + 1)]; }

 private:
  std::vector<Index> fill_;  // insertion cursors, kept to avoid an allocation per step
  std::vector<Index> cell_;  // the cell of each point (-1: outside the grid)
};

// Quadrature points of one step with the basis evaluated once at each (D eq. 3.7-3.9, 5.16-5.17).
// A reconstruction mapping fills x, w and element, then calls evaluate(); the assemble_*
// functions integrate reconstructed fields given at the points.
//
// The assembly is a Gauss-point-to-grid scatter run like the particle scatters of the explicit
// core (core/parallel.hpp): the points are split into the fixed chunks of ParticleChunks (a
// function of the point count only), each chunk sums its points in order into its own slice of
// grid buffer (the DOF range its stencils touch, recorded by evaluate()), and the slices are
// added in chunk order. The result is bitwise the same for any thread count; up to
// ParticleChunks::kMinSize points it is one chunk, summed exactly as a serial loop.
template <int Dim>
struct GaussPoints {
  std::vector<Vec<Dim>> x;  // position [m]
  std::vector<double> w;    // weight [m^Dim]
  std::vector<Index> element;

  void clear() {
    x.clear();
    w.clear();
    element.clear();
  }
  void add(const Vec<Dim>& xg, double wg, Index e) {
    x.push_back(xg);
    w.push_back(wg);
    element.push_back(e);
  }
  // n points, to be set by index (a mapping that places them in parallel).
  void resize(std::size_t n) {
    x.resize(n);
    w.resize(n);
    element.resize(n);
  }
  std::size_t size() const { return x.size(); }
};

// The points with the basis stencils at them. Only the stencils depend on the basis: a mapping
// places the points and reconstructs its fields there in code compiled once per dimension
// (GaussPoints), and evaluates the basis and assembles here, once per basis.
template <int Dim, class Basis>
struct QuadraturePoints : GaussPoints<Dim> {
  using GaussPoints<Dim>::x;
  using GaussPoints<Dim>::size;
  std::vector<typename Basis::StencilT> stencil;
  // Scatter state of the assembly: the DOF range of every chunk of points (evaluate()) and the
  // chunk buffers. Mutable: integrating a field does not change the points.
  ChunkDofRanges ranges;
  mutable GridAccumulator<double> scalar;
  mutable GridAccumulator<Vec<Dim>> vector;

  // The basis at every point; step and time name the moment if an iterative basis fails at
  // some point (basis/basis.hpp, kIterative).
  void evaluate(const Basis& basis, Index step, double time) {
    const auto n = static_cast<Index>(x.size());
    stencil.resize(x.size());
    for_each_chunk(n, [&](int c, Index b, Index e) {
      Index lo = std::numeric_limits<Index>::max(), hi = -1;
      for (Index g = b; g < e; ++g) {
        auto& s = stencil[static_cast<std::size_t>(g)];
        basis.evaluate_point(x[static_cast<std::size_t>(g)], s);
        for (int a = 0; a < s.kSize; ++a) {
          lo = std::min(lo, s.dof[a]);
          hi = std::max(hi, s.dof[a]);
        }
      }
      ranges.lo[static_cast<std::size_t>(c)] = lo;
      ranges.hi[static_cast<std::size_t>(c)] = hi;
    });
    ranges.particles = n;
    if constexpr (Basis::kIterative) basis.throw_if_failed(step, time, "Gauss points");
  }
};

// The quadrature points of a simulation type Sim (those of its basis).
template <class Sim>
using QuadraturePointsOf = QuadraturePoints<Sim::kDim, typename Sim::BasisT>;

// The quadrature points of a reconstruction mapping hold basis stencils, whose type depends on
// the basis of the simulation, not known to the mapping class, so a mapping keeps them
// type-erased and recovers them once per call (no allocation after the first step: the vectors keep
// their capacity). map_mass, the first mapping call of every step, prepares them.
class QuadratureStore {
 public:
  template <class Sim>
  QuadraturePointsOf<Sim>& prepare() {
    if (auto* q = std::any_cast<QuadraturePointsOf<Sim>>(&points_)) return *q;
    return points_.emplace<QuadraturePointsOf<Sim>>();
  }
  // The points of the current step; throws when map_mass has not run (a scheme bug).
  template <class Sim>
  const QuadraturePointsOf<Sim>& prepared() const {
    const auto* q = get<Sim>();
    if (q == nullptr)
      throw std::logic_error("a reconstruction mapping needs map_mass first in every step");
    return *q;
  }
  // nullptr before the first map_mass for this Sim.
  template <class Sim>
  const QuadraturePointsOf<Sim>* get() const {
    return std::any_cast<QuadraturePointsOf<Sim>>(&points_);
  }

 private:
  std::any points_;
};

// m_i = sum_g phi_i rho_g w_g (lumped row sums); with consistent mass also
// M_ij = sum_g phi_i rho_g phi_j w_g (D eq. 3.9, 5.17; the triplet list stays serial).
template <int Dim, class B>
void assemble_mass(RunState<Dim>& sim, const QuadraturePoints<Dim, B>& q,
                   const std::vector<double>& rho) {
  auto& m = sim.nodes.mass;
  q.scalar.scatter(m, 0.0, q.ranges, [&](Index g, const auto& slice) {
    const auto gi = static_cast<std::size_t>(g);
    const auto& s = q.stencil[gi];
    const double rw = rho[gi] * q.w[gi];
    for (int a = 0; a < s.kSize; ++a) slice[s.dof[a]] += s.w[a] * rw;
  });
  if (sim.mass_type != MassType::Consistent) return;
  sim.consistent.begin(sim.nodes.size());
  for (std::size_t g = 0; g < q.size(); ++g) {
    const auto& s = q.stencil[g];
    const double rw = rho[g] * q.w[g];
    for (int a = 0; a < s.kSize; ++a)
      for (int b = 0; b < s.kSize; ++b)
        if (s.w[a] != 0.0 && s.w[b] != 0.0)
          sim.consistent.add(s.dof[a], s.dof[b], s.w[a] * rw * s.w[b]);
  }
}

// q_i = sum_g phi_i (rho v)_g w_g (D eq. 3.8, 5.16).
template <int Dim, class B>
void assemble_momentum(RunState<Dim>& sim, const QuadraturePoints<Dim, B>& q,
                       const std::vector<Vec<Dim>>& rhov) {
  using V = Vec<Dim>;
  q.vector.scatter(sim.nodes.momentum, V::Zero(), q.ranges, [&](Index g, const auto& slice) {
    const auto gi = static_cast<std::size_t>(g);
    const auto& s = q.stencil[gi];
    for (int a = 0; a < s.kSize; ++a) slice[s.dof[a]] += (s.w[a] * q.w[gi]) * rhov[gi];
  });
}

// f_i = sum_g ( phi_i (rho b)_g - sigma_g grad phi_i ) w_g (D eq. 3.7 and 5.11 with the body
// force integrated the same way).
template <int Dim, class B>
void assemble_forces(RunState<Dim>& sim, const QuadraturePoints<Dim, B>& q,
                     const std::vector<Vec<Dim>>& rhob, const std::vector<Mat<Dim>>& sigma) {
  using V = Vec<Dim>;
  q.vector.scatter(sim.nodes.force, V::Zero(), q.ranges, [&](Index g, const auto& slice) {
    const auto gi = static_cast<std::size_t>(g);
    const auto& s = q.stencil[gi];
    for (int a = 0; a < s.kSize; ++a)
      slice[s.dof[a]] += q.w[gi] * (s.w[a] * rhob[gi] - sigma[gi] * s.grad[a]);
  });
}

}  // namespace mpm
