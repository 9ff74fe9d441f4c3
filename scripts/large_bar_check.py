#!/usr/bin/env python3
"""Independent check of the large-deformation vibrating bar (D 5.4.1): MUSL-MPM stress errors.

A second, self-contained implementation (numpy/scipy only, written without reading the C++ of
this project) of the benchmark of D 5.4.1 / Table 5.4: a bar on [0, 1] m with both ends fixed,
rho0 = 2000 kg/m^3, E = 4e4 Pa, sigma = E (1 - 1/F) advanced in rate form
sigma += (E - sigma) dt L_p (004 eq. 4.16), u = 0, sigma = 0, v(X, 0) = v0 sin(pi X), v0 = 0.8
m/s, T = 0.1 s. MUSL (D Algorithm 2) with direct mapping (plain particle sums), Euler-Cromer,
8 particles per cell at the cell-centred positions (j + 1/2) h / 8, m_p = rho0 h / 8,
V_p = F_p h / 8; n = 10, 20, 40, 80 cells; dt = 1e-4 s (and 2.5e-5 s for n = 20). Two bases,
both from one Cox-de Boor routine on an open uniform knot vector: P1 (degree 1, n + 1 hats,
nodes 0 and n fixed) and B2 (degree 2, n + 2 C^1 B-splines, first and last coefficient fixed);
two mass matrices: lumped (row sums) and consistent (solved on the free coefficients only).

Reference: a total-Lagrangian FEM of rho0 u_tt = dP/dX, P = E (1 - 1/F), F = 1 + u_X (linear
elements, lumped mass, central differences, nodal initial velocity v0 sin(pi X_i), Courant
number <= 0.5 on the tangent wave speed sqrt(E / rho0) / F), run with 1000 ... 8000 elements;
the finest one is the reference. sigma_ref(X) is the element stress linearly interpolated
between the element centres (material coordinates).

Error at T: e = sqrt(sum_p V0_p (sigma_p - sigma_ref(X_p))^2 / sum_p V0_p sigma_ref(X_p)^2)
with X_p the material position, over all particles and over the interior ones (X_p at least
2 cells from both ends). Also a one-projection check at t = 0 (no time stepping): v_p =
sin(pi x_p), grid velocity by the lumped and the consistent projection, L_p = sum_i N_i,x v_i,
relative RMS error against pi cos(pi x_p) over the interior particles.

Prints Markdown tables: (1) MPM stress errors and observed orders, the n = 20 table with the
ratio "P1 lumped / this" at both time steps; (2) the projection check; (3) the reference
self-convergence.

    /usr/bin/python3 scripts/large_bar_check.py [--cells 20 ...] [--no-fine-dt]
        [--ref 1000 2000 4000 8000] [--v0 0.8] [--json FILE]     (about 45 s for the defaults)

--v0 0.008 is a sanity check of the implementation: the particles then move less than their
spacing (no cell crossing) and the errors converge (P1 order 1, B2 consistent order 2).
"""
import argparse
import json
import time

import numpy as np
from scipy.linalg import cho_factor, cho_solve

L, RHO0, E, V0, T = 1.0, 2000.0, 4.0e4, 0.8, 0.1
PPC = 8
DEGREE = {"P1": 1, "B2": 2}


# ---------------------------------------------------------------------------------------------
# Basis: B-splines of degree p on the open uniform knot vector {0 (p+1 times), h, ..., 1 (p+1)}
# (p = 1 gives the P1 hat functions on the grid nodes).
def knots(n, p):
    return np.concatenate([np.zeros(p), np.linspace(0.0, L, n + 1), np.full(p, L)])


