#include "driver/run.hpp"

#include <fmt/format.h>

#include "benchmarks/benchmarks.hpp"
#include "driver/driver.hpp"
#include "driver/run_mpm.hpp"
#include "io/checkpoint.hpp"
#include "scheme/variants.hpp"
#include "setup/registry.hpp"

namespace mpm {
namespace {

using namespace driver;

// method.solver = "ulfem": the updated-Lagrangian FEM on the problem's body, one linear element
// per grid cell covered by the body; outputs and errors at the element midpoints.
RunResult run_ulfem(Problem<1>& pb, const Config& cfg, const RunOptions& opt) {
  const auto t_start = Clock::now();
  const TimeSetup ts = time_setup(cfg);
  OutputSession<1> out(opt, cfg, pb);
  const auto elements =
      std::max<Index>(1, std::llround((pb.body_max[0] - pb.body_min[0]) / pb.grid.h[0]));
  check_stability(cfg, ts.dt, (pb.body_max[0] - pb.body_min[0]) / static_cast<double>(elements),
                  pb.material, 1.0, 1, "linear elements");
  Ulfem1D fem(pb, elements);
  RunResult res;
  res.benchmark = pb.benchmark;
  res.dim = 1;
  res.cells = elements;
  res.h = (pb.body_max[0] - pb.body_min[0]) / static_cast<double>(elements);
  res.particles = elements;
  Index start = 0;
  if (opt.restart) {
    const io::Checkpoint& c = *opt.restart;
    const std::string what = fmt::format("checkpoint '{}'", opt.restart_name);
    if (c.solver != "ulfem" || !c.fem)
      throw InputError(fmt::format("{} holds a {} run, not a ulfem run", what, c.solver));
    fem.restore(io::unpack_fem(*c.fem, what));
    out.resume(c);
    start = c.step;
  }
  const std::string config_text = cfg.to_toml();
  drive<1>(
      ts, cfg, opt, out, start, [&](Index) { fem.step(ts.dt); }, [] {},
      [&] {
        return StateView<1>{fem.elements(), fem.time(), pb.material};
      },
      [&](Index step) {
        io::Checkpoint c;
        c.config = config_text;
        c.solver = "ulfem";
        c.dim = 1;
        c.step = step;
        c.time = fem.time();
        c.fem = io::pack_fem(fem.save());
        c.frames = out.frames();
        c.frame_times = out.frame_times();
        out.checkpoint(c);
      },
      res);
  if (res.exit_code == exit_code::kOk) {
    // Element midpoints of equal length: no cell of the body is special, so no interior cut.
    Grid<1> element_grid(pb.body_min, pb.body_max, IVec<1>{elements});
    res.errors = error_norms<1>(fem.elements(), element_grid, pb.exact, fem.time(), ts.dt,
                                /*velocity_time=*/-0.5, /*boundary_cells=*/1);
  }
  res.wall_seconds = seconds_since(t_start);
  res.summary =
      make_summary(res, cfg, pb.material, ts, fem.time(),
                   {{"solver", "ulfem"}, {"elements", elements}, {"mass", "lumped"}}, -0.5);
  out.summary(res.summary);
  return res;
}

}  // namespace

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

RunResult run(const Config& cfg, const RunOptions& opt) {
  AnyProblem problem = make_problem(cfg);
  if (cfg.get_string("method.solver") == "ulfem") {
    if (auto* pb = std::get_if<Problem<1>>(&problem)) return run_ulfem(*pb, cfg, opt);
    throw InputError(fmt::format("{}: method.solver = \"ulfem\" is one-dimensional",
                                 cfg.where("method.solver")));
  }
  auto with_key = [&](const char* key, auto&& fn) {
    try {
      return fn();
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}", cfg.where(key), e.what()));
    }
  };
  const auto basis = with_key("method.basis", [&] {
    return choose_basis(cfg.get_string("method.basis"),
                        static_cast<int>(cfg.get_int("method.degree")));
  });
  const auto mapping = with_key("method.mapping", [&] {
    return choose_alternative<MappingKind>(cfg.get_string("method.mapping"), "method.mapping");
  });
  const auto scheme = with_key("method.scheme", [&] {
    return choose_alternative<Scheme>(cfg.get_string("method.scheme"), "method.scheme");
  });
  return std::visit(
      [&](auto& pb) {
        constexpr int Dim = std::decay_t<decltype(pb)>::kDim;
        return run_mpm<Dim>(pb, cfg, opt, basis, mapping, scheme);
      },
      problem);
}

}  // namespace mpm
