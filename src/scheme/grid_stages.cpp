// The stages that read and write only the grid quantities of RunState (scheme/stages.hpp):
// compiled once per dimension here, not in every (basis, mapping) stepper unit.
#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/parallel.hpp"
#include "scheme/stages.hpp"

namespace mpm::stages {

namespace detail {
// The active set and the mass conservation check, and the consistent matrix if requested,
// from the nodal masses of the mapping.
template <int Dim>
void after_mass(RunState<Dim>& sim) {
  const auto& m = sim.nodes.mass;
  const auto& mp = sim.particles.mass;
  const double total = deterministic_sum(static_cast<Index>(m.size()), 0.0,
                                         [&](Index i) { return m[static_cast<std::size_t>(i)]; });
  const double largest = m.empty() ? 0.0 : *std::max_element(m.begin(), m.end());
  // sum m_p: taken by the mapping's scatter when it has one (the same bits), else a pass here.
  auto& sc = sim.scatter;
  const double particle_mass =
      sc.has_particle_mass ? sc.particle_mass.total(static_cast<Index>(mp.size()), 0.0)
                           : deterministic_sum(static_cast<Index>(mp.size()), 0.0, [&](Index p) {
                               return mp[static_cast<std::size_t>(p)];
                             });
  sc.has_particle_mass = false;
  if (particle_mass > 0.0) {
    sim.diag.rel_mass_error = std::abs(total - particle_mass) / particle_mass;
    sim.diag.max_rel_mass_error = std::max(sim.diag.max_rel_mass_error, sim.diag.rel_mass_error);
  }
  const double threshold = sim.mass_tolerance * largest;
  parallel_for(static_cast<Index>(m.size()), [&](Index k) {
    const auto i = static_cast<std::size_t>(k);
    sim.nodes.active[i] = m[i] > threshold ? 1 : 0;
  });
  if (sim.mass_type == MassType::Consistent) {
    constexpr std::uint8_t kAll = (1u << Dim) - 1u;
    const auto& act = sim.nodes.active;
    const auto& fixed = sim.nodes.fixed;
    // Fixed DOFs are eliminated: the prescribed value is zero, so M y = r with identity rows.
    // One factorisation serves every component unless some DOF is fixed in only some of them
    // (rollers): then component d gets its own (slot d).
    const bool per_component = sim.consistent_per_component;
    for (int d = 0; d < (per_component ? Dim : 1); ++d) {
      const auto bit = static_cast<std::uint8_t>(per_component ? 1u << d : kAll);
      if (!sim.consistent.factorize(
              [&](Index i) {
                const auto k = static_cast<std::size_t>(i);
                return act[k] && !(fixed[k] & bit);
              },
              d))
        throw RunError(exit_code::kNonFinite,
                       fmt::format("step {}, t = {:.9g} s: the consistent mass matrix is singular "
                                   "(a cell with too few particles); use method.mass = \"lumped\"",
                                   sim.step, sim.time));
    }
  }
}

// The momentum conservation check from the nodal momenta of the mapping.
template <int Dim>
void after_momentum(RunState<Dim>& sim) {
  const auto& q = sim.nodes.momentum;
  const Vec<Dim> grid_p =
      deterministic_sum(static_cast<Index>(q.size()), Vec<Dim>::Zero().eval(),
                        [&](Index i) { return q[static_cast<std::size_t>(i)]; });
  // (sum m_p v_p, sum m_p |v_p|) as one vector: taken by the mapping's scatter when it has one
  // (the same bits), else one pass over the particles here.
  using Sums = Eigen::Matrix<double, Dim + 1, 1>;
  const auto& P = sim.particles;
  auto& sc = sim.scatter;
  const Sums sums = sc.has_particle_momentum
                        ? sc.particle_momentum.total(P.size(), Sums::Zero().eval())
                        : deterministic_sum(P.size(), Sums::Zero().eval(), [&](Index p) {
                            const auto i = static_cast<std::size_t>(p);
                            Sums r;
                            r.template head<Dim>() = P.mass[i] * P.v[i];
                            r[Dim] = P.mass[i] * P.v[i].norm();
                            return r;
                          });
  sc.has_particle_momentum = false;
  const Vec<Dim> part_p = sums.template head<Dim>();
  const double scale = sums[Dim];
  if (scale > 0.0) {
    sim.diag.rel_momentum_error = (grid_p - part_p).norm() / scale;
    sim.diag.max_rel_momentum_error =
        std::max(sim.diag.max_rel_momentum_error, sim.diag.rel_momentum_error);
  }
}
}  // namespace detail

namespace {
// y = M^{-1} r on the active, unconstrained DOFs; zero elsewhere (D eq. 2.46 / 2.49).
template <int Dim, class V>
void solve_grid(const RunState<Dim>& sim, const std::vector<V>& r, std::vector<V>& y) {
  const auto& nd = sim.nodes;
  const auto n = r.size();
  if (sim.mass_type == MassType::Lumped) {
    parallel_for(static_cast<Index>(n), [&](Index k) {
      const auto i = static_cast<std::size_t>(k);
      y[i] = nd.active[i] ? V(r[i] / nd.mass[i]) : V::Zero();
    });
  } else {
    Eigen::VectorXd rhs(static_cast<Index>(n));
    for (int d = 0; d < Dim; ++d) {
      const int slot = sim.consistent_per_component ? d : 0;
      for (std::size_t i = 0; i < n; ++i)
        rhs[static_cast<Index>(i)] = (nd.active[i] && !(nd.fixed[i] & (1u << d))) ? r[i][d] : 0.0;
      const Eigen::VectorXd sol = sim.consistent.solve(rhs, slot);
      for (std::size_t i = 0; i < n; ++i) y[i][d] = sol[static_cast<Index>(i)];
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    if (nd.fixed[i])
      for (int d = 0; d < Dim; ++d)
        if (nd.fixed[i] & (1u << d)) y[i][d] = 0.0;
}
}  // namespace

// a_i = M^{-1} f_i with Dirichlet components zero (D eq. 2.46).
template <int Dim>
void solve_acceleration(RunState<Dim>& sim) {
  solve_grid(sim, sim.nodes.force, sim.nodes.accel);
}

// v_i = M^{-1} q_i with Dirichlet components zero (D eq. 2.35 / 2.49).
template <int Dim>
void solve_velocity(RunState<Dim>& sim) {
  solve_grid(sim, sim.nodes.momentum, sim.nodes.velocity);
}

// Euler-Cromer on the grid: v_i^{s+1} = v_i^s + dt a_i^s (D eq. 2.36; USL, USF).
template <int Dim>
void advance_grid_velocity(RunState<Dim>& sim, double dt) {
  auto& nd = sim.nodes;
  parallel_for(nd.size(), [&](Index k) {
    const auto i = static_cast<std::size_t>(k);
    nd.velocity[i] += dt * nd.accel[i];
  });
}

template void detail::after_mass<1>(RunState<1>&);
template void detail::after_momentum<1>(RunState<1>&);
template void solve_acceleration<1>(RunState<1>&);
template void solve_velocity<1>(RunState<1>&);
template void advance_grid_velocity<1>(RunState<1>&, double);
template void detail::after_mass<2>(RunState<2>&);
template void detail::after_momentum<2>(RunState<2>&);
template void solve_acceleration<2>(RunState<2>&);
template void solve_velocity<2>(RunState<2>&);
template void advance_grid_velocity<2>(RunState<2>&, double);

}  // namespace mpm::stages
