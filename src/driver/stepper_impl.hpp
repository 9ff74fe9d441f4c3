#pragma once
// The stepper of one (dimension, basis, mapping): included only by the generated units
// (driver/stepper_kind.cpp.in), one per (dimension, basis kind), which instantiate it for every
// mapping of that dimension.
#include <fmt/format.h>
#include <algorithm>
#include <cstddef>
#include <memory>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "basis/basis.hpp"
#include "driver/sparse_mass.hpp"
#include "driver/stepper.hpp"
#include "io/checkpoint.hpp"
#include "mapping/mapping.hpp"
#include "parallel/distribution.hpp"
#include "scheme/partial_lumping.hpp"
#include "scheme/schemes.hpp"
#include "setup/run_settings.hpp"
#include "state/sort.hpp"

namespace mpm::driver {

// Before the first step: with method.tls_completion = "none" every element holding particles
// must support the Taylor basis on its own (D 5.2.3, 6.3.1); otherwise the run would stop at
// step 0, so the input is refused with what to change.
template <int Dim, class Basis, class Mapping>
void check_reconstruction_input(const MethodSettings& method, const Grid<Dim>& grid,
                                const Basis& basis, const Particles<Dim>& P,
                                const Mapping& mapping) {
  if constexpr (std::is_same_v<Mapping, TlsMapping> && Basis::kTriangleMesh) {
    const TlsSettings& s = mapping.settings();
    if (s.completion != TlsCompletion::None) return;
    TlsTriangleReconstruction recon(basis.mesh(), tls_triangle_settings(s));
    const TlsTriangleReport& rep = recon.set_points(P.x);
    const Index failed = std::max(rep.plain.failed, rep.conservative.failed);
    if (failed > 0) {
      const Index plain = rep.plain.first_deficient, cons = rep.conservative.first_deficient;
      const Index e = plain < 0 ? cons : cons < 0 ? plain : std::min(plain, cons);
      const auto& info = recon.element(e);
      throw InputError(fmt::format(
          "{}: method.tls_completion = \"none\", but the initial particles cannot support {} "
          "Taylor terms in {} triangle(s) or more: triangle {} has {} particle(s) (condition "
          "number {:.3g}, limit method.tls_max_condition = {:.3g}); seed more particles "
          "(particles.per_triangle), use fewer terms (method.tls_terms) or set "
          "method.tls_completion = \"reduce\", \"min_norm\" or \"graded\"",
          method.where_tls_completion, recon.terms(), failed, e, info.points,
          std::max(info.plain.condition, info.conservative.condition), s.max_condition));
    }
  } else if constexpr (std::is_same_v<Mapping, TlsMapping>) {
    const TlsSettings& s = mapping.settings();
    if (s.completion != TlsCompletion::None) return;
    BasicTlsReconstruction<Dim> recon(s);
    const TlsReport& rep = recon.set_points(grid, P);
    if (rep.failed > 0)
      throw InputError(fmt::format(
          "{}: method.tls_completion = \"none\", but the initial particles cannot support {} "
          "Taylor terms in {} element(s): element {} has {} particle(s) (condition number "
          "{:.3g}, limit method.tls_max_condition = {:.3g}); seed more particles "
          "(particles.per_cell), use fewer terms (method.tls_terms) or set "
          "method.tls_completion = \"reduce\", \"virtual\" or \"neighbour\"",
          method.where_tls_completion, s.terms_used(Dim), rep.failed,
          recon.describe(rep.failed_element), rep.failed_points, rep.failed_condition,
          s.max_condition));
  }
}

// What a distributed run does not do yet, refused before the first step with the
// key to change: the exchange shares the particle-to-grid sums of every mapping (the
// reconstructions read the other processes' particles near a process's own: ghost particles,
// MappingFor's kGhostParticles) for every basis on the grid (DDMPM's node sums with the next
// cell layer lent, CPDI2's corners moved with their particles: Stepper::export_carried);
// consistent mass is solved by distributed CG or Jacobi-smoothed p-multigrid; the tractions'
// points follow their particles (localize_tractions) and their forces the DOFs that hold mass
// (share_grid_sums).
// The bases on the grid's triangles (P1, Powell-Sabin) number their DOFs by grid vertex (the
// criss-cross centres after the corners, which widens a process's DOF range but not what it
// sums); their TLS fits every triangle holding particles, ghosts included, and integrates the
// triangles whose lowest particle id is its own (tls_triangle_mapping.cpp).
inline void check_distributed_run(const MethodSettings& method) {
  constexpr std::string_view kHow = "run it on one process (without mpirun)";
  if (method.mass == MassType::Consistent && method.mass_solver.kind == MassSolver::Direct)
    throw InputError(fmt::format(
        "{}: method.mass = \"consistent\" runs on several processes with method.mass_solver = "
        "\"cg\" or \"pmg\" (on distributed vectors); the direct solver factorises the whole "
        "matrix on one process; choose \"cg\" or \"pmg\", or {}",
        method.where_mass, kHow));
  if (method.mass == MassType::Consistent && method.mass_solver.kind == MassSolver::Pmg &&
      method.mass_solver.pmg.smoother == Smoother::GaussSeidel)
    throw InputError(fmt::format(
        "{}: method.mass_solver = \"pmg\" runs on several processes with method.pmg_smoother = "
        "\"jacobi\"; Gauss-Seidel sweeps through the whole grid in sequence, which no "
        "distribution of the grid reproduces; choose \"jacobi\" or {}",
        method.where_mass, kHow));
}

template <int Dim, class Basis, class Mapping>
class TypedStepper final : public Stepper<Dim> {
 public:
  using Sim = Simulation<Dim, Basis, Mapping>;
  static_assert(mpm::Basis<Basis, Dim>, "basis/basis.hpp");
  static_assert(MappingFor<Mapping, Sim>, "mapping/mapping.hpp");

