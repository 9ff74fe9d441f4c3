#!/usr/bin/env python3
"""Independent 1D TLS (Taylor least squares, D 5.2-5.3) check for the large-deformation bar.

A second implementation (numpy; written from D without reading mpmlab's C++) of BSMPM-TLS,
to test whether the stalled convergence of mpmlab's TLS at small strain is D's method or a
defect: it is D's method. The conservative constant a_1 = sum_{p in e} m_p / h counts the
particles whose centre lies in the fixed cell, i.e. the content of a material region; under a
strain it is off by a relative u_X whatever h. The 'overlap' variant (each particle's mass and
momentum split among the cells its current domain [x_p - V_p/2, x_p + V_p/2] overlaps) removes
the floor and conserves to round-off; mpmlab's `method.tls_cell_integrals = "domains"` is that
variant. Reproduces mpmlab's numbers (docs/verification.md) to 3-4 digits.

    /usr/bin/python3 scripts/tls_constant_check.py [--quick]   (5 min; --quick about a minute)

Bar on [0, 1], fixed ends, rho0 = 2000, E = 4e4, sigma += (E - sigma) dt L_p, v(X,0) = v0 sin(pi X),
T = 0.1, 8 PPC, MUSL, quadratic B-splines on the open knot vector. Reference: TL-FEM of
large_bar_check.py (4000 elements), error as in large_bar_check.stress_error (all particles).

TLS per element e = [x_e, x_e + h] (fixed grid cell), centre x_c, Delta x = h/2, s = (x - x_c)/Delta x:
  Taylor basis (D 5.2.2):  psi_1 = 1, psi_2 = s, psi_3 = s^2/2 - mean_e(s^2)/2 = (s^2 - 1/3)/2
  (so that int_e psi_i = 0 for i > 1, eq. 5.7).
  Conservative fit (D eq. 5.9, 5.14, 5.3.1): a_1 = (sum_{p in e} m_p [v_p]) / h; (a_2, a_3) = the
  least-squares solution of  min sum_{p in e} (a_1 + a_2 psi_2(x_p) + a_3 psi_3(x_p) - f_p)^2,
  i.e. D' [a_2, a_3] = sum_p psi'(x_p) (f_p - a_1), D' = sum_p psi' psi'^T, psi' = (psi_2, psi_3);
  f_p = m_p / V_p (density) or m_p v_p / V_p (momentum density).
  Plain fit (stress, eq. 5.12; also the 'plain' switch for density/momentum): all three
  coefficients by eq. 5.1.
  Gauss-Legendre with ng points per cell (default 2):  M_ij = sum_g w_g rho(x_g) N_i N_j,
  lumped m_i = sum_g w_g rho(x_g) N_i, q_i = sum_g w_g (rho v)(x_g) N_i,
  f_i = - sum_g w_g sigma(x_g) N_i,x(x_g).
"""
import os
import sys
import time
import argparse
import numpy as np
from scipy.linalg import cho_factor, cho_solve

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import large_bar_check as lbc  # noqa: E402

L, RHO0, E, T, PPC = lbc.L, lbc.RHO0, lbc.E, lbc.T, lbc.PPC


# ------------------------------------------------------------------------------------------
def taylor(x, cell, h, nb):
    """Taylor basis values (len(x), nb) of D 5.2.2 in the given cells."""
    xc = (cell + 0.5) * h
    s = (x - xc) / (0.5 * h)
    cols = [np.ones_like(x), s, 0.5 * (s * s - 1.0 / 3.0)]
    return np.stack(cols[:nb], axis=1)


def tls_fit(x, f, n, nb, integral=None):
    """Per-cell fit. integral=None: plain LS (eq. 5.1). Otherwise integral[e] = value the
    integral over cell e must have (a_1 = integral / h, remaining coefficients LS of f - a_1).
    Returns coefficients (n, nb) and the condition numbers of the LS matrices."""
    h = L / n
    cell = np.clip(np.floor(x / h).astype(int), 0, n - 1)
    psi = taylor(x, cell, h, nb)
    D = np.zeros((n, nb, nb))
    np.add.at(D, cell, psi[:, :, None] * psi[:, None, :])
    coef = np.zeros((n, nb))
    if integral is None:
        b = np.zeros((n, nb))
        np.add.at(b, cell, psi * f[:, None])
        coef = np.linalg.solve(D, b[:, :, None])[:, :, 0]
        cond = np.linalg.cond(D)
    else:
        a1 = integral / h
        coef[:, 0] = a1
        if nb > 1:
            r = f - a1[cell]
            b = np.zeros((n, nb - 1))
            np.add.at(b, cell, psi[:, 1:] * r[:, None])
            coef[:, 1:] = np.linalg.solve(D[:, 1:, 1:], b[:, :, None])[:, :, 0]
            cond = np.linalg.cond(D[:, 1:, 1:])
        else:
            cond = np.ones(n)
    return coef, cond


