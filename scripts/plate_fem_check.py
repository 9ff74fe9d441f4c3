#!/usr/bin/env python3
"""Second implementation for 001's plate at large amplitude: a total-Lagrangian finite-element
solution of the same manufactured problem, without particles, grid crossing or mappings.

Written for issue 22 (docs/verification.md, "The published convergence set-up of 001") to tell
whether the breakdown of the material point runs at A = 0.1 m is a property of those methods or
of the manufactured solution itself: if a plain FEM on a body-fitted mesh, whose only errors are
those of its elements and its time step, also departs from the exact solution exponentially, at
a rate that does not fall under refinement, the exact solution is dynamically unstable (its
perturbations grow), and no discretisation can track it for long.

Problem (001 eq. 38-42; plane strain, rollers on the four sides): unit square, neo-Hookean
P = mu (F - F^-T) + lambda ln(J) F^-T, rho0 = 1000 kg/m^3, E = 1e7 Pa, nu = 0.3,
u = (A sin(2 pi X) sin(w t), -A sin(2 pi Y) sin(w t)), w = pi c, c = sqrt(E / rho0) (001's c),
and the body force b = u_tt - Div P / rho0, evaluated here by central differences of P in X (no
closed form is used, so this script does not share mpmlab's derivation; --check compares the
two).

Discretisation: bilinear quadrilaterals (Q1) on an n x n mesh of the reference square, 2 x 2
Gauss points for the internal force, 3 x 3 for the body force, row-sum lumped mass, central
differences in time (u at whole steps, v at half steps), the rollers by zeroing the normal
acceleration. Output per run: the kinetic energy at the quarter periods (where the exact one is
zero: the energy of the error), divided by the exact largest kinetic energy, and, at the end or
at the first non-finite value, the RMS displacement error at the nodes and the largest |F_12|
(zero in the exact solution: the shear that the perturbation carries).

Usage:
    python3 scripts/plate_fem_check.py --cells 16 32 64 [--amplitude 0.1] [--end 0.2]
        [--dt 1e-5] [--perturb 1e-6] [--poisson 0.3] [--check] [--floquet PERIODS]
"""

import argparse
import math
import sys

import numpy as np

RHO0 = 1000.0
E = 1.0e7
NU = 0.3
LAM = E * NU / ((1 + NU) * (1 - 2 * NU))
MU = E / (2 * (1 + NU))
C = math.sqrt(E / RHO0)
W = math.pi * C  # 001: omega = c pi / L, L = 1
K = 2 * math.pi


def piola(F):
    """P(F) for an array of 2x2 matrices (..., 2, 2)."""
    J = F[..., 0, 0] * F[..., 1, 1] - F[..., 0, 1] * F[..., 1, 0]
    Finv_T = np.empty_like(F)
    Finv_T[..., 0, 0] = F[..., 1, 1] / J
    Finv_T[..., 1, 1] = F[..., 0, 0] / J
    Finv_T[..., 0, 1] = -F[..., 1, 0] / J
    Finv_T[..., 1, 0] = -F[..., 0, 1] / J
    return MU * (F - Finv_T) + (LAM * np.log(J))[..., None, None] * Finv_T, J


def exact_u(X, Y, t, A):
    s = math.sin(W * t)
    return A * np.sin(K * X) * s, -A * np.sin(K * Y) * s


def exact_v(X, Y, t, A):
    c = W * math.cos(W * t)
    return A * np.sin(K * X) * c, -A * np.sin(K * Y) * c


def exact_F(X, Y, t, A):
    s = math.sin(W * t)
    F = np.zeros(X.shape + (2, 2))
    F[..., 0, 0] = 1 + A * K * np.cos(K * X) * s
    F[..., 1, 1] = 1 - A * K * np.cos(K * Y) * s
    return F


def body_force(X, Y, t, A, eps=1e-6):
    """b = u_tt - Div P / rho0 with Div P by central differences of the exact P."""
    ux, uy = exact_u(X, Y, t, A)
    div = np.zeros(X.shape + (2,))
    Pxp, _ = piola(exact_F(X + eps, Y, t, A))
    Pxm, _ = piola(exact_F(X - eps, Y, t, A))
    Pyp, _ = piola(exact_F(X, Y + eps, t, A))
    Pym, _ = piola(exact_F(X, Y - eps, t, A))
    # (Div P)_i = dP_i0/dX + dP_i1/dY
    div[..., 0] = (Pxp[..., 0, 0] - Pxm[..., 0, 0] + Pyp[..., 0, 1] - Pym[..., 0, 1]) / (2 * eps)
    div[..., 1] = (Pxp[..., 1, 0] - Pxm[..., 1, 0] + Pyp[..., 1, 1] - Pym[..., 1, 1]) / (2 * eps)
    b = np.empty_like(div)
    b[..., 0] = -W * W * ux - div[..., 0] / RHO0
    b[..., 1] = -W * W * uy - div[..., 1] / RHO0
    return b


