#pragma once
// Dual domain MPM (DDMPM, D 2.6.4): the P1 basis with smoothed gradients
//   grad_bar phi_i(x) = alpha(x) grad phi_i(x) + (1 - alpha(x)) grad_tilde phi_i(x),
//   grad_tilde phi_i(x) = sum_j phi_j(x) / V_j  int_Omega phi_j grad phi_i dOmega,
//   V_j = int_Omega phi_j dOmega.
// Values are the P1 values; only gradients change (forces and velocity gradients, D 2.6.4).
//
// The integrals over the material domain Omega (method.ddmpm_integrals; D does not say how they
// are evaluated): "particles" takes the particles as quadrature points (sum_p V_p ...), as in the
// original DDMPM; "quadrature" integrates exactly over the grid cells that hold particles, by
// 2 Gauss-Legendre points per direction (phi_j grad phi_i is of degree 2 at most in each
// direction). Either way they follow the particles and are refreshed every step by prepare().
//
// The weight alpha. D requires only that alpha vanish on the cell boundaries (it is "not
// uniquely specified") and gives it in 1D (D ch. 5):
//   alpha(x) = 2 sum_i phi_i(x) phi_{i+1}(x) = 2 xi (1 - xi),   xi in [0, 1] in the cell.
// D does not give a multi-dimensional alpha; two are derived here (method.ddmpm_weight).
// - "per_direction" (the default): component d of the gradient is blended by
//     alpha_d(x) = 2 xi_d (1 - xi_d),
//   grad_bar_d phi_i = alpha_d d_d phi_i + (1 - alpha_d) d_d tilde phi_i. On the tensor grid the
//   P1 derivative d_d phi_i = N_i'(x_d) prod_{e != d} N_i(x_e) jumps only across the faces normal
//   to d (along the others it is continuous), and alpha_d vanishes exactly there, so grad_bar is
//   continuous, the purpose of D's alpha. It reduces to D's weight in 1D, and a field uniform in
//   y (a y-uniform 2D run, a z-uniform 3D one) has the velocity gradient and the forces of the
//   lower-dimensional run: alpha_x does not depend on y, and the y factor of the smoothed term
//   sums to one over a row of nodes holding particles (partition of unity of the y hats).
// - "product": every component by alpha = prod_d 2 xi_d (1 - xi_d), which vanishes on every
//   face and equals 2 (phi_00 phi_11 + phi_10 phi_01) over the cell's nodes in 2D. It depends on
//   y, so a y-uniform 2D bar develops y-layered stresses (docs/verification.md).
// The smoothed term needs nothing dimension-specific: on the tensor grid phi_j grad phi_i is
// non-zero only for nodes i, j of a common cell, i.e. i - j in {-1, 0, 1}^Dim, so each node j
// stores 3^Dim vectors G_j[i - j] = (1/V_j) int phi_j grad phi_i.
//
// Properties at any x (D 2.5): the values are P1's (partition of unity, linear reproduction).
// sum_i grad_bar phi_i = 0 because sum_i grad phi_i = 0 at every point. Where every node of x's
// cell carries volume, sum_i x_i grad_bar phi_i^T = I, since both integrals keep
// sum_i x_i grad phi_i^T = I, so sum_i x_i G_j[i - j]^T = I for every j with V_j > 0, and either
// weight blends each component d of two gradients that both reproduce e_d.
// Stencil: the nodes c_d - 1 .. c_d + 2 per direction around x's cell c (4^Dim slots); the outer
// ones carry zero value and only the smoothed gradient.
#include <algorithm>
#include <array>
#include <limits>
#include <string_view>
#include <vector>

#include "basis/basis.hpp"
#include "basis/ddmpm_settings.hpp"
#include "basis/gauss_legendre.hpp"
#include "basis/linear.hpp"
#include "core/dof_array.hpp"

namespace mpm {

template <int Dim>
class DdmpmBasis {
  static constexpr int kNeighbours = ipow(3, Dim);  // i - j in {-1, 0, 1}^Dim
  static constexpr int kCellNodes = ipow(2, Dim);

 public:
  static constexpr std::string_view kName = "ddmpm";
  static constexpr int kPerDim = 4;  // nodes c-1 .. c+2 carry smoothed gradients
  // Capabilities (basis/basis.hpp): full stencils at the particle position; prepare() refreshes
  // the node volumes from the particles before each evaluation pass.
  static constexpr bool kTensorProduct = false, kParticleDomain = false, kPrepare = true,
                        kNodalSums = true, kTrackedCorners = false, kIterative = false,
                        kTriangleMesh = false;
  using StencilT = Stencil<Dim, ipow(kPerDim, Dim)>;

