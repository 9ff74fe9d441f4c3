#include "driver/stepper.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <utility>

#include "basis/bspline.hpp"
#include "mapping/quadrature.hpp"

namespace mpm::driver {

// The generated units (CMakeLists.txt) instantiate make_stepper_for<Dim, I> for I below this.
static_assert(std::variant_size_v<BasisKind> == MPM_BASIS_KINDS,
              "CMakeLists.txt generates one stepper unit per BasisKind alternative: update "
              "MPM_BASIS_KINDS there");

template <int Dim>
std::unique_ptr<Stepper<Dim>> make_stepper(const BasisKind& basis, const StepperInput<Dim>& in) {
  return [&]<std::size_t... I>(std::index_sequence<I...>) {
    std::unique_ptr<Stepper<Dim>> s;
    ((basis.index() == I ? (s = make_stepper_for<Dim, I>(in), true) : false) || ...);
    return s;
  }
  (std::make_index_sequence<std::variant_size_v<BasisKind>>{});
}

template std::unique_ptr<Stepper<1>> make_stepper<1>(const BasisKind&, const StepperInput<1>&);
template std::unique_ptr<Stepper<2>> make_stepper<2>(const BasisKind&, const StepperInput<2>&);

namespace {

// Explicit stability (Euler-Cromer, lumped mass): dt <= 2 / omega_max, omega_max^2 bounded by
// Gershgorin's theorem on M_L^-1 K of a uniform 1D bar (E = rho = h = 1), so
// dt_crit = factor h / c. P1: factor 1 exactly (h / c). B-splines of degree p: computed from
// exact Gauss integrals of their stiffness and lumped mass over a grid of 4p + 4 cells (the
// small end functions of the open knot vector set the bound). GIMP, CPDI and DDMPM use the P1
// bound (their gradients are averages of P1's).
template <int P>
double bspline_stability_factor() {
  const Index n = 4 * P + 4;
  const Grid<1> g(Vec<1>(0.0), Vec<1>(static_cast<double>(n)), IVec<1>{n});
  const BSplineBasis<1, P> basis(g);
  const auto nd = static_cast<std::size_t>(basis.num_dofs());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(static_cast<Index>(nd), static_cast<Index>(nd));
  Eigen::VectorXd m = Eigen::VectorXd::Zero(static_cast<Index>(nd));
  const GaussRule rule = gauss_legendre(P + 1);
  typename BSplineBasis<1, P>::StencilT st;
  for (Index c = 0; c < n; ++c)
    for (std::size_t k = 0; k < rule.xi.size(); ++k) {
      basis.evaluate_point(Vec<1>(static_cast<double>(c) + 0.5 + 0.5 * rule.xi[k]), st);
      const double w = 0.5 * rule.w[k];
      for (int a = 0; a < st.kSize; ++a) {
        m[st.dof[a]] += w * st.w[a];
        for (int b = 0; b < st.kSize; ++b)
          K(st.dof[a], st.dof[b]) += w * st.grad[a][0] * st.grad[b][0];
      }
    }
  double omega2 = 0.0;
  for (Index i = 0; i < K.rows(); ++i) omega2 = std::max(omega2, K.row(i).cwiseAbs().sum() / m[i]);
  return 2.0 / std::sqrt(omega2);
}

}  // namespace

void report_mapping(nlohmann::ordered_json& summary, const TlsMapping& m, int) {
  const auto& t = m.totals();
  summary["tls"] = {{"element_fits", t.active},
                    {"full", t.full},
                    {"reduced", t.reduced},
                    {"with_virtual", t.with_virtual},
                    {"with_neighbours", t.with_neighbours},
                    {"min_terms", t.min_terms},
                    {"max_condition", t.max_condition}};
}

namespace {
template <class Mapping>
void report_mls(nlohmann::ordered_json& summary, const Mapping& m, int dim) {
  const auto& t = m.totals();
  summary["mls"] = {{"degree", m.settings().degree},
                    {"dilation", m.settings().dilation},
                    {"evaluations", t.points},
                    {"empty_support", t.empty},
                    {"ill_conditioned", t.ill_conditioned},
                    {"singular", t.singular},
                    {"reduced", t.reduced},
                    {"widened", t.widened},
                    {"max_condition", t.max_condition},
                    {"worst_x", t.worst_x}};
  if (dim == 2) summary["mls"]["worst_y"] = t.worst_y;
}
}  // namespace

void report_mapping(nlohmann::ordered_json& summary, const MlsMapping& m, int dim) {
  report_mls(summary, m, dim);
}
void report_mapping(nlohmann::ordered_json& summary, const ImlsMapping& m, int dim) {
  report_mls(summary, m, dim);
}

double stability_factor(const BasisKind& basis) {
  return std::visit(
      [](auto k) {
        if constexpr (decltype(k)::kDegree > 0)
          return bspline_stability_factor<decltype(k)::kDegree>();
        else
          return 1.0;
      },
      basis);
}

// One cell for nodal bases, p cells for B-splines of degree p, whose asymmetric end functions
// phi_0 .. phi_{p-1} of the open knot vector reach p cells into the domain (D Fig. 5.10).
int boundary_cells(const BasisKind& basis) {
  const int p = basis_degree(basis);
  return p > 0 ? p : 1;
}

std::string_view basis_name(const BasisKind& basis) {
  return std::visit([](auto k) { return decltype(k)::kName; }, basis);
}

int basis_degree(const BasisKind& basis) {
  return std::visit([](auto k) { return decltype(k)::kDegree; }, basis);
}

}  // namespace mpm::driver
