// The stages that read and write only the grid quantities of RunState (scheme/stages.hpp), and
// the stages' failure messages: compiled once per dimension here, not in every stepper unit.
#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/parallel.hpp"
#include "grid/triangle_mesh.hpp"
#include "parallel/distributed_pmg.hpp"
#include "scheme/stages.hpp"

namespace mpm::stages {

namespace {
// Formats at most `limit` particles (indices) by stable id with their positions for failure
// messages.
template <int Dim>
std::string describe_particles(const Particles<Dim>& P, const std::vector<Index>& ids,
                               std::size_t limit = 8) {
  std::string out;
  for (std::size_t k = 0; k < ids.size() && k < limit; ++k) {
    const auto i = static_cast<std::size_t>(ids[k]);
    out += fmt::format("{}particle {} at x = (", k ? "; " : "", i < P.id.size() ? P.id[i] : ids[k]);
    for (int d = 0; d < Dim; ++d) out += fmt::format("{}{:.6g}", d ? ", " : "", P.x[i][d]);
    out += ")";
  }
  if (ids.size() > limit) out += fmt::format("; and {} more", ids.size() - limit);
  return out;
}

// A point as "0.5" in 1D and "(0.5, 0.25)" in more dimensions.
template <int Dim>
std::string describe_point(const Vec<Dim>& x) {
  if constexpr (Dim == 1) return fmt::format("{:.6g}", x[0]);
  std::string out = "(";
  for (int d = 0; d < Dim; ++d) out += fmt::format("{}{:.6g}", d ? ", " : "", x[d]);
  return out + ")";
}

// The grid's extent as "[0, 1]" in 1D and "[0, 1] x [0, 2]" in more dimensions.
template <int Dim>
std::string describe_box(const Grid<Dim>& g) {
  const Vec<Dim> hi = g.upper();
  std::string out;
  for (int d = 0; d < Dim; ++d)
    out += fmt::format("{}[{:.6g}, {:.6g}]", d ? " x " : "", g.origin[d], hi[d]);
  return out;
}
}  // namespace

template <int Dim>
void throw_unfit(const RunState<Dim>& sim, const std::vector<Index>& ids, std::string_view basis) {
  throw RunError(
      exit_code::kInvertedDeformation,
      fmt::format("step {}, t = {:.9g} s: the domain of {} particle(s) cannot be "
                  "represented by the {} basis (stretched beyond its stencil or "
                  "reaching outside the grid): {}",
                  sim.step, sim.time, ids.size(), basis, describe_particles(sim.particles, ids)));
}

template <int Dim>
void throw_left_grid(const RunState<Dim>& sim) {
  const auto& P = sim.particles;
  std::vector<Index> ids;
  for (Index p = 0; p < P.size(); ++p)
    if (!sim.grid.inside(P.x[static_cast<std::size_t>(p)])) ids.push_back(p);
  throw RunError(
      exit_code::kLeftGrid,
      fmt::format("step {}, t = {:.9g} s: {} particle(s) left the grid {}: {}", sim.step, sim.time,
                  ids.size(), describe_box(sim.grid), describe_particles(P, ids)));
}

void throw_left_mesh(const RunState<2>& sim, const TriangleMesh& mesh) {
  const auto& P = sim.particles;
  std::vector<Index> ids;
  for (Index p = 0; p < P.size(); ++p)
    if (!sim.grid.inside(P.x[static_cast<std::size_t>(p)])) throw_left_grid(sim);
  for (Index p = 0; p < P.size(); ++p)
    if (!mesh.inside(P.x[static_cast<std::size_t>(p)])) ids.push_back(p);
  throw RunError(
      exit_code::kLeftGrid,
      fmt::format("step {}, t = {:.9g} s: {} particle(s) left the mesh ({}): {}", sim.step,
                  sim.time, ids.size(), mesh.source(), describe_particles(P, ids)));
}

template <int Dim>
void throw_face_left_grid(const RunState<Dim>& sim, std::size_t i, const Vec<Dim>& x_face,
                          bool mesh) {
  throw RunError(exit_code::kLeftGrid,
                 fmt::format("step {}, t = {:.9g} s: the loaded face of the body (particle "
                             "{}, face point at x = {}) left the {}",
                             sim.step, sim.time, sim.particles.id[i], describe_point(x_face),
                             mesh ? std::string("mesh (no triangle holds it)")
                                  : "grid " + describe_box(sim.grid)));
}

// The laws of the particles `which` (their materials'), as "a" or "a and b".
template <int Dim>
std::string failed_law_names(const RunState<Dim>& sim, const std::vector<Index>& which) {
  Materials laws;
  for (const Index p : which) {
    const std::size_t k =
        sim.materials.size() == 1 ? 0 : sim.particles.material[static_cast<std::size_t>(p)];
    if (laws.find(sim.materials.name(k)) == laws.size())
      laws.add(sim.materials.name(k), sim.materials[k]);
  }
  return laws.law_names();
}

template <int Dim>
void throw_particle_failure(const RunState<Dim>& sim) {
  const auto& P = sim.particles;
  std::vector<Index> inverted, nonfinite, unreturned;
  std::vector<double> residual;
  for (Index p = 0; p < P.size(); ++p) {
    const auto i = static_cast<std::size_t>(p);
    if (!std::isfinite(P.stress[i].sum()) || !std::isfinite(P.F[i].sum())) {
      nonfinite.push_back(p);
    } else if (!(P.F[i].determinant() > 0.0)) {
      inverted.push_back(p);
    } else if (const auto r = failed_update<Dim>(sim.materials, P, i)) {
      unreturned.push_back(p);
      residual.push_back(*r);
    }
  }
  if (!unreturned.empty()) {
    // Each particle with the stress its update left (the trial stress) and the residual.
    std::string what;
    constexpr std::size_t kLimit = 8;
    for (std::size_t k = 0; k < unreturned.size() && k < kLimit; ++k) {
      const auto i = static_cast<std::size_t>(unreturned[k]);
      what += fmt::format("{}{}: trial Cauchy stress [", k ? "; " : "",
                          describe_particles(P, {unreturned[k]}));
      for (int a = 0; a < Dim; ++a)
        for (int b = a; b < Dim; ++b)
          what += fmt::format("{}s{}{} = {:.6g}", a + b ? ", " : "", "xyz"[a], "xyz"[b],
                              P.stress[i](a, b));
      what += fmt::format("] Pa, yield function there {:.6g} Pa", residual[k]);
    }
    if (unreturned.size() > kLimit)
      what += fmt::format("; and {} more", unreturned.size() - kLimit);
    throw RunError(exit_code::kReturnMapping,
                   fmt::format("step {}, t = {:.9g} s: the return mapping of material.model = "
                               "\"{}\" found no admissible stress at {} particle(s): {}",
                               sim.step, sim.time, failed_law_names(sim, unreturned),
                               unreturned.size(), what));
  }
  if (!nonfinite.empty())
    throw RunError(
        exit_code::kNonFinite,
        fmt::format("step {}, t = {:.9g} s: non-finite stress or deformation "
                    "gradient at {} particle(s): {}",
                    sim.step, sim.time, nonfinite.size(), describe_particles(P, nonfinite)));
  throw RunError(exit_code::kInvertedDeformation,
                 fmt::format("step {}, t = {:.9g} s: det F <= 0 (inverted or degenerate "
                             "deformation) at {} particle(s): {}",
                             sim.step, sim.time, inverted.size(), describe_particles(P, inverted)));
}

namespace {
// The DOFs this rank's sums touch: the range [lo, hi] of their numbers and the box [box_lo,
// box_hi] of their coordinates (RunState::dof_stride's layout): the particle stencils' (the
// chunk ranges and the box evaluate_basis recorded) and a reconstruction mapping's quadrature
// points' (a range, whose box is that of every DOF between its ends). Empty (lo > hi) without
// either.
template <int Dim>
struct TouchedDofs {
  std::array<Index, 2> range;
  IVec<Dim> box_lo, box_hi;
};

template <int Dim>
TouchedDofs<Dim> touched_dofs(const RunState<Dim>& sim) {
  TouchedDofs<Dim> t{sim.scatter.ranges.span(), {}, {}};
  t.box_lo.fill(std::numeric_limits<Index>::max());
  t.box_hi.fill(-1);
  const IVec<Dim>& stride = sim.dof_stride;
  // The DOFs per direction of the layout.
  IVec<Dim> n;
  for (int d = 0; d + 1 < Dim; ++d) n[d] = stride[d + 1] / stride[d];
  n[Dim - 1] = sim.nodes.size() / stride[Dim - 1];
  // Extends the box by that of the DOFs [a, b]: along the highest direction where a's and b's
  // coordinates differ, from a's to b's; below it, the whole layout; above it, theirs.
  const auto add_range = [&](Index a, Index b) {
    const IVec<Dim> ca = dof_coords<Dim>(a, stride), cb = dof_coords<Dim>(b, stride);
    bool whole = false;
    for (int d = Dim - 1; d >= 0; --d) {
      t.box_lo[d] = std::min(t.box_lo[d], whole ? 0 : ca[d]);
      t.box_hi[d] = std::max(t.box_hi[d], whole ? n[d] - 1 : cb[d]);
      whole = whole || ca[d] != cb[d];
    }
  };
  if (sim.stencil_box_particles == sim.own_particles()) {
    for (int d = 0; d < Dim; ++d) {
      t.box_lo[d] = sim.stencil_box[0][d];
      t.box_hi[d] = sim.stencil_box[1][d];
    }
  } else if (t.range[0] <= t.range[1]) {
    add_range(t.range[0], t.range[1]);  // stencils filled some other way
  }
  const auto& q = sim.quadrature_dofs;
  if (q[0] <= q[1]) {
    t.range = {std::min(t.range[0], q[0]), std::max(t.range[1], q[1])};
    add_range(q[0], q[1]);
  }
  return t;
}

// The tractions' nodal forces of this step (RunState::face_forces, after_forces): added here
// where this process holds the DOF (DofRanges::holds), else sent to the lowest process that
// holds it (which adds them, in rank order, to its partial sums before they are shared). A DOF
// no process holds has no mass on any process, so it is inactive and its force unused, as on one
// process.
template <int Dim>
void place_face_forces(RunState<Dim>& sim) {
  const Comm& comm = *sim.comm;
  const int me = comm.rank();
  const auto& sh = sim.shared;
  auto& force = sim.nodes.force;
  constexpr std::size_t kRecord = sizeof(Index) + Dim * sizeof(double);
  std::vector<std::vector<std::byte>> send(static_cast<std::size_t>(comm.size()));
  for (const auto& [i, f] : sim.face_forces) {
    if (sh.holds(me, i)) {
      force[static_cast<std::size_t>(i)] += f;
      continue;
    }
    for (int r = 0; r < comm.size(); ++r)
      if (sh.holds(r, i)) {
        auto& out = send[static_cast<std::size_t>(r)];
        const std::size_t at = out.size();
        out.resize(at + kRecord);
        std::memcpy(out.data() + at, &i, sizeof(Index));
        std::memcpy(out.data() + at + sizeof(Index), f.data(), Dim * sizeof(double));
        break;
      }
  }
  sim.face_forces.clear();
  const auto recv = comm.alltoall(send);
  for (const auto& buf : recv)
    for (std::size_t at = 0; at + kRecord <= buf.size(); at += kRecord) {
      Index i;
      Vec<Dim> f;
      std::memcpy(&i, buf.data() + at, sizeof(Index));
      std::memcpy(f.data(), buf.data() + at + sizeof(Index), Dim * sizeof(double));
      force[static_cast<std::size_t>(i)] += f;
    }
}
}  // namespace

template <int Dim>
void share_grid_sums(RunState<Dim>& sim, unsigned what) {
  const Comm* comm = sim.comm;
  if (comm == nullptr || !comm->distributed()) return;
  comm->check();  // a rank that failed in this step stops every rank here
  const TouchedDofs<Dim> t = touched_dofs(sim);
  sim.shared = DofRanges::gather(*comm, t.range, sim.dof_stride, t.box_lo, t.box_hi);
  using namespace grid_sum;
  auto& nd = sim.nodes;
  const bool M = (what & kMass) != 0, Q = (what & kMomentum) != 0, F = (what & kForces) != 0;
  if (F && !sim.all_tractions.empty()) place_face_forces(sim);
  const std::size_t width = (M ? 1 : 0) + (Q ? Dim : 0) + (F ? Dim : 0);
  sum_over_sharing_ranks(*comm, sim.shared, width, 100, [&](Index i, auto&& f) {
    const auto k = static_cast<std::size_t>(i);
    if (M) f(nd.mass[k]);
    if (Q)
      for (int d = 0; d < Dim; ++d) f(nd.momentum[k][d]);
    if (F)
      for (int d = 0; d < Dim; ++d) f(nd.force[k][d]);
  });
}

namespace {
// A sum of this rank (double or an Eigen vector), summed over the ranks (rank order).
template <class T>
T over_ranks(const Comm* comm, T v) {
  if (comm == nullptr || !comm->distributed()) return v;
  if constexpr (std::is_same_v<T, double>)
    return comm->sum(v);
  else
    comm->sum(std::span<double>(v.data(), static_cast<std::size_t>(v.size())));
  return v;
}

// sum over the DOFs of a grid array, each DOF counted once over the ranks of a distributed run
// (by the lowest rank that holds it), combined in rank order. T: double or Vec<Dim>.
template <int Dim, class T>
T grid_total(const RunState<Dim>& sim, const DofArray<T>& a, const T& zero) {
  if (sim.comm == nullptr || !sim.comm->distributed())
    return deterministic_sum(static_cast<Index>(a.size()), zero,
                             [&](Index i) { return a[a.first() + i]; });
  const auto [lo, end] = sim.dof_window();
  const Index first = lo;
  return over_ranks(sim.comm, deterministic_sum(end - lo, zero, [&](Index k) {
                      return sim.shared.owns(sim.comm->rank(), first + k) ? a[first + k] : zero;
                    }));
}

// Partial lumping (method.partial_lumping, RunState::PartialLumping). Each element's fill is the
// particles' current volumes V_p in it over its volume, at most 1 (an over-full element, a
// particle more than its share after a crossing or compression, does not make up for an empty
// one); DOF i's cover is the fill averaged over its function's integral,
//   c_i = sum_e min(fill_e, 1) int_e N_i / int N_i,
// 1 inside the body, about 1/2 for a function cut in half by a free surface, 0 outside. The DOFs
// with c_i below sim.lumping.below get lumped rows of this step's consistent matrix.
// O(particles + elements x stencil), serial: below the cost of the solve.
template <int Dim>
void mark_lumped_rows(RunState<Dim>& sim) {
  const auto& L = sim.lumping;
  const auto& P = sim.particles;
  const auto elements = L.volume.size();
  std::vector<double> fill(elements, 0.0);
  for (Index p = 0; p < P.size(); ++p) {
    const auto i = static_cast<std::size_t>(p);
    const Index e = L.element_of ? L.element_of(P.x[i]) : static_cast<Index>(sim.cell[i]);
    if (e >= 0) fill[static_cast<std::size_t>(e)] += P.volume[i];
  }
  std::vector<double> cover(L.integral.size(), 0.0);
  for (std::size_t e = 0; e < elements; ++e) {
    const double f = std::min(fill[e] / L.volume[e], 1.0);
    if (f > 0.0)
      for (auto k = static_cast<std::size_t>(L.first[e]);
           k < static_cast<std::size_t>(L.first[e + 1]); ++k)
        cover[static_cast<std::size_t>(L.dofs[k])] += f * L.share[k];
  }
  // A distributed run: an element's particles are all on the process of its cell layer (the
  // slabs are whole layers, and particles move to their process after every step), so each
  // element's fill is whole on one process; the covers of the DOFs two processes share are the
  // sums of their parts, added in rank order as the grid sums, so every process lumps the same
  // rows and the sum of the processes' lumped matrices is the lumped sum (the change is linear).
  if (sim.comm)
    sum_over_sharing_ranks(*sim.comm, sim.shared, 1, 250,
                           [&](Index i, auto&& f) { f(cover[static_cast<std::size_t>(i)]); });
  std::vector<unsigned char> rows(static_cast<std::size_t>(sim.nodes.size()), 0);
  for (std::size_t i = 0; i < rows.size(); ++i)
    rows[i] = cover[i] < L.below * L.integral[i] ? 1 : 0;
  // Active lumped DOFs, each counted once over the processes.
  const auto [first, end] = sim.dof_window();
  Index lumped = 0;
  for (Index i = first; i < end; ++i)
    if (!sim.comm || sim.shared.owns(sim.comm->rank(), i))
      lumped += rows[static_cast<std::size_t>(i)] && sim.nodes.active[static_cast<std::size_t>(i)];
  if (sim.comm) lumped = sim.comm->sum(lumped);
  sim.diag.lumped_dofs = lumped;
  sim.diag.max_lumped_dofs = std::max(sim.diag.max_lumped_dofs, lumped);
  sim.consistent.set_lumped(std::move(rows));
}
}  // namespace

// The active set and the mass conservation check, and the consistent matrix if requested,
// from the nodal masses of the mapping.
template <int Dim>
void after_mass(RunState<Dim>& sim) {
  const auto& m = sim.nodes.mass;
  const auto& mp = sim.particles.mass;
  const double total = grid_total(sim, m, 0.0);
  const auto [first, end] = sim.dof_window();
  double largest = 0.0;
  if (first < end)
    largest = *std::max_element(m.begin() + (first - m.first()), m.begin() + (end - m.first()));
  if (sim.comm) largest = sim.comm->max(largest);
  // sum m_p: taken by the mapping's scatter when it has one (the same bits), else a pass here.
  auto& sc = sim.scatter;
  const double particle_mass = over_ranks(
      sim.comm, sc.has_particle_mass
                    ? sc.particle_mass.total(static_cast<Index>(mp.size()), 0.0)
                    : deterministic_sum(static_cast<Index>(mp.size()), 0.0,
                                        [&](Index p) { return mp[static_cast<std::size_t>(p)]; }));
  sc.has_particle_mass = false;
  if (particle_mass > 0.0) {
    sim.diag.rel_mass_error = std::abs(total - particle_mass) / particle_mass;
    sim.diag.max_rel_mass_error = std::max(sim.diag.max_rel_mass_error, sim.diag.rel_mass_error);
    // (Negated so that a NaN error stops the run as well.)
    if (!(sim.diag.rel_mass_error <= sim.conservation_limit))
      throw RunError(
          exit_code::kConservation,
          fmt::format("step {}, t = {:.9g} s: the particle-to-grid mapping does not conserve "
                      "mass: the grid holds {:.9g}, the particles {:.9g} (relative error {:.3g}, "
                      "above method.conservation_limit = {:.3g}); {}",
                      sim.step, sim.time, total, particle_mass, sim.diag.rel_mass_error,
                      sim.conservation_limit,
                      total < particle_mass
                          ? "the mapping's support does not cover the particles (for MLS/IMLS, "
                            "is method.mls_dilation too small?)"
                          : "the reconstruction integrates to more mass than the particles "
                            "carry (for MLS/IMLS, method.mls_conservative = true rescales it)"));
  }
  const double threshold = sim.mass_tolerance * largest;
  const Index offset = first;
  parallel_for(end - first, [&](Index k) {
    const auto i = static_cast<std::size_t>(offset + k);
    sim.nodes.active[i] = m[i] > threshold ? 1 : 0;
  });
  const auto singular = [&] {
    return RunError(exit_code::kNonFinite,
                    fmt::format("step {}, t = {:.9g} s: the consistent mass matrix is singular "
                                "(a cell with too few particles); use method.mass = \"lumped\"{}",
                                sim.step, sim.time,
                                sim.lumping.below > 0.0 ? "" : " or method.partial_lumping = 0.5"));
  };
  // A distributed run solves with CG or p-multigrid on the matrices of the ranks' particles
  // (solve_grid): nothing to factorise; p-multigrid's levels are built here.
  if (sim.mass_type == MassType::Consistent && sim.comm != nullptr) {
    if (sim.lumping.below > 0.0) mark_lumped_rows(sim);
    if (sim.consistent.settings().kind == MassSolver::Pmg) {
      sim.distributed_pmg = std::make_shared<DistributedPmg<Dim>>(sim);
      if (!sim.distributed_pmg->positive()) throw singular();
    }
    return;
  }
  if (sim.mass_type == MassType::Consistent) {
    if (sim.lumping.below > 0.0) mark_lumped_rows(sim);
    constexpr std::uint8_t kAll = (1u << Dim) - 1u;
    const auto& act = sim.nodes.active;
    const auto& fixed = sim.nodes.fixed;
    // Fixed DOFs are eliminated: the prescribed value is zero, so M y = r with identity rows.
    // One factorisation serves every component unless some DOF is fixed in only some of them
    // (rollers): then component d gets its own (slot d).
    const bool per_component = sim.consistent_per_component;
    if (sim.consistent.settings().kind == MassSolver::Pmg)
      sim.consistent.pmg_builder = [&sim, per_component](const std::vector<unsigned char>& keep,
                                                         int slot, const SparseMatrixD& fine) {
        // The coarse levels by rediscretisation at the particles (their masses as weights),
        // without the functions of the sides whose DOFs this slot fixes.
        const auto& P = sim.particles;
        PointSet<Dim> pts;
        pts.x.assign(P.x.begin(), P.x.end());
        pts.w.assign(P.mass.begin(), P.mass.end());
        const auto bit = static_cast<std::uint8_t>(per_component ? 1u << slot : kAll);
        const auto sides = spline_fixed_sides(sim, bit);
        return spline_pmg(sim.grid, sim.spline_degree, pts, keep, sides,
                          sim.consistent.settings().pmg, &fine);
      };
    if (!sim.nodes.projected.empty()) {
      // Rollers on inclined boundaries couple the components: one system for all of them.
      auto& proj = sim.coupled_projector;
      proj.assign(act.size(), Mat<Dim>::Zero());
      for (std::size_t i = 0; i < act.size(); ++i)
        if (act[i])
          for (int d = 0; d < Dim; ++d) proj[i](d, d) = (fixed[i] & (1u << d)) ? 0.0 : 1.0;
      for (const auto& e : sim.nodes.projected)
        if (act[static_cast<std::size_t>(e.dof)]) proj[static_cast<std::size_t>(e.dof)] = e.free;
      // (Fixed-size Eigen matrices are stored contiguously, and the projectors are symmetric,
      // so column-major blocks read as the row-major ones factorize_coupled takes.)
      if (!sim.consistent.factorize_coupled(
              Dim, std::span<const double>(proj.data()->data(), proj.size() * Dim * Dim)))
        throw singular();
      return;
    }
    for (int d = 0; d < (per_component ? Dim : 1); ++d) {
      const auto bit = static_cast<std::uint8_t>(per_component ? 1u << d : kAll);
      if (!sim.consistent.factorize(
              [&](Index i) {
                const auto k = static_cast<std::size_t>(i);
                return act[k] && !(fixed[k] & bit);
              },
              d))
        throw singular();
    }
  }
}

// The momentum conservation check from the nodal momenta of the mapping.
template <int Dim>
void after_momentum(RunState<Dim>& sim) {
  const auto& q = sim.nodes.momentum;
  const Vec<Dim> grid_p = grid_total(sim, q, Vec<Dim>::Zero().eval());
  // (sum m_p v_p, sum m_p |v_p|) as one vector: taken by the mapping's scatter when it has one
  // (the same bits), else one pass over the particles here.
  using Sums = Eigen::Matrix<double, Dim + 1, 1>;
  const auto& P = sim.particles;
  auto& sc = sim.scatter;
  const Sums sums =
      over_ranks(sim.comm, sc.has_particle_momentum
                               ? sc.particle_momentum.total(P.size(), Sums::Zero().eval())
                               : deterministic_sum(P.size(), Sums::Zero().eval(), [&](Index p) {
                                   const auto i = static_cast<std::size_t>(p);
                                   Sums r;
                                   r.template head<Dim>() = P.mass[i] * P.v[i];
                                   r[Dim] = P.mass[i] * P.v[i].norm();
                                   return r;
                                 }));
  sc.has_particle_momentum = false;
  const Vec<Dim> part_p = sums.template head<Dim>();
  const double scale = sums[Dim];
  if (scale > 0.0) {
    sim.diag.rel_momentum_error = (grid_p - part_p).norm() / scale;
    sim.diag.max_rel_momentum_error =
        std::max(sim.diag.max_rel_momentum_error, sim.diag.rel_momentum_error);
    if (!(sim.diag.rel_momentum_error <= sim.conservation_limit))
      throw RunError(
          exit_code::kConservation,
          fmt::format("step {}, t = {:.9g} s: the particle-to-grid mapping does not conserve "
                      "momentum: |sum of nodal momenta - sum m_p v_p| = {:.9g}, {:.3g} of "
                      "sum m_p |v_p| = {:.9g} (above method.conservation_limit = {:.3g})",
                      sim.step, sim.time, (grid_p - part_p).norm(), sim.diag.rel_momentum_error,
                      scale, sim.conservation_limit));
  }
}

namespace {
// An iterative mass solve that did not reach its tolerance: the step, the component, the
// residual and its history (every iteration up to 12, then a sample).
template <int Dim>
[[noreturn]] void throw_mass_solver_failure(const RunState<Dim>& sim, int component,
                                            const IterationReport& rep) {
  const MassSolverSettings& s = sim.consistent.settings();
  std::string hist;
  const std::size_t n = rep.history.size();
  const std::size_t stride = n <= 12 ? 1 : n / 12;
  for (std::size_t k = 0; k < n; k += stride)
    hist += fmt::format("{}{}: {:.3g}", hist.empty() ? "" : ", ", k, rep.history[k]);
  if (n > 0 && (n - 1) % stride != 0)
    hist += fmt::format(", {}: {:.3g}", n - 1, rep.history.back());
  throw RunError(
      exit_code::kSolver,
      fmt::format("step {}, t = {:.9g} s: the {} mass solver did not converge for velocity "
                  "{}: relative residual {:.3g} after {} {} (method.mass_solver_"
                  "tolerance = {:.3g}, method.mass_solver_max_iterations = {}); residual "
                  "history (iteration: relative residual): {}",
                  sim.step, sim.time, s.kind == MassSolver::Cg ? "cg" : "pmg",
                  component < 0 ? std::string("components (coupled by inclined rollers)")
                                : fmt::format("component {}", "xyz"[component]),
                  rep.relative_residual, rep.iterations,
                  s.kind == MassSolver::Cg ? "iterations" : "V-cycles", s.tolerance,
                  s.max_iterations, hist));
}

// v on the DOFs of this rank's window: the sum over the ranks that share each DOF, in rank order
// (as share_grid_sums, for one array).
template <int Dim>
void share_vector(const RunState<Dim>& sim, Eigen::VectorXd& v) {
  sum_over_sharing_ranks(*sim.comm, sim.shared, 1, 200, [&](Index i, auto&& f) { f(v[i]); });
}

// y = M^{-1} r with consistent mass in a distributed run: CG (method.mass_solver = "cg") on
// the operator x -> sum over ranks of M_rank (P x), shared like the grid sums, plus (I - P) x
// for the eliminated DOFs (P: the kept DOFs, active and not fixed in the component); the
// inner products over the DOFs each rank owns, summed in rank order, so every rank takes the
// same iterations. The same system as the one process's CG on the assembled matrix; "pmg":
// the same system by the V-cycles of DistributedPmg (built in after_mass).
template <int Dim, class V>
void solve_distributed(RunState<Dim>& sim, const DofArray<V>& r, DofArray<V>& y) {
  const auto& nd = sim.nodes;
  // The solver's vectors span every DOF (the assembled matrix's numbering), the grid arrays
  // this rank's window.
  const Index n = nd.size();
  const auto [first, end] = sim.dof_window();
  const Index lo = first, count = end - first;
  std::vector<unsigned char> owned(static_cast<std::size_t>(count));
  for (Index k = 0; k < count; ++k)
    owned[static_cast<std::size_t>(k)] = sim.shared.owns(sim.comm->rank(), lo + k);
  const InnerProduct dot = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return sim.comm->sum(deterministic_sum(count, 0.0, [&](Index k) {
      return owned[static_cast<std::size_t>(k)] ? a[lo + k] * b[lo + k] : 0.0;
    }));
  };
  const SparseMatrixD& M = sim.consistent.assembled();
  const MassSolverSettings& s = sim.consistent.settings();
  constexpr std::uint8_t kAll = (1u << Dim) - 1u;
  std::vector<unsigned char> keep(static_cast<std::size_t>(count));
  Eigen::VectorXd t(n), b(n), x(n);
  for (int d = 0; d < Dim; ++d) {
    const auto bit = static_cast<std::uint8_t>(sim.consistent_per_component ? 1u << d : kAll);
    for (Index k = 0; k < count; ++k) {
      const auto i = static_cast<std::size_t>(lo + k);
      keep[static_cast<std::size_t>(k)] = nd.active[i] && !(nd.fixed[i] & bit);
    }
    b.setZero();
    for (Index k = 0; k < count; ++k)
      if (keep[static_cast<std::size_t>(k)]) b[lo + k] = r[static_cast<std::size_t>(lo + k)][d];
    const LinearOperator A = [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
      t.setZero();
      for (Index k = 0; k < count; ++k)
        if (keep[static_cast<std::size_t>(k)]) t[lo + k] = v[lo + k];
      out.noalias() = M * t;
      share_vector(sim, out);
      for (Index k = 0; k < count; ++k)
        if (!keep[static_cast<std::size_t>(k)]) out[lo + k] = v[lo + k];
    };
    x.setZero();
    const IterationReport rep =
        s.kind == MassSolver::Pmg
            ? sim.distributed_pmg->solve(sim.consistent_per_component ? d : 0, b, x)
            : conjugate_gradient(A, b, x, s.tolerance, s.max_iterations, dot);
    sim.diag.mass_solver_iterations += rep.iterations;
    sim.diag.max_mass_solver_iterations =
        std::max(sim.diag.max_mass_solver_iterations, rep.iterations);
    if (!rep.converged) throw_mass_solver_failure(sim, d, rep);
    for (Index k = 0; k < count; ++k) y[static_cast<std::size_t>(lo + k)][d] = x[lo + k];
  }
}

// y = M^{-1} r on the active, unconstrained DOFs; zero elsewhere (D eq. 2.46 / 2.49).
template <int Dim, class V>
void solve_grid(RunState<Dim>& sim, const DofArray<V>& r, DofArray<V>& y) {
  const auto& nd = sim.nodes;
  // One process (the consistent paths below): the window is every DOF.
  const auto n = static_cast<std::size_t>(nd.size());
  if (sim.mass_type == MassType::Lumped) {
    const Index offset = sim.dof_window()[0], count = sim.dof_window()[1] - offset;
    parallel_for(count, [&](Index k) {
      const auto i = static_cast<std::size_t>(offset + k);
      y[i] = nd.active[i] ? V(r[i] / nd.mass[i]) : V::Zero();
    });
  } else if (sim.comm != nullptr) {
    solve_distributed(sim, r, y);
  } else if (!nd.projected.empty()) {
    // The coupled system of the inclined rollers (ConsistentMass::factorize_coupled).
    const auto& proj = sim.coupled_projector;
    Eigen::VectorXd rhs(static_cast<Index>(n * Dim));
    for (std::size_t i = 0; i < n; ++i)
      rhs.template segment<Dim>(static_cast<Index>(i * Dim)) = proj[i] * r[i];
    IterationReport rep;
    const Eigen::VectorXd sol = sim.consistent.solve(rhs, ConsistentMass::kCoupled, &rep);
    if (sim.consistent.settings().kind != MassSolver::Direct) {
      sim.diag.mass_solver_iterations += rep.iterations;
      sim.diag.max_mass_solver_iterations =
          std::max(sim.diag.max_mass_solver_iterations, rep.iterations);
      if (!rep.converged) throw_mass_solver_failure(sim, -1, rep);
    }
    for (std::size_t i = 0; i < n; ++i)
      y[i] = sol.template segment<Dim>(static_cast<Index>(i * Dim));
  } else {
    Eigen::VectorXd rhs(static_cast<Index>(n));
    for (int d = 0; d < Dim; ++d) {
      const int slot = sim.consistent_per_component ? d : 0;
      for (std::size_t i = 0; i < n; ++i)
        rhs[static_cast<Index>(i)] = (nd.active[i] && !(nd.fixed[i] & (1u << d))) ? r[i][d] : 0.0;
      IterationReport rep;
      const Eigen::VectorXd sol = sim.consistent.solve(rhs, slot, &rep);
      if (sim.consistent.settings().kind != MassSolver::Direct) {
        sim.diag.mass_solver_iterations += rep.iterations;
        sim.diag.max_mass_solver_iterations =
            std::max(sim.diag.max_mass_solver_iterations, rep.iterations);
        if (!rep.converged) throw_mass_solver_failure(sim, d, rep);
      }
      for (std::size_t i = 0; i < n; ++i) y[i][d] = sol[static_cast<Index>(i)];
    }
  }
  const auto [first, end] = sim.dof_window();
  for (auto i = static_cast<std::size_t>(first); i < static_cast<std::size_t>(end); ++i)
    if (nd.fixed[i])
      for (int d = 0; d < Dim; ++d)
        if (nd.fixed[i] & (1u << d)) y[i][d] = 0.0;
  // v . n = 0 on the inclined rollers: exact for lumped mass (the reaction acts along n alone),
  // round-off clean-up of the coupled solve.
  for (const auto& e : nd.projected) {
    if (!y.holds(e.dof)) continue;
    auto& yi = y[e.dof];
    yi = V(e.free * yi);
  }
}
}  // namespace

