#include "methods/ulfem.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mpm {

namespace {

// A body end counts as lying on a grid side when they coincide up to round-off of the grid
// extent (grid.upper() is origin + cells h, which need not reproduce body_max bit for bit).
bool coincide(double a, double b, double scale) {
  return std::abs(a - b) <= 1e-10 * scale;
}

// At most `limit` element ids with their current midpoints, for failure messages (the style of
// the failure messages of scheme/grid_stages.cpp).
std::string describe_elements(const Particles<1>& E, const std::vector<Index>& ids,
                              std::size_t limit = 8) {
  std::string out;
  for (std::size_t k = 0; k < ids.size() && k < limit; ++k) {
    const auto i = static_cast<std::size_t>(ids[k]);
    out += fmt::format("{}element {} at x = {:.6g} (X = {:.6g}, F = {:.6g})", k ? "; " : "", ids[k],
                       E.x[i][0], E.x0[i][0], E.F[i](0, 0));
  }
  if (ids.size() > limit) out += fmt::format("; and {} more", ids.size() - limit);
  return out;
}

}  // namespace

Ulfem1D::Ulfem1D(const Problem<1>& pb, Index elements)
    : material_(pb.materials.single()), body_force_(pb.body_force), tractions_(pb.tractions) {
  const double lo = pb.body_min[0], hi = pb.body_max[0];
  if (elements < 1)
    throw InputError(fmt::format("ULFEM needs at least one element, got {}", elements));
  if (!(hi > lo)) throw InputError(fmt::format("ULFEM: the body [{}, {}] is empty", lo, hi));

  const double rho0 = std::visit([](const auto& law) { return law.p.density; }, material_);
  const auto ne = static_cast<std::size_t>(elements);
  const std::size_t nn = ne + 1;
  X_lo_ = lo;
  dX_ = (hi - lo) / static_cast<double>(elements);

  const double scale = std::max(pb.grid.upper()[0] - pb.grid.origin[0], hi - lo);
  for (const auto& f : pb.fixed_sides) {
    if (f.direction != 0 || !(f.components & 1u)) continue;
    if (f.side == 0 && coincide(pb.grid.origin[0], lo, scale)) fixed_lo_ = true;
    if (f.side == 1 && coincide(pb.grid.upper()[0], hi, scale)) fixed_hi_ = true;
  }

  X_.resize(nn);
  x_.resize(nn);
  v_.resize(nn);
  m_.assign(nn, 0.0);
  force_.assign(nn, 0.0);
  for (std::size_t i = 0; i < nn; ++i) {
    // The last node is placed at hi exactly so the body keeps its length bit for bit.
    X_[i] = i + 1 == nn ? hi : lo + static_cast<double>(i) * dX_;
    x_[i] = X_[i];
    v_[i] = pb.initial_velocity ? pb.initial_velocity(Vec<1>(X_[i]))[0] : 0.0;
  }
  if (fixed_lo_) v_.front() = 0.0;
  if (fixed_hi_) v_.back() = 0.0;

  el_.resize(elements);
  el_.state.set_names(state_names(material_));
  for (std::size_t e = 0; e < ne; ++e) {
    const double L0 = X_[e + 1] - X_[e];
    const double mass = rho0 * L0;
    m_[e] += 0.5 * mass;  // lumped: half the element mass to each end node
    m_[e + 1] += 0.5 * mass;
    const double Xm = 0.5 * (X_[e] + X_[e + 1]);
    el_.x0[e][0] = el_.x[e][0] = Xm;
    el_.v[e][0] = 0.5 * (v_[e] + v_[e + 1]);
    el_.mass[e] = mass;
    el_.volume[e] = el_.volume0[e] = L0;
    el_.F[e](0, 0) = 1.0;
    el_.stress[e] = pb.initial_stress ? pb.initial_stress(Vec<1>(Xm)) : Mat<1>::Zero();
  }

  nodes_.resize(static_cast<Index>(nn));
  for (std::size_t i = 0; i < nn; ++i) {
    nodes_.x[i][0] = nodes_.x0[i][0] = X_[i];
    nodes_.v[i][0] = v_[i];
    nodes_.mass[i] = m_[i];
  }
  // Constant body forces are filled once, as in the MPM runner.
  if (body_force_.fill) body_force_.fill(nodes_, 0.0, nodes_.body);
  for (std::size_t e = 0; e < ne; ++e) el_.body[e] = 0.5 * (nodes_.body[e] + nodes_.body[e + 1]);
}

