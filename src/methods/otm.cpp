// OTM and the unified approach, 1D and 2D (methods/otm.hpp; D Algorithms 3 and 4).
#include "methods/otm.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <type_traits>
#include <variant>

#include "basis/bspline.hpp"
#include "basis/maxent.hpp"
#include "basis/powell_sabin.hpp"
#include "scheme/stages.hpp"

namespace mpm {

namespace {
// fn(flat index) for the 3^Dim cells of a lattice of n cells per direction (x fastest) around
// cell c, c included, those outside the lattice left out; in the order of the offsets (-1, 0, 1)
// with x fastest (the order fixes the rounding of what fn sums).
template <int Dim, class Fn>
void for_each_neighbour(const IVec<Dim>& c, const IVec<Dim>& n, Fn&& fn) {
  for (int k = 0; k < ipow(3, Dim); ++k) {
    Index flat = 0, stride = 1;
    int kk = k;
    bool inside = true;
    for (int d = 0; d < Dim; ++d) {
      const Index cd = c[d] + kk % 3 - 1;
      kk /= 3;
      inside = inside && cd >= 0 && cd < n[d];
      flat += cd * stride;
      stride *= n[d];
    }
    if (inside) fn(flat);
  }
}
}  // namespace

template <int Dim>
Otm<Dim>::Otm(Problem<Dim>& pb, const OtmSettings& s)
    : st_(pb.grid, std::move(pb.particles), pb.materials), s_(s) {
  const char* solver = s.unified ? "unified" : "otm";
  // OTM-P1 in 2D: the bilinear functions of the advected quadrilaterals, i.e. the unified
  // approach's isoparametric map with degree 1 (a particle keeps its material coordinate, as
  // OTM-P1 keeps its local coordinate in 1D), with OTM's particle velocity. OTM-maxent in 2D:
  // max-ent on the advected lattice of nodes, found through bins of the current positions.
  const bool ps = s.basis == OtmBasis::PowellSabin;
  iso_ = s.unified || (Dim > 1 && s.basis == OtmBasis::Linear);
  degree_ = s.unified && !ps ? s.degree : 1;
  if (ps && !(s.unified && Dim == 2))
    throw InputError(
        "Powell-Sabin splines on advected degrees of freedom: method.solver = "
        "\"unified\", 2D");
  if (s.mesh && !ps)
    throw InputError(
        fmt::format("method.solver = \"{}\": grid.mesh needs method.basis = "
                    "\"powell_sabin\" (the mesh is the body's triangulation)",
                    solver));
  // The nodes discretise the body only (D 4.4: OTM has no empty elements): the grid's nodes
  // from the body's first to its last per direction, which must be nodes of the grid. A mesh
  // file (grid.mesh) is the body itself, so every grid side is a side of it.
  const Grid<Dim>& g = st_.grid;
  IVec<Dim> cells = g.cells;
  Vec<Dim> lo = g.origin, hi = g.upper();
  std::array<std::array<bool, 2>, Dim> touches{};
  if (s.mesh)
    for (auto& t : touches) t = {true, true};
  for (int d = 0; d < Dim && !s.mesh; ++d) {
    const double h = g.h[d], b0 = pb.body_min[d], b1 = pb.body_max[d];
    const double i0 = (b0 - g.origin[d]) / h, i1 = (b1 - g.origin[d]) / h;
    if (std::abs(i0 - std::round(i0)) > 1e-9 || std::abs(i1 - std::round(i1)) > 1e-9)
      throw InputError(fmt::format(
          "method.solver = \"{}\": the nodes are carried by the material and discretise the "
          "body only, so its ends [{}, {}] must be grid nodes (grid [{}, {}], cell size {}, "
          "direction {})",
          solver, b0, b1, g.origin[d], g.upper()[d], h, "xyz"[d]));
    cells[d] = static_cast<Index>(std::llround(i1) - std::llround(i0));
    lo[d] = g.origin[d] + h * std::round(i0);
    hi[d] = g.origin[d] + h * std::round(i1);
    touches[static_cast<std::size_t>(d)] = {std::abs(b0 - g.origin[d]) <= 1e-9 * h,
                                            std::abs(b1 - g.upper()[d]) <= 1e-9 * h};
  }
  body_ = Grid<Dim>(lo, hi, cells);
  if (s.basis == OtmBasis::MaxEnt && !(s.maxent.dmax > 1.0 && s.maxent.dmax <= 3.0))
    throw InputError(fmt::format("method.maxent_dmax = {}: must be in (1, 3]", s.maxent.dmax));
  if (s.unified && !ps && !(s.basis == OtmBasis::BSpline && s.degree >= 1 && s.degree <= 5))
    throw InputError(
        "method.solver = \"unified\": B-splines of degree 1 to 5 or Powell-Sabin "
        "splines");
  // In 2D the face points need the functions at material points: the isoparametric maps only.
  if (Dim != 1 && !pb.tractions.empty() && !iso_)
    throw InputError(fmt::format(
        "method.solver = \"{}\": tractions in 2D act through the isoparametric map of the "
        "unified approach and of OTM-P1; OTM-maxent in 2D has none",
        solver));
  for (const auto& tr : pb.tractions)
    if (Dim != 1 && tr.offset.size() != tr.particles.size())
      throw InputError(
          fmt::format("method.solver = \"{}\": a traction whose points have no place on "
                      "the face (offsets) cannot act through the map in 2D",
                      solver));
  // The nodes (unified: the B-spline control points at their Greville abscissae, so that
  // x(X) = X at the start) and, per grid side the body touches, the Dirichlet conditions: a
  // condition on a side the body does not touch constrains no material node.
  std::vector<std::vector<Index>> side_nodes(2 * Dim);
  Index n = 0;
  if (ps) {
    if constexpr (Dim == 2) {
      ps_ = std::make_shared<const PowellSabinGridBasis<2>>(
          s.mesh ? PowellSabinGridBasis<2>(s.mesh) : PowellSabinGridBasis<2>(body_, s.triangles));
      n = ps_->num_dofs();
      x_.resize(static_cast<std::size_t>(n * Dim));
      for (Index i = 0; i < n; ++i)  // Q_ij: x(X) = X
        for (int d = 0; d < Dim; ++d)
          x_[static_cast<std::size_t>(i * Dim + d)] = ps_->dof_position(i)[d];
      for (int d = 0; d < Dim; ++d)
        for (int side = 0; side < 2; ++side)
          if (touches[static_cast<std::size_t>(d)][static_cast<std::size_t>(side)])
            side_nodes[static_cast<std::size_t>(2 * d + side)] = ps_->boundary_dofs(d, side);
    }
  } else if (iso_ || Dim > 1) {  // (2D max-ent: the nodes of degree 1, the lattice x fastest)
    with_bspline_degree(degree_, [&](auto degree) {
      const BSplineBasis<Dim, decltype(degree)::value> basis(body_);
      n = basis.num_dofs();
      x_.resize(static_cast<std::size_t>(n * Dim));
      for (Index i = 0; i < n; ++i)
        for (int d = 0; d < Dim; ++d)
          x_[static_cast<std::size_t>(i * Dim + d)] = basis.dof_position(i)[d];
      for (int d = 0; d < Dim; ++d)
        for (int side = 0; side < 2; ++side)
          side_nodes[static_cast<std::size_t>(2 * d + side)] = basis.boundary_dofs(d, side);
    });
  } else {
    n = cells[0] + 1;
    x_.resize(static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i)
      x_[static_cast<std::size_t>(i)] = lo[0] + g.h[0] * static_cast<double>(i);
    side_nodes[0] = {0};
    side_nodes[1] = {n - 1};
  }
  st_.nodes.resize(n);
  for (const auto& f : pb.fixed_sides) {
    if (f.normal != std::array<double, 3>{} || !f.vertex_normals.empty())
      throw InputError(fmt::format(
          "method.solver = \"{}\": a roller on an inclined or bent boundary (\"{}\") is not "
          "implemented; the conditions fix velocity components on straight axis-aligned sides",
          solver, f.boundary));
    const auto mask = static_cast<std::uint8_t>(f.components & ((1u << Dim) - 1u));
    if (!f.boundary.empty()) {  // a named boundary of the mesh (unified PS, grid.mesh)
      if constexpr (Dim == 2)
        for (Index i : ps_->boundary_dofs(f.boundary))
          st_.nodes.fixed[static_cast<std::size_t>(i)] |= mask;
      continue;
    }
    if (!touches[static_cast<std::size_t>(f.direction)][static_cast<std::size_t>(f.side)]) continue;
    for (Index i : side_nodes[static_cast<std::size_t>(2 * f.direction + f.side)])
      st_.nodes.fixed[static_cast<std::size_t>(i)] |= mask;
  }
  constexpr std::uint8_t kAll = (1u << Dim) - 1u;
  st_.consistent_per_component = std::any_of(st_.nodes.fixed.begin(), st_.nodes.fixed.end(),
                                             [](std::uint8_t f) { return f != 0 && f != kAll; });
  st_.tractions = pb.tractions;
  st_.mass_type = s.mass;
  st_.mass_tolerance = s.mass_tolerance;
  st_.consistent.configure(s.mass_solver);
  st_.conservation_limit = s.conservation_limit;
  st_.body_force = pb.body_force;
  auto& P = st_.particles;
  if (st_.body_force.fill) st_.body_force.fill(P, 0.0, P.body);
  element_.assign(static_cast<std::size_t>(P.size()), 0);
  if (!iso_ && Dim == 1)
    for (std::size_t p = 0; p < element_.size(); ++p)
      element_[p] = std::clamp<Index>(body_.cell_of(P.x[p][0], 0), 0, cells[0] - 1);
  if constexpr (Dim == 2)
    for (std::size_t p = 0; ps && p < element_.size(); ++p) {
      element_[p] = ps_->mesh().cell_index(P.x0[p]);
      if (element_[p] < 0)
        throw InputError(fmt::format(
            "method.solver = \"unified\": particle {} at X = ({:.9g}, {:.9g}) lies outside the "
            "body's triangles; the body must be the mesh",
            P.id[p], P.x0[p][0], P.x0[p][1]));
    }
}

template <int Dim>
void Otm<Dim>::set_nodes(const std::vector<double>& x, const std::string& what) {
  if (x.size() != x_.size())
    throw InputError(fmt::format("{} holds {} OTM node coordinates; this run has {} nodes of {}",
                                 what, x.size(), x_.size() / Dim, Dim));
  for (std::size_t i = 1; i < x.size() && !iso_ && Dim == 1; ++i)
    if (!(x[i] > x[i - 1]))
      throw InputError(
          fmt::format("{}: OTM nodes {} and {} are not in increasing order", what, i - 1, i));
  x_ = x;
}

template <int Dim>
bool Otm<Dim>::maxent_at(double x, Index e, Index p) {
  const auto n = static_cast<Index>(x_.size());
  const double ell = x_[static_cast<std::size_t>(e + 1)] - x_[static_cast<std::size_t>(e)];
  // Candidates: the nodes on either side until one lies beyond its own support and its
  // neighbour's (supports vary smoothly with the node spacing).
  constexpr int kMax = 32;
  std::array<Index, kMax> ids{};
  std::array<Vec<1>, kMax> y, dw, grad;
  std::array<double, kMax> w{}, phi{};
  int m = 0;
  bool overflow = false;
  const bool on_lo = x <= x_.front(), on_hi = x >= x_.back();
  auto consider = [&](Index i) {
    const double xi = x_[static_cast<std::size_t>(i)];
    const double d = support_[static_cast<std::size_t>(i)], dist = std::abs(x - xi), r = dist / d;
    if ((on_lo && i != 0) || (on_hi && i != n - 1)) return dist < 3.0 * d;
    const double wi = maxent_prior(r);
    if (wi > 0.0 && m == kMax) overflow = true;
    if (wi > 0.0 && m < kMax) {
      ids[static_cast<std::size_t>(m)] = i;
      y[static_cast<std::size_t>(m)] = Vec<1>((xi - x) / ell);
      w[static_cast<std::size_t>(m)] = wi;
      // d w / d(x / ell) = ell dw/dr dr/dx, dr/dx = sign(x - x_i) / d
      dw[static_cast<std::size_t>(m)] =
          Vec<1>(dist > 0.0 ? maxent_prior_slope(r) * ell / d * (x > xi ? 1.0 : -1.0) : 0.0);
      ++m;
    }
    return dist < 3.0 * d;  // keep scanning while a farther node could still reach x
  };
  for (Index i = e; i >= 0 && consider(i); --i) {
  }
  for (Index i = e + 1; i < n && consider(i); ++i) {
  }
  if (overflow)
    throw RunError(
        exit_code::kBasis,
        fmt::format("step {}, t = {:.9g} s: more than {} advected nodes lie in the "
                    "max-ent support at particle {} ({:.17g}): the nodes are crowded",
                    st_.step, st_.time, kMax, st_.particles.id[static_cast<std::size_t>(p)], x));
  const std::array<bool, 1> fixed{on_lo || on_hi};
  const bool boundary = fixed[0];
  const MaxEntStatus st = maxent_solve<1>(m, y.data(), w.data(), dw.data(), fixed, s_.maxent,
                                          phi.data(), boundary ? nullptr : grad.data());
  if (!st.converged) return false;
  if (boundary) {
    // On an end node phi is 1 there (weak Kronecker delta); the gradient is that of the point a
    // millionth of the element inside (continuous up to the end).
    const double inner = x + (on_lo ? 1e-6 : -1e-6) * ell;
    const std::size_t before = node_.size();
    if (!maxent_at(inner, e, p)) return false;
    std::vector<Index> nodes(node_.begin() + static_cast<std::ptrdiff_t>(before), node_.end());
    std::vector<double> grads(g_.begin() + static_cast<std::ptrdiff_t>(before), g_.end());
    node_.resize(before);
    w_.resize(before);
    g_.resize(before);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      double value = 0.0;
      for (int j = 0; j < m; ++j)
        if (ids[static_cast<std::size_t>(j)] == nodes[k]) value = phi[static_cast<std::size_t>(j)];
      node_.push_back(nodes[k]);
      w_.push_back(value);
      g_.push_back(grads[k]);
    }
    return true;
  }
  for (int j = 0; j < m; ++j) {
    const auto k = static_cast<std::size_t>(j);
    node_.push_back(ids[k]);
    w_.push_back(phi[k]);
    g_.push_back(grad[k][0] / ell);
  }
  return true;
}