def closed_form_b(X, Y, t, A):
    """001 eq. 42 with pi^2 (METHODS.md errata), only for --check."""
    ux, uy = exact_u(X, Y, t, A)
    F = exact_F(X, Y, t, A)
    lnJ = np.log(F[..., 0, 0] * F[..., 1, 1])
    out = []
    for u, f in ((ux, F[..., 0, 0]), (uy, F[..., 1, 1])):
        dPdF = (LAM * (1 - lnJ) + MU) / f**2 + MU
        out.append(u * (K * K * dPdF / RHO0 - W * W))
    return np.stack(out, axis=-1)


def gauss(m):
    x, w = np.polynomial.legendre.leggauss(m)
    return x, w


def q1(xi, eta):
    """Q1 shape functions and reference derivatives, nodes (-1,-1),(1,-1),(1,1),(-1,1)."""
    sx = np.array([-1, 1, 1, -1.0])
    sy = np.array([-1, -1, 1, 1.0])
    N = 0.25 * (1 + sx * xi) * (1 + sy * eta)
    dxi = 0.25 * sx * (1 + sy * eta)
    deta = 0.25 * sy * (1 + sx * xi)
    return N, dxi, deta


class Mesh:
    """n x n Q1 elements on the unit square: nodes (i, j) -> i (n + 1) + j, the row-sum lumped
    mass, the roller flags, and Gauss rules (quadrature)."""

    def __init__(self, n):
        self.h = h = 1.0 / n
        self.nn = nn = n + 1
        xs = np.linspace(0, 1, nn)
        NX, NY = np.meshgrid(xs, xs, indexing="ij")
        self.NX, self.NY = NX.ravel(), NY.ravel()
        ii, jj = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        ii, jj = ii.ravel(), jj.ravel()
        self.conn = np.stack([ii * nn + jj, (ii + 1) * nn + jj, (ii + 1) * nn + jj + 1,
                              ii * nn + jj + 1], 1)
        self.flat = self.conn.ravel()
        ne = self.conn.shape[0]
        self.mass = np.bincount(self.flat, np.full(4 * ne, RHO0 * h * h / 4), minlength=nn * nn)
        self.fix_x = (self.NX < 1e-12) | (self.NX > 1 - 1e-12)
        self.fix_y = (self.NY < 1e-12) | (self.NY > 1 - 1e-12)

    def quadrature(self, m):
        """m x m Gauss points of every element: N (G, 4), dN/dX (G, 4, 2), weights (G,), and
        their reference positions X, Y (E, G)."""
        h = self.h
        g, w = gauss(m)
        x0, y0 = self.NX[self.conn[:, 0]], self.NY[self.conn[:, 0]]
        N, dN, wg, XG, YG = [], [], [], [], []
        for a, wa in zip(g, w):
            for b, wb in zip(g, w):
                Na, dxi, deta = q1(a, b)
                N.append(Na)
                dN.append(np.stack([dxi * 2 / h, deta * 2 / h], 1))
                wg.append(wa * wb * h * h / 4)
                XG.append(x0 + (a + 1) * h / 2)
                YG.append(y0 + (b + 1) * h / 2)
        return np.array(N), np.array(dN), np.array(wg), np.array(XG).T, np.array(YG).T

    def accelerations(self, fe):
        """Element forces (E, 4, 2) summed into the nodes, divided by the lumped mass, the
        normal components zeroed on the rollers."""
        nodes = self.nn * self.nn
        f = np.stack([np.bincount(self.flat, fe[..., d].ravel(), minlength=nodes)
                      for d in range(2)], 1)
        a = f / self.mass[:, None]
        a[self.fix_x, 0] = 0
        a[self.fix_y, 1] = 0
        return a


