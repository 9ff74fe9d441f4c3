// Reference kernel in 3D (issue 20, item 4): the smallest honest 3D explicit MUSL step with
// quadratic B-splines (uniform knots, padded grid, 27-node stencil), compressible neo-Hookean,
// double precision, one thread. It is the 3D analogue of the 2D yardstick
// ../shared/tools/refkernel.cpp, line for line: the same passes in the same order (P2G mass,
// momentum and internal force; grid accelerations; G2P velocity; the second momentum P2G of
// MUSL; grid velocities; G2P position, velocity gradient, F, volume, stress), the basis
// recomputed from x in every pass, particles in lattice order (x fastest). mpmlab's step on the
// same problem (`mpm bench --dim 3 --problem refkernel`) is compared with it in the same run by
// scripts/refkernel3d.sh.
//
// Problem: n^3 cells on the unit cube plus two padding cells per side (G = n + 4 nodes per side,
// the B-spline stencil of every particle is interior); PPC particles per cell (a perfect cube,
// s = cbrt(PPC) per direction) at the centres of the sub-cells; E = 1e7 Pa, nu = 0.3,
// rho0 = 1000 kg/m^3; v = (0.1 sin(2 pi x), -0.1 sin(2 pi y), 0.1 sin(2 pi z)) m/s with x, y, z
// from the cube's corner; F = I, sigma = 0; no body force, no boundary condition; dt = 1e-6 s.
// Stress: sigma = (mu (b - I) + lambda ln(J) I) / J, b = F F^T, as NeoHookean::update<3> in
// src/material/materials.hpp and, restricted to x-y, refkernel.cpp's plane-strain law.
//
// Build: g++ -O3 -march=native -DNDEBUG refkernel3d.cpp
// Usage: refkernel3d CELLS PPC STEPS   (default 32 8 10: 262,144 particles, the size of the 3D
//        bench in BENCHMARKS.md, `mpm bench --dim 3 --particles 262144 --steps 10`)
// Output, two lines on stdout (only the step loop is timed):
//   particles NP cells N^3 steps S ns_per_particle_step T checksum C
//     C: refkernel.cpp's sampled checksum, the sum over every 97th particle of x + y + z [m]
//        (padded coordinates) + 1e-9 (sxx + syy + szz) [Pa]
//   sums x SX y SY z SZ momentum P0x P0y P0z -> P1x P1y P1z scale M drift D
//     SX, SY, SZ: the particles' coordinates summed over all particles [m], 17 digits, to compare
//     two builds; P0, P1: total momentum sum_p m_p v_p before and after the steps [kg m/s];
//     M = sum_p m_p |v_p| before [kg m/s] (total mass 1000 kg); D = max_a |P1a - P0a| / M.
// Momentum (no body force, free boundaries; sum_i grad N_ip = 0 gives sum_i f_i = 0, so the
// particles' momentum changes by round-off only; the initial field is odd about the cube's
// centre, so P0 is round-off too), measured with this file: `32 8 10` P0 = (-6.3e-19, 1.8e-17,
// -6.3e-14) -> P1 = (1.3e-16, 1.2e-15, -7.1e-15), M = 119.38, D = 4.7e-16; `64 8 10` D = 5.9e-17;
// `32 27 100` D = 4.1e-17. A copy with 0.05 m/s added to vx (P0x = 50 kg m/s), `32 8 100`:
// P1x - P0x = 2.6e-13 kg m/s (5e-15 of P0x), D = 2.0e-15, and the sum of x grew by 1.31072 m =
// 262144 x 0.05 m/s x 1e-4 s. Stress after one step at an interior particle against the exact
// sigma(F = I + dt grad v) of the initial field: 3.9 % off on 16^3 cells, 1.0 % on 32^3 (O(h^2)).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

struct W {
  double w[3], dw[3];
  int base;
};