def basis(x, n, p):
    """Cox-de Boor (NURBS book A2.2) vectorised over x. Returns (idx, N, dN), each (len(x), p+1):
    the indices of the p + 1 functions that can be nonzero at x, their values and derivatives."""
    t = knots(n, p)
    cell = np.clip(np.floor(x / L * n).astype(int), 0, n - 1)
    span = cell + p  # t[span] <= x < t[span + 1]
    m = x.size

    def values(q):
        Nq = np.zeros((m, q + 1))
        Nq[:, 0] = 1.0
        left = np.zeros((m, q + 1))
        right = np.zeros((m, q + 1))
        for j in range(1, q + 1):
            left[:, j] = x - t[span + 1 - j]
            right[:, j] = t[span + j] - x
            saved = np.zeros(m)
            for r in range(j):
                tmp = Nq[:, r] / (right[:, r + 1] + left[:, j - r])
                Nq[:, r] = saved + right[:, r + 1] * tmp
                saved = left[:, j - r] * tmp
            Nq[:, j] = saved
        return Nq  # functions span - q ... span

    N = values(p)
    Nm1 = values(p - 1)  # degree p - 1: functions span - p + 1 ... span
    # N'_{k,p} = p N_{k,p-1} / (t_{k+p} - t_k) - p N_{k+1,p-1} / (t_{k+p+1} - t_{k+1})
    ext = np.zeros((m, p + 2))
    ext[:, 1:p + 1] = Nm1  # ext[:, r] = N_{span-p+r, p-1}; r = 0 and p + 1 are zero
    dN = np.zeros((m, p + 1))
    for r in range(p + 1):
        k = span - p + r
        d1 = t[k + p] - t[k]
        d2 = t[k + p + 1] - t[k + 1]
        a = np.where(d1 > 0, ext[:, r] / np.where(d1 > 0, d1, 1.0), 0.0)
        b = np.where(d2 > 0, ext[:, r + 1] / np.where(d2 > 0, d2, 1.0), 0.0)
        dN[:, r] = p * (a - b)
    idx = span[:, None] - p + np.arange(p + 1)[None, :]
    return idx, N, dN


def dense(idx, vals, nb):
    A = np.zeros((idx.shape[0], nb))
    np.put_along_axis(A, idx, vals, axis=1)
    return A


def self_test():
    """Partition of unity, linear reproduction (Greville abscissae), derivative against finite
    differences, and P1 against the closed-form hats. Raises on failure."""
    rng = np.random.default_rng(1)
    out = {}
    for name, p in DEGREE.items():
        for n in (3, 10, 20):
            nb = n + p
            x = np.concatenate([rng.uniform(0.0, L, 2000), [0.0, L * (1 - 1e-15)]])
            idx, N, dN = basis(x, n, p)
            Nd, Gd = dense(idx, N, nb), dense(idx, dN, nb)
            t = knots(n, p)
            grev = np.array([t[i + 1:i + p + 1].mean() for i in range(nb)])
            e1 = np.abs(Nd.sum(1) - 1).max()
            e2 = np.abs(Nd @ grev - x).max()
            e3 = np.abs(Gd.sum(1)).max() + np.abs(Gd @ grev - 1).max()
            eps = 1e-7
            xi = np.clip(x[:-2], 2 * eps, L - 2 * eps)
            ip, Np, _ = basis(xi + eps, n, p)
            im, Nmn, _ = basis(xi - eps, n, p)
            _, _, dNi = basis(xi, n, p)
            same = (ip == im).all(1)  # skip the few points where x +- eps straddle a knot
            ii, _, _ = basis(xi, n, p)
            fd = dense(ip[same], Np[same], nb) - dense(im[same], Nmn[same], nb)
            e4 = np.abs(fd / (2 * eps) - dense(ii[same], dNi[same], nb)).max() * (L / n)
            assert (N >= -1e-15).all()
            assert e1 < 1e-13 and e2 < 1e-13 and e3 < 1e-9 * n and e4 < 1e-5, (name, n, e1, e2, e3, e4)
            if p == 1:
                nodes = np.linspace(0.0, L, n + 1)
                hat = np.maximum(0.0, 1.0 - np.abs(x[:, None] - nodes[None, :]) * n / L)
                assert np.abs(hat - Nd).max() < 1e-12
            out[f"{name}_n{n}"] = dict(pu=e1, linear=e2, grad=e3, fd=e4)
    return out


# ---------------------------------------------------------------------------------------------
# MPM, MUSL (D Algorithm 2), direct mapping.
def particles(n):
    h = L / n
    X = ((np.arange(n)[:, None] + (np.arange(PPC)[None, :] + 0.5) / PPC) * h).ravel()
    return X, np.full(X.size, RHO0 * h / PPC), np.full(X.size, h / PPC)


def grid_solve(Nd, w, rhs, consistent, fixed):
    """Solve M y = rhs with M = sum_p N_ip w_p N_jp (lumped: its row sums); y = 0 on `fixed`."""
    nb = Nd.shape[1]
    free = np.setdiff1d(np.arange(nb), fixed)
    y = np.zeros(nb)
    if consistent:
        M = Nd.T @ (w[:, None] * Nd)
        y[free] = cho_solve(cho_factor(M[np.ix_(free, free)]), rhs[free])
    else:
        m = Nd.T @ w
        assert (m[free] > 0).all(), "empty node / coefficient"
        y[free] = rhs[free] / m[free]
    return y