def run(n, A, T, dt, perturb, seed=1):
    mesh = Mesh(n)
    NX, NY, conn, mass = mesh.NX, mesh.NY, mesh.conn, mesh.mass
    fix_x, fix_y, nn = mesh.fix_x, mesh.fix_y, mesh.nn
    _, dN, wg, _, _ = mesh.quadrature(2)  # internal force
    N3, _, w3g, XG, YG = mesh.quadrature(3)  # body force, at fixed reference points

    def accel(u, t):
        ue = u[conn]  # (E, 4, 2)
        F = np.eye(2) + np.einsum("ead,gab->egdb", ue, dN)
        P, J = piola(F)
        if not np.all(J > 0) or not np.all(np.isfinite(P)):
            return None, F
        fe = -np.einsum("egdb,gab,g->ead", P, dN, wg)
        b = body_force(XG, YG, t, A)  # (E, G3, 2)
        fe += RHO0 * np.einsum("egd,ga,g->ead", b, N3, w3g)
        return mesh.accelerations(fe), F

    u = np.zeros((nn * nn, 2))
    v = np.stack(exact_v(NX, NY, 0.0, A), 1)
    if perturb > 0:
        rng = np.random.default_rng(seed)
        v += perturb * rng.standard_normal(v.shape)
        v[fix_x, 0] = 0
        v[fix_y, 1] = 0
    ke_max = 0.5 * RHO0 * A * A * W * W  # exact largest kinetic energy per metre of thickness
    steps = int(round(T / dt))
    a, F = accel(u, 0.0)
    vh = v + 0.5 * dt * a  # v at t = dt/2
    quarter = 0.25 * 2 * math.pi / W  # the exact velocity vanishes at odd multiples
    period = 2 * math.pi / W
    marks = {int(round((quarter + k * period / 2) / dt)): quarter + k * period / 2
             for k in range(int(T / (period / 2)) + 1)}
    energies = []
    stop = None
    for s in range(1, steps + 1):
        t = s * dt
        u += dt * vh
        a, F = accel(u, t)
        if a is None:
            stop = t
            break
        vn = vh + 0.5 * dt * a  # v at t
        if s in marks:
            energies.append((marks[s], 0.5 * np.sum(mass[:, None] * vn * vn) / ke_max))
        vh = vn + 0.5 * dt * a
    t_end = stop if stop is not None else steps * dt
    ux, uy = exact_u(NX, NY, t_end, A)
    err = np.sqrt(np.mean((u[:, 0] - ux) ** 2 + (u[:, 1] - uy) ** 2))
    shear = float(np.max(np.abs(F[..., 0, 1]))) if F is not None else float("nan")
    return energies, stop, err, shear


def dpiola(F, dF):
    """The directional derivative dP/dF [dF] of P at F, for arrays of 2x2 matrices."""
    J = F[..., 0, 0] * F[..., 1, 1] - F[..., 0, 1] * F[..., 1, 0]
    Fi = np.empty_like(F)  # F^-1
    Fi[..., 0, 0] = F[..., 1, 1] / J
    Fi[..., 1, 1] = F[..., 0, 0] / J
    Fi[..., 0, 1] = -F[..., 0, 1] / J
    Fi[..., 1, 0] = -F[..., 1, 0] / J
    FiT = np.swapaxes(Fi, -1, -2)
    # d(F^-T) = -F^-T dF^T F^-T, d(ln J) = tr(F^-1 dF)
    dFiT = -FiT @ np.swapaxes(dF, -1, -2) @ FiT
    tr = np.einsum("...ij,...ji->...", Fi, dF)
    return MU * (dF - dFiT) + LAM * (tr[..., None, None] * FiT + np.log(J)[..., None, None] * dFiT)


