#pragma once
// Local maximum-entropy (max-ent) basis on the nodes of a uniform grid (D 4.3, eq. 4.36-4.51;
// Arroyo and Ortiz 2006): at a point x, phi_i(x) = w_i(x) exp(-lambda . (x_i - x)) / Z, with
// the cubic-spline prior w_i of D eq. 4.48 on the support radius d_i = d_max zeta_i (eq. 4.46,
// 4.47; zeta_i, the distance from node i to its nearest neighbour, is the smallest cell size on
// a uniform grid), and lambda the minimiser of ln Z (eq. 4.42), found by a safeguarded Newton
// method (maxent.cpp). The functions are non-negative, a partition of unity, reproduce affine
// functions, and interpolate at the nodes of the grid's boundary (weak Kronecker-delta property,
// D eq. 4.52).
//
// Neighbours come from the cell structure: the nodes of a window of kWindow = 6 nodes per
// direction around the point's cell hold every node closer than 3 zeta, so d_max is at most 3
// (D uses 2 in 1D and 3 on the plate). The stencil is the whole window (6^Dim entries, zero
// where the prior vanishes).
//
// A point where Newton does not converge is recorded (the point, the particle id when there is
// one, the nodes, the iterations and the last residual), its weights are NaN, and the stage
// that evaluated it calls throw_if_failed(step, time, where), which stops the run with exit code 10
// (capability kIterative, basis/basis.hpp): never a silent result.
#include <array>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "basis/basis.hpp"
#include "basis/maxent_settings.hpp"
#include "basis/stencil.hpp"
#include "grid/grid.hpp"
#include "particles/particles.hpp"

namespace mpm {

// The outcome of one point's Newton iteration.
struct MaxEntStatus {
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;  // |sum_i phi_i (x_i - x)| / zeta at the last iterate
};

// The max-ent functions at one point from the n nodes of nonzero prior: y[i] = (x_i - x) / zeta,
// w[i] = w_i(x) > 0 and dw[i] = zeta grad w_i(x) (the prior and its gradient in units of zeta).
// Writes phi[i] and zeta grad phi_i (D eq. 4.43, with the signs derived in maxent.cpp) when
// `grad` is not null. `fixed[d]`: x lies on the boundary of the nodes' convex hull normal to d
// (all y[i][d] of one sign); the caller has kept only the nodes with y[i][d] = 0, and lambda_d
// is not solved for (weak Kronecker-delta property). Compiled once per dimension (maxent.cpp).
template <int Dim>
MaxEntStatus maxent_solve(int n, const Vec<Dim>* y, const double* w, const Vec<Dim>* dw,
                          const std::array<bool, Dim>& fixed, const MaxEntSettings& s, double* phi,
                          Vec<Dim>* grad);

// The cubic-spline prior of D eq. 4.48 at r = |x - x_i| / d_i, and dw/dr. (D's eq. 4.49 has
// -12 r^2 in its second branch; the derivative of 4/3 - 4r + 4r^2 - 4/3 r^3 is -4 + 8r - 4r^2.)
double maxent_prior(double r);
double maxent_prior_slope(double r);

template <int Dim>
class MaxEntBasis {
 public:
  static constexpr std::string_view kName = "maxent";
  static constexpr int kWindow = 6;  // nodes per direction around the point's cell
  // Capabilities (basis/basis.hpp): full stencils evaluated from the particle position (no
  // tensor-product form), no particle domain, no preparation pass, no per-particle state; the
  // evaluation is iterative and can fail (throw_if_failed).
  static constexpr bool kTensorProduct = false, kParticleDomain = false, kPrepare = false,
                        kNodalSums = false, kTrackedCorners = false, kIterative = true,
                        kTriangleMesh = false;
  using StencilT = Stencil<Dim, ipow(kWindow, Dim)>;

  // InputError when the grid has fewer than kWindow - 1 cells in some direction or d_max is
  // outside (1, 3].
  MaxEntBasis(const Grid<Dim>& g, const MaxEntSettings& s);
  MaxEntBasis(const MaxEntBasis& o) : MaxEntBasis(o.grid_, o.settings_) {}
  MaxEntBasis& operator=(const MaxEntBasis& o) {
    if (this != &o) *this = MaxEntBasis(o);
    return *this;
  }
  MaxEntBasis(MaxEntBasis&&) noexcept = default;
  MaxEntBasis& operator=(MaxEntBasis&&) noexcept = default;

  const Grid<Dim>& grid() const { return grid_; }
  const MaxEntSettings& settings() const { return settings_; }
  double zeta() const { return zeta_; }
  IVec<Dim> dofs_per_dim() const { return n_; }
  Index num_dofs() const { return dof_count<Dim>(n_); }
  Vec<Dim> dof_position(Index i) const { return node_position<Dim>(grid_.origin, grid_.h, n_, i); }
  // The nodes on a side of the grid: the weak Kronecker-delta property makes the basis
  // interpolatory there, so a Dirichlet condition prescribes them as for P1.
  std::vector<Index> boundary_dofs(int d, int side) const { return side_dofs<Dim>(n_, d, side); }

  // Requires grid().inside(x). On failure: NaN weights, recorded for throw_if_failed().
  void evaluate(const Particles<Dim>& P, Index p, StencilT& s) const;
  void evaluate_point(const Vec<Dim>& x, StencilT& s) const;

  // Throws RunError (exit code 10) describing the first failed point (the lowest particle index,
  // else the first point in coordinate order) and how many failed since the last call; `where`
  // names the evaluation ("particles", "Gauss points", "traction faces"), step and time the
  // moment (step < 0: before the run). Resets the record.
  void throw_if_failed(Index step, double time, std::string_view where) const;

 private:
  struct Failure {
    Vec<Dim> x;
    Index particle = -1;  // index into the particles (-1: not a particle)
    Index id = -1;        // its stable id
    MaxEntStatus status;
    int nodes = 0;
  };
  struct FailureLog {
    std::mutex mutex;
    Index count = 0;
    bool any = false;
    Failure first;
  };

  // The window of x, the priors, the solve; false when Newton did not converge (weights NaN).
  bool compute(const Vec<Dim>& x, StencilT& s, MaxEntStatus& status, int& nodes) const;
  void record(const Vec<Dim>& x, Index particle, Index id, const MaxEntStatus& status,
              int nodes) const;

  Grid<Dim> grid_;
  MaxEntSettings settings_;
  IVec<Dim> n_{}, stride_{};
  double zeta_ = 1.0;
  std::unique_ptr<FailureLog> failures_ = std::make_unique<FailureLog>();
};

static_assert(Basis<MaxEntBasis<1>, 1> && Basis<MaxEntBasis<2>, 2>);

}  // namespace mpm
