// Where mpmlab's one-thread step spends the time the yardstick does not (issue 23, item 3).
//
// The yardstick ../shared/tools/refkernel.cpp is the smallest honest MUSL step: it keeps no
// displacement, density, body force or stencil cache, and checks nothing. mpmlab's step on the
// same problem (`mpm bench --problem refkernel`) does more per particle, for its outputs, its
// checks and its generality. This program is the yardstick's algorithm, line for line, with
// that extra work added back one piece at a time (compile-time flags, so a variant without a
// piece pays nothing for it), so that the gap can be attributed by measurement rather than
// assumed. Every variant, mask 0 included, fuses MUSL's particle velocity update with the second
// momentum scatter per particle, as mpm does (the same sums in the same order as the yardstick's
// two passes: mask 0 prints the yardstick's checksum). It is a measuring instrument, not part of
// mpm: scripts/refkernel_gap.sh builds it with the yardstick's flags and runs every variant
// alternating with the yardstick.
//
// Pieces (bits of the variant mask, argv[4]):
//   1  state:  u_p += dx (displacement, an output), rho_p = m_p / V_p (an output), V_p from V0_p
//   2  checks: the conservation sums of every step (sum m_p; sum m_p v_p; sum m_p |v_p|, a sqrt
//              per particle) and the failure check of every particle (J > 0, finite stress)
//   4  body:   the body-force term phi_i m_p b_p of the force scatter, b_p stored per particle
//              (zero on this problem, as in mpm's data; mpm now skips it per particle)
//   8  cache:  the basis evaluated once per step into a cached compact stencil (first DOF and the
//              1D values and derivatives, 104 bytes) read by the three later passes, instead of
//              recomputed from x in every pass
//  16  slices: the scatters add into per-chunk grid slices (64 chunks, as mpm's deterministic
//              parallel scatter) that are then summed in chunk order into the grid arrays
// Usage: refkernel_gap CELLS PPC STEPS MASK  -> prints ns per particle-step and a checksum
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

struct W {
  double w[3], dw[3];
  int base;
};

inline W weights(double xg) {  // the yardstick's closed-form quadratic weights
  W r;
  r.base = int(xg - 0.5);
  double fx = xg - r.base;
  r.w[0] = 0.5 * (1.5 - fx) * (1.5 - fx);
  r.w[1] = 0.75 - (fx - 1.0) * (fx - 1.0);
  r.w[2] = 0.5 * (fx - 0.5) * (fx - 0.5);
  r.dw[0] = fx - 1.5;
  r.dw[1] = -2.0 * (fx - 1.0);
  r.dw[2] = fx - 0.5;
  return r;
}

struct Cached {  // mpm's TensorStencil<2, 3>: 8 + 2 x 2 x 3 x 8 = 104 bytes
  long dof0;
  double w[2][3], dw[2][3];
};

constexpr unsigned kState = 1, kChecks = 2, kBody = 4, kCache = 8, kSlices = 16;
constexpr int kChunks = 64;

