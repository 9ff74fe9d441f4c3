#include "benchmarks/initial_stress.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "setup/material_settings.hpp"

namespace mpm {

namespace {

// "(x, y) = (1, 2)" for messages.
template <int Dim>
std::string point(const Vec<Dim>& X) {
  if constexpr (Dim == 2) return fmt::format("(x, y) = ({:.6g}, {:.6g})", X[0], X[1]);
  return fmt::format("(x, y, z) = ({:.6g}, {:.6g}, {:.6g})", X[0], X[1], X[Dim - 1]);
}

}  // namespace

void refuse_initial_stress(const Config& cfg, const Material& material, int dim, const char* key) {
  if (incremental(material)) return;
  const std::string laws = laws_in(dim, /*incremental_only=*/true);
  throw InputError(fmt::format(
      "{}: {} gives an initial stress, which needs an incremental law{}; material.model = \"{}\" "
      "computes the stress from F = I{}",
      cfg.where(key), key, laws.empty() ? "" : fmt::format(" ({})", laws), material_name(material),
      laws.empty() ? fmt::format(" (no {}D law is incremental: leave {} at 0)", dim, key) : ""));
}

template <int Dim>
std::optional<Geostatic<Dim>> geostatic_from_config(const Config& cfg, const Problem<Dim>& pb,
                                                    const std::vector<Expression>& body_force,
                                                    const MassAbove<Dim>& mass_above) {
  if (cfg.get_string("initial.geostatic") == "none") {
    std::vector<std::string> keys{"initial.k0"};
    for (std::size_t k = 0; k < pb.materials.size(); ++k)
      keys.push_back((k == 0 ? std::string("material") : "material." + pb.materials.name(k)) +
                     ".k0");
    for (const std::string& key : keys)
      if (!cfg.at_default(key))
        throw InputError(
            fmt::format("{}: {} is read with initial.geostatic = \"k0\", and this run has "
                        "initial.geostatic = \"none\" (set it to \"k0\", or leave {} out)",
                        cfg.where(key), key, key));
    return std::nullopt;
  }
  const std::string where = cfg.where("initial.geostatic");
  const std::vector<std::string> given = cfg.get_expressions("initial.stress");
  if (!(given.size() == 1 && given[0] == "0"))
    throw InputError(fmt::format(
        "{}: initial.geostatic = \"k0\" computes the initial stress; leave initial.stress (given "
        "at {}) at 0",
        where, cfg.where("initial.stress")));
  if (!cfg.at_default("initial.stress_zz"))
    throw InputError(fmt::format(
        "{}: initial.geostatic = \"k0\" computes the initial stress, out of the plane too; leave "
        "initial.stress_zz (given at {}) at 0",
        where, cfg.where("initial.stress_zz")));
  if (!cfg.get_string("body.particles").empty())
    throw InputError(fmt::format(
        "{}: initial.geostatic = \"k0\" takes the overburden of a box body (body.min, "
        "body.max) or of a body mesh (body.mesh), not of a particle file (body.particles); give "
        "initial.stress{} as expressions of the position, or the stress columns of the particle "
        "file, instead",
        where, Dim == 2 ? " and initial.stress_zz" : ""));
  if (pb.mesh && !mass_above)
    throw InputError(fmt::format(
        "{}: initial.geostatic = \"k0\" takes the overburden of a box body (body.min, "
        "body.max) or of a body mesh (body.mesh), not of the triangles of grid.mesh; give "
        "initial.stress{} as expressions of x and y instead",
        where, Dim == 2 ? " and initial.stress_zz" : ""));
  constexpr const char* kAxes = "xyz";
  Vec<Dim> g;
  for (int d = 0; d < Dim; ++d) {
    const Expression& e = body_force[static_cast<std::size_t>(d)];
    if (!e.is_constant())
      throw InputError(fmt::format(
          "{}: initial.geostatic = \"k0\" needs a constant body force; loading.body_force (at "
          "{}) changes with {} in its {} component",
          where, cfg.where("loading.body_force"), e.uses_time() ? "time" : "position", kAxes[d]));
    g[d] = e(0.0);
  }
  for (int d = 0; d + 1 < Dim; ++d)
    if (g[d] != 0.0)
      throw InputError(fmt::format(
          "{}: initial.geostatic = \"k0\" needs the body force along the last axis ({}), the "
          "vertical; loading.body_force (at {}) has {} = {}",
          where, kAxes[Dim - 1], cfg.where("loading.body_force"), kAxes[d], g[d]));
  if (!(g[Dim - 1] < 0.0))
    throw InputError(fmt::format(
        "{}: initial.geostatic = \"k0\" needs a body force downwards, along -{}; "
        "loading.body_force (at {}) has {} = {}",
        where, kAxes[Dim - 1], cfg.where("loading.body_force"), kAxes[Dim - 1], g[Dim - 1]));
  // K0 of each material: its material.k0, else initial.k0 (read only when some material takes
  // it: a missing one is reported then).
  Geostatic<Dim> geo;
  for (std::size_t k = 0; k < pb.materials.size(); ++k) {
    const std::string table = k == 0 ? std::string("material") : "material." + pb.materials.name(k);
    const double own = cfg.get_real(table + ".k0");
    if (own < 0.0 && own != -1.0)
      throw InputError(fmt::format("{}: {}.k0 = {} is out of range: K0 >= 0, or -1 for initial.k0",
                                   cfg.where(table + ".k0"), table, own));
    geo.k0.push_back(own >= 0.0 ? own : cfg.get_real("initial.k0"));
  }
  const double g_v = g[Dim - 1];
  if (mass_above) {
    // A body mesh: g times the mass above a point per unit area (its parts' densities).
    geo.vertical = [g_v, mass_above](const Vec<Dim>& X) { return g_v * mass_above(X); };
  } else {
    // A box body, of body.material's density.
    const double weight =
        pb.materials.density(material_index(cfg, pb.materials, "body.material")) * g_v;
    geo.vertical = [weight, top = pb.body_max[Dim - 1]](const Vec<Dim>& X) {
      return weight * (top - X[Dim - 1]);
    };
  }
  return geo;
}

template <int Dim>
void set_initial_stress(const Config& cfg, Problem<Dim>& pb,
                        std::function<Mat<Dim>(const Vec<Dim>&)> from_expressions,
                        const std::vector<Expression>& body_force,
                        const MassAbove<Dim>& mass_above) {
  const std::optional<Geostatic<Dim>> k0 =
      geostatic_from_config<Dim>(cfg, pb, body_force, mass_above);
  std::optional<Expression> zz;
  if constexpr (Dim == 2) {
    if (!k0) zz.emplace(cfg.get_string("initial.stress_zz"), cfg.constants());
  } else if (!cfg.at_default("initial.stress_zz")) {
    throw InputError(fmt::format(
        "{}: initial.stress_zz is the out-of-plane stress of a 2D (plane-strain) run; in {}D "
        "initial.stress gives every component",
        cfg.where("initial.stress_zz"), Dim));
  }
  auto& P = pb.particles;
  P.state.set_names(pb.materials.state_names());
  // (A function of the position alone: with K0, that of body.material's K0.)
  if (k0)
    pb.initial_stress = [geo = *k0, k = material_index(cfg, pb.materials, "body.material")](
                            const Vec<Dim>& X) { return geo.stress(X, k); };
  else
    pb.initial_stress = std::move(from_expressions);
  const char* key = k0 ? "initial.geostatic" : "initial.stress";
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    P.stress[i] = k0 ? k0->stress(P.x0[i], P.material[i]) : pb.initial_stress(P.x0[i]);
    if (!P.stress[i].allFinite())
      throw InputError(fmt::format("{}: {} is not finite at {} (particle {})", cfg.where(key), key,
                                   point<Dim>(P.x0[i]), P.id[i]));
    double out_of_plane = 0.0;
    if constexpr (Dim == 2) {
      out_of_plane = k0 ? k0->out_of_plane(P.x0[i], P.material[i]) : (*zz)(P.x0[i][0], P.x0[i][1]);
      if (!std::isfinite(out_of_plane))
        throw InputError(fmt::format("{}: initial.stress_zz is not finite at {} (particle {})",
                                     cfg.where("initial.stress_zz"), point<Dim>(P.x0[i]), P.id[i]));
    }
    // The particle's law: whether it takes an initial stress, and where it keeps the stress
    // normal to the plane of a 2D run, if it does.
    const Material& law = pb.materials[P.material[i]];
    if (P.stress[i] != Mat<Dim>::Zero()) refuse_initial_stress(cfg, law, Dim, key);
    const auto names = state_names(law);
    const auto column = std::find(names.begin(), names.end(), kOutOfPlaneStressName);
    const bool keeps_zz = Dim == 2 && column != names.end();
    if (out_of_plane != 0.0) {
      refuse_initial_stress(cfg, law, Dim, k0 ? key : "initial.stress_zz");
      if (!keeps_zz)
        throw InputError(
            fmt::format("{}: material.model = \"{}\" keeps no stress normal to the plane; leave "
                        "initial.stress_zz at 0",
                        cfg.where("initial.stress_zz"), material_name(law)));
    }
    if (keeps_zz)
      P.state[i][pb.materials.state_offset(P.material[i]) +
                 static_cast<std::size_t>(column - names.begin())] = out_of_plane;
  }
}

template std::optional<Geostatic<2>> geostatic_from_config<2>(const Config&, const Problem<2>&,
                                                              const std::vector<Expression>&,
                                                              const MassAbove<2>&);
template std::optional<Geostatic<3>> geostatic_from_config<3>(const Config&, const Problem<3>&,
                                                              const std::vector<Expression>&,
                                                              const MassAbove<3>&);
template void set_initial_stress<2>(const Config&, Problem<2>&,
                                    std::function<Mat<2>(const Vec<2>&)>,
                                    const std::vector<Expression>&, const MassAbove<2>&);
template void set_initial_stress<3>(const Config&, Problem<3>&,
                                    std::function<Mat<3>(const Vec<3>&)>,
                                    const std::vector<Expression>&, const MassAbove<3>&);

}  // namespace mpm