def mpm(basis_name, consistent, n, dt):
    p = DEGREE[basis_name]
    nb = n + p
    fixed = np.array([0, nb - 1])
    X, mp, V0p = particles(n)
    x, v = X.copy(), V0 * np.sin(np.pi * X / L)
    F, sig = np.ones_like(X), np.zeros_like(X)
    steps = int(round(T / dt))
    for _ in range(steps):
        idx, N, dN = basis(x, n, p)
        Nd, Gd = dense(idx, N, nb), dense(idx, dN, nb)
        f = -Gd.T @ (sig * F * V0p)
        a = grid_solve(Nd, mp, f, consistent, fixed)
        v = v + dt * (Nd @ a)
        vg = grid_solve(Nd, mp, Nd.T @ (mp * v), consistent, fixed)
        x = x + dt * (Nd @ vg)
        Lp = Gd @ vg
        F = F * (1.0 + dt * Lp)
        sig = sig + (E - sig) * dt * Lp
    return dict(X=X, x=x, v=v, F=F, sig=sig, V0p=V0p, steps=steps,
                closed_form_gap=float(np.abs(sig - E * (1 - 1 / F)).max() / E))


# ---------------------------------------------------------------------------------------------
# Reference: total-Lagrangian FEM, linear elements, lumped mass, central differences.
def fem(ne, courant=0.5, fmin=0.7):
    """dt from the Courant number on sqrt(E / rho0) / fmin (fmin a conservative guess of the
    smallest F; the Courant number actually reached is returned and checked)."""
    he = L / ne
    Xn = np.linspace(0.0, L, ne + 1)
    c_max = np.sqrt(E / RHO0) / fmin
    steps = int(np.ceil(T / (courant * he / c_max)))
    dt = T / steps
    mass = np.full(ne + 1, RHO0 * he)  # interior lumped mass; ends are fixed anyway
    u = np.zeros(ne + 1)
    v = V0 * np.sin(np.pi * Xn / L)
    v[[0, -1]] = 0.0

    def accel(u):
        Fe = 1.0 + np.diff(u) / he
        P = E * (1.0 - 1.0 / Fe)
        a = np.zeros_like(u)
        a[1:-1] = (P[1:] - P[:-1]) / mass[1:-1]
        return a, Fe, P

    a, Fe, P = accel(u)
    vh = v + 0.5 * dt * a  # v^{1/2}
    worst, Fmin, Fmax = 0.0, 1.0, 1.0
    for s in range(steps):
        u = u + dt * vh
        a, Fe, P = accel(u)
        if s < steps - 1:
            vh = vh + dt * a
        worst = max(worst, np.sqrt(E / RHO0) / Fe.min() * dt / he)
        Fmin, Fmax = min(Fmin, Fe.min()), max(Fmax, Fe.max())
    assert worst < 1.0, f"FEM unstable: Courant {worst}"
    Xc = 0.5 * (Xn[1:] + Xn[:-1])
    return dict(ne=ne, dt=dt, steps=steps, courant=worst, Fmin=Fmin, Fmax=Fmax,
                Xc=Xc, P=P, umax=float(np.abs(u).max()))


def sigma_ref(ref, X):
    """Element stress linearly interpolated between element centres (constant beyond the
    outermost centres, which no particle reaches for ne >= 1000)."""
    return np.interp(X, ref["Xc"], ref["P"])


def stress_error(res, ref, n):
    X, sig, w = res["X"], res["sig"], res["V0p"]
    sr = sigma_ref(ref, X)
    h = L / n
    inner = (X >= 2 * h) & (X <= L - 2 * h)

    def rel(mask):
        return float(np.sqrt((w[mask] * (sig[mask] - sr[mask]) ** 2).sum()
                             / (w[mask] * sr[mask] ** 2).sum()))

    return rel(np.ones_like(inner)), rel(inner)


