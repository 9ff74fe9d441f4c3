// The OTM solver (methods/otm.hpp) behind the driver's Stepper interface: the time loop, outputs,
// error norms, summary and checkpoints are those of every MPM run (driver/run_mpm.cpp).
#include <fmt/format.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <type_traits>
#include <variant>
#include <vector>

#include "basis/powell_sabin.hpp"
#include "driver/sparse_mass.hpp"
#include "driver/stepper.hpp"
#include "io/checkpoint.hpp"
#include "methods/otm.hpp"

namespace mpm::driver {
namespace {

template <int Dim>
class OtmStepper final : public Stepper<Dim> {
 public:
  OtmStepper(Problem<Dim>& pb, const OtmSettings& s) : otm_(pb, s) {}
  const Otm<Dim>& otm() const { return otm_; }
  void step(double dt) override { otm_.step(dt); }
  bool sort_if_due() override { return false; }  // the particles' order never changes
  RunState<Dim>& state() override { return otm_.state(); }
  const RunState<Dim>& state() const override { return otm_.state(); }
  // The advected node positions (the particles, with v_p = (x_p^s - x_p^{s-1}) / dt, are in
  // the RunState part of the checkpoint).
  void save(io::Checkpoint& c) const override { c.basis_state = otm_.nodes(); }
  void load(const io::Checkpoint& c, const std::string& what) override {
    otm_.set_nodes(c.basis_state, what);
  }
  // OTM runs on one process (MpmRun refuses it on several), and its particles never move
  // between processes.
  void export_carried() override {}
  void resize_particle_caches() override {}
  std::vector<Vec<Dim>> dof_positions() const override {
    const std::vector<double>& flat = otm_.nodes();
    std::vector<Vec<Dim>> x(flat.size() / Dim);
    for (std::size_t i = 0; i < x.size(); ++i)
      for (int d = 0; d < Dim; ++d) x[i][d] = flat[Dim * i + static_cast<std::size_t>(d)];
    return x;
  }
  void report(nlohmann::ordered_json& summary) const override {
    const auto& x = otm_.nodes();
    const OtmSettings& s = otm_.settings();
    summary["otm"] = {{"algorithm", s.unified ? "unified (D Algorithm 4)" : "OTM (D Algorithm 3)"},
                      {"nodes", x.size() / Dim},
                      {"basis", s.basis == OtmBasis::Linear        ? "linear"
                                : s.basis == OtmBasis::MaxEnt      ? "maxent"
                                : s.basis == OtmBasis::PowellSabin ? "powell_sabin"
                                                                   : "bspline"},
                      {"first_node", std::vector<double>(x.begin(), x.begin() + Dim)},
                      {"last_node", std::vector<double>(x.end() - Dim, x.end())}};
    if (s.basis == OtmBasis::BSpline) summary["otm"]["degree"] = s.degree;
    if (otm_.settings().basis == OtmBasis::MaxEnt)
      summary["otm"]["maxent_dmax"] = otm_.settings().maxent.dmax;
  }

 private:
  Otm<Dim> otm_;
};

}  // namespace

template <int Dim>
std::unique_ptr<Stepper<Dim>> make_otm_stepper(const StepperInput<Dim>& in) {
  {
    const MethodSettings& m = in.method;
    OtmSettings s;
    s.unified = m.solver == Solver::Unified;
    // The basis on the advected nodes, as its kind declares it (methods/kinds.hpp); run_settings
    // has refused the kinds that are neither OTM's nor the unified approach's.
    std::visit(
        [&](const auto& k) {
          using K = std::decay_t<decltype(k)>;
          if constexpr (K::kOtmNodes || K::kUnified)
            if (s.unified ? K::kUnified : K::kOtmNodes) {
              k.configure_otm(s, in.problem.mesh);
              return;
            }
          throw std::logic_error(
              fmt::format("make_otm_stepper: basis \"{}\" for this solver", K::kName));
        },
        m.basis);
    s.mass = m.mass;
    s.mass_tolerance = m.mass_tolerance;
    s.mass_solver = m.mass_solver;
    s.conservation_limit = m.conservation_limit;
    auto stepper = std::make_unique<OtmStepper<Dim>>(in.problem, s);
    // The material points are the quadrature of the unified PS mass matrix as they are of
    // PS-MPM's, with the same need of particles per triangle (a free plate with 4.5 per triangle
    // and consistent mass inverts within five steps under a face load; 8 run).
    if constexpr (Dim == 2)
      if (const auto* ps = stepper->otm().powell_sabin())
        warn_sparse_consistent_mass<2>(m, *ps, stepper->state().particles, nullptr,
                                       in.problem.warnings);
    return stepper;
  }
}

template std::unique_ptr<Stepper<1>> make_otm_stepper<1>(const StepperInput<1>&);
template std::unique_ptr<Stepper<2>> make_otm_stepper<2>(const StepperInput<2>&);

}  // namespace mpm::driver