  // The basis is built from its kind (make_basis: with the kind's settings), the mapping from the
  // configured one of the settings (run_settings, make_mapping; stepped_mapping_t).
  TypedStepper(const StepperInput<Dim>& in, Basis basis, Mapping mapping)
      : scheme_(in.method.scheme),
        sim_(in.problem.grid, std::move(basis), std::move(mapping), std::move(in.problem.particles),
             in.problem.materials,
             // A process of a distributed run allocates the grid arrays of its slab only, from
             // the first step on (RunState::fit_dof_window).
             /*whole_grid=*/in.comm == nullptr || !in.comm->distributed()) {
    const MethodSettings& method = in.method;
    const Problem<Dim>& pb = in.problem;
    if (in.check_input) {
      check_reconstruction_input<Dim>(method, sim_.grid, sim_.basis, sim_.particles, sim_.mapping);
      warn_sparse_consistent_mass<Dim>(method, sim_.basis, sim_.particles, in.comm,
                                       in.problem.warnings);
    }
    sim_.mass_type = method.mass;
    sim_.mass_tolerance = method.mass_tolerance;
    sim_.consistent.configure(method.mass_solver);
    sim_.spline_degree = basis_degree(method.basis);
    if (method.partial_lumping > 0.0) setup_partial_lumping(sim_, method.partial_lumping);
    sim_.conservation_limit = method.conservation_limit;
    sim_.local_damping = method.local_damping;
    sim_.sorting.mode = method.sort;
    for (const auto& f : pb.fixed_sides) {
      Vec<Dim> n;
      for (int d = 0; d < Dim; ++d) n[d] = f.normal[static_cast<std::size_t>(d)];
      if (f.boundary.empty())
        sim_.fix_side(f.direction, f.side, f.components);
      else if (!f.vertex_normals.empty())
        sim_.fix_vertex_normals(f.vertex_normals);
      else if (n != Vec<Dim>::Zero())
        sim_.fix_boundary_normal(f.boundary, n);
      else
        sim_.fix_boundary(f.boundary, f.components);
    }
    std::vector<Index> prescribed;
    if (pb.prescribed) {
      prescribed = sim_.prescribe_box(*pb.prescribed);
      if (prescribed.empty())
        throw InputError(
            "prescribed.min, prescribed.max: the box holds no degree of freedom of the basis (its "
            "positions: the grid nodes, a B-spline's Greville abscissae, the mesh's vertices)");
    }
    for (const FrictionWall& w : pb.friction_walls) {
      FixedSide where{w.direction, w.side};
      Vec<Dim> normal = Vec<Dim>::Zero();
      if (w.boundary.empty()) {
        normal[w.direction] = w.side == 0 ? -1.0 : 1.0;
      } else {
        where.boundary = w.boundary;
        for (int d = 0; d < Dim; ++d) normal[d] = w.normal[static_cast<std::size_t>(d)];
      }
      std::vector<Index> dofs = sim_.side_dofs(where);
      std::sort(dofs.begin(), dofs.end());  // (searched: stages::solve_velocity)
      const std::size_t n = dofs.size();
      sim_.walls.push_back({std::move(dofs), normal, w.mu, std::vector<unsigned char>(n, 0)});
    }
    if (pb.reactions) {
      for (const auto& f : pb.fixed_sides) sim_.reaction_dofs.push_back(sim_.side_dofs(f));
      for (const auto& w : sim_.walls) sim_.reaction_dofs.push_back(w.dofs);
      if (pb.prescribed) sim_.reaction_dofs.push_back(prescribed);
      sim_.reaction_whole.assign(sim_.reaction_dofs.size(), 0);
      for (std::size_t k = 0; k < sim_.walls.size(); ++k)
        sim_.reaction_whole[pb.fixed_sides.size() + k] = 1;
    }
    sim_.body_force = pb.body_force;
    sim_.tractions = pb.tractions;
    if (sim_.body_force.fill) sim_.body_force.fill(sim_.particles, 0.0, sim_.particles.body);
    if (in.comm != nullptr && in.comm->distributed()) {
      check_distributed_run(method);
      sim_.comm = in.comm;
      // The problem's traction points name their particles by id here (driver/run_mpm.cpp).
      sim_.all_tractions = std::move(sim_.tractions);
      localize_tractions(sim_);
      sim_.scatter.ranges.bounded = true;  // the grid work of this rank's slab only
    }
  }