// The reaction on each constrained boundary (RunState::reaction_dofs) into diag.reactions:
// R_i = C_i (m_i a_i - f_i) summed over the boundary's DOFs, C_i the projector onto DOF i's
// constrained velocities (its fixed components, or 1 - the free projector of an inclined
// roller; the identity on a frictional wall, whose normal and friction forces act in every
// component):
// the force the support exerts on the body, so that m_i a_i = f_i + R_i. With lumped mass a_i
// vanishes on the fixed components, so there R_i = -C_i f_i (f_i the nodal force of the step,
// internal, external and body forces); on a frictional wall it is the normal and friction
// force. A DOF on two boundaries (a corner) counts in both. A distributed run sums each DOF once
// (its owner's), then over the processes in rank order.
template <int Dim>
void sum_reactions(RunState<Dim>& sim) {
  const auto& nd = sim.nodes;
  const auto [first, end] = sim.dof_window();
  const bool split = sim.comm != nullptr && sim.comm->distributed();
  auto& out = sim.diag.reactions;
  out.assign(sim.reaction_dofs.size() * Dim, 0.0);
  for (std::size_t g = 0; g < sim.reaction_dofs.size(); ++g) {
    Vec<Dim> sum = Vec<Dim>::Zero();
    for (const Index i : sim.reaction_dofs[g]) {
      if (i < first || i >= end) continue;
      if (split && !sim.shared.owns(sim.comm->rank(), i)) continue;
      const auto k = static_cast<std::size_t>(i);
      Mat<Dim> C = Mat<Dim>::Zero();
      if (!sim.reaction_whole.empty() && sim.reaction_whole[g]) C.setIdentity();
      for (int d = 0; d < Dim; ++d)
        if (nd.fixed[k] & (1u << d)) C(d, d) = 1.0;
      const auto it = std::lower_bound(
          nd.projected.begin(), nd.projected.end(), i,
          [](const typename GridState<Dim>::Projected& e, Index j) { return e.dof < j; });
      if (it != nd.projected.end() && it->dof == i) C = Mat<Dim>::Identity() - it->free;
      sum += C * (nd.mass[k] * nd.accel[k] - nd.force[k]);
    }
    for (int d = 0; d < Dim; ++d) out[g * Dim + static_cast<std::size_t>(d)] = sum[d];
  }
  if (split) sim.comm->sum(std::span<double>(out));
}