// The tractions. A 1D traction loads an end of the body (model/problem.hpp, body_face_traction),
// and the body's ends are its end nodes, carried by the material: the end node of OTM (P1 and
// max-ent interpolate there, weak Kronecker-delta property) and the end control point of the
// unified approach (the open knot vector's B_i interpolate at its ends). So the force tau A acts
// on that node alone, where the MPM stage evaluates the basis at the end particle's face.
// In 2D (the isoparametric maps: unified, OTM-P1) a face point k of particle p sits at the
// material point X_p + offset_k, where the functions are N_i(X), and takes tau A_k with A_k its
// share of the face before deformation, as the MPM stage's face points (stages::after_forces,
// the point alone: the particles' own quadrature, that of the masses here): f_i += N_i(X_k) tau
// A_k, so sum_i f_i = tau sum_k A_k by the partition of unity.
template <int Dim>
void Otm<Dim>::add_tractions() {
  auto& nd = st_.nodes;
  if constexpr (Dim == 1) {
    for (const auto& tr : st_.tractions) {
      const Vec<1> tau = tr.value(st_.time);
      double area = 0.0;
      for (double a : tr.area) area += a;
      nd.force[tr.side > 0 ? x_.size() - 1 : 0] += tau * area;
    }
  } else {
    const auto& P = st_.particles;
    // fn(X_k, particle, f_k) for every face point: its material position and its load.
    auto each_point = [&](auto&& fn) {
      for (const auto& tr : st_.tractions) {
        const Vec<Dim> tau = tr.value(st_.time);
        const double p = tr.pressure ? tr.pressure(st_.time) : 0.0;
        for (std::size_t k = 0; k < tr.particles.size(); ++k) {
          const auto i = static_cast<std::size_t>(tr.particles[k]);
          fn(Vec<Dim>(P.x0[i] + tr.offset[k]), i, tr.point_force(k, tau, p));
        }
      }
    };
    auto load = [&](const auto& s, const Vec<Dim>& f) {
      for (int a = 0; a < s.kSize; ++a) nd.force[static_cast<std::size_t>(s.dof[a])] += s.w[a] * f;
    };
    if (ps_) {
      if constexpr (Dim == 2)
        each_point([&](const Vec<2>& X, std::size_t i, const Vec<2>& f) {
          PowellSabinBasis::StencilT s;
          // On the body's boundary; a point the triangle search misses by round-off is
          // evaluated in its particle's triangle (the piece extrapolated, C1 across edges).
          if (!ps_->splines().evaluate_point(X, s)) ps_->splines().evaluate_in(element_[i], X, s);
          load(s, f);
        });
    } else {
      with_bspline_degree(degree_, [&](auto degree) {
        const BSplineBasis<Dim, decltype(degree)::value> basis(body_);  // B_i(X), once a step
        each_point([&](const Vec<Dim>& X, std::size_t, const Vec<Dim>& f) {
          typename BSplineBasis<Dim, decltype(degree)::value>::StencilT s;
          basis.evaluate_point(X, s);
          load(s, f);
        });
      });
    }
  }
}