def floquet(n, A, periods, dt, seed=2):
    """Growth per period of perturbations of the exact solution: the FEM of the linearised
    equation rho0 w'' = Div(dP/dF(F_exact(X, t)) [Grad w]) (no body force: it does not depend on
    w), rollers, from a random start, renormalised every period. After the first periods the
    norm grows by the largest Floquet multiplier's modulus per period; returns those factors."""
    mesh = Mesh(n)
    fix_x, fix_y, mass, conn, nn = mesh.fix_x, mesh.fix_y, mesh.mass, mesh.conn, mesh.nn
    _, dN, wg, XG, YG = mesh.quadrature(2)

    def accel(w, t):
        dF = np.einsum("ead,gab->egdb", w[conn], dN)
        dP = dpiola(exact_F(XG, YG, t, A), dF)
        return mesh.accelerations(-np.einsum("egdb,gab,g->ead", dP, dN, wg))

    rng = np.random.default_rng(seed)
    w = np.zeros((nn * nn, 2))
    v = rng.standard_normal((nn * nn, 2))
    v[fix_x, 0] = 0
    v[fix_y, 1] = 0
    ref = W  # scales the displacement part of the norm to a velocity

    def norm(w, v):
        return math.sqrt(np.sum(mass[:, None] * (v * v + ref * ref * w * w)))

    steps = int(round(2 * math.pi / W / dt))
    scale = norm(w, v)
    w /= scale
    v /= scale
    factors = []
    t = 0.0
    for _ in range(periods):
        a = accel(w, t)
        for s in range(steps):
            v += 0.5 * dt * a
            w += dt * v
            t += dt
            a = accel(w, t)
            v += 0.5 * dt * a
        g = norm(w, v)
        factors.append(g)
        w /= g
        v /= g
    return factors


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cells", type=int, nargs="+", default=[16, 32, 64])
    ap.add_argument("--amplitude", type=float, default=0.1)
    ap.add_argument("--end", type=float, default=0.2)
    ap.add_argument("--dt", type=float, default=1e-5)
    ap.add_argument("--perturb", type=float, default=0.0,
                    help="standard deviation of a random initial velocity added [m/s]")
    ap.add_argument("--poisson", type=float, default=NU, help="Poisson's ratio (default 0.3)")
    ap.add_argument("--check", action="store_true",
                    help="compare the finite-difference body force with 001 eq. 42 (pi^2)")
    ap.add_argument("--floquet", type=int, default=0, metavar="PERIODS",
                    help="instead of the runs: growth per period of the linearised equation "
                    "about the exact solution, over this many periods")
    args = ap.parse_args()
    global LAM, MU
    LAM = E * args.poisson / ((1 + args.poisson) * (1 - 2 * args.poisson))
    MU = E / (2 * (1 + args.poisson))
    if args.floquet:
        print(f"A = {args.amplitude} m, nu = {args.poisson}, dt = {args.dt} s: growth of the "
              "linearised problem's norm per period")
        for n in args.cells:
            f = floquet(n, args.amplitude, args.floquet, args.dt)
            tail = f[len(f) // 2:]
            mean = math.exp(sum(math.log(x) for x in tail) / len(tail))
            print(f"n = {n}: " + ", ".join(f"{x:.3f}" for x in f) +
                  f"; geometric mean of the last {len(tail)}: {mean:.3f}")
            sys.stdout.flush()
        return
    if args.check:
        rng = np.random.default_rng(0)
        X, Y = rng.uniform(0.01, 0.99, 50), rng.uniform(0.01, 0.99, 50)
        for t in (0.003, 0.005, 0.013):
            bf, bc = body_force(X, Y, t, args.amplitude), closed_form_b(X, Y, t, args.amplitude)
            print(f"body force check t = {t}: max |b_fd - b_closed| / max |b| = "
                  f"{np.max(np.abs(bf - bc)) / np.max(np.abs(bc)):.2e}")
        F = np.eye(2) + 0.3 * rng.standard_normal((20, 2, 2))
        dF = rng.standard_normal((20, 2, 2))
        eps = 1e-6
        fd = (piola(F + eps * dF)[0] - piola(F - eps * dF)[0]) / (2 * eps)
        print(f"tangent check: max |dP_fd - dP| / max |dP| = "
              f"{np.max(np.abs(fd - dpiola(F, dF))) / np.max(np.abs(fd)):.2e}")
    print(f"A = {args.amplitude} m, T = {args.end} s, dt = {args.dt} s, perturbation "
          f"{args.perturb} m/s; kinetic energy at the quarter periods / exact largest")
    for n in args.cells:
        energies, stop, err, shear = run(n, args.amplitude, args.end, args.dt, args.perturb)
        per = [e for _, e in energies]
        growth = ""
        if len(per) >= 5:
            # per period = two quarter-period marks; first two and last two periods
            growth = (f"; growth per period, first two {math.sqrt(per[4] / per[0]):.2f}, "
                      f"last two {math.sqrt(per[-1] / per[-5]):.2f}")
        status = f"stops at t = {stop:.5f} s" if stop is not None else "reaches T"
        print(f"n = {n}: {status}; u RMS error {err:.3e} m; largest |F_12| {shear:.3e}{growth}")
        print("  " + ", ".join(f"t={t:.3f}: {e:.2e}" for t, e in energies))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