# ---------------------------------------------------------------------------------------------
# One projection at t = 0.
def projection(basis_name, mode, n):
    p = DEGREE[basis_name]
    nb = n + p
    X, mp, _ = particles(n)
    vp = np.sin(np.pi * X / L)
    idx, N, dN = basis(X, n, p)
    Nd, Gd = dense(idx, N, nb), dense(idx, dN, nb)
    q = Nd.T @ (mp * vp)
    if mode == "lumped":
        vg = q / (Nd.T @ mp)
    elif mode == "consistent":  # full system, no boundary constraint
        vg = grid_solve(Nd, mp, q, True, np.array([], dtype=int))
    else:  # "consistent, ends 0": first / last coefficient set to 0, solved for the rest
        vg = grid_solve(Nd, mp, q, True, np.array([0, nb - 1]))
    Lp = Gd @ vg
    exact = np.pi / L * np.cos(np.pi * X / L)
    h = L / n
    inner = (X >= 2 * h) & (X <= L - 2 * h)
    return float(np.sqrt(((Lp - exact)[inner] ** 2).mean() / (exact[inner] ** 2).mean()))


def order(a, b, ra=2.0):
    return float(np.log(a / b) / np.log(ra))


def fmt_o(o):
    return "" if o is None else f" ({o:.2f})"