template <int Dim>
template <class Stencil>
void Otm<Dim>::append_isoparametric_row(Index p, const Stencil& s) {
  const auto i = static_cast<std::size_t>(p);
  // dx/dX at X_p: sum_i c_i grad_X B_i^T; grad_x phi_i = (dx/dX)^-T grad_X B_i.
  Mat<Dim> J = Mat<Dim>::Zero();
  for (int a = 0; a < s.kSize; ++a)
    J += Eigen::Map<const Vec<Dim>>(&x_[static_cast<std::size_t>(s.dof[a] * Dim)]) *
         s.grad[a].transpose();
  const double det = J.determinant();
  if (!(det > 0.0)) {
    const auto& Pt = st_.particles;
    throw RunError(exit_code::kInvertedDeformation,
                   fmt::format("step {}, t = {:.9g} s: the advected {} map is inverted at "
                               "particle {} (X_1 = {:.9g}, det dx/dX = {:.3g})",
                               st_.step, st_.time, ps_ ? "Powell-Sabin" : "B-spline", Pt.id[i],
                               Pt.x0[i][0], det));
  }
  const Mat<Dim> JinvT = J.inverse().transpose();
  for (int a = 0; a < s.kSize; ++a) {
    node_.push_back(s.dof[a]);
    w_.push_back(s.w[a]);
    const Vec<Dim> gx = JinvT * s.grad[a];
    g_.insert(g_.end(), gx.data(), gx.data() + Dim);
  }
  row_.push_back(static_cast<Index>(node_.size()));
}

