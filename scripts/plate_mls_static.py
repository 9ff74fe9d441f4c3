#!/usr/bin/env python3
"""How well can 001's MLS reconstruct the density of the plate at its largest deformation?

Static check, no time stepping: the particles are placed where the manufactured solution of
`plate_mms_2d` (001 eq. 38, A = 0.1 m) puts them at sin(omega t) = s (default 1, the largest
deformation), with 3 x 3 particles per cell of the reference configuration and the exact
density rho0 / J. The density is reconstructed with MLS as in 001 eq. 14-17 (basis [1, x, y],
quadratic-spline weight r = |x - x_p| / (a l) per direction, tensor product; a = 2 in 001) at
2 x 2 Gauss points per cell, and integrated as in 001 eq. 22 (sum over Gauss points of
rho_g w_g = the total lumped mass, by the partition of unity of the B-splines). Prints the
relative mass error and the RMS density error at the Gauss points (against the exact density
there, found by inverting x(X) per direction with Newton's method).

    /usr/bin/python3 scripts/plate_mls_static.py [--s 1.0] [--dilation 2]   (a few seconds)
"""
import argparse

import numpy as np

A, RHO0, L = 0.1, 1000.0, 1.0


def weight(r):
    """001 eq. 17: the quadratic spline, nonzero for |r| < 3/2."""
    r = np.abs(r)
    w = np.zeros_like(r)
    inner = r <= 0.5
    outer = (r > 0.5) & (r < 1.5)
    w[inner] = 0.75 - r[inner] ** 2
    w[outer] = 0.5 * (1.5 - r[outer]) ** 2
    return w


def stretch(X, s, sign):
    """F_dd of 001 eq. 38: 1 + sign 2 pi A cos(2 pi X / L) s / L."""
    return 1.0 + sign * 2.0 * np.pi * A / L * np.cos(2.0 * np.pi * X / L) * s


def position(X, s, sign):
    return X + sign * A * np.sin(2.0 * np.pi * X / L) * s


def reference(x, s, sign):
    """X with position(X) = x (monotone for 2 pi A < 1), by Newton's method."""
    X = x.copy()
    for _ in range(60):
        X -= (position(X, s, sign) - x) / stretch(X, s, sign)
    return X


def study(cells, s, dilation, per_cell=3):
    h = L / cells
    g = (np.arange(cells * per_cell) + 0.5) / (cells * per_cell) * L
    X, Y = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    x, y = position(X, s, +1), position(Y, s, -1)  # u_y has the opposite sign (001 eq. 38)
    rho = RHO0 / (stretch(X, s, +1) * stretch(Y, s, -1))
    mass = RHO0 * L * L
    gp = np.array([-1.0, 1.0]) / np.sqrt(3.0)
    line = ((np.arange(cells) + 0.5) * h)[:, None] + 0.5 * h * gp[None, :]
    XG, YG = (a.ravel() for a in np.meshgrid(line.ravel(), line.ravel(), indexing="ij"))
    wg = (0.5 * h) ** 2
    total, sq = 0.0, 0.0
    for b in range(0, XG.size, 256):
        xg, yg = XG[b:b + 256, None], YG[b:b + 256, None]
        # Only the particles within the support of some point of this batch (same x column).
        near = np.abs(x - xg.mean()) < 1.5 * dilation * h + np.ptp(xg)
        xn, yn, rn = x[near], y[near], rho[near]
        w = weight((xg - xn) / (dilation * h)) * weight((yg - yn) / (dilation * h))
        P = np.stack([np.ones_like(w), (xn - xg) / h, (yn - yg) / h], axis=-1)
        Am = np.einsum("gp,gpi,gpj->gij", w, P, P)  # 001 eq. 10
        Bm = np.einsum("gp,gpi,p->gi", w, P, rn)
        rho_g = np.linalg.solve(Am, Bm)[:, 0]  # p(x_g) = e_1 in shifted coordinates
        total += rho_g.sum() * wg
        exact = RHO0 / (stretch(reference(xg[:, 0], s, +1), s, +1) *
                        stretch(reference(yg[:, 0], s, -1), s, -1))
        sq += ((rho_g - exact) ** 2).sum()
    return abs(total - mass) / mass, np.sqrt(sq / XG.size) / RHO0, rho.min(), rho.max()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--s", type=float, default=1.0, help="sin(omega t) of the configuration")
    ap.add_argument("--dilation", type=float, default=2.0, help="a in r = dx / (a l) (001: 2)")
    args = ap.parse_args()
    print(f"plate_mms_2d, A = {A} m, sin(omega t) = {args.s}, MLS dilation a = {args.dilation}:\n")
    print("| cells | relative mass error | RMS density error / rho0 | particle density range |")
    print("|---|---|---|---|")
    prev = None
    for cells in (8, 16, 32, 64):
        m, r, lo, hi = study(cells, args.s, args.dilation)
        order = "" if prev is None else f" ({np.log(prev / m) / np.log(2.0):.2f})"
        print(f"| {cells} | {m:.3e}{order} | {r:.3e} | {lo:.0f} - {hi:.0f} kg/m^3 |")
        prev = m


if __name__ == "__main__":
    main()
