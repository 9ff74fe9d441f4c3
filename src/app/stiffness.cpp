#include "app/stiffness.hpp"

#include <fmt/format.h>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>
#include <ostream>
#include <variant>

#include "basis/bspline.hpp"
#include "basis/linear.hpp"
#include "benchmarks/benchmarks.hpp"
#include "io/checkpoint.hpp"
#include "mapping/direct.hpp"
#include "mapping/tls.hpp"
#include "scheme/stages.hpp"
#include "setup/config.hpp"
#include "setup/method_settings.hpp"

namespace mpm {
namespace {

constexpr int kDim = 2;
// Above this many velocity components the dense eigenvalue solve (O(n^3)) takes minutes.
constexpr Eigen::Index kMaxComponents = 6000;

// The grid force per unit grid velocity, column (j, e) for component e of DOF j; the lumped
// masses; which components are fixed (zero acceleration for a unit force: a Dirichlet side).
struct Linearised {
  Eigen::MatrixXd force;
  Eigen::VectorXd mass;
  std::vector<char> fixed;
};

template <class Sim>
Linearised linearise(Sim& sim) {
  auto& P = sim.particles;
  for (auto& b : P.body) b.setZero();  // body forces do not depend on v
  stages::evaluate_basis(sim);
  stages::map_mass(sim);
  const Index n = sim.nodes.size();
  const Eigen::Index comps = static_cast<Eigen::Index>(n) * kDim;
  if (comps > kMaxComponents)
    throw InputError(fmt::format(
        "mpm stiffness: {} velocity components; the dense eigenvalue solve takes at most {} "
        "(use fewer cells, grid.cells)",
        comps, kMaxComponents));
  Linearised lin;
  lin.mass.resize(n);
  for (Index i = 0; i < n; ++i) lin.mass[i] = sim.nodes.mass[static_cast<std::size_t>(i)];
  for (auto& f : sim.nodes.force) f = Vec<kDim>::Ones();
  stages::solve_acceleration(sim, 0.0);  // (no frictional walls here: dt unused)
  lin.fixed.resize(static_cast<std::size_t>(comps));
  for (Index i = 0; i < n; ++i)
    for (int d = 0; d < kDim; ++d)
      lin.fixed[static_cast<std::size_t>(i * kDim + d)] =
          sim.nodes.accel[static_cast<std::size_t>(i)][d] == 0.0;
  const Particles<kDim> frozen = P;
  // dsigma by central differences of the law's own update over a velocity of eps: the tangent
  // of each particle's state (for an elastic law at F = I, C : sym(L)); eps small against 1 (a
  // strain increment) and large against round-off of the stress (E eps >> 1e-16 |sigma|).
  constexpr double eps = 1e-8;
  std::vector<Mat<kDim>> dsigma(frozen.x.size());
  lin.force.setZero(comps, comps);
  for (Index j = 0; j < n; ++j)
    for (int e = 0; e < kDim; ++e) {
      if (lin.fixed[static_cast<std::size_t>(j * kDim + e)]) continue;
      std::fill(dsigma.begin(), dsigma.end(), Mat<kDim>::Zero());
      for (const double sign : {1.0, -1.0}) {
        P = frozen;
        for (auto& v : sim.nodes.velocity) v.setZero();
        sim.nodes.velocity[static_cast<std::size_t>(j)][e] = sign * eps;
        stages::mapped_strain_rates(sim);  // TLS's adjoint rate, where configured
        stages::update_stress(sim, 1.0);
        for (std::size_t p = 0; p < dsigma.size(); ++p) dsigma[p] += sign * P.stress[p];
      }
      P = frozen;  // positions, volumes and F as they were; only the stress is the rate
      for (std::size_t p = 0; p < dsigma.size(); ++p) P.stress[p] = dsigma[p] / (2.0 * eps);
      stages::map_forces(sim);
      for (Index i = 0; i < n; ++i)
        for (int d = 0; d < kDim; ++d)
          lin.force(i * kDim + d, j * kDim + e) = sim.nodes.force[static_cast<std::size_t>(i)][d];
    }
  P = frozen;
  return lin;
}

StiffnessRow spectrum(const Linearised& f, const Linearised& m) {
  const double mmax = m.mass.maxCoeff();
  std::vector<Eigen::Index> act;
  for (Eigen::Index k = 0; k < f.force.rows(); ++k)
    if (!f.fixed[static_cast<std::size_t>(k)] && !m.fixed[static_cast<std::size_t>(k)] &&
        m.mass[k / kDim] > 1e-12 * mmax)
      act.push_back(k);
  const auto a = static_cast<Eigen::Index>(act.size());
  Eigen::MatrixXd S(a, a), K(a, a);
  for (Eigen::Index r = 0; r < a; ++r)
    for (Eigen::Index c = 0; c < a; ++c) {
      S(r, c) = f.force(act[static_cast<std::size_t>(r)], act[static_cast<std::size_t>(c)]);
      K(r, c) = S(r, c) / m.mass[act[static_cast<std::size_t>(r)] / kDim];
    }
  StiffnessRow row;
  row.dofs = static_cast<int>(a);
  row.asymmetry = S.norm() > 0.0 ? (S - S.transpose()).norm() / S.norm() : 0.0;
  const Eigen::EigenSolver<Eigen::MatrixXd> es(K, /*computeEigenvectors=*/false);
  for (Eigen::Index k = 0; k < a; ++k) {
    const std::complex<double> lambda = std::sqrt(es.eigenvalues()[k]);  // Re >= 0
    row.growth = std::max(row.growth, lambda.real());
    row.omega = std::max(row.omega, std::abs(lambda.imag()));
  }
  return row;
}

template <class Basis>
void analyse(const Config& cfg, Problem<kDim>& pb, const Particles<kDim>& P, bool tls,
             StiffnessReport& rep) {
  auto with_sides = [&](auto& sim) -> auto& {
    for (const auto& s : pb.fixed_sides) sim.fix_side(s.direction, s.side, s.components);
    return sim;
  };
  Simulation<kDim, Basis, DirectMapping> direct(pb.grid, Basis(pb.grid), DirectMapping{}, P,
                                                pb.materials);
  const Linearised d = linearise(with_sides(direct));
  auto row = [&](const char* force, const char* mass, const Linearised& f, const Linearised& m) {
    StiffnessRow r = spectrum(f, m);
    r.force = force;
    r.mass = mass;
    rep.rows.push_back(r);
  };
  row("direct", "direct", d, d);
  if (!tls) return;
  Simulation<kDim, Basis, TlsMapping> fit(
      pb.grid, Basis(pb.grid), TlsMapping(tls_settings(cfg, kDim), kDim), P, pb.materials);
  const Linearised t = linearise(with_sides(fit));
  row("tls", "tls", t, t);
  row("tls", "direct", t, d);
  row("direct", "tls", d, t);
}

}  // namespace

StiffnessReport stiffness_spectrum(const StiffnessOptions& opt) {
  const Config cfg = Config::load(opt.config, opt.sets);
  AnyProblem any = make_problem(cfg);
  auto* pb = std::get_if<Problem<kDim>>(&any);
  if (pb == nullptr)
    throw InputError(fmt::format("{}: mpm stiffness analyses 2D problems; this benchmark is {}D",
                                 cfg.where("benchmark"), any.index() + 1));
  if (pb->mesh)
    throw InputError(
        "grid.mesh: mpm stiffness analyses bases on the grid's cells, not on a mesh's triangles");
  for (const auto& s : pb->fixed_sides)
    if (!s.boundary.empty())
      throw InputError(
          "mpm stiffness: a condition on a named boundary; it analyses the grid's "
          "sides only");
  const std::string basis = cfg.get_string("method.basis");
  const std::int64_t degree = cfg.get_int("method.degree");
  const std::string mapping = cfg.get_string("method.mapping");
  if (!(basis == "linear" || (basis == "bspline" && degree == 2)))
    throw InputError(
        fmt::format("{}: mpm stiffness analyses method.basis = \"linear\" or \"bspline\" with "
                    "method.degree = 2, not \"{}\"{}",
                    cfg.where("method.basis"), basis,
                    basis == "bspline" ? fmt::format(" of degree {}", degree) : std::string()));
  if (mapping != "direct" && mapping != "tls")
    throw InputError(
        fmt::format("{}: mpm stiffness analyses method.mapping = \"direct\" or \"tls\", not \"{}\"",
                    cfg.where("method.mapping"), mapping));
  StiffnessReport rep;
  rep.basis = basis == "linear" ? "linear" : "bspline2";
  rep.mapping = mapping;
  rep.state = "the initial layout";
  Particles<kDim> P = pb->particles;
  if (!opt.checkpoint.empty()) {
    const io::Checkpoint c = io::read_whole_checkpoint(opt.checkpoint);
    const std::string what = fmt::format("checkpoint '{}'", opt.checkpoint);
    if (c.solver != "mpm" || c.dim != kDim)
      throw InputError(
          fmt::format("{} holds a {} run in {}D, not a 2D mpm run", what, c.solver, c.dim));
    P = io::unpack_particles<kDim>(c.particles, what);
    try {
      P.state.set_names(pb->materials.state_names());
    } catch (const std::invalid_argument& e) {
      throw InputError(fmt::format("{}: {}", what, e.what()));
    }
    rep.state = fmt::format("t = {:.6g} s (step {}) of {}", c.time, c.step, opt.checkpoint);
  }
  if (opt.layout_only) {
    for (auto& s : P.stress) s.setZero();
    for (auto& F : P.F) F.setIdentity();
    rep.state += ", unstressed";
  }
  rep.particles = static_cast<int>(P.size());
  if (basis == "linear")
    analyse<LinearBasis<kDim>>(cfg, *pb, P, mapping == "tls", rep);
  else
    analyse<BSplineBasis<kDim, 2>>(cfg, *pb, P, mapping == "tls", rep);
  return rep;
}

void print_stiffness(std::ostream& os, const StiffnessOptions& opt, const StiffnessReport& r) {
  os << fmt::format("{} with {}, {} particles at {}\n", r.basis, r.mapping, r.particles, r.state);
  os << fmt::format("{:<8} {:<8} {:>6} {:>16} {:>14} {:>12}{}\n", "force", "mass", "dofs",
                    "max Re lambda", "max omega", "asymmetry",
                    opt.period > 0.0 ? fmt::format(" {:>20}", "energy per period") : "");
  for (const auto& row : r.rows)
    os << fmt::format(
        "{:<8} {:<8} {:>6} {:>12.4g} 1/s {:>10.4g} 1/s {:>12.3g}{}\n", row.force, row.mass,
        row.dofs, row.growth, row.omega, row.asymmetry,
        opt.period > 0.0 ? fmt::format(" {:>20.4g}", std::exp(2.0 * row.growth * opt.period)) : "");
}

}  // namespace mpm