template <int Dim>
template <int P>
void Otm<Dim>::bspline_rows() {
  const BSplineBasis<Dim, P> basis(body_);  // B_i(X) on the material (initial) body grid
  typename BSplineBasis<Dim, P>::StencilT s;
  const auto& Pt = st_.particles;
  for (Index p = 0; p < Pt.size(); ++p) {
    basis.evaluate_point(Pt.x0[static_cast<std::size_t>(p)], s);
    append_isoparametric_row(p, s);
  }
}

template <int Dim>
void Otm<Dim>::powell_sabin_rows() {
  if constexpr (Dim == 2) {
    PowellSabinBasis::StencilT s;
    const auto& Pt = st_.particles;
    for (Index p = 0; p < Pt.size(); ++p) {
      const auto i = static_cast<std::size_t>(p);
      ps_->splines().evaluate_in(element_[i], Pt.x0[i], s);  // N_ij(X_p) on its material triangle
      append_isoparametric_row(p, s);
    }
  }
}

// OTM-maxent in 2D (D 4.3 on the advected nodes): d_i = d_max zeta_i with zeta_i the distance
// from node i to its nearest lattice neighbour (the eight around it; the nearest node of a
// lattice that has not folded), and the nodes within d_i of a particle found through square bins
// of side max_i d_i over the nodes' bounding box (the 3^Dim bins around the particle's hold them
// all), never an all-pairs search. The particles lie inside the nodes' convex hull (the body),
// so no multiplier is fixed; a particle outside it, or any point where Newton's method does not
// converge, stops the run (exit code 10) with the particle and its nodes.
template <int Dim>
void Otm<Dim>::maxent_rows() {
  auto& P = st_.particles;
  const auto n = static_cast<Index>(x_.size() / Dim);
  IVec<Dim> lat;
  for (int d = 0; d < Dim; ++d) lat[d] = body_.cells[d] + 1;
  auto pos = [&](Index i) {
    return Eigen::Map<const Vec<Dim>>(&x_[static_cast<std::size_t>(i * Dim)]);
  };
  support_.resize(static_cast<std::size_t>(n));
  Vec<Dim> lo = pos(0), hi = pos(0);
  double dmax_all = 0.0;
  for (Index i = 0; i < n; ++i) {
    IVec<Dim> c;
    Index rem = i;
    for (int d = 0; d < Dim; ++d) {
      c[d] = rem % lat[d];
      rem /= lat[d];
    }
    double z = std::numeric_limits<double>::infinity();
    for_each_neighbour<Dim>(c, lat, [&](Index j) {
      if (j != i) z = std::min(z, (pos(j) - pos(i)).norm());
    });
    support_[static_cast<std::size_t>(i)] = s_.maxent.dmax * z;
    dmax_all = std::max(dmax_all, s_.maxent.dmax * z);
    lo = lo.cwiseMin(pos(i));
    hi = hi.cwiseMax(pos(i));
  }
  // The bins (counting sort of the nodes by bin).
  IVec<Dim> nb;
  for (int d = 0; d < Dim; ++d)
    nb[d] = std::max<Index>(1, static_cast<Index>(std::floor((hi[d] - lo[d]) / dmax_all)) + 1);
  auto bin_of = [&](const Vec<Dim>& x, int d) {
    return std::clamp<Index>(static_cast<Index>(std::floor((x[d] - lo[d]) / dmax_all)), 0,
                             nb[d] - 1);
  };
  const Index nbins = dof_count<Dim>(nb);
  std::vector<Index> start(static_cast<std::size_t>(nbins + 1), 0),
      order(static_cast<std::size_t>(n));
  auto flat = [&](const Vec<Dim>& x) {
    Index b = 0, stride = 1;
    for (int d = 0; d < Dim; ++d) {
      b += bin_of(x, d) * stride;
      stride *= nb[d];
    }
    return b;
  };
  for (Index i = 0; i < n; ++i) ++start[static_cast<std::size_t>(flat(pos(i)) + 1)];
  for (Index b = 0; b < nbins; ++b)
    start[static_cast<std::size_t>(b + 1)] += start[static_cast<std::size_t>(b)];
  {
    std::vector<Index> fill(start.begin(), start.end() - 1);
    for (Index i = 0; i < n; ++i)
      order[static_cast<std::size_t>(fill[static_cast<std::size_t>(flat(pos(i)))]++)] = i;
  }
  const double ell = body_.h.minCoeff();  // the length unit of the Newton iteration
  constexpr int kMax = 216;               // maxent_solve's largest node set
  std::array<Index, kMax> ids{};
  std::array<Vec<Dim>, kMax> y, dw, grad;
  std::array<double, kMax> w{}, phi{};
  const std::array<bool, Dim> fixed{};
  for (Index p = 0; p < P.size(); ++p) {
    const auto i = static_cast<std::size_t>(p);
    const Vec<Dim> x = P.x[i];
    if (!st_.grid.inside(x)) stages::throw_left_grid(st_);
    int m = 0;
    IVec<Dim> b0;
    for (int d = 0; d < Dim; ++d) b0[d] = bin_of(x, d);
    for_each_neighbour<Dim>(b0, nb, [&](Index b) {
      for (Index t = start[static_cast<std::size_t>(b)]; t < start[static_cast<std::size_t>(b + 1)];
           ++t) {
        const Index j = order[static_cast<std::size_t>(t)];
        const Vec<Dim> r_vec = x - pos(j);
        const double dj = support_[static_cast<std::size_t>(j)], dist = r_vec.norm();
        const double wj = maxent_prior(dist / dj);
        if (!(wj > 0.0)) continue;
        if (m == kMax)
          throw RunError(exit_code::kBasis,
                         fmt::format("step {}, t = {:.9g} s: more than {} advected nodes lie in "
                                     "the max-ent support at particle {}: the nodes are crowded",
                                     st_.step, st_.time, kMax, P.id[i]));
        const auto q = static_cast<std::size_t>(m++);
        ids[q] = j;
        y[q] = -r_vec / ell;
        w[q] = wj;
        // zeta grad w = ell dw/dr (x - x_j) / (|x - x_j| d_j)
        dw[q] = dist > 0.0 ? Vec<Dim>(maxent_prior_slope(dist / dj) * ell / (dist * dj) * r_vec)
                           : Vec<Dim>::Zero();
      }
    });
    const MaxEntStatus status = maxent_solve<Dim>(m, y.data(), w.data(), dw.data(), fixed,
                                                  s_.maxent, phi.data(), grad.data());
    if (!status.converged) {
      std::string where;
      for (int d = 0; d < Dim; ++d) where += fmt::format("{}{:.9g}", d ? ", " : "", x[d]);
      // Which of the two causes: max-ent functions exist at x iff x lies inside the convex hull
      // of the nodes whose supports reach it (D 4.3), i.e. seen from x no half-plane holds
      // them all: the largest angle between consecutive node directions is below 180 degrees.
      std::vector<double> angle;
      for (int j = 0; j < m; ++j) {
        const Vec<Dim>& r = y[static_cast<std::size_t>(j)];
        angle.push_back(Dim == 1 ? (r[0] > 0.0 ? 0.0 : 180.0)
                                 : std::atan2(r[Dim - 1], r[0]) * 180.0 / std::numbers::pi);
      }
      std::sort(angle.begin(), angle.end());
      double gap = angle.empty() ? 360.0 : angle.front() + 360.0 - angle.back();
      for (std::size_t k = 1; k < angle.size(); ++k) gap = std::max(gap, angle[k] - angle[k - 1]);
      const std::string cause =
          gap >= 180.0
              ? fmt::format(
                    "the particle lies outside the convex hull of those nodes (seen from it they "
                    "leave a gap of {:.1f} degrees), so it has no max-ent functions: each node's "
                    "support is method.maxent_dmax = {:.3g} times its distance to its nearest "
                    "lattice neighbour, and where the lattice is compressed the supports shrink "
                    "and no longer surround every particle (a larger method.maxent_dmax widens "
                    "them)",
                    gap, s_.maxent.dmax)
              : fmt::format(
                    "the particle lies inside the convex hull of those nodes (largest "
                    "gap between them seen from it {:.1f} degrees): the iteration itself "
                    "failed",
                    gap);
      throw RunError(
          exit_code::kBasis,
          fmt::format("step {}, t = {:.9g} s: the max-ent basis on the advected nodes could not "
                      "be evaluated at particle {} ({}; {} nodes in its support): Newton's method "
                      "for the Lagrange multipliers stopped after {} iterations at residual "
                      "{:.3g} (method.maxent_tolerance = {:.3g}, method.maxent_max_iterations = "
                      "{}); {}",
                      st_.step, st_.time, P.id[i], where, m, status.iterations, status.residual,
                      s_.maxent.tolerance, s_.maxent.max_iterations, cause));
    }
    for (int j = 0; j < m; ++j) {
      const auto q = static_cast<std::size_t>(j);
      node_.push_back(ids[q]);
      w_.push_back(phi[q]);
      const Vec<Dim> gx = grad[q] / ell;
      g_.insert(g_.end(), gx.data(), gx.data() + Dim);
    }
    row_.push_back(static_cast<Index>(node_.size()));
  }
}