// Cundall's local non-viscous damping (method.local_damping; Cundall 1987, as in PFC, FLAC,
// Anura3D and cb-geo's MPM): each free component of an active DOF's force loses alpha |f| against
// the DOF's velocity v_i = q_i / m_i (the row sum of the mass matrix: the sign alone is needed),
//   f_i,d <- f_i,d - alpha |f_i,d| sign(v_i,d).
// It removes a fraction alpha of the unbalanced force while the node moves and none at rest, so
// an equilibrium, and the limit load of a quasi-static problem, are those of the undamped
// equations; the transient is not. Every scheme maps the momentum of the step before its
// acceleration is solved (MUSL too when damping is on).
template <int Dim>
void damp_forces(RunState<Dim>& sim) {
  auto& nd = sim.nodes;
  const double alpha = sim.local_damping;
  const auto [first, end] = sim.dof_window();
  const Index offset = first;
  parallel_for(end - first, [&](Index k) {
    const auto i = static_cast<std::size_t>(offset + k);
    if (!nd.active[i]) return;
    for (int d = 0; d < Dim; ++d) {
      if (nd.fixed[i] & (1u << d)) continue;
      const double q = nd.momentum[i][d];
      const double s = q > 0.0 ? 1.0 : (q < 0.0 ? -1.0 : 0.0);
      nd.force[i][d] -= alpha * std::abs(nd.force[i][d]) * s;
    }
  });
}