class Quad:
    """Gauss points of every cell and the B-spline basis there."""

    def __init__(self, n, p, ng):
        h = L / n
        xi, wi = np.polynomial.legendre.leggauss(ng)
        self.cell = np.repeat(np.arange(n), ng)
        self.x = ((np.arange(n)[:, None] + 0.5 + 0.5 * xi[None, :]) * h).ravel()
        self.w = np.tile(0.5 * h * wi, n)
        nbas = n + p
        idx, N, dN = lbc.basis(self.x, n, p)
        self.N, self.G = lbc.dense(idx, N, nbas), lbc.dense(idx, dN, nbas)
        self.n, self.h = n, h

    def evaluate(self, coef):
        nb = coef.shape[1]
        psi = taylor(self.x, self.cell, self.h, nb)
        return (psi * coef[self.cell]).sum(1)


def cell_integrals(x, vals, n, mode, Vp=None):
    """'particles': sum of vals over the particles located in the cell (D eq. 5.14).
    'overlap' (diagnostic, not D): vals distributed over the particle's current domain
    [x_p - V_p/2, x_p + V_p/2] (clipped to [0, L]) and split between cells by overlap length."""
    h = L / n
    if mode == "particles":
        cell = np.clip(np.floor(x / h).astype(int), 0, n - 1)
        return np.bincount(cell, weights=vals, minlength=n)
    lo = np.clip(x - 0.5 * Vp, 0.0, L)
    hi = np.clip(x + 0.5 * Vp, 0.0, L)
    edges = np.linspace(0.0, L, n + 1)
    ov = np.clip(np.minimum(hi[:, None], edges[None, 1:]) - np.maximum(lo[:, None], edges[None, :-1]),
                 0.0, None)
    ov /= ov.sum(1, keepdims=True)
    return ov.T @ vals


# ------------------------------------------------------------------------------------------
def mpm(n, dt, v0, mass="tls", mom="tls", force="tls", lumped=False, fit="cons", ng=2, nb=3,
        p=2, check=False):
    """MUSL as large_bar_check.mpm(). mass/mom/force in {'tls', 'direct'} pick where each grid
    quantity comes from; fit in {'cons', 'plain', 'overlap'} for density and momentum."""
    nbas = n + p
    free = np.arange(1, nbas - 1)
    X, mp, V0p = lbc.particles(n)
    x, v = X.copy(), v0 * np.sin(np.pi * X / L)
    F, sig = np.ones_like(X), np.zeros_like(X)
    Q = Quad(n, p, ng)
    steps = int(round(T / dt))
    diag = dict(mass_err=0.0, mom_err=0.0, cond_max=0.0)
    h = L / n
    cell0 = np.floor(X / h)
    ever = np.zeros(X.size, bool)

    def grid_mass(Nd, Vp):
        if mass == "direct":
            Mfull = Nd.T @ (mp[:, None] * Nd)
        else:
            if fit == "plain":
                c, cd = tls_fit(x, mp / Vp, n, nb)
            else:
                c, cd = tls_fit(x, mp / Vp, n, nb,
                                cell_integrals(x, mp, n, "particles" if fit == "cons" else "overlap", Vp))
            diag["cond_max"] = max(diag["cond_max"], float(cd.max()))
            rg = Q.evaluate(c)
            Mfull = Q.N.T @ ((Q.w * rg)[:, None] * Q.N)
        if check:
            diag["mass_err"] = max(diag["mass_err"], abs(Mfull.sum() - mp.sum()) / mp.sum())
        if lumped:
            return Mfull.sum(1)
        return Mfull

    def solve(M, rhs):
        y = np.zeros(nbas)
        if lumped:
            y[free] = rhs[free] / M[free]
        else:
            y[free] = cho_solve(cho_factor(M[np.ix_(free, free)]), rhs[free])
        return y

    def grid_mom(Nd, Vp, v):
        if mom == "direct":
            q = Nd.T @ (mp * v)
        else:
            if fit == "plain":
                c, _ = tls_fit(x, mp * v / Vp, n, nb)
            else:
                c, _ = tls_fit(x, mp * v / Vp, n, nb,
                               cell_integrals(x, mp * v, n, "particles" if fit == "cons" else "overlap", Vp))
            q = Q.N.T @ (Q.w * Q.evaluate(c))
        if check and abs((mp * v).sum()) > 0:
            diag["mom_err"] = max(diag["mom_err"], abs(q.sum() - (mp * v).sum()) / np.abs(mp * v).sum())
        return q

    for _ in range(steps):
        idx, N, dN = lbc.basis(x, n, p)
        Nd, Gd = lbc.dense(idx, N, nbas), lbc.dense(idx, dN, nbas)
        Vp = F * V0p
        if force == "direct":
            f = -Gd.T @ (sig * Vp)
        else:
            cs, _ = tls_fit(x, sig, n, nb)
            f = -Q.G.T @ (Q.w * Q.evaluate(cs))
        M = grid_mass(Nd, Vp)
        a = solve(M, f)
        v = v + dt * (Nd @ a)
        vg = solve(M, grid_mom(Nd, Vp, v))
        x = x + dt * (Nd @ vg)
        Lp = Gd @ vg
        F = F * (1.0 + dt * Lp)
        sig = sig + (E - sig) * dt * Lp
        ever |= np.floor(np.clip(x / h, 0, n - 1e-12)) != cell0
    crossed = int(ever.sum())
    return dict(X=X, x=x, v=v, F=F, sig=sig, V0p=V0p, steps=steps, crossed=crossed, **diag)


