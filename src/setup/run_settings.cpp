#include "setup/run_settings.hpp"

#include <fmt/format.h>
#include <cmath>
#include <string_view>
#include <variant>

#include "setup/config.hpp"
#include "setup/method_settings.hpp"
#include "setup/registry.hpp"
#include "setup/variant_name.hpp"

namespace mpm {
namespace {

// A basis kind matches by name and, for B-splines, by degree (method.degree).
template <std::size_t I = 0>
BasisKind choose_basis(std::string_view name, int degree) {
  if constexpr (I < std::variant_size_v<BasisKind>) {
    using Alt = std::variant_alternative_t<I, BasisKind>;
    // B-spline kinds match by degree too (kDegree 0: not a B-spline).
    const bool match = name == Alt::kName && (Alt::kDegree == 0 || degree == Alt::kDegree);
    if (match) return BasisKind(std::in_place_index<I>);
    return choose_basis<I + 1>(name, degree);
  } else {
    std::string choices;
    for (const auto& e : registry::kBases)
      choices += fmt::format("{}{}", choices.empty() ? "" : ", ", e.name);
    throw InputError(fmt::format(
        "method.basis = \"{}\" (method.degree = {}) is not available; choose one of: {}", name,
        degree, choices));
  }
}

TimeSettings time_settings(const Config& cfg) {
  TimeSettings t;
  t.dt = cfg.get_real("time.dt");
  t.end = cfg.get_real("time.end");
  t.allow_unstable = cfg.get_bool("time.allow_unstable");
  t.where_dt = cfg.where("time.dt");
  t.where_end = cfg.where("time.end");
  const double ratio = t.end / t.dt;
  t.steps = static_cast<Index>(std::llround(ratio));
  if (t.steps < 1 || std::abs(ratio - static_cast<double>(t.steps)) > 1e-6 * std::max(1.0, ratio))
    throw InputError(fmt::format(
        "{}: time.end = {} must be a positive whole multiple of time.dt = {} (it is {:.6g} "
        "steps)",
        t.where_end, t.end, t.dt, ratio));
  return t;
}

// The mapping alternative with its settings from the configuration (make_mapping).
template <int Dim>
MappingKind configured_mapping(const MappingKind& chosen, const Config& cfg) {
  return std::visit(
      [&](const auto& m) -> MappingKind {
        using M = std::decay_t<decltype(m)>;
        if constexpr (!M::supports_dimension(Dim))
          return m;  // refused before this (run_settings)
        else
          return make_mapping<Dim, M>(cfg);
      },
      chosen);
}

}  // namespace

BlockShapeRequest blocks_request(const Config& cfg) {
  return BlockShapeRequest::parse(cfg.get_string("parallel.blocks"), cfg.where("parallel.blocks"));
}

RunSettings run_settings(const Config& cfg, int dim) {
  RunSettings s;
  MethodSettings& m = s.method;
  const std::string solver = cfg.get_string("method.solver");
  m.solver = solver == "ulfem"     ? Solver::Ulfem
             : solver == "otm"     ? Solver::Otm
             : solver == "unified" ? Solver::Unified
                                   : Solver::Mpm;
  if (m.solver == Solver::Ulfem && dim != 1)
    throw InputError(fmt::format("{}: method.solver = \"{}\" is one-dimensional (so far)",
                                 cfg.where("method.solver"), solver));
  if ((m.solver == Solver::Otm || m.solver == Solver::Unified) && dim == 3)
    throw InputError(
        fmt::format("{}: method.solver = \"{}\" runs in 1D and 2D (so far); in 3D choose \"mpm\"",
                    cfg.where("method.solver"), solver));
  m.where_solver = cfg.where("method.solver");
  m.where_mass = cfg.where("method.mass");
  m.where_basis = cfg.where("method.basis");
  m.where_mapping = cfg.where("method.mapping");
  m.where_tls_completion = cfg.where("method.tls_completion");
  if (m.solver != Solver::Ulfem) {
    auto with_key = [&](const char* key, auto&& fn) {
      try {
        return fn();
      } catch (const InputError& e) {
        throw InputError(fmt::format("{}: {}", cfg.where(key), e.what()));
      }
    };
    m.basis = with_key("method.basis", [&] {
      return choose_basis(cfg.get_string("method.basis"),
                          static_cast<int>(cfg.get_int("method.degree")));
    });
    const TrianglePattern pattern = cfg.get_string("method.triangles") == "criss_cross"
                                        ? TrianglePattern::criss_cross
                                        : TrianglePattern::right;
    set_triangle_pattern(m.basis, pattern);
    if (auto* k = std::get_if<MaxEntKind>(&m.basis)) {
      k->settings.dmax = cfg.get_real("method.maxent_dmax");
      k->settings.tolerance = cfg.get_real("method.maxent_tolerance");
      k->settings.max_iterations = static_cast<int>(cfg.get_int("method.maxent_max_iterations"));
    }
    if (auto* k = std::get_if<DdmpmKind>(&m.basis)) {
      k->settings.integrals = cfg.get_string("method.ddmpm_integrals") == "quadrature"
                                  ? DdmpmIntegrals::quadrature
                                  : DdmpmIntegrals::particles;
      k->settings.weight = cfg.get_string("method.ddmpm_weight") == "product"
                               ? DdmpmWeight::product
                               : DdmpmWeight::per_direction;
    } else {
      for (const char* key : {"method.ddmpm_integrals", "method.ddmpm_weight"})
        if (!cfg.at_default(key))
          throw InputError(
              fmt::format("{}: {} sets the DDMPM basis, and this run uses "
                          "method.basis = \"{}\": remove it or set method.basis = "
                          "\"ddmpm\"",
                          cfg.where(key), key, name_of(m.basis)));
    }
    m.mapping = with_key("method.mapping", [&] {
      return choose_alternative<MappingKind>(cfg.get_string("method.mapping"), "method.mapping");
    });
    m.scheme = with_key("method.scheme", [&] {
      return choose_alternative<Scheme>(cfg.get_string("method.scheme"), "method.scheme");
    });
    if (!std::visit([&](auto k) { return decltype(k)::supports_dimension(dim); }, m.basis))
      throw InputError(fmt::format("{}: method.basis = \"{}\" is not available in {}D",
                                   m.where_basis, name_of(m.basis), dim));
    if (!std::visit(
            [&](const auto& k) { return std::decay_t<decltype(k)>::supports_dimension(dim); },
            m.mapping))
      throw InputError(fmt::format("{}: method.mapping = \"{}\" is not available in {}D",
                                   m.where_mapping, name_of(m.mapping), dim));
    const bool together = std::visit(
        [](const auto& k, const auto& map) {
          return supports_mapping<std::decay_t<decltype(k)>, std::decay_t<decltype(map)>>();
        },
        m.basis, m.mapping);
    if (!together)
      throw InputError(fmt::format(
          "{}: method.mapping = \"{}\" is not available with method.basis = \"{}\"; the {} "
          "basis runs with the direct mapping only (methods/kinds.hpp, docs/verification.md)",
          m.where_mapping, name_of(m.mapping), name_of(m.basis), name_of(m.basis)));
  }
  s.time = time_settings(cfg);
  s.output.frames = static_cast<int>(cfg.get_int("output.frames"));
  s.output.history_every = cfg.get_int("output.history_every");
  s.output.checkpoint_every = cfg.get_int("output.checkpoint_every");
  s.parallel.rebalance = cfg.get_real("parallel.rebalance");
  s.parallel.blocks = blocks_request(cfg);
  s.output.csv = cfg.get_bool("output.csv");
  s.output.vtk = cfg.get_bool("output.vtk");
  s.output.vtk_binary = cfg.get_string("output.vtk_format") == "binary";
  std::vector<std::string> tables{"material"};
  for (const std::string& name : cfg.instances("material")) tables.push_back("material." + name);
  for (const std::string& table : tables) {
    MaterialSettings& ms = s.materials.emplace_back();
    ms.name = table == "material" ? table : table.substr(std::string("material.").size());
    ms.model = cfg.get_string(table + ".model");
    ms.elastic.density = cfg.get_real(table + ".density");
    ms.elastic.youngs_modulus = cfg.get_real(table + ".youngs_modulus");
    ms.elastic.poisson_ratio = cfg.get_real(table + ".poisson_ratio");
    for (const MaterialParameter& m : parameters_of(ms.model)) {
      const std::string key = fmt::format("{}.{}", table, m.name);
      if (m.choices.empty())
        ms.parameters.push_back({std::string(m.name), cfg.get_real(key), ""});
      else
        ms.parameters.push_back({std::string(m.name), 0.0, cfg.get_string(key)});
    }
  }
  s.reference_dofs = cfg.get_int("reference.dofs");
  m.mass = cfg.get_string("method.mass") == "consistent" ? MassType::Consistent : MassType::Lumped;
  m.mass_tolerance = cfg.get_real("method.mass_tolerance");
  m.partial_lumping = cfg.get_real("method.partial_lumping");
  if (m.partial_lumping > 0.0 && (m.mass != MassType::Consistent || m.solver != Solver::Mpm))
    throw InputError(fmt::format(
        "{}: method.partial_lumping = {} lumps rows of the consistent mass matrix of the MPM "
        "solver, and this run uses method.mass = \"{}\" with method.solver = \"{}\": set "
        "method.mass = \"consistent\" (method.solver = \"mpm\") or remove "
        "method.partial_lumping",
        cfg.where("method.partial_lumping"), m.partial_lumping, cfg.get_string("method.mass"),
        cfg.get_string("method.solver")));
  {
    const std::string solver = cfg.get_string("method.mass_solver");
    MassSolverSettings& ms = m.mass_solver;
    ms.kind = solver == "cg"    ? MassSolver::Cg
              : solver == "pmg" ? MassSolver::Pmg
                                : MassSolver::Direct;
    ms.tolerance = cfg.get_real("method.mass_solver_tolerance");
    ms.max_iterations = static_cast<int>(cfg.get_int("method.mass_solver_max_iterations"));
    ms.pmg.smoother = cfg.get_string("method.pmg_smoother") == "jacobi" ? Smoother::Jacobi
                                                                        : Smoother::GaussSeidel;
    ms.pmg.pre = ms.pmg.post = static_cast<int>(cfg.get_int("method.pmg_smoothing_steps"));
    if (ms.kind != MassSolver::Direct && m.mass != MassType::Consistent)
      throw InputError(fmt::format(
          "{}: method.mass_solver = \"{}\" solves the consistent mass matrix, and this run uses "
          "method.mass = \"lumped\" (a diagonal: nothing to solve): set method.mass = "
          "\"consistent\" or remove method.mass_solver",
          cfg.where("method.mass_solver"), solver));
    if (ms.kind == MassSolver::Pmg && (m.solver != Solver::Mpm || basis_degree(m.basis) == 0))
      throw InputError(fmt::format(
          "{}: method.mass_solver = \"pmg\" runs over the degrees of a B-spline basis on the "
          "grid: method.solver = \"mpm\" with method.basis = \"bspline\" (this run: solver "
          "\"{}\", basis \"{}\"); \"cg\" works with every basis",
          cfg.where("method.mass_solver"), cfg.get_string("method.solver"), name_of(m.basis)));
  }
  m.conservation_limit = cfg.get_real("method.conservation_limit");
  m.local_damping = cfg.get_real("method.local_damping");
  if (m.local_damping > 0.0 && m.solver != Solver::Mpm)
    throw InputError(fmt::format(
        "{}: method.local_damping damps the grid forces of the MPM solver; method.solver = "
        "\"{}\" has none (use method.solver = \"mpm\" or leave method.local_damping out)",
        cfg.where("method.local_damping"), cfg.get_string("method.solver")));
  m.sort = cfg.get_string("method.sort") == "never" ? SortMode::Never : SortMode::Auto;
  if (m.solver != Solver::Ulfem)
    m.mapping = dim == 1   ? configured_mapping<1>(m.mapping, cfg)
                : dim == 2 ? configured_mapping<2>(m.mapping, cfg)
                           : configured_mapping<3>(m.mapping, cfg);
  if (auto* tls = std::get_if<TlsMapping>(&m.mapping); tls && m.solver == Solver::Mpm) {
    const bool triangles = on_triangles(m.basis);
    *tls =
        TlsMapping(tls_settings_for_basis(cfg, tls->settings(), triangles, name_of(m.basis)), dim);
    // Under a constant load, B-spline TLS with consistent mass grows an
    // oscillation among the highest modes of the consistent matrix, at loads that fall with the
    // cell size; lumped mass, P1-TLS and the direct mapping stay neutral (docs/verification.md,
    // "PS-MPM with partially filled elements": the growing mode).
    const int degree = basis_degree(m.basis);
    if (!triangles && dim >= 2 && degree >= 2 && m.mass == MassType::Consistent &&
        !cfg.get_bool("method.allow_unstable"))
      throw InputError(fmt::format(
          "{}: method.mass = \"consistent\" with method.mapping = \"tls\" and B-splines of "
          "degree {} is refused in {}D: under a constant load it grows an oscillation among the "
          "highest modes of the consistent matrix (TLS's operator is not symmetric), at loads "
          "that fall with the cell size (measured in 2D; docs/verification.md, \"PS-MPM with "
          "partially filled elements\"). Choose method.mass = \"lumped\", or method.basis = "
          "\"linear\" (P1-TLS; with method.partial_lumping = 0.5 where cells are partly "
          "filled), or set method.allow_unstable = true to run it anyway",
          m.where_mass, degree, dim));
  }
  if (m.solver == Solver::Otm) {
    // OTM's update x_p = sum phi_i x_i needs consistent bases (D eq. 4.14-4.16), and it
    // integrates at the material points (D Algorithm 3).
    if (!otm_nodes(m.basis))
      throw InputError(fmt::format(
          "{}: method.solver = \"otm\" needs a basis with partition of unity and linear "
          "completeness on its advected nodes (D eq. 4.15-4.16): method.basis = {}, not \"{}\"",
          m.where_basis, basis_names_where([](const auto& k) { return k.kOtmNodes; }),
          name_of(m.basis)));
  }
  if (m.solver == Solver::Unified && !unified_dofs(m.basis))
    throw InputError(fmt::format(
        "{}: method.solver = \"unified\" carries the control points of an isoparametric map "
        "of the body with the material (D Algorithm 4, D 7.3): method.basis = {}, not \"{}\"",
        m.where_basis, basis_names_where([](const auto& k) { return k.kUnified; }),
        name_of(m.basis)));
  if ((m.solver == Solver::Otm || m.solver == Solver::Unified) &&
      !std::holds_alternative<DirectMapping>(m.mapping))
    throw InputError(fmt::format(
        "{}: method.solver = \"{}\" integrates at the material points (D Algorithms 3, 4): "
        "method.mapping = \"direct\", not \"{}\"",
        m.where_mapping, solver, name_of(m.mapping)));
  return s;
}

}  // namespace mpm