namespace {
// The wall conditions on a velocity v of DOF i (in place): on each frictional wall through i, no
// normal velocity where the wall held i in this step's acceleration solve, none into the wall
// elsewhere. Every velocity solve applies them and the walls' friction starts from the velocity
// so conditioned, so that the velocity a scheme advances (v_i^{s+1} = v_i^s + dt a_i: USL, USF,
// USAVG) is the one the friction took, and a remapped one (MUSL, USAVG) holds the DOFs the wall
// held in the step (neither entering the wall nor drifting off it by rectified round-off).
template <int Dim>
void wall_conditions(const RunState<Dim>& sim, Index i, Vec<Dim>& v) {
  for (const auto& w : sim.walls) {
    const auto it = std::lower_bound(w.dofs.begin(), w.dofs.end(), i);
    if (it == w.dofs.end() || *it != i) continue;
    const bool held =
        w.contact_step == sim.step && w.contact[static_cast<std::size_t>(it - w.dofs.begin())] != 0;
    // (On a grid side, n = +-e_d: v_d is set to 0 exactly.)
    const double vn = v.dot(w.normal);
    if (held || vn > 0.0) v -= vn * w.normal;
  }
}

// Coulomb friction on the rigid walls (boundary.* = "friction"; lumped mass), on the
// accelerations of the step, so that every scheme's particle and grid updates carry it. For a
// DOF of a wall with outward normal n, velocity v (q_i / m_i, its fixed components zero, under
// wall_conditions) and acceleration a:
//   the normal velocity after the step, w_n = (v + dt a) . n; w_n <= 0: the node leaves the
//   wall or stays on it without pressing, and nothing acts;
//   w_n > 0: contact. The wall stops the normal velocity (an impulse per unit mass p = w_n,
//   the contact force m p / dt), and friction acts on the tangential velocity after the step,
//   w_t = (v + dt a)_t: it sticks (w_t = 0) when |w_t| <= mu p, and otherwise slips, |w_t|
//   reduced by mu p against its direction
// (the rigid-wall form of Bardenhagen et al. 2001's contact, with separation: cb-geo's frictional
// boundaries hold the normal velocity instead). A node that does not press is free, so that a
// vibrating body's tension at the wall neither holds it nor adds friction. A DOF on two walls (a
// corner) meets them in turn.
template <int Dim>
void apply_wall_friction(RunState<Dim>& sim, double dt) {
  auto& nd = sim.nodes;
  for (auto& w : sim.walls) {
    w.contact_step = -1;  // the velocities start from the conditions before this solve
    for (std::size_t k = 0; k < w.dofs.size(); ++k) {
      const Index dof = w.dofs[k];
      w.contact[k] = 0;
      if (!nd.accel.holds(dof)) continue;
      const auto i = static_cast<std::size_t>(dof);
      if (!nd.active[i]) continue;
      Vec<Dim> v = nd.momentum[i] / nd.mass[i];
      for (int c = 0; c < Dim; ++c)
        if (nd.fixed[i] & (1u << c)) v[c] = 0.0;
      wall_conditions(sim, dof, v);
      Vec<Dim> after = v + dt * nd.accel[i];
      const double pn = after.dot(w.normal);  // the normal impulse per unit mass [m/s]
      w.contact[k] = pn > 0.0 ? 1 : 0;
      if (!w.contact[k]) continue;
      after -= pn * w.normal;  // the tangential part w_t
      const double wt = after.norm();
      if (wt > w.mu * pn)
        after *= 1.0 - w.mu * pn / wt;  // slip
      else
        after.setZero();  // stick
      for (int c = 0; c < Dim; ++c)
        if (!(nd.fixed[i] & (1u << c))) nd.accel[i][c] = (after[c] - v[c]) / dt;
    }
  }
  for (auto& w : sim.walls) w.contact_step = sim.step;
}
}  // namespace