  void step(double dt) override {
    std::visit([&](auto scheme) { decltype(scheme)::step(sim_, dt); }, scheme_);
  }

  bool sort_if_due() override {
    const Index sorts = sim_.sorting.sorts;
    // As BasisState: the sort does not depend on the mapping (one instance per basis).
    sort_particles_if_due(static_cast<BasisState<Dim, Basis>&>(sim_));
    return sim_.sorting.sorts != sorts;
  }

  RunState<Dim>& state() override { return sim_; }
  const RunState<Dim>& state() const override { return sim_; }

  // A distributed checkpoint gathers the corners with the particles (export_carried) and
  // replaces basis_state with them (driver/run_mpm.cpp).
  void save(io::Checkpoint& c) const override {
    if constexpr (Mapping::kRunTotals) c.mapping_totals = sim_.mapping.save_totals();
    if constexpr (Basis::kTrackedCorners) c.basis_state = flat_corners();
  }

  void load(const io::Checkpoint& c, const std::string& what) override {
    if constexpr (Mapping::kRunTotals) sim_.mapping.load_totals(c.mapping_totals, what);
    // CPDI2: the tracked corners, 2^Dim per particle; a distributed restart has put this
    // process's share in state().carried (driver/run_mpm.cpp), which resize_particle_caches
    // gives the basis.
    if constexpr (Basis::kTrackedCorners)
      if (sim_.carried_width == 0) {
        if (c.basis_state.size() != kCornerValues * sim_.particles.x.size())
          throw InputError(fmt::format("{} holds {} values of basis state; the {} basis needs {}",
                                       what, c.basis_state.size(), Basis::kName,
                                       kCornerValues * sim_.particles.x.size()));
        set_flat_corners(c.basis_state);
      }
  }