template <unsigned Mask>
double run(int n, int ppc, int steps, double& checksum) {
  constexpr bool state = Mask & kState, checks = Mask & kChecks, body = Mask & kBody,
                 cache = Mask & kCache, slices = Mask & kSlices;
  const double L = 1.0, h = L / n, inv_h = 1.0 / h, dt = 1e-6;
  const double E = 1e7, nu = 0.3, rho0 = 1000.0;
  const double mu = E / (2 * (1 + nu)), lam = E * nu / ((1 + nu) * (1 - 2 * nu));
  const int pad = 2, G = n + 2 * pad;
  const int s = int(std::lround(std::sqrt(double(ppc))));
  const size_t np = size_t(n) * n * s * s;
  std::vector<double> x(np), y(np), vx(np), vy(np), F(4 * np), sx(np), sy(np), sxy(np), V(np),
      m(np);
  std::vector<double> ux, uy, rho, V0, bx, by;
  if (state) ux.assign(np, 0.0), uy.assign(np, 0.0), rho.assign(np, rho0), V0.resize(np);
  if (body) bx.assign(np, 0.0), by.assign(np, 0.0);
  std::vector<Cached> st(cache ? np : 0);
  size_t p = 0;
  for (int j = 0; j < n * s; ++j)
    for (int i = 0; i < n * s; ++i, ++p) {
      x[p] = (i + 0.5) * h / s + pad * h;
      y[p] = (j + 0.5) * h / s + pad * h;
      vx[p] = 0.1 * std::sin(2 * M_PI * (x[p] - pad * h));
      vy[p] = -0.1 * std::sin(2 * M_PI * (y[p] - pad * h));
      F[4 * p] = F[4 * p + 3] = 1.0;
      F[4 * p + 1] = F[4 * p + 2] = 0.0;
      V[p] = h * h / (s * s);
      m[p] = rho0 * V[p];
      if (state) V0[p] = V[p];
      sx[p] = sy[p] = sxy[p] = 0.0;
    }
  const size_t ng = size_t(G) * G;
  std::vector<double> gm(ng), gpx(ng), gpy(ng), gfx(ng), gfy(ng), gvx(ng), gvy(ng), gax(ng),
      gay(ng);
  // slices: each chunk's DOF range [lo, hi] and its slices of the sums, back to back.
  std::vector<long> lo(kChunks), hi(kChunks);
  std::vector<size_t> off(kChunks + 1);
  std::vector<double> sm, spx, spy, sfx, sfy;
  auto chunk_begin = [&](int c) { return np * size_t(c) / kChunks; };
  double sum_m = 0, sum_px = 0, sum_py = 0, sum_pn = 0;
  bool failed = false;

  // f(k, w, gx, gy) for the 9 entries of particle q (recomputed or cached).
  auto entries = [&](size_t q, auto&& f) {
    if constexpr (cache) {
      const Cached& c = st[q];
      for (int b = 0; b < 3; ++b)
        for (int a = 0; a < 3; ++a)
          f(size_t(c.dof0 + a + long(b) * G), c.w[0][a] * c.w[1][b], c.dw[0][a] * c.w[1][b],
            c.dw[1][b] * c.w[0][a]);
    } else {
      W wx = weights(x[q] * inv_h), wy = weights(y[q] * inv_h);
      for (int b = 0; b < 3; ++b)
        for (int a = 0; a < 3; ++a)
          f(size_t(wy.base + b) * G + (wx.base + a), wx.w[a] * wy.w[b], wx.dw[a] * wy.w[b] * inv_h,
            wx.w[a] * wy.dw[b] * inv_h);
    }
  };
  // The slices of chunk c start at DOF lo[c]; with slices off the grid arrays themselves.
  auto scatter = [&](auto&& per_particle, std::vector<double>* grid[], std::vector<double>* buf[],
                     int nt) {
    if constexpr (slices) {
      for (int c = 0; c < kChunks; ++c) {
        double* sl[5];
        for (int t = 0; t < nt; ++t) {
          sl[t] = buf[t]->data() + off[c] - size_t(lo[c]);
          std::fill(buf[t]->data() + off[c], buf[t]->data() + off[c + 1], 0.0);
        }
        for (size_t q = chunk_begin(c); q < chunk_begin(c + 1); ++q) per_particle(q, sl);
      }
      for (int t = 0; t < nt; ++t) {
        std::fill(grid[t]->begin(), grid[t]->end(), 0.0);
        for (int c = 0; c < kChunks; ++c)
          for (long k = lo[c]; k <= hi[c]; ++k)
            (*grid[t])[size_t(k)] += (*buf[t])[off[c] + size_t(k - lo[c])];
      }
    } else {
      double* sl[5];
      for (int t = 0; t < nt; ++t) {
        std::fill(grid[t]->begin(), grid[t]->end(), 0.0);
        sl[t] = grid[t]->data();
      }
      for (size_t q = 0; q < np; ++q) per_particle(q, sl);
    }
  };

  auto t0 = std::chrono::steady_clock::now();
  for (int step = 0; step < steps; ++step) {
    if constexpr (cache) {  // evaluate_basis: one pass writing the stencils
      for (size_t q = 0; q < np; ++q) {
        W wx = weights(x[q] * inv_h), wy = weights(y[q] * inv_h);
        Cached& c = st[q];
        c.dof0 = long(wy.base) * G + wx.base;
        for (int a = 0; a < 3; ++a) {
          c.w[0][a] = wx.w[a], c.w[1][a] = wy.w[a];
          c.dw[0][a] = wx.dw[a] * inv_h, c.dw[1][a] = wy.dw[a] * inv_h;
        }
      }
    }
    if constexpr (slices) {  // the chunks' DOF ranges (mpm records them in evaluate_basis)
      off[0] = 0;
      for (int c = 0; c < kChunks; ++c) {
        long l = long(ng), u = -1;
        for (size_t q = chunk_begin(c); q < chunk_begin(c + 1); ++q) {
          const long b = long(int(y[q] * inv_h - 0.5)) * G + int(x[q] * inv_h - 0.5);
          l = std::min(l, b), u = std::max(u, b + 2 + 2L * G);
        }
        lo[c] = l, hi[c] = u, off[c + 1] = off[c] + size_t(u - l + 1);
      }
      for (auto* b : {&sm, &spx, &spy, &sfx, &sfy}) b->resize(off[kChunks]);
    }
    // P2G: mass, momentum, internal (and body) force
    if constexpr (checks) sum_m = 0;
    {
      std::vector<double>* grid[] = {&gm, &gpx, &gpy, &gfx, &gfy};
      std::vector<double>* buf[] = {&sm, &spx, &spy, &sfx, &sfy};
      scatter(
          [&](size_t q, double** g) {
            if constexpr (checks) sum_m += m[q];
            const double mbx = body ? m[q] * bx[q] : 0.0, mby = body ? m[q] * by[q] : 0.0;
            entries(q, [&](size_t k, double w, double gx, double gy) {
              g[0][k] += w * m[q];
              g[1][k] += w * m[q] * vx[q];
              g[2][k] += w * m[q] * vy[q];
              if constexpr (body) {
                g[3][k] += w * mbx - V[q] * (sx[q] * gx + sxy[q] * gy);
                g[4][k] += w * mby - V[q] * (sxy[q] * gx + sy[q] * gy);
              } else {
                g[3][k] -= V[q] * (sx[q] * gx + sxy[q] * gy);
                g[4][k] -= V[q] * (sxy[q] * gx + sy[q] * gy);
              }
            });
          },
          grid, buf, 5);
    }
    for (size_t k = 0; k < ng; ++k) {
      double inv = gm[k] > 1e-14 ? 1.0 / gm[k] : 0.0;
      gax[k] = gfx[k] * inv;
      gay[k] = gfy[k] * inv;
    }
    // G2P 1 and P2G 2 (MUSL), fused per particle as mpm does: v_p, then its momentum
    if constexpr (checks) sum_px = sum_py = sum_pn = 0;
    {
      std::vector<double>* grid[] = {&gpx, &gpy};
      std::vector<double>* buf[] = {&spx, &spy};
      scatter(
          [&](size_t q, double** g) {
            double ax = 0, ay = 0;
            entries(q, [&](size_t k, double w, double, double) {
              ax += w * gax[k];
              ay += w * gay[k];
            });
            vx[q] += dt * ax;
            vy[q] += dt * ay;
            const double mvx = m[q] * vx[q], mvy = m[q] * vy[q];
            if constexpr (checks) {
              sum_px += mvx, sum_py += mvy;
              sum_pn += m[q] * std::sqrt(vx[q] * vx[q] + vy[q] * vy[q]);
            }
            entries(q, [&](size_t k, double w, double, double) {
              g[0][k] += w * mvx;
              g[1][k] += w * mvy;
            });
          },
          grid, buf, 2);
    }
    for (size_t k = 0; k < ng; ++k) {
      double inv = gm[k] > 1e-14 ? 1.0 / gm[k] : 0.0;
      gvx[k] = gpx[k] * inv;
      gvy[k] = gpy[k] * inv;
    }
    // G2P 2: positions, velocity gradient, F, volume, neo-Hookean stress
    for (size_t q = 0; q < np; ++q) {
      double dux = 0, duy = 0, l00 = 0, l01 = 0, l10 = 0, l11 = 0;
      entries(q, [&](size_t k, double w, double gx, double gy) {
        dux += w * gvx[k];
        duy += w * gvy[k];
        l00 += gvx[k] * gx;
        l01 += gvx[k] * gy;
        l10 += gvy[k] * gx;
        l11 += gvy[k] * gy;
      });
      x[q] += dt * dux;
      y[q] += dt * duy;
      if constexpr (state) ux[q] += dt * dux, uy[q] += dt * duy;
      double* f = &F[4 * q];
      double a00 = 1 + dt * l00, a01 = dt * l01, a10 = dt * l10, a11 = 1 + dt * l11;
      double f00 = a00 * f[0] + a01 * f[2], f01 = a00 * f[1] + a01 * f[3];
      double f10 = a10 * f[0] + a11 * f[2], f11 = a10 * f[1] + a11 * f[3];
      f[0] = f00, f[1] = f01, f[2] = f10, f[3] = f11;
      double J = f00 * f11 - f01 * f10;
      if constexpr (state) {
        V[q] = J * V0[q];
        rho[q] = m[q] / V[q];
      } else {
        V[q] = J * (m[q] / rho0);
      }
      double lnJ = std::log(J), iJ = 1.0 / J;
      double b00 = f00 * f00 + f01 * f01, b11 = f10 * f10 + f11 * f11, b01 = f00 * f10 + f01 * f11;
      sx[q] = lam * lnJ * iJ + mu * iJ * (b00 - 1.0);
      sy[q] = lam * lnJ * iJ + mu * iJ * (b11 - 1.0);
      sxy[q] = mu * iJ * b01;
      if constexpr (checks) failed |= !(J > 0.0) || !std::isfinite(sx[q] + sy[q] + 2 * sxy[q]);
    }
  }
  double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  checksum = 0;
  for (size_t q = 0; q < np; q += 97) checksum += x[q] + sx[q] * 1e-9;
  if (checks) checksum += 1e-30 * (sum_m + sum_px + sum_py + sum_pn) + (failed ? 1.0 : 0.0);
  if (state) checksum += 1e-30 * (ux[0] + rho[0]);
  return sec * 1e9 / (double(np) * steps);
}

template <unsigned M = 0>
double dispatch(unsigned mask, int n, int ppc, int steps, double& chk) {
  if constexpr (M < 32) {
    if (mask == M) return run<M>(n, ppc, steps, chk);
    return dispatch<M + 1>(mask, n, ppc, steps, chk);
  } else {
    std::fprintf(stderr, "refkernel_gap: MASK must be 0..31, got %u\n", mask);
    std::exit(2);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr,
                 "usage: refkernel_gap CELLS PPC STEPS MASK (MASK 0..31, see the source)\n");
    return 2;
  }
  const int n = std::atoi(argv[1]), ppc = std::atoi(argv[2]), steps = std::atoi(argv[3]);
  const unsigned mask = unsigned(std::atoi(argv[4]));
  double chk = 0;
  const double ns = dispatch(mask, n, ppc, steps, chk);
  std::printf("mask %u ns_per_particle_step %.2f checksum %.6e\n", mask, ns, chk);
}
