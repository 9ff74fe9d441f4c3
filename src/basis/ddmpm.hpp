#pragma once
// Dual domain MPM (DDMPM, D 2.6.4): the P1 basis with smoothed gradients
//   grad_bar phi_i(x) = alpha(x) grad phi_i(x) + (1 - alpha(x)) grad_tilde phi_i(x),
//   grad_tilde phi_i(x) = sum_j phi_j(x) / V_j  int_Omega phi_j grad phi_i dOmega,
//   V_j = int_Omega phi_j dOmega,   alpha(x) = 2 sum_i phi_i(x) phi_{i+1}(x)   (1D, D ch. 5).
// The integrals run over the material domain and are evaluated with the particles as
// quadrature points (sum_p V_p ...), as in the original DDMPM, so they are refreshed every
// step by prepare(). Values are the P1 values; only gradients change (forces and velocity
// gradients, D 2.6.4). One-dimensional, as the weight alpha is specified only in 1D.
#include <array>
#include <string_view>
#include <vector>

#include "basis/linear.hpp"

namespace mpm {

template <int Dim>
class DdmpmBasis {
  static_assert(Dim == 1, "DDMPM is specified in one dimension (D 2.6.4, ch. 5)");

 public:
  static constexpr std::string_view kName = "ddmpm";
  static constexpr int kPerDim = 4;  // nodes c-1 .. c+2 carry smoothed gradients
  using StencilT = Stencil<Dim, 4>;

  explicit DdmpmBasis(const Grid<Dim>& g) : p1_(g), n_(g.cells[0] + 1) {
    G_.assign(static_cast<std::size_t>(n_), {0.0, 0.0, 0.0});
  }

  const Grid<Dim>& grid() const { return p1_.grid(); }
  IVec<Dim> dofs_per_dim() const { return p1_.dofs_per_dim(); }
  Index num_dofs() const { return p1_.num_dofs(); }
  Vec<Dim> dof_position(Index i) const { return p1_.dof_position(i); }
  std::vector<Index> boundary_dofs(int d, int side) const { return p1_.boundary_dofs(d, side); }

  // G_j[k] = (1/V_j) sum_p V_p phi_j(x_p) dphi_{j-1+k}/dx(x_p), k = 0, 1, 2 [1/m].
  // Particles outside the grid are skipped; the time step reports them.
  void prepare(const Particles<Dim>& P) {
    std::vector<double> V(static_cast<std::size_t>(n_), 0.0);
    for (auto& g : G_) g = {0.0, 0.0, 0.0};
    typename LinearBasis<Dim>::StencilT s;
    for (Index p = 0; p < P.size(); ++p) {
      const auto i = static_cast<std::size_t>(p);
      if (!grid().inside(P.x[i])) continue;
      p1_.evaluate(P, p, s);
      const double Vp = P.volume[i];
      for (int a = 0; a < 2; ++a) {
        const Index j = s.dof[a];
        V[static_cast<std::size_t>(j)] += Vp * s.w[a];
        for (int b = 0; b < 2; ++b) {
          const Index k = s.dof[b] - j + 1;  // 0, 1 or 2
          G_[static_cast<std::size_t>(j)][static_cast<std::size_t>(k)] +=
              Vp * s.w[a] * s.grad[b][0];
        }
      }
    }
    for (std::size_t j = 0; j < G_.size(); ++j)
      for (double& g : G_[j]) g = V[j] > 0.0 ? g / V[j] : 0.0;
  }

  // Values of P1 at x_p; gradients smoothed. Slots 0 and 3 (nodes c-1, c+2) have zero weight.
  void evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
    evaluate_point(P.x[static_cast<std::size_t>(p)], s);
  }

  // The DDMPM basis at any point of the grid: quadrature points of the reconstruction mappings
  // (DDMPM-TLS, D 5.3) need the smoothed gradients there too.
  void evaluate_point(const Vec<Dim>& x, StencilT& s) const {
    typename LinearBasis<Dim>::StencilT q;
    p1_.evaluate_point(x, q);
    const Index c = q.dof[0];
    const double alpha = 2.0 * q.w[0] * q.w[1];
    for (int k = 0; k < 4; ++k) {
      const Index node = c - 1 + k;
      s.dof[k] = std::clamp<Index>(node, 0, n_ - 1);
      s.w[k] = (k == 1 || k == 2) ? q.w[k - 1] : 0.0;
      double smooth = 0.0;  // grad_tilde phi_node at x
      for (int a = 0; a < 2; ++a) {
        const Index j = c + a;
        const Index off = node - j + 1;
        if (off >= 0 && off <= 2 && node >= 0 && node < n_)
          smooth += q.w[a] * G_[static_cast<std::size_t>(j)][static_cast<std::size_t>(off)];
      }
      const double plain = (k == 1 || k == 2) ? q.grad[k - 1][0] : 0.0;
      s.grad[k][0] = (node >= 0 && node < n_) ? alpha * plain + (1.0 - alpha) * smooth : 0.0;
    }
  }

 private:
  LinearBasis<Dim> p1_;
  Index n_;
  std::vector<std::array<double, 3>> G_;
};

}  // namespace mpm