# ------------------------------------------------------------------------------------------
def self_checks():
    rng = np.random.default_rng(0)
    n, nb = 5, 3
    out = {}
    x = np.sort(rng.uniform(0, L, 60))
    g = lambda y: 1.3 - 2.0 * y + 5.0 * y * y
    G = lambda y: 1.3 * y - y * y + 5.0 * y ** 3 / 3
    edges = np.linspace(0, L, n + 1)
    Q = Quad(n, 2, 2)
    c, _ = tls_fit(x, g(x), n, nb)
    out["plain_quadratic_reproduction"] = float(np.abs(Q.evaluate(c) - g(Q.x)).max())
    c, _ = tls_fit(x, g(x), n, nb, integral=G(edges[1:]) - G(edges[:-1]))
    out["cons_quadratic_reproduction"] = float(np.abs(Q.evaluate(c) - g(Q.x)).max())
    # integral constraint with arbitrary data
    f = rng.normal(size=x.size)
    I = rng.normal(size=n)
    c, _ = tls_fit(x, f, n, nb, integral=I)
    out["cons_integral_constraint"] = float(np.abs(np.bincount(Q.cell, Q.w * Q.evaluate(c)) - I).max())
    # mass / momentum conservation of the grid quantities at t = 0 (particles of n = 10)
    n = 10
    X, mp, V0p = lbc.particles(n)
    Xp = X + 1e-3 * np.sin(3 * X)  # perturbed positions
    Q = Quad(n, 2, 2)
    c, _ = tls_fit(Xp, mp / V0p * (1 + 0.1 * X), n, 3, cell_integrals(Xp, mp, n, "particles"))
    M = Q.N.T @ ((Q.w * Q.evaluate(c))[:, None] * Q.N)
    out["mass_sum_Mij_rel"] = float(abs(M.sum() - mp.sum()) / mp.sum())
    vp = np.cos(2 * X) + 0.3
    c, _ = tls_fit(Xp, mp * vp / V0p, n, 3, cell_integrals(Xp, mp * vp, n, "particles"))
    q = Q.N.T @ (Q.w * Q.evaluate(c))
    out["momentum_sum_q_rel"] = float(abs(q.sum() - (mp * vp).sum()) / abs((mp * vp).sum()))
    return out