static inline W weights(double xg) {  // xg: position in cell units
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

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 32;
  const int ppc = argc > 2 ? std::atoi(argv[2]) : 8;
  const int steps = argc > 3 ? std::atoi(argv[3]) : 10;
  const double L = 1.0, h = L / n, inv_h = 1.0 / h, dt = 1e-6;
  const double E = 1e7, nu = 0.3, rho0 = 1000.0;
  const double mu = E / (2 * (1 + nu)), lam = E * nu / ((1 + nu) * (1 - 2 * nu));
  const int pad = 2, G = n + 2 * pad;  // padded grid nodes per side
  const int s = int(std::lround(std::cbrt(double(ppc))));
  if (n < 1 || steps < 1 || s < 1 || s * s * s != ppc) {
    std::fprintf(stderr,
                 "usage: refkernel3d CELLS PPC STEPS (PPC a perfect cube: 1, 8, 27, ...)\n");
    return 2;
  }
  const size_t np = size_t(n) * n * n * s * s * s;
  std::vector<double> x(np), y(np), z(np), vx(np), vy(np), vz(np), F(9 * np), V(np), m(np);
  std::vector<double> sxx(np), syy(np), szz(np), sxy(np), syz(np), sxz(np);
  size_t p = 0;
  for (int l = 0; l < n * s; ++l)
    for (int j = 0; j < n * s; ++j)
      for (int i = 0; i < n * s; ++i, ++p) {
        x[p] = (i + 0.5) * h / s + pad * h;
        y[p] = (j + 0.5) * h / s + pad * h;
        z[p] = (l + 0.5) * h / s + pad * h;
        vx[p] = 0.1 * std::sin(2 * M_PI * (x[p] - pad * h));
        vy[p] = -0.1 * std::sin(2 * M_PI * (y[p] - pad * h));
        vz[p] = 0.1 * std::sin(2 * M_PI * (z[p] - pad * h));
        double* f = &F[9 * p];
        for (int c = 0; c < 9; ++c) f[c] = (c % 4 == 0) ? 1.0 : 0.0;  // F = I (row-major)
        V[p] = h * h * h / (s * s * s);
        m[p] = rho0 * V[p];
        sxx[p] = syy[p] = szz[p] = sxy[p] = syz[p] = sxz[p] = 0.0;
      }
  // Initial momentum and its scale, for the conservation line (not timed).
  double P0[3] = {0, 0, 0}, scale = 0;
  for (size_t q = 0; q < np; ++q) {
    P0[0] += m[q] * vx[q];
    P0[1] += m[q] * vy[q];
    P0[2] += m[q] * vz[q];
    scale += m[q] * std::sqrt(vx[q] * vx[q] + vy[q] * vy[q] + vz[q] * vz[q]);
  }
  const size_t ng = size_t(G) * G * G;
  std::vector<double> gm(ng), gpx(ng), gpy(ng), gpz(ng), gfx(ng), gfy(ng), gfz(ng);
  std::vector<double> gvx(ng), gvy(ng), gvz(ng), gax(ng), gay(ng), gaz(ng);
  auto t0 = std::chrono::steady_clock::now();
  for (int st = 0; st < steps; ++st) {
    std::fill(gm.begin(), gm.end(), 0.0);
    std::fill(gpx.begin(), gpx.end(), 0.0);
    std::fill(gpy.begin(), gpy.end(), 0.0);
    std::fill(gpz.begin(), gpz.end(), 0.0);
    std::fill(gfx.begin(), gfx.end(), 0.0);
    std::fill(gfy.begin(), gfy.end(), 0.0);
    std::fill(gfz.begin(), gfz.end(), 0.0);
    // P2G: mass, momentum, internal force
    for (size_t q = 0; q < np; ++q) {
      W wx = weights(x[q] * inv_h), wy = weights(y[q] * inv_h), wz = weights(z[q] * inv_h);
      for (int c = 0; c < 3; ++c)
        for (int b = 0; b < 3; ++b)
          for (int a = 0; a < 3; ++a) {
            size_t k = (size_t(wz.base + c) * G + (wy.base + b)) * G + (wx.base + a);
            double w = wx.w[a] * wy.w[b] * wz.w[c];
            double gx = wx.dw[a] * wy.w[b] * wz.w[c] * inv_h;
            double gy = wx.w[a] * wy.dw[b] * wz.w[c] * inv_h;
            double gz = wx.w[a] * wy.w[b] * wz.dw[c] * inv_h;
            gm[k] += w * m[q];
            gpx[k] += w * m[q] * vx[q];
            gpy[k] += w * m[q] * vy[q];
            gpz[k] += w * m[q] * vz[q];
            gfx[k] -= V[q] * (sxx[q] * gx + sxy[q] * gy + sxz[q] * gz);
            gfy[k] -= V[q] * (sxy[q] * gx + syy[q] * gy + syz[q] * gz);
            gfz[k] -= V[q] * (sxz[q] * gx + syz[q] * gy + szz[q] * gz);
          }
    }
    // grid: accelerations (nodes without mass get none)
    for (size_t k = 0; k < ng; ++k) {
      double inv = gm[k] > 1e-14 ? 1.0 / gm[k] : 0.0;
      gax[k] = gfx[k] * inv;
      gay[k] = gfy[k] * inv;
      gaz[k] = gfz[k] * inv;
    }
    // G2P 1: particle velocity update; clear momentum for the second transfer
    for (size_t q = 0; q < np; ++q) {
      W wx = weights(x[q] * inv_h), wy = weights(y[q] * inv_h), wz = weights(z[q] * inv_h);
      double ax = 0, ay = 0, az = 0;
      for (int c = 0; c < 3; ++c)
        for (int b = 0; b < 3; ++b)
          for (int a = 0; a < 3; ++a) {
            size_t k = (size_t(wz.base + c) * G + (wy.base + b)) * G + (wx.base + a);
            double w = wx.w[a] * wy.w[b] * wz.w[c];
            ax += w * gax[k];
            ay += w * gay[k];
            az += w * gaz[k];
          }
      vx[q] += dt * ax;
      vy[q] += dt * ay;
      vz[q] += dt * az;
    }
    std::fill(gpx.begin(), gpx.end(), 0.0);
    std::fill(gpy.begin(), gpy.end(), 0.0);
    std::fill(gpz.begin(), gpz.end(), 0.0);
    // P2G 2 (MUSL): momentum from updated particle velocities
    for (size_t q = 0; q < np; ++q) {
      W wx = weights(x[q] * inv_h), wy = weights(y[q] * inv_h), wz = weights(z[q] * inv_h);
      for (int c = 0; c < 3; ++c)
        for (int b = 0; b < 3; ++b)
          for (int a = 0; a < 3; ++a) {
            size_t k = (size_t(wz.base + c) * G + (wy.base + b)) * G + (wx.base + a);
            double w = wx.w[a] * wy.w[b] * wz.w[c];
            gpx[k] += w * m[q] * vx[q];
            gpy[k] += w * m[q] * vy[q];
            gpz[k] += w * m[q] * vz[q];
          }
    }
    for (size_t k = 0; k < ng; ++k) {
      double inv = gm[k] > 1e-14 ? 1.0 / gm[k] : 0.0;
      gvx[k] = gpx[k] * inv;
      gvy[k] = gpy[k] * inv;
      gvz[k] = gpz[k] * inv;
    }
    // G2P 2: positions, velocity gradient, F, volume, neo-Hookean stress
    for (size_t q = 0; q < np; ++q) {
      W wx = weights(x[q] * inv_h), wy = weights(y[q] * inv_h), wz = weights(z[q] * inv_h);
      double ux = 0, uy = 0, uz = 0;
      double l00 = 0, l01 = 0, l02 = 0, l10 = 0, l11 = 0, l12 = 0, l20 = 0, l21 = 0, l22 = 0;
      for (int c = 0; c < 3; ++c)
        for (int b = 0; b < 3; ++b)
          for (int a = 0; a < 3; ++a) {
            size_t k = (size_t(wz.base + c) * G + (wy.base + b)) * G + (wx.base + a);
            double w = wx.w[a] * wy.w[b] * wz.w[c];
            double gx = wx.dw[a] * wy.w[b] * wz.w[c] * inv_h;
            double gy = wx.w[a] * wy.dw[b] * wz.w[c] * inv_h;
            double gz = wx.w[a] * wy.w[b] * wz.dw[c] * inv_h;
            ux += w * gvx[k];
            uy += w * gvy[k];
            uz += w * gvz[k];
            // clang-format off
            l00 += gvx[k] * gx; l01 += gvx[k] * gy; l02 += gvx[k] * gz;
            l10 += gvy[k] * gx; l11 += gvy[k] * gy; l12 += gvy[k] * gz;
            l20 += gvz[k] * gx; l21 += gvz[k] * gy; l22 += gvz[k] * gz;
            // clang-format on
          }
      x[q] += dt * ux;
      y[q] += dt * uy;
      z[q] += dt * uz;
      // F <- (I + dt L) F, row-major
      double* f = &F[9 * q];
      double a00 = 1 + dt * l00, a01 = dt * l01, a02 = dt * l02;
      double a10 = dt * l10, a11 = 1 + dt * l11, a12 = dt * l12;
      double a20 = dt * l20, a21 = dt * l21, a22 = 1 + dt * l22;
      double f00 = a00 * f[0] + a01 * f[3] + a02 * f[6], f01 = a00 * f[1] + a01 * f[4] + a02 * f[7],
             f02 = a00 * f[2] + a01 * f[5] + a02 * f[8];
      double f10 = a10 * f[0] + a11 * f[3] + a12 * f[6], f11 = a10 * f[1] + a11 * f[4] + a12 * f[7],
             f12 = a10 * f[2] + a11 * f[5] + a12 * f[8];
      double f20 = a20 * f[0] + a21 * f[3] + a22 * f[6], f21 = a20 * f[1] + a21 * f[4] + a22 * f[7],
             f22 = a20 * f[2] + a21 * f[5] + a22 * f[8];
      // clang-format off
      f[0] = f00; f[1] = f01; f[2] = f02;
      f[3] = f10; f[4] = f11; f[5] = f12;
      f[6] = f20; f[7] = f21; f[8] = f22;
      // clang-format on
      double J = f00 * (f11 * f22 - f12 * f21) - f01 * (f10 * f22 - f12 * f20) +
                 f02 * (f10 * f21 - f11 * f20);
      V[q] = J * (m[q] / rho0);
      double lnJ = std::log(J), iJ = 1.0 / J;
      // b = F F^T (symmetric: six entries)
      double b00 = f00 * f00 + f01 * f01 + f02 * f02, b11 = f10 * f10 + f11 * f11 + f12 * f12;
      double b22 = f20 * f20 + f21 * f21 + f22 * f22, b01 = f00 * f10 + f01 * f11 + f02 * f12;
      double b12 = f10 * f20 + f11 * f21 + f12 * f22, b02 = f00 * f20 + f01 * f21 + f02 * f22;
      sxx[q] = lam * lnJ * iJ + mu * iJ * (b00 - 1.0);
      syy[q] = lam * lnJ * iJ + mu * iJ * (b11 - 1.0);
      szz[q] = lam * lnJ * iJ + mu * iJ * (b22 - 1.0);
      sxy[q] = mu * iJ * b01;
      syz[q] = mu * iJ * b12;
      sxz[q] = mu * iJ * b02;
    }
  }
  double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double chk = 0;
  for (size_t q = 0; q < np; q += 97) chk += x[q] + y[q] + z[q] + (sxx[q] + syy[q] + szz[q]) * 1e-9;
  std::printf("particles %zu cells %zu steps %d ns_per_particle_step %.2f checksum %.6e\n", np,
              size_t(n) * n * n, steps, sec * 1e9 / (double(np) * steps), chk);
  // Sums and momentum over all particles (not timed): see the header for the format.
  double SX = 0, SY = 0, SZ = 0, P1[3] = {0, 0, 0};
  for (size_t q = 0; q < np; ++q) {
    SX += x[q];
    SY += y[q];
    SZ += z[q];
    P1[0] += m[q] * vx[q];
    P1[1] += m[q] * vy[q];
    P1[2] += m[q] * vz[q];
  }
  double drift = std::fmax(std::fabs(P1[0] - P0[0]),
                           std::fmax(std::fabs(P1[1] - P0[1]), std::fabs(P1[2] - P0[2]))) /
                 scale;
  std::printf(
      "sums x %.17g y %.17g z %.17g momentum %.3e %.3e %.3e -> %.3e %.3e %.3e scale %.6e drift "
      "%.2e\n",
      SX, SY, SZ, P0[0], P0[1], P0[2], P1[0], P1[1], P1[2], scale, drift);
}