// a_i = M^{-1} f_i with Dirichlet components zero (D eq. 2.46), after the local damping, with
// the walls' contact and friction, and with the reactions where asked.
template <int Dim>
void solve_acceleration(RunState<Dim>& sim, double dt) {
  const StageTimer timer(sim.clock, Stage::kGrid);
  if (sim.local_damping > 0.0) damp_forces(sim);
  solve_grid(sim, sim.nodes.force, sim.nodes.accel);
  if (!sim.walls.empty()) apply_wall_friction(sim, dt);
  if (!sim.reaction_dofs.empty()) sum_reactions(sim);
}

// v_i = M^{-1} q_i with Dirichlet components zero (D eq. 2.35 / 2.49), the prescribed
// velocities (RunState's nodes.prescribed) in their components, and the frictional walls'
// conditions (wall_conditions: a particle never crosses a wall).
template <int Dim>
void solve_velocity(RunState<Dim>& sim) {
  const StageTimer timer(sim.clock, Stage::kGrid);
  auto& nd = sim.nodes;
  solve_grid(sim, nd.momentum, nd.velocity);
  for (const auto& [i, v] : nd.prescribed) {
    if (!nd.velocity.holds(i)) continue;
    const auto k = static_cast<std::size_t>(i);
    for (int d = 0; d < Dim; ++d)
      if (nd.fixed[k] & (1u << d)) nd.velocity[k][d] = v[d];
  }
  for (const auto& w : sim.walls)
    for (const Index dof : w.dofs)
      if (nd.velocity.holds(dof) && nd.active[static_cast<std::size_t>(dof)])
        wall_conditions(sim, dof, nd.velocity[static_cast<std::size_t>(dof)]);
}