  // No node holds a smoothed gradient before the first prepare().
  explicit DdmpmBasis(const Grid<Dim>& g, DdmpmSettings settings = {})
      : p1_(g), n_(p1_.dofs_per_dim()), settings_(settings) {}

  const DdmpmSettings& settings() const { return settings_; }

  const Grid<Dim>& grid() const { return p1_.grid(); }
  IVec<Dim> dofs_per_dim() const { return p1_.dofs_per_dim(); }
  Index num_dofs() const { return p1_.num_dofs(); }
  Vec<Dim> dof_position(Index i) const { return p1_.dof_position(i); }
  std::vector<Index> boundary_dofs(int d, int side) const { return p1_.boundary_dofs(d, side); }

  // G_j[k] = (1/V_j) int phi_j grad phi_i [1/m], node i = j + o with k = sum_d (o_d + 1) 3^d,
  // by the particles (sum_p V_p ...) or by Gauss points over the cells holding particles
  // (settings().integrals). Particles outside the grid are skipped; the time step reports them.
  // G_ and V_ hold the window of the nodes of the particles' cells (DofArray): 3^Dim gradients a
  // node (152 bytes in 2D, 656 in 3D) over the whole grid were more than the step's grid arrays,
  // held by every process of a distributed run and zeroed every step; a node outside has no
  // particle near it, so its G_j is zero (evaluate_point).
  void prepare(const Particles<Dim>& P) {
    // The window from P1's compact stencils (the first node and the 1D factors, no products).
    IVec<Dim> stride;
    stride[0] = 1;
    for (int d = 1; d < Dim; ++d) stride[d] = stride[d - 1] * n_[d - 1];
    typename LinearBasis<Dim>::CachedStencilT cell;
    Index lo = std::numeric_limits<Index>::max(), hi = -1;
    for (Index p = 0; p < P.size(); ++p) {
      if (!grid().inside(P.x[static_cast<std::size_t>(p)])) continue;
      p1_.evaluate(P, p, cell);
      const auto [a, b] = dof_bounds(cell, stride);
      lo = std::min(lo, a);
      hi = std::max(hi, b);
    }
    Neighbours zero;
    zero.fill(Vec<Dim>::Zero());
    const Index count = hi >= lo ? hi - lo + 1 : 0;
    G_.assign(count > 0 ? lo : 0, count, zero);
    V_.assign(count > 0 ? lo : 0, count, 0.0);
    typename LinearBasis<Dim>::StencilT s;
    if (settings_.integrals == DdmpmIntegrals::particles) {
      for (Index p = 0; p < P.size(); ++p) {
        const auto i = static_cast<std::size_t>(p);
        if (!grid().inside(P.x[i])) continue;
        p1_.evaluate(P, p, s);
        add_point(s, P.volume[i]);
      }
    } else {
      // The cells holding particles, each once, in index order (the sums' order).
      const Grid<Dim>& g = grid();
      std::vector<Index> cells;
      cells.reserve(static_cast<std::size_t>(P.size()));
      for (const Vec<Dim>& x : P.x)
        if (g.inside(x)) cells.push_back(g.cell_index(x));
      std::sort(cells.begin(), cells.end());
      cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
      // 2 Gauss-Legendre points per direction moved from [-1, 1] to [0, 1]: exact to degree 3.
      const GaussRule rule = gauss_legendre(2);
      double cell_volume = 1.0;
      for (int d = 0; d < Dim; ++d) cell_volume *= g.h[d];
      for (const Index c : cells) {
        const IVec<Dim> cx = g.cell_coords(c);
        for (int q = 0; q < ipow(2, Dim); ++q) {
          Vec<Dim> x;
          double w = cell_volume;
          for (int d = 0; d < Dim; ++d) {
            const auto j = static_cast<std::size_t>((q >> d) & 1);
            x[d] = g.origin[d] + (static_cast<double>(cx[d]) + 0.5 * (rule.xi[j] + 1.0)) * g.h[d];
            w *= 0.5 * rule.w[j];
          }
          p1_.evaluate_point(x, s);
          add_point(s, w);
        }
      }
    }
    for (Index j = G_.first(); j < G_.stop(); ++j)
      for (auto& g : G_[j]) g = V_[j] > 0.0 ? Vec<Dim>(g / V_[j]) : Vec<Dim>::Zero();
  }

  // Values of P1 at x_p; gradients smoothed.
  void evaluate(const Particles<Dim>& P, Index p, StencilT& s) const {
    evaluate_point(P.x[static_cast<std::size_t>(p)], s);
  }

