#!/usr/bin/env python3
"""The vibration spectrum of the column of docs/verification.md ("PS-MPM with partially filled
elements": examples/custom_plate_2d.toml, 0.2 m x 1.0 m on a grid of 0.2 m x 1.1 m, rollers on
the sides, fixed bottom, free top) with quadratic B-splines, written independently of mpmlab
(numpy only): the open-knot B2 basis per direction, the initial particles (n x n per cell at
(k + 1/2) / n), the stiffness sum_p V_p B^T D B (plane strain, linear elastic) and the mass
sum_p m_p N N^T, consistent or lumped (row sums), on the control points the particles reach.

It prints the highest frequencies of K u = omega^2 M u and, for each, the share of the mode's
kinetic energy (u^T M u) carried by the control points within two of a side and of the body's
top: where the mode lives. With --compare FILE (a particles_*.csv frame of mpm run), also the
frame's velocity field in these modes: the control-point velocities that fit the particle
velocities best (least squares, the particles at their initial positions), expanded in the
M-orthonormal modes of the mass matrix, and the modes that carry most of its kinetic energy.
Used by the section on what stops B2-TLS with consistent mass: the growing mode of that run is
compared with these.

    scripts/column_modes.py [--cells 4] [--per-cell 4] [--top 1.0] [--modes 6] [--compare F]
                            [--json OUT]
"""
import argparse
import csv
import json

import numpy as np


def open_knots(lo, hi, cells, p):
    inner = np.linspace(lo, hi, cells + 1)
    return np.concatenate([[lo] * p, inner, [hi] * p])