// D Algorithm 3 / 4, step 3: the basis at the material points from the advected nodes.
template <int Dim>
void Otm<Dim>::evaluate_basis() {
  auto& P = st_.particles;
  const auto n = static_cast<Index>(x_.size());
  row_.assign(1, 0);
  node_.clear();
  w_.clear();
  g_.clear();
  if (ps_) return powell_sabin_rows();
  if (iso_)
    return with_bspline_degree(degree_,
                               [&](auto degree) { bspline_rows<decltype(degree)::value>(); });
  if constexpr (Dim != 1) {
    maxent_rows();
  } else {
    if (s_.basis == OtmBasis::MaxEnt) {
      // d_i = d_max zeta_i (D eq. 4.47), zeta_i the distance to node i's nearest neighbour: once
      // per step, not per particle.
      support_.resize(x_.size());
      for (Index i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        double z = std::numeric_limits<double>::infinity();
        if (i > 0) z = std::min(z, x_[k] - x_[k - 1]);
        if (i + 1 < n) z = std::min(z, x_[k + 1] - x_[k]);
        support_[k] = s_.maxent.dmax * z;
      }
    }
    Index failed = 0, first_failed = -1;
    for (Index p = 0; p < P.size(); ++p) {
      const auto i = static_cast<std::size_t>(p);
      const double x = P.x[i][0];
      if (!(x >= x_.front() && x <= x_.back())) stages::throw_left_grid(st_);
      Index e = element_[i];
      while (e > 0 && x < x_[static_cast<std::size_t>(e)]) --e;
      while (e < n - 2 && x > x_[static_cast<std::size_t>(e + 1)]) ++e;
      element_[i] = e;
      if (s_.basis == OtmBasis::Linear) {
        const double a = x_[static_cast<std::size_t>(e)], b = x_[static_cast<std::size_t>(e + 1)];
        const double len = b - a;
        node_.insert(node_.end(), {e, e + 1});
        w_.insert(w_.end(), {(b - x) / len, (x - a) / len});  // D eq. 2.56 on the element
        g_.insert(g_.end(), {-1.0 / len, 1.0 / len});
      } else if (!maxent_at(x, e, p)) {
        if (failed++ == 0) first_failed = p;
      }
      row_.push_back(static_cast<Index>(node_.size()));
    }
    if (failed > 0) {
      const auto i = static_cast<std::size_t>(first_failed);
      throw RunError(
          exit_code::kBasis,
          fmt::format("step {}, t = {:.9g} s: the max-ent basis on the advected nodes could not "
                      "be evaluated at {} particle(s): at the first, particle {} ({:.17g}), "
                      "Newton's method for the Lagrange multipliers did not converge "
                      "(method.maxent_tolerance = {:.3g}, method.maxent_max_iterations = {})",
                      st_.step, st_.time, failed, P.id[i], P.x[i][0], s_.maxent.tolerance,
                      s_.maxent.max_iterations));
    }
  }
}