void Ulfem1D::refresh_body_force(double t) {
  if (!body_force_.fill || !(body_force_.time_dependent || body_force_.position_dependent)) return;
  if (body_force_.position_dependent)
    for (std::size_t i = 0; i < x_.size(); ++i) nodes_.x[i][0] = x_[i];
  body_force_.fill(nodes_, t, nodes_.body);
}

void Ulfem1D::step(double dt) {
  const std::size_t nn = x_.size(), ne = nn - 1;
  const double t = time_;
  refresh_body_force(t);

  // External forces: body force m_i b_i, end tractions as point forces (unit area).
  for (std::size_t i = 0; i < nn; ++i) force_[i] = m_[i] * nodes_.body[i][0];
  for (const auto& tr : tractions_) force_[tr.side > 0 ? nn - 1 : 0] += tr.value(t)[0];
  // Internal forces f_int,i = int sigma dN_i/dx dx = -sigma_e (left node), +sigma_e (right):
  // an element in tension pulls its nodes together. force_ holds f_ext - f_int.
  for (std::size_t e = 0; e < ne; ++e) {
    const double s = el_.stress[e](0, 0);
    force_[e] += s;
    force_[e + 1] -= s;
  }

  // Euler-Cromer (D eq. 2.36-2.38): v^{s+1} = v^s + dt a^s, x^{s+1} = x^s + dt v^{s+1}.
  for (std::size_t i = 0; i < nn; ++i) v_[i] += dt * force_[i] / m_[i];
  if (fixed_lo_) v_.front() = 0.0;
  if (fixed_hi_) v_.back() = 0.0;
  for (std::size_t i = 0; i < nn; ++i) x_[i] += dt * v_[i];

  // Kinematics and stress per element. dtL = dt (v_{e+1} - v_e) / l^s = l^{s+1} / l^s - 1, so
  // F^{s+1} = (1 + dtL) F^s = l^{s+1} / L0 exactly as the MPM stage would compute it.
  bool bad = false;
  std::visit(
      [&](const auto& law) {
        for (std::size_t e = 0; e < ne; ++e) {
          const double l = x_[e + 1] - x_[e];
          const double F_old = el_.F[e](0, 0);
          const double F_new = l / el_.volume0[e];
          Mat<1> dtL;
          dtL(0, 0) = F_new / F_old - 1.0;
          el_.F[e](0, 0) = F_new;
          el_.volume[e] = l;
          el_.x[e][0] = 0.5 * (x_[e] + x_[e + 1]);
          el_.v[e][0] = 0.5 * (v_[e] + v_[e + 1]);
          el_.body[e] = 0.5 * (nodes_.body[e] + nodes_.body[e + 1]);
          using Law = std::decay_t<decltype(law)>;
          const bool updated =
              law.update(el_.stress[e], state_row<Law>(el_.state, e), el_.F[e], dtL);
          // (The 1D laws have no return mapping that could fail: make_material refuses the
          // plastic ones in 1D.)
          if (!updated) throw std::logic_error("ULFEM: a 1D law's stress update failed");
          bad |= !(F_new > 0.0) || !std::isfinite(el_.stress[e](0, 0));
        }
      },
      material_);
  if (bad) check_elements();

  ++steps_;
  if (dt != last_dt_) {
    time_anchor_ = time_;
    steps_since_anchor_ = 0;
    last_dt_ = dt;
  }
  ++steps_since_anchor_;
  time_ = time_anchor_ + static_cast<double>(steps_since_anchor_) * dt;
}