  // The DDMPM basis at any point of the grid: quadrature points of the reconstruction mappings
  // (DDMPM-TLS, D 5.3) need the smoothed gradients there too.
  void evaluate_point(const Vec<Dim>& x, StencilT& s) const {
    typename LinearBasis<Dim>::StencilT q;
    p1_.evaluate_point(x, q);
    // Cell and local coordinate as LinearBasis computes them, for the window and alpha.
    const Grid<Dim>& g = grid();
    IVec<Dim> c;
    Vec<Dim> alpha;  // the weight of each gradient component (settings().weight)
    for (int d = 0; d < Dim; ++d) {
      const double s_d = (x[d] - g.origin[d]) / g.h[d];
      c[static_cast<std::size_t>(d)] = g.cell_of(x[d], d);
      const double xi = s_d - static_cast<double>(c[static_cast<std::size_t>(d)]);
      alpha[d] = 2.0 * (1.0 - xi) * xi;  // 1D: 2 phi_c phi_{c+1} (D ch. 5)
    }
    if (settings_.weight == DdmpmWeight::product) {
      double product = 1.0;
      for (int d = 0; d < Dim; ++d) product *= alpha[d];
      alpha.setConstant(product);
    }
    for (int k = 0; k < StencilT::kSize; ++k) {
      // Node of slot k: c_d - 1 + k_d; P1 slot (c_d + a_d) when every k_d is 1 or 2.
      IVec<Dim> node;
      Index dof = 0, stride = 1;
      int rem = k, a = 0, astride = 1;
      bool inside = true, in_cell = true;
      for (int d = 0; d < Dim; ++d) {
        const auto e = static_cast<std::size_t>(d);
        const int kd = rem % kPerDim;
        rem /= kPerDim;
        node[e] = c[e] - 1 + kd;
        inside = inside && node[e] >= 0 && node[e] < n_[e];
        in_cell = in_cell && (kd == 1 || kd == 2);
        a += (kd - 1) * astride;
        astride *= 2;
        dof += std::clamp<Index>(node[e], 0, n_[e] - 1) * stride;
        stride *= n_[e];
      }
      const auto ku = static_cast<std::size_t>(k);
      s.dof[ku] = dof;
      s.w[ku] = in_cell ? q.w[static_cast<std::size_t>(a)] : 0.0;
      Vec<Dim> smooth = Vec<Dim>::Zero();  // grad_tilde phi_node at x
      for (int b = 0; b < kCellNodes; ++b) {
        // Cell node j = c + bits of b; offset node - j must lie in {-1, 0, 1}^Dim.
        int off = 0, ostride = 1;
        bool near = true;
        for (int d = 0; d < Dim; ++d) {
          const auto e = static_cast<std::size_t>(d);
          const Index o = node[e] - (c[e] + ((b >> d) & 1));
          near = near && o >= -1 && o <= 1;
          off += static_cast<int>(o + 1) * ostride;
          ostride *= 3;
        }
        const Index j = q.dof[static_cast<std::size_t>(b)];
        if (near && inside && G_.holds(j))
          smooth += q.w[static_cast<std::size_t>(b)] * G_[j][static_cast<std::size_t>(off)];
      }
      const Vec<Dim> plain = in_cell ? q.grad[static_cast<std::size_t>(a)] : Vec<Dim>::Zero();
      for (int d = 0; d < Dim; ++d)
        s.grad[ku][d] = inside ? alpha[d] * plain[d] + (1.0 - alpha[d]) * smooth[d] : 0.0;
    }
  }

 private:
  using Neighbours = std::array<Vec<Dim>, kNeighbours>;

  // One quadrature point (a particle, or a Gauss point of weight V) of the integrals, with the
  // P1 stencil s there.
  void add_point(const typename LinearBasis<Dim>::StencilT& s, double V) {
    // P1 slot a is node first + bits of a (tensor_product), so node b - node a = bits b - a.
    for (int a = 0; a < kCellNodes; ++a) {
      const auto j = static_cast<std::size_t>(s.dof[static_cast<std::size_t>(a)]);
      const double Vw = V * s.w[static_cast<std::size_t>(a)];
      V_[j] += Vw;
      for (int b = 0; b < kCellNodes; ++b) {
        int k = 0, stride = 1;
        for (int d = 0; d < Dim; ++d) {
          k += (((b >> d) & 1) - ((a >> d) & 1) + 1) * stride;
          stride *= 3;
        }
        G_[j][static_cast<std::size_t>(k)] += Vw * s.grad[static_cast<std::size_t>(b)];
      }
    }
  }

  LinearBasis<Dim> p1_;
  IVec<Dim> n_;
  DofArray<Neighbours> G_;  // per node j: (1/V_j) int phi_j grad phi_{j+o}, o in {-1,0,1}^Dim
  DofArray<double> V_;      // V_j [m^Dim], scratch of prepare()
  DdmpmSettings settings_;
};

// The basis concept (basis/basis.hpp).
static_assert(Basis<DdmpmBasis<1>, 1> && Basis<DdmpmBasis<2>, 2>);

}  // namespace mpm