  void report(nlohmann::ordered_json& summary) const override {
    report_mapping(summary, sim_.mapping, Dim);
  }

  void export_carried() override {
    if constexpr (Basis::kTrackedCorners) {
      sim_.carried_width = static_cast<int>(kCornerValues);
      sim_.carried = flat_corners();
    }
  }

  std::vector<Vec<Dim>> dof_positions() const override {
    std::vector<Vec<Dim>> x(static_cast<std::size_t>(sim_.basis.num_dofs()));
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = sim_.basis.dof_position(static_cast<Index>(i));
    return x;
  }
  void resize_particle_caches() override {
    sim_.stencils.resize(static_cast<std::size_t>(sim_.particles.size()));
    if (sim_.comm && !sim_.all_tractions.empty()) localize_tractions(sim_);
    if constexpr (Basis::kTrackedCorners)
      if (sim_.carried_width > 0) {
        set_flat_corners(sim_.carried);
        sim_.carried.clear();
        sim_.carried_width = 0;
      }
  }

 private:
  // CPDI2's corners as doubles, kCornerValues per particle in particle order (checkpoints, the
  // carried state), and back.
  static constexpr std::size_t kCornerValues = [] {
    if constexpr (Basis::kTrackedCorners)
      return std::tuple_size_v<typename Basis::Corners> * Dim;
    else
      return std::size_t{0};
  }();
  std::vector<double> flat_corners() const {
    std::vector<double> v;
    if constexpr (Basis::kTrackedCorners) {
      v.reserve(kCornerValues * sim_.basis.corners().size());
      for (const auto& corners : sim_.basis.corners())
        for (const auto& x : corners)
          for (int d = 0; d < Dim; ++d) v.push_back(x[d]);
    }
    return v;
  }
  void set_flat_corners(const std::vector<double>& v) {
    if constexpr (Basis::kTrackedCorners) {
      std::vector<typename Basis::Corners> corners(v.size() / kCornerValues);
      std::size_t k = 0;
      for (auto& cs : corners)
        for (auto& x : cs)
          for (int d = 0; d < Dim; ++d) x[d] = v[k++];
      sim_.basis.set_corners(std::move(corners));
    }
  }
  Scheme scheme_;
  Sim sim_;
};

template <int Dim, std::size_t I>
std::unique_ptr<Stepper<Dim>> make_stepper_for(const StepperInput<Dim>& in) {
  using Kind = std::variant_alternative_t<I, BasisKind>;
  if constexpr (!supports_dimension<Kind>(Dim)) {
    throw std::logic_error("make_stepper_for: basis not available in this dimension");
  } else {
    using Basis = typename Kind::template type<Dim>;
    return std::visit(
        [&](const auto& m) -> std::unique_ptr<Stepper<Dim>> {
          using Chosen = std::decay_t<decltype(m)>;
          // MLS and IMLS run as one type (mapping/mapping.hpp, stepped_mapping).
          using Mapping = stepped_mapping_t<Chosen>;
          if constexpr (!supports_dimension<Chosen>(Dim))
            throw std::logic_error("make_stepper_for: mapping not available in this dimension");
          else if constexpr (!supports_mapping<Kind, Chosen>())
            throw std::logic_error("make_stepper_for: basis and mapping not available together");
          else
            return std::make_unique<TypedStepper<Dim, Basis, Mapping>>(
                in, make_basis<Dim>(std::get<I>(in.method.basis), in.problem.grid, in.problem.mesh),
                Mapping(m));
        },
        in.method.mapping);
  }
}

}  // namespace mpm::driver