def modified_fem(ne, v0, mass=True, mom=True, courant=0.5, fmin=0.7):
    """Reference for the modified equations that the conservative TLS mapping (a_1 from the
    masses / momenta of the particles located in the fixed cell) approximates for smooth fields,
    to first order in the displacement u:
        v_t(X) = P_X / (rho0 F)     (TLS density ~ rho0: Lagrangian cell mass on the Eulerian cell)
        u_t(X) = v(X + u(X))        (TLS grid velocity at x = particle velocity field at label x)
    with F = 1 + u_X, P = E (1 - 1/F). The modified system is ill-posed at wavelengths below ~u
    (which the MPM cells never resolve), so it is solved as true solution + first-order
    perturbation: (u, v) from the true TL-FEM (as lbc.fem) and (du, dv) from the linear wave
    equation with the sources S_u = u v_X and S_v = (P_X / rho0) (1/F - 1) evaluated on the true
    solution: du_t = dv + S_u, rho0 dv_t = E du_XX + rho0 S_v. Returns P + E du_X per element.
    Only the TLS density (mass=True, mom=False; grid velocity v / F): S_u = -u_X v and S_v as above.
    Only the TLS momentum (mass=False, mom=True; grid velocity F (v + u v_X)): S_u = (u v)_X, S_v = 0.
    Both: S_u = u v_X (the sum of the two)."""
    he = L / ne
    Xn = np.linspace(0.0, L, ne + 1)
    c_max = np.sqrt(E / RHO0) / fmin
    steps = int(np.ceil(T / (courant * he / c_max)))
    dt = T / steps
    u = np.zeros(ne + 1)
    du = np.zeros(ne + 1)
    v = v0 * np.sin(np.pi * Xn / L)
    v[[0, -1]] = 0.0

    def accel(u, du):
        Fe = 1.0 + np.diff(u) / he
        P = E * (1.0 - 1.0 / Fe)
        a = np.zeros_like(u)
        a[1:-1] = (P[1:] - P[:-1]) / (RHO0 * he)
        Fn = 0.5 * (Fe[1:] + Fe[:-1])
        da = np.zeros_like(u)
        dP = E * np.diff(du) / he
        da[1:-1] = (dP[1:] - dP[:-1]) / (RHO0 * he) + (a[1:-1] * (1.0 / Fn - 1.0) if mass else 0.0)
        return a, da, P, dP

    a, da, P, dP = accel(u, du)
    vh = v + 0.5 * dt * a
    dvh = 0.5 * dt * da
    for s in range(steps):
        uh = u + 0.5 * dt * vh  # u at the half step, for the source u v_X
        vX = np.zeros_like(u)
        vX[1:-1] = (vh[2:] - vh[:-2]) / (2 * he)
        uX = np.zeros_like(u)
        uX[1:-1] = (uh[2:] - uh[:-2]) / (2 * he)
        Su = (uX * vh + uh * vX if mom else 0.0) - (uX * vh if mass else 0.0)
        u = u + dt * vh
        du = du + dt * (dvh + Su)
        a, da, P, dP = accel(u, du)
        if s < steps - 1:
            vh = vh + dt * a
            dvh = dvh + dt * da
    return dict(Xc=0.5 * (Xn[1:] + Xn[:-1]), P=P + dP, dP=dP)


_refs = {}
_runs = {}


def run(n, dt, v0, kw):
    key = (n, dt, v0, tuple(sorted(kw.items())))
    if key not in _runs:
        _runs[key] = mpm(n, dt, v0, **kw)
    return _runs[key]


def reference(v0, kind="true"):
    key = (v0, kind)
    if key not in _refs:
        lbc.V0 = v0
        if kind == "true":
            _refs[key] = lbc.fem(4000)
        else:
            _refs[key] = modified_fem(4000, v0, mass=kind in ("modified", "modified_mass"),
                                      mom=kind in ("modified", "modified_mom"))
    return _refs[key]


def err(res, v0, n, kind="true"):
    return lbc.stress_error(res, reference(v0, kind), n)[0]