def bspline(knots, p, x):
    """Values and derivatives of all B-splines of degree p at x (Cox-de Boor)."""
    n = len(knots) - p - 1
    # Degree 0 on the span holding x (the last span holds its right end).
    span = min(np.searchsorted(knots, x, side="right") - 1, len(knots) - p - 2)
    N = np.zeros(len(knots) - 1)
    N[span] = 1.0
    for k in range(1, p + 1):
        M = np.zeros(len(knots) - 1 - k)
        for i in range(len(M)):
            a = knots[i + k] - knots[i]
            b = knots[i + k + 1] - knots[i + 1]
            M[i] = ((x - knots[i]) / a * N[i] if a > 0 else 0.0) + (
                (knots[i + k + 1] - x) / b * N[i + 1] if b > 0 else 0.0)
        if k == p:
            dN = np.zeros(n)
            for i in range(n):
                a = knots[i + p] - knots[i]
                b = knots[i + p + 1] - knots[i + 1]
                dN[i] = (p / a * N[i] if a > 0 else 0.0) - (p / b * N[i + 1] if b > 0 else 0.0)
        N = M
    return N[:n], dN


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cells", type=int, default=4, help="cells across the 0.2 m width")
    ap.add_argument("--per-cell", type=int, default=4, help="particles per cell and direction")
    ap.add_argument("--top", type=float, default=1.0, help="the body's top [m]")
    ap.add_argument("--modes", type=int, default=6, help="highest modes to print")
    ap.add_argument("--compare", help="a particles_*.csv frame whose velocities to compare")
    ap.add_argument("--json", help="also write the figures printed to this file")
    a = ap.parse_args()
    E, nu, rho, p = 1.0e6, 0.3, 1000.0, 2
    h = 0.2 / a.cells
    ny = round(1.1 / h)
    kx, ky = open_knots(0.0, 0.2, a.cells, p), open_knots(0.0, 1.1, ny, p)
    nx_c, ny_c = a.cells + p, ny + p  # control points per direction
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    D = np.array([[lam + 2 * mu, lam, 0], [lam, lam + 2 * mu, 0], [0, 0, mu]])
    n = 2 * nx_c * ny_c
    K, M = np.zeros((n, n)), np.zeros((n, n))
    k = a.per_cell
    V = h * h / k ** 2
    rows = round(a.top / h * k)  # particle rows (the top at a cell face or inside a cell)
    for jx in range(a.cells * k):
        for jy in range(rows):
            x, y = (jx + 0.5) * h / k, (jy + 0.5) * h / k
            if y > a.top:
                continue
            Nx, dNx = bspline(kx, p, x)
            Ny, dNy = bspline(ky, p, y)
            ids, Nv, B = [], [], []
            for i in np.nonzero(Nx)[0]:
                for j in np.nonzero(Ny)[0]:
                    ids.append(i + nx_c * j)
                    Nv.append(Nx[i] * Ny[j])
                    B.append((dNx[i] * Ny[j], Nx[i] * dNy[j]))
            dof = np.array([[2 * c, 2 * c + 1] for c in ids]).ravel()
            Bm = np.zeros((3, len(dof)))
            for q, (gx, gy) in enumerate(B):
                Bm[:, 2 * q] = (gx, 0, gy)
                Bm[:, 2 * q + 1] = (0, gy, gx)
            K[np.ix_(dof, dof)] += V * Bm.T @ D @ Bm
            Nm = np.zeros((2, len(dof)))
            Nm[0, 0::2] = Nv
            Nm[1, 1::2] = Nv
            M[np.ix_(dof, dof)] += rho * V * Nm.T @ Nm
    # Constraints: rollers (u_x = 0 on the first and last control column), fixed bottom row.
    keep = np.diag(M) > 0
    for c in range(nx_c * ny_c):
        i, j = c % nx_c, c // nx_c
        if i in (0, nx_c - 1):
            keep[2 * c] = False
        if j == 0:
            keep[2 * c] = keep[2 * c + 1] = False
    K, M = K[np.ix_(keep, keep)], M[np.ix_(keep, keep)]
    # The frame's particles: velocities, and the map from kept DOFs to velocities there.
    if a.compare:
        with open(a.compare, newline="") as f:
            frame = list(csv.DictReader(f))
        vel = np.array([[float(r["v_1"]), float(r["v_2"])] for r in frame]).ravel()
        at = np.zeros((vel.size, n))
        for q, r in enumerate(frame):
            Nx, _ = bspline(kx, p, float(r["x0_1"]))
            Ny, _ = bspline(ky, p, float(r["x0_2"]))
            for i in np.nonzero(Nx)[0]:
                for j in np.nonzero(Ny)[0]:
                    c = i + nx_c * j
                    at[2 * q, 2 * c] = at[2 * q + 1, 2 * c + 1] = Nx[i] * Ny[j]
        at = at[:, keep]
    ctrl = np.nonzero(keep)[0] // 2
    ci, cj = ctrl % nx_c, ctrl // nx_c
    top_row = max(cj)
    corner = ((ci <= 1) | (ci >= nx_c - 2)) & (cj >= top_row - 1)
    c_p = np.sqrt((lam + 2 * mu) / rho)
    print(f"column 0.2 m x {a.top} m, B2, {a.cells} cells across (h = {h:g} m), "
          f"{k} x {k} particles per cell; c_P = {c_p:.4g} m/s, c_P / h = {c_p / h:.4g} 1/s")
    out = {"h": h, "c_P": c_p}
    for name, Mx in (("consistent", M), ("lumped", np.diag(M.sum(axis=1)))):
        res = out[name] = {"highest": [], "frame": None}
        L = np.linalg.cholesky(Mx)
        Li = np.linalg.inv(L)
        w2, Y = np.linalg.eigh(Li @ K @ Li.T)
        U = Li.T @ Y  # M-orthonormal modes
        print(f"{name}: highest frequencies [Hz] and the share of each mode's kinetic energy "
              f"in the top corners (control points within two of a side and of the top)")
        for m in range(1, a.modes + 1):
            u = U[:, -m]
            e = u * (Mx @ u)
            share = e[corner].sum() / e.sum()
            res["highest"].append({"hz": np.sqrt(w2[-m]) / (2 * np.pi), "top_corners": share})
            print(f"  {np.sqrt(w2[-m]) / (2 * np.pi):8.1f} Hz  ({np.sqrt(w2[-m]) * h / c_p:.2f} "
                  f"c_P / h)  top corners {share:.2f}")
        if a.compare:
            v = np.linalg.lstsq(at, vel, rcond=None)[0]
            c = U.T @ (Mx @ v)
            e = c * c / (c @ c)
            f = np.sqrt(np.maximum(w2, 0.0)) / (2 * np.pi)
            fit = np.linalg.norm(at @ v - vel) / np.linalg.norm(vel)
            print(f"  the frame's velocities (fitted to {fit:.2g} relative) in these modes: "
                  f"kinetic energy above {f.max() / 2:.1f} Hz (half the highest) {e[f > f.max() / 2].sum():.3f}; "
                  f"the modes with most of it:")
            res["frame"] = {"fit": fit, "above_half": e[f > f.max() / 2].sum(), "modes": []}
            for m in np.argsort(-e)[:5]:
                u = U[:, m]
                eu = u * (Mx @ u)
                res["frame"]["modes"].append({"hz": f[m], "share": e[m],
                                              "top_corners": eu[corner].sum() / eu.sum()})
                print(f"  mode {f[m]:8.1f} Hz  ({f[m] * 2 * np.pi * h / c_p:.2f} c_P / h)  "
                      f"energy share {e[m]:.3f}  top corners {eu[corner].sum() / eu.sum():.2f}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1, default=float)


if __name__ == "__main__":
    main()