template <int Dim>
void Otm<Dim>::step(double dt) {
  auto& P = st_.particles;
  auto& nd = st_.nodes;
  if (st_.body_force.time_dependent || st_.body_force.position_dependent)
    st_.body_force.fill(P, st_.time, P.body);
  evaluate_basis();
  auto node = [&](Index k) { return static_cast<std::size_t>(node_[static_cast<std::size_t>(k)]); };
  auto weight = [&](Index k) { return w_[static_cast<std::size_t>(k)]; };
  auto grad = [&](Index k) {
    return Eigen::Map<const Vec<Dim>>(&g_[static_cast<std::size_t>(k * Dim)]);
  };

  // Step 4: M, q and f (D eq. 4.28-4.30 / 4.81-4.83), in particle order (the same rounding
  // every run); the internal force with the sign of D eq. 2.33.
  const auto n = static_cast<Index>(x_.size() / Dim);
  std::fill(nd.mass.begin(), nd.mass.end(), 0.0);
  std::fill(nd.momentum.begin(), nd.momentum.end(), Vec<Dim>::Zero());
  std::fill(nd.force.begin(), nd.force.end(), Vec<Dim>::Zero());
  const bool consistent = st_.mass_type == MassType::Consistent;
  if (consistent) st_.consistent.begin(n);
  for (Index p = 0; p < P.size(); ++p) {
    const auto i = static_cast<std::size_t>(p);
    const double m = P.mass[i];
    for (Index k = row_[i]; k < row_[i + 1]; ++k) {
      const auto a = node(k);
      const double w = weight(k);
      nd.mass[a] += w * m;
      nd.momentum[a] += w * m * P.v[i];
      nd.force[a] += -P.volume[i] * (P.stress[i] * grad(k)) + w * m * P.body[i];
      if (consistent)
        for (Index l = row_[i]; l < row_[i + 1]; ++l)
          st_.consistent.add(static_cast<Index>(a), static_cast<Index>(node(l)), w * m * weight(l));
    }
  }
  add_tractions();
  stages::after_mass(st_);  // conservation check, active nodes, factorisation
  stages::after_momentum(st_);

  // v_i = M^-1 (q + dt f) with the Dirichlet conditions, a_i = M^-1 f; x_i += dt v_i (4.31,
  // 4.84-4.86, constant dt).
  stages::solve_velocity(st_);
  stages::solve_acceleration(st_, dt);
  stages::advance_grid_velocity(st_, dt);

  // x_p = sum phi_i x_i^{s+1} written as x_p + dt sum phi_i v_i (the same by linear
  // completeness, without the Newton residual of max-ent; D eq. 4.87 for the unified approach),
  // F, V, rho and the stress; the particle velocity of each algorithm.
  std::vector<Mat<Dim>> L(static_cast<std::size_t>(P.size()), Mat<Dim>::Zero());
  for (Index p = 0; p < P.size(); ++p) {
    const auto i = static_cast<std::size_t>(p);
    Vec<Dim> dx = Vec<Dim>::Zero();
    for (Index k = row_[i]; k < row_[i + 1]; ++k) {
      const Vec<Dim>& v = nd.velocity[node(k)];
      dx += weight(k) * v;
      L[i].noalias() += v * grad(k).transpose();
    }
    dx *= dt;
    P.x[i] += dx;
    if (s_.unified) {
      // USL's velocity update (D eq. 4.88).
      Vec<Dim> acc = Vec<Dim>::Zero();
      for (Index k = row_[i]; k < row_[i + 1]; ++k) acc += weight(k) * nd.accel[node(k)];
      P.v[i] += dt * acc;
    } else {
      P.v[i] = dx / dt;  // OTM: the momentum of the next step (4.29)
    }
  }
  const bool bad = stages::deform_particles(P, st_.materials, 0, P.size(), L.data(), dt);
  if (bad) stages::throw_particle_failure(st_);
  for (Index i = 0; i < n; ++i)
    for (int d = 0; d < Dim; ++d)
      x_[static_cast<std::size_t>(i * Dim + d)] += dt * nd.velocity[static_cast<std::size_t>(i)][d];
  // OTM's elements must stay ordered (the unified approach checks its map at the particles).
  for (Index i = 1; i < n && !iso_ && Dim == 1; ++i)
    if (!(x_[static_cast<std::size_t>(i)] > x_[static_cast<std::size_t>(i - 1)]))
      throw RunError(exit_code::kInvertedDeformation,
                     fmt::format("step {}, t = {:.9g} s: the advected OTM nodes {} and {} crossed "
                                 "(an inverted element, x = {:.9g} and {:.9g})",
                                 st_.step, st_.time, i - 1, i, x_[static_cast<std::size_t>(i - 1)],
                                 x_[static_cast<std::size_t>(i)]));
}

template class Otm<1>;
template class Otm<2>;

}  // namespace mpm