def table(title, rows_spec, cells, v0, dt=1e-4, kinds=("true",), extra=None):
    """rows_spec: (name, mpm kwargs) or (name, mpm kwargs, reference kinds)."""
    print(f"\n### {title}  (v0 = {v0}, dt = {dt:g})\n")
    hdr = "| variant | " + " | ".join(f"n={n}" for n in cells) + " |"
    print(hdr)
    print("|---|" + "---|" * len(cells))
    results = {}
    for spec in rows_spec:
        name, kw = spec[:2]
        for kind in (spec[2] if len(spec) > 2 else kinds):
            vals, prev = [], None
            for n in cells:
                key = (name, n)
                if key not in results:
                    results[key] = run(n, dt, v0, kw)
                e = err(results[key], v0, n, kind)
                o = "" if prev is None else f" ({np.log2(prev / e):.2f})"
                vals.append(f"{e:.3e}{o}")
                prev = e
            lab = name if kind == "true" else f"{name} vs {kind} ref"
            print(f"| {lab} | " + " | ".join(vals) + " |")
    return results


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="40 and 80 cells, the main and ingredient tables only (about a minute; "
                         "docs/verification.md); without it about 5 minutes")
    args = ap.parse_args()
    t0 = time.time()
    print("Self checks:", {k: f"{v:.1e}" for k, v in self_checks().items()})

    # conservation during a run
    r = mpm(20, 1e-4, 0.008, check=True)
    print(f"TLS run n=20 v0=0.008: max rel. mass error {r['mass_err']:.1e}, max rel. momentum "
          f"error {r['mom_err']:.1e}, max cond(D') {r['cond_max']:.1f}, particles that changed "
          f"cell {r['crossed']}")

    cells = [40, 80] if args.quick else [10, 20, 40, 80]
    direct = dict(mass="direct", mom="direct", force="direct")
    tls = dict()
    res = table("Main: relative L2 stress error, consistent mass",
                [("direct", direct), ("TLS (cons.)", tls), ("TLS (cons.) lumped", dict(lumped=True)),
                 ("direct lumped", dict(direct, lumped=True))], cells, 0.008)
    if not args.quick:
        for v0 in (0.0008, 0.08):
            table("Amplitude", [("direct", direct), ("TLS (cons.)", tls)], [40, 80], v0)

    # TLS vs direct difference, projection on cos(2 pi X)
    print("\n### Shape of sigma_TLS - sigma_direct at T (v0 = 0.008)\n")
    print("| n | rel. L2 of diff | coefficient on cos(2 pi X) / rel. | fraction of diff energy in cos(2piX) |")
    print("|---|---|---|---|")
    for n in cells:
        a, b = res[("TLS (cons.)", n)], res[("direct", n)]
        d = a["sig"] - b["sig"]
        Xp = a["X"]
        c2 = np.cos(2 * np.pi * Xp)
        coef = (d * c2).sum() / (c2 * c2).sum()
        sr = reference(0.008)
        norm = np.sqrt((lbc.sigma_ref(sr, Xp) ** 2).mean())
        frac = (coef * c2).var() / d.var() if d.var() > 0 else 0
        frac = 1 - ((d - coef * c2) ** 2).sum() / (d ** 2).sum()
        print(f"| {n} | {np.sqrt((d ** 2).mean()) / norm:.3e} | {coef / norm:.3e} | {frac:.3f} |")

    # Ingredient switches
    sw = [
        ("TLS all (cons.)", tls),
        ("mass direct, mom TLS, force TLS", dict(mass="direct")),
        ("mass TLS, mom direct, force TLS", dict(mom="direct")),
        ("mass TLS, mom TLS, force direct", dict(force="direct")),
        ("mass direct, mom direct, force TLS", dict(mass="direct", mom="direct")),
        ("mass TLS, mom direct, force direct", dict(mom="direct", force="direct")),
        ("mass direct, mom TLS, force direct", dict(mass="direct", force="direct")),
        ("TLS all, plain density/momentum fit", dict(fit="plain")),
        ("TLS all, cons. with overlap cell masses (not D)", dict(fit="overlap")),
        ("TLS all, linear Taylor (nb=2)", dict(nb=2)),
        ("TLS all, 3 Gauss points", dict(ng=3)),
    ]
    table("Ingredient switches, consistent mass", sw, cells, 0.008)
    if args.quick:
        print(f"\nTotal {time.time() - t0:.0f} s")
        return
    table("Ingredient switches, lumped mass",
          [("TLS all (cons.) lumped", dict(lumped=True)),
           ("TLS plain fits lumped", dict(lumped=True, fit="plain")),
           ("TLS overlap lumped", dict(lumped=True, fit="overlap")),
           ("mass direct lumped, mom/force TLS", dict(lumped=True, mass="direct"))], cells, 0.008)
    both, mo, ms = ("true", "modified"), ("true", "modified_mom"), ("true", "modified_mass")
    table("Errors against the true reference and against the first-order modified equations "
          "of each TLS ingredient (modified_fem)",
          [("TLS (cons.)", tls, both), ("direct", direct, both),
           ("mass direct, mom TLS", dict(mass="direct"), mo),
           ("mass TLS, mom direct", dict(mom="direct"), ms),
           ("TLS (cons.) lumped", dict(lumped=True), both), ("direct lumped", dict(direct, lumped=True), both)],
          cells, 0.008)
    table("Amplitudes against the modified equations", [("TLS (cons.)", tls, both), ("direct", direct, both)],
          [40, 80], 0.0008)
    table("Amplitudes against the modified equations", [("TLS (cons.)", tls, both), ("direct", direct, both)],
          [40, 80], 0.08)
    table("Time step dt/4 (2.5e-5)", [("TLS (cons.)", tls, both), ("direct", direct)], [40, 80], 0.008, dt=2.5e-5)
    crossed = {k: v["crossed"] for k, v in _runs.items() if v["crossed"]}
    print("\nRuns in which some particle left its initial cell at some time:",
          {f"n={k[0]} v0={k[2]} {dict(k[3])}": c for k, c in crossed.items()} or "none")
    print(f"\nTotal {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