// Euler-Cromer on the grid: v_i^{s+1} = v_i^s + dt a_i^s (D eq. 2.36; USL, USF).
template <int Dim>
void advance_grid_velocity(RunState<Dim>& sim, double dt) {
  const StageTimer timer(sim.clock, Stage::kGrid);
  auto& nd = sim.nodes;
  const auto [first, end] = sim.dof_window();
  const Index offset = first;
  parallel_for(end - first, [&](Index k) {
    const auto i = static_cast<std::size_t>(offset + k);
    nd.velocity[i] += dt * nd.accel[i];
  });
}

template void share_grid_sums<1>(RunState<1>&, unsigned);
template void share_grid_sums<2>(RunState<2>&, unsigned);
template void share_grid_sums<3>(RunState<3>&, unsigned);
template void after_mass<1>(RunState<1>&);
template void after_momentum<1>(RunState<1>&);
template void solve_acceleration<1>(RunState<1>&, double);
template void solve_velocity<1>(RunState<1>&);
template void advance_grid_velocity<1>(RunState<1>&, double);
template void after_mass<2>(RunState<2>&);
template void after_mass<3>(RunState<3>&);
template void after_momentum<2>(RunState<2>&);
template void after_momentum<3>(RunState<3>&);
template void solve_acceleration<2>(RunState<2>&, double);
template void solve_acceleration<3>(RunState<3>&, double);
template void solve_velocity<2>(RunState<2>&);
template void solve_velocity<3>(RunState<3>&);
template void advance_grid_velocity<2>(RunState<2>&, double);
template void advance_grid_velocity<3>(RunState<3>&, double);
template void throw_unfit<1>(const RunState<1>&, const std::vector<Index>&, std::string_view);
template void throw_left_grid<1>(const RunState<1>&);
template void throw_face_left_grid<1>(const RunState<1>&, std::size_t, const Vec<1>&, bool);
template void throw_particle_failure<1>(const RunState<1>&);
template void throw_unfit<2>(const RunState<2>&, const std::vector<Index>&, std::string_view);
template void throw_unfit<3>(const RunState<3>&, const std::vector<Index>&, std::string_view);
template void throw_left_grid<2>(const RunState<2>&);
template void throw_left_grid<3>(const RunState<3>&);
template void throw_face_left_grid<2>(const RunState<2>&, std::size_t, const Vec<2>&, bool);
template void throw_face_left_grid<3>(const RunState<3>&, std::size_t, const Vec<3>&, bool);
template void throw_particle_failure<2>(const RunState<2>&);
template void throw_particle_failure<3>(const RunState<3>&);

}  // namespace mpm::stages