def main():
    global V0
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells", type=int, nargs="+", default=[10, 20, 40, 80])
    ap.add_argument("--dt", type=float, default=1e-4)
    ap.add_argument("--fine-dt", type=float, default=2.5e-5, help="time-refinement check (n = 20)")
    ap.add_argument("--no-fine-dt", action="store_true")
    ap.add_argument("--ref", type=int, nargs="+", default=[1000, 2000, 4000, 8000],
                    help="FEM element counts; the last one is the reference")
    ap.add_argument("--v0", type=float, default=V0,
                    help="initial velocity amplitude (e.g. 0.008: no grid crossing, a sanity check)")
    ap.add_argument("--json", help="write all numbers to this file")
    args = ap.parse_args()
    V0 = args.v0
    t0 = time.time()
    out = {"parameters": dict(L=L, rho0=RHO0, E=E, v0=V0, T=T, ppc=PPC, dt=args.dt,
                              fine_dt=args.fine_dt, cells=args.cells, ref=args.ref)}
    out["basis_self_test"] = self_test()

    # Reference FEM runs.
    refs = [fem(ne) for ne in sorted(args.ref)]
    ref = refs[-1]

    variants = [(b, c) for b in ("P1", "B2") for c in (False, True)]
    mname = {False: "lumped", True: "consistent"}
    runs = []
    cases = [(n, args.dt) for n in args.cells]
    if not args.no_fine_dt and 20 in args.cells:
        cases.append((20, args.fine_dt))
    for b, c in variants:
        for n, dt in cases:
            r = mpm(b, c, n, dt)
            ea, ei = stress_error(r, ref, n)
            runs.append(dict(basis=b, mass=mname[c], cells=n, dt=dt, e_all=ea, e_interior=ei,
                             steps=r["steps"], closed_form_gap=r["closed_form_gap"],
                             F_min=float(r["F"].min()), F_max=float(r["F"].max()),
                             x_disp_max=float(np.abs(r["x"] - r["X"]).max())))

    print(f"Large-deformation vibrating bar (D 5.4.1): E = {E:g} Pa, rho0 = {RHO0:g} kg/m^3, "
          f"v0 = {V0} m/s, T = {T} s, {PPC} PPC, MUSL, direct mapping.")
    print(f"Reference: TL-FEM with {ref['ne']} elements (dt = {ref['dt']:.3e} s, Courant "
          f"<= {ref['courant']:.3f}, F in [{ref['Fmin']:.4f}, {ref['Fmax']:.4f}], "
          f"max |u| = {ref['umax']:.4f} m).\n")

    print(f"### (1) Relative L2 stress error at T, dt = {args.dt:g} s (observed order in brackets)\n")
    print("| basis | mass | cells | e (all) | e (interior) | max |sigma - E(1-1/F)| / E |")
    print("|---|---|---|---|---|---|")
    for b, c in variants:
        prev = None
        for n in args.cells:
            r = next(q for q in runs if q["basis"] == b and q["mass"] == mname[c]
                     and q["cells"] == n and q["dt"] == args.dt)
            oa = oi = None
            if prev is not None:
                ra = n / prev["cells"]
                oa, oi = order(prev["e_all"], r["e_all"], ra), order(prev["e_interior"], r["e_interior"], ra)
                r["order_all"], r["order_interior"] = oa, oi
            print(f"| {b} | {mname[c]} | {n} | {r['e_all']:.4e}{fmt_o(oa)} | "
                  f"{r['e_interior']:.4e}{fmt_o(oi)} | {r['closed_form_gap']:.1e} |")
            prev = r

    if 20 in args.cells:
        dts = [args.dt] + ([] if args.no_fine_dt else [args.fine_dt])
        print("\n### (1b) n = 20: time-step check and ratio P1-lumped error / this error\n")
        print("| basis | mass | dt | e (all) | ratio (all) | e (interior) | ratio (interior) |")
        print("|---|---|---|---|---|---|---|")
        out["ratios_n20"] = []
        for dt in dts:
            base = next(q for q in runs if q["basis"] == "P1" and q["mass"] == "lumped"
                        and q["cells"] == 20 and q["dt"] == dt)
            for b, c in variants:
                r = next(q for q in runs if q["basis"] == b and q["mass"] == mname[c]
                         and q["cells"] == 20 and q["dt"] == dt)
                ra, ri = base["e_all"] / r["e_all"], base["e_interior"] / r["e_interior"]
                out["ratios_n20"].append(dict(basis=b, mass=mname[c], dt=dt, ratio_all=ra,
                                              ratio_interior=ri))
                print(f"| {b} | {mname[c]} | {dt:g} | {r['e_all']:.4e} | {ra:.2f} | "
                      f"{r['e_interior']:.4e} | {ri:.2f} |")
    out["mpm"] = runs

    # Projection check.
    print("\n### (2) One projection at t = 0, v_p = sin(pi x_p): relative RMS error of L_p "
          "against pi cos(pi x_p), interior particles (observed order)\n")
    modes = ["lumped", "consistent", "consistent, ends 0"]
    cols = [(b, m) for b in ("P1", "B2") for m in modes]
    print("| cells | " + " | ".join(f"{b} {m}" for b, m in cols) + " |")
    print("|---|" + "---|" * len(cols))
    proj, prev = [], None
    for n in args.cells:
        row = {(b, m): projection(b, m, n) for b, m in cols}
        cells = []
        for k in cols:
            o = None if prev is None else order(prev[1][k], row[k], n / prev[0])
            cells.append(f"{row[k]:.3e}{fmt_o(o)}")
            proj.append(dict(basis=k[0], mode=k[1], cells=n, error=row[k], order=o))
        print(f"| {n} | " + " | ".join(cells) + " |")
        prev = (n, row)
    out["projection"] = proj

    # Reference self-convergence.
    print("\n### (3) Reference self-convergence (TL-FEM): differences at T between successive "
          "resolutions, sigma interpolated between element centres\n")
    Xs = particles(max(args.cells))[0]
    w = np.full(Xs.size, 1.0)
    print(f"| elements | dt | Courant (max) | rel. L2 diff to next (at the {Xs.size} particles of "
          f"n = {max(args.cells)}) | max |diff| / max |sigma| | vs finest: rel. L2 |")
    print("|---|---|---|---|---|---|")
    selfconv = []
    sf = sigma_ref(ref, Xs)
    for i, r in enumerate(refs):
        s = sigma_ref(r, Xs)
        vs_fine = float(np.sqrt((w * (s - sf) ** 2).sum() / (w * sf ** 2).sum()))
        if i + 1 < len(refs):
            s2 = sigma_ref(refs[i + 1], Xs)
            d = float(np.sqrt((w * (s - s2) ** 2).sum() / (w * s2 ** 2).sum()))
            dm = float(np.abs(s - s2).max() / np.abs(s2).max())
            ds, dms = f"{d:.3e}", f"{dm:.3e}"
        else:
            d = dm = None
            ds = dms = "-"
        selfconv.append(dict(ne=r["ne"], dt=r["dt"], steps=r["steps"], courant=r["courant"],
                             Fmin=r["Fmin"], Fmax=r["Fmax"], diff_to_next=d,
                             maxdiff_to_next=dm, diff_to_finest=vs_fine))
        print(f"| {r['ne']} | {r['dt']:.3e} | {r['courant']:.3f} | {ds} | {dms} | "
              f"{vs_fine:.3e} |")
    out["reference"] = selfconv
    emin = min(q["e_interior"] for q in runs)
    last = selfconv[-2]["diff_to_next"] if len(selfconv) > 1 else None
    if last is not None:
        print(f"\nFinest reference difference {last:.2e} vs smallest MPM error (interior) "
              f"{emin:.2e}: ratio {emin / last:.0f}.")
    out["seconds"] = time.time() - t0
    print(f"\nTotal run time {out['seconds']:.1f} s.")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