void Ulfem1D::check_elements() const {
  std::vector<Index> inverted, nonfinite;
  for (Index e = 0; e < el_.size(); ++e) {
    const auto i = static_cast<std::size_t>(e);
    const double F = el_.F[i](0, 0);
    if (!std::isfinite(el_.stress[i](0, 0)) || !std::isfinite(F))
      nonfinite.push_back(e);
    else if (!(F > 0.0))
      inverted.push_back(e);
  }
  if (!nonfinite.empty())
    throw RunError(exit_code::kNonFinite,
                   fmt::format("step {}, t = {:.9g} s: ULFEM: non-finite stress or deformation "
                               "gradient in {} element(s): {}",
                               steps_, time_, nonfinite.size(), describe_elements(el_, nonfinite)));
  if (!inverted.empty())
    throw RunError(exit_code::kInvertedDeformation,
                   fmt::format("step {}, t = {:.9g} s: ULFEM: F <= 0 (inverted or degenerate "
                               "element) in {} element(s): {}",
                               steps_, time_, inverted.size(), describe_elements(el_, inverted)));
}

double Ulfem1D::stress_at(double X) const {
  const Index ne = el_.size();
  // Midpoints are evenly spaced: X_m,e = X_lo + (e + 1/2) L0.
  const double s = (X - X_lo_) / dX_ - 0.5;
  if (!(s > 0.0)) return el_.stress.front()(0, 0);
  if (s >= static_cast<double>(ne - 1)) return el_.stress.back()(0, 0);
  const auto e = static_cast<std::size_t>(std::floor(s));
  const double w = s - static_cast<double>(e);
  return (1.0 - w) * el_.stress[e](0, 0) + w * el_.stress[e + 1](0, 0);
}

double Ulfem1D::kinetic_energy() const {
  double k = 0.0;
  for (std::size_t i = 0; i < v_.size(); ++i) k += 0.5 * m_[i] * v_[i] * v_[i];
  return k;
}

double Ulfem1D::strain_energy() const {
  return std::visit(
      [&](const auto& law) {
        double w = 0.0;
        using Law = std::decay_t<decltype(law)>;
        for (std::size_t e = 0; e < el_.F.size(); ++e)
          w += law.energy(el_.stress[e], state_row<Law>(el_.state, e), el_.F[e], el_.volume[e],
                          el_.volume0[e]);
        return w;
      },
      material_);
}

double Ulfem1D::momentum() const {
  double p = 0.0;
  for (std::size_t i = 0; i < v_.size(); ++i) p += m_[i] * v_[i];
  return p;
}

Ulfem1D::State Ulfem1D::save() const {
  return {x_, v_, nodes_.body, el_, time_, time_anchor_, last_dt_, steps_, steps_since_anchor_};
}

void Ulfem1D::restore(const State& s) {
  const auto nn = x_.size();
  if (s.x.size() != nn || s.v.size() != nn || s.node_body.size() != nn ||
      s.elements.size() != el_.size() || s.elements.x0.size() != el_.x0.size() ||
      s.elements.stress.size() != el_.stress.size())
    throw InputError(fmt::format(
        "ULFEM state of {} nodes and {} elements does not fit this mesh of {} nodes and {} "
        "elements",
        s.x.size(), s.elements.size(), nn, el_.size()));
  x_ = s.x;
  v_ = s.v;
  nodes_.body = s.node_body;
  const auto names = el_.state.names();
  el_ = s.elements;
  // (Checks the stored rows' width against the law's.)
  try {
    el_.state.set_names(names);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("ULFEM state: {}", e.what()));
  }
  time_ = s.time;
  time_anchor_ = s.time_anchor;
  last_dt_ = s.last_dt;
  steps_ = s.steps;
  steps_since_anchor_ = s.steps_since_anchor;
}

double Ulfem1D::critical_dt() const {
  double lmin = el_.volume.front();
  for (double l : el_.volume) lmin = std::min(lmin, l);
  return lmin / wave_speed(material_);
}

}  // namespace mpm
