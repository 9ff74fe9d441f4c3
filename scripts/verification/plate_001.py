"""The plate of 001 at A = 0.1 m: the published convergence set-up, which does not run through
(the prose of templates/plate_001.md, block section, with the MLS density tables of
scripts/plate_mls_static.py); TLS against the direct mapping, where each run stops and how the
error's energy grows (a_growth); where that growth comes from, by `mpm stiffness` on frozen
layouts (a_stiffness); the strain rate made the adjoint of TLS's force (a_adjoint). With
--long, the 001 study to T = 0.2 s (sec_long)."""
import csv
import math
import os
import subprocess
import sys

from .common import EX, ROOT, e, fail_time, fig_md, o
from .plots import plot_study
from .template import render


def sec_001(R, ctx):
    """The static 001 text, with the MLS density table of scripts/plate_mls_static.py computed
    now (a = 2 as published, a = 1 for comparison; about a minute), and the runs of TLS at
    A = 0.1 on 16 cells (a_growth; about four minutes on 2 cores)."""
    tables = []
    for a in ("2", "1"):
        res = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "plate_mls_static.py"),
                              "--dilation", a], check=True, capture_output=True, text=True)
        tables.append(res.stdout.strip())
    b2_tls_factor, growth_text = a_growth(R)
    return (render("plate_001", "section", mls_static="\n\n".join(tables)).rstrip() + "\n\n"
            + growth_text + "\n" + a_stiffness(R, b2_tls_factor))


# The runs of a_growth: (label, settings) per basis, on top of the plate at A = 0.1 m, 16 cells,
# T = 0.2 s, 9 particles per cell, every step in history.csv.
A_GROWTH = [("direct", ["method.mapping=direct"]),
            ("TLS, 2D defaults", ["method.mapping=tls"]),
            ("TLS, virtual completion", ["method.mapping=tls", "method.tls_completion=virtual"]),
            ("TLS, limit 3", ["method.mapping=tls", "method.tls_max_condition=3"]),
            ("TLS, limit 1e2", ["method.mapping=tls", "method.tls_max_condition=100"]),
            ("TLS, no positivity", ["method.mapping=tls", "method.tls_positivity=off"]),
            ("TLS, D's element sums", ["method.mapping=tls", "method.tls_cell_integrals=centres"]),
            ("TLS, 3 Gauss points", ["method.mapping=tls", "method.gauss_points=3"]),
            ("TLS, linear fits", ["method.mapping=tls", "method.tls_terms=3"]),
            ("TLS, constant fits", ["method.mapping=tls", "method.tls_terms=1"]),
            ("TLS, USL", ["method.mapping=tls", "method.scheme=usl"]),
            ("TLS, dt / 2", ["method.mapping=tls", "time.dt=5e-6"]),
            # Not a setting of the TLS above: the strain rate changed (a_adjoint).
            ("TLS, adjoint strain rate", ["method.mapping=tls", "method.tls_strain_rate=adjoint"])]
# Quarter periods of the manufactured solution (omega = 100 pi, period 0.02 s), where its
# velocity and so its kinetic energy are zero: the kinetic energy of a run there is error.
A_QUARTERS = (0.005, 0.045, 0.085, 0.125, 0.165)


def quarter_energies(r):
    """The run's kinetic energy at every quarter period t = 0.005 + 0.01 k s (where the exact
    velocity is zero) divided by the exact largest, 5 omega^2 (rho = 1000, A = 0.1: 0.5 rho
    (A omega)^2 over the unit square, both components), from history.csv, up to the run's end."""
    path = os.path.join(r["_dir"], "history.csv")
    if not os.path.exists(path):
        return {}
    with open(path, newline="") as f:
        h = [(float(x["time"]), float(x["kinetic_energy"])) for x in csv.DictReader(f)]
    top = 5.0 * (100.0 * math.pi) ** 2
    out, k = {}, 0
    for t, ke in h:
        tq = 0.005 + 0.01 * k
        if abs(t - tq) < 5e-7:
            out[round(tq, 3)] = ke / top
            k += 1
    return out


def per_period(q, last):
    """The factor per period (0.02 s) of the error's energy over two periods: from the start
    (t = 0.005 to 0.045 s) or up to the last quarter period before the end or the stop."""
    ts = sorted(q)
    if len(ts) < 5:
        return None
    a, b = (ts[-5], ts[-1]) if last else (ts[0], ts[4])
    return (q[b] / q[a]) ** 0.5 if q[a] > 0 else None


def a_growth(R):
    """TLS against the direct mapping at A = 0.1 on 16 cells: where each run stops, and the
    kinetic energy at the quarter periods (exactly zero) as the error's energy over time.
    Returns (B2-TLS's growth factor per period, the text)."""
    base = ["grid.cells=16", "time.end=0.2", "output.history_every=1", "mms.allow_unstable=true"]
    specs, keys = [], []
    for basis, bsets in (("B2", ["method.basis=bspline", "method.degree=2"]),
                         ("P1", ["method.basis=linear"])):
        for label, sets in A_GROWTH:
            specs.append(("plate_mms_2d", base + bsets + sets, 1, f"a01_{basis}_{label}"))
            keys.append((basis, label))
    res = dict(zip(keys, R.many(specs)))
    head = ("| basis | mapping | result at T = 0.2 s | "
            + " | ".join(f"t = {t:g}" for t in A_QUARTERS)
            + " | per period, first two | per period, last two |")
    lines = [head, "|" + "---|" * (5 + len(A_QUARTERS))]
    for (basis, label), r in res.items():
        if r.get("status") == "ok":
            result = f"finishes, sigma RMS {e(r['errors'].get('stress_rms'))} Pa"
        else:
            result = f"stops at t = {fail_time(r.get('failure'))} s"
        q = quarter_energies(r)
        lines.append(f"| {basis} | {label} | {result} | "
                     + " | ".join(e(q[t]) if t in q else "" for t in A_QUARTERS)
                     + f" | {o(per_period(q, False))} | {o(per_period(q, True))} |")
    tls = [(k, r) for k, r in res.items() if k[1] != "direct" and "adjoint" not in k[1]]
    adj = {b: res[(b, "TLS, adjoint strain rate")] for b in ("B2", "P1")}
    adj_text = {b: (f"finishes (sigma RMS {e(r['errors'].get('stress_rms'))} Pa)"
                    if r.get("status") == "ok" else f"stops at t = {fail_time(r.get('failure'))} s")
                for b, r in adj.items()}
    adj_q = {b: quarter_energies(r) for b, r in adj.items()}
    tls_ok = [k for k, r in tls if r.get("status") == "ok"]
    q = {k: quarter_energies(r) for k, r in res.items()}

    def growth(key):
        return q[key][0.165] / q[key][0.005] if 0.165 in q[key] and q[key][0.005] > 0 else None

    def factors(basis, last):
        """The factors per period of basis's TLS runs but the constant fits (min, max)."""
        f = [per_period(q[k], last) for k, _ in tls if k[0] == basis and "constant" not in k[1]]
        f = [x for x in f if x is not None]
        return f"{min(f):.2f}-{max(f):.2f}"

    def fin(basis):
        return [k for k in tls_ok if k[0] == basis]

    b2_fin = fin("B2")
    b2_direct_sigma = res[("B2", "direct")]["errors"].get("stress_rms")
    fin_text = (
        f"{len(b2_fin)} of them reach T ({'; '.join(k[1][5:] for k in b2_fin)}), with the "
        f"error's energy at t = 0.165 s at "
        f"{min(q[k][0.165] for k in b2_fin):.2f}-{max(q[k][0.165] for k in b2_fin):.2f} times the "
        f"exact largest (B2 direct: {q[('B2', 'direct')][0.165]:.3f}) and stress errors "
        f"{min(res[k]['errors']['stress_rms'] for k in b2_fin) / b2_direct_sigma:.1f}-"
        f"{max(res[k]['errors']['stress_rms'] for k in b2_fin) / b2_direct_sigma:.1f} times "
        "B2 direct's: they finish because T comes first" if b2_fin else "none reaches T")
    p1_fin = fin("P1")
    dt_t = {b: fail_time(res[(b, "TLS, dt / 2")].get("failure")) for b in ("B2", "P1")}
    def_t = {b: fail_time(res[(b, "TLS, 2D defaults")].get("failure")) for b in ("B2", "P1")}
    const_t = [fail_time(res[(b, "TLS, constant fits")].get("failure")) for b in ("B2", "P1")]
    # With the text, B2-TLS's (2D defaults) growth factor of the error's energy per period over
    # the first two periods, for the next subsection (a_stiffness).
    return (per_period(q[("B2", "TLS, 2D defaults")], False),
            render("plate_001", "growth", top_energy=5.0 * (100.0 * math.pi) ** 2,
                   table="\n".join(lines), growth_b2_direct=growth(("B2", "direct")),
                   b2_direct_start=per_period(q[("B2", "direct")], False),
                   b2_direct_end=per_period(q[("B2", "direct")], True),
                   growth_p1_direct=growth(("P1", "direct")),
                   b2_start_factors=factors("B2", False), b2_end_factors=factors("B2", True),
                   fin_text=fin_text,
                   p1_first_ratio=(q[("P1", "direct")][0.005]
                                   / q[("P1", "TLS, 2D defaults")][0.005]),
                   p1_end_factors=factors("P1", True), n_p1_fin=len(p1_fin),
                   n_p1_tls=len([k for k, _ in tls if k[0] == "P1"]), const_t_0=const_t[0],
                   const_t_1=const_t[1], dt_t_b2=dt_t["B2"], dt_t_p1=dt_t["P1"],
                   def_t_b2=def_t["B2"], def_t_p1=def_t["P1"], adj_text_b2=adj_text["B2"],
                   adj_b2_start=o(per_period(adj_q["B2"], False)),
                   adj_b2_end=o(per_period(adj_q["B2"], True)), adj_text_p1=adj_text["P1"]))


# The layouts of the 16-cell plate at A = 0.1 analysed by `mpm stiffness`: the runs of
# a_growth (B2, MUSL, direct and TLS) stopped at a quarter period (t = 0.005 s, the particles at
# their farthest) and at three instants of zero exact displacement.
A_LAYOUTS = (0.005, 0.05, 0.1, 0.15)


def stiffness_rows(R, checkpoint, sets):
    """`mpm stiffness --layout-only` on a checkpoint: {(force, mass): (growth, asymmetry)}."""
    cmd = [R.mpm, "stiffness", os.path.join(EX, "plate_mms_2d.toml"), "--checkpoint", checkpoint,
           "--layout-only"]
    for x in ["grid.cells=16", "method.mapping=tls"] + sets:
        cmd += ["--set", x]
    res = subprocess.run(cmd, capture_output=True, text=True, env=R.env)
    rows = {}
    for line in res.stdout.splitlines():
        f = line.split()
        if len(f) >= 8 and f[0] in ("direct", "tls") and f[1] in ("direct", "tls"):
            rows[(f[0], f[1])] = (float(f[3]), float(f[7]))
    return rows


def a_stiffness(R, factor):
    """Where the growth of B2-TLS at A = 0.1 comes from: the linearised operator of the direct
    mapping and of TLS on the layouts of the runs (mpm stiffness, app/stiffness.hpp)."""
    b2 = ["method.basis=bspline", "method.degree=2"]
    p1 = ["method.basis=linear"]
    specs, keys = [], []
    # B2's runs at the layouts of A_LAYOUTS; P1-TLS's at three instants up to just before its
    # stop (t = 0.096 s in the table above).
    for run, basis, times in (("direct", b2, A_LAYOUTS), ("tls", b2, A_LAYOUTS),
                              ("P1-TLS", p1, (0.05, 0.08, 0.09))):
        for t in times:
            steps = round(t / 1e-5)
            mapping = "direct" if run == "direct" else "tls"
            specs.append(("plate_mms_2d", ["grid.cells=16", "mms.allow_unstable=true"] + basis + [
                f"method.mapping={mapping}", f"time.end={t}",
                f"output.checkpoint_every={steps}"], 1, f"a01_layout_{run}_{t}"))
            keys.append((run, t))
    runs = dict(zip(keys, R.many(specs)))
    res = {k: (stiffness_rows(R, os.path.join(r["_dir"], "checkpoint.bin"), b2),
               stiffness_rows(R, os.path.join(r["_dir"], "checkpoint.bin"), p1))
           for k, r in runs.items()}
    # The same layouts with the strain rate the adjoint of TLS's force (a_adjoint).
    adjoint = ["method.tls_strain_rate=adjoint"]
    res_adj = {k: (stiffness_rows(R, os.path.join(r["_dir"], "checkpoint.bin"), b2 + adjoint),
                   stiffness_rows(R, os.path.join(r["_dir"], "checkpoint.bin"), p1 + adjoint))
               for k, r in runs.items()}
    # P1-TLS on its last layout with a condition limit that reduces (almost) no fit to fewer
    # terms: whether its order reductions take part in the asymmetry there.
    late = runs.get(("P1-TLS", 0.09))
    p1_limit = stiffness_rows(R, os.path.join(late["_dir"], "checkpoint.bin"),
                              p1 + ["method.tls_max_condition=1e12"]) if late else {}
    lines = ["| layout: run, t | B2, direct force | B2-TLS force, TLS mass | B2-TLS force, direct "
             "mass | B2-TLS: asymmetry | P1, direct force | P1-TLS | P1-TLS: asymmetry "
             "| B2-TLS, adjoint rate | its asymmetry | P1-TLS, adjoint rate | its asymmetry |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (m, t), (bb, pp) in res.items():
        ab, ap = res_adj[(m, t)]
        cell = lambda rows, k: f"{rows[k][0]:.3g}" if k in rows else "n/a"
        asym = lambda rows: f"{rows[('tls', 'tls')][1]:.2g}" if ("tls", "tls") in rows else "n/a"
        lines.append(f"| {m if m == 'P1-TLS' else 'B2 ' + m}, {t:g} s"
                     f"{' (quarter period)' if t == 0.005 else ''} | "
                     f"{cell(bb, ('direct', 'direct'))} | {cell(bb, ('tls', 'tls'))} | "
                     f"{cell(bb, ('tls', 'direct'))} | {asym(bb)} | "
                     f"{cell(pp, ('direct', 'direct'))} | {cell(pp, ('tls', 'tls'))} | {asym(pp)} | "
                     f"{cell(ab, ('tls', 'tls'))} | {asym(ab)} | {cell(ap, ('tls', 'tls'))} | "
                     f"{asym(ap)} |")
    ok = [v for v in res.values() if ("tls", "tls") in v[0] and ("tls", "tls") in v[1]]
    direct_max = max(max(v[0][("direct", "direct")][0], v[0][("direct", "tls")][0],
                         v[1][("direct", "direct")][0]) for v in ok) if ok else None
    tls_b2 = [v[0][("tls", "tls")][0] for k, v in res.items() if k[0] != "P1-TLS" and v in ok]
    b2_layouts = [v for k, v in res.items() if k[0] != "P1-TLS" and v in ok]
    p1_max = max(v[1][("tls", "tls")][0] for v in b2_layouts) if b2_layouts else None
    p1_asym = max(v[1][("tls", "tls")][1] for v in b2_layouts) if b2_layouts else None
    own = {t: v[1].get(("tls", "tls")) for (run, t), v in res.items() if run == "P1-TLS"}
    own_text = "; ".join(f"t = {t:g} s: Re lambda {g[0]:.3g} 1/s, asymmetry {g[1]:.2g}"
                         for t, g in own.items() if g)
    limit_text = (f"{p1_limit[('tls', 'tls')][1]:.2g} (Re lambda "
                  f"{p1_limit[('tls', 'tls')][0]:.3g} 1/s)" if ("tls", "tls") in p1_limit
                  else "n/a")
    adj_rows = [r for v in res_adj.values() for rows in v for k, r in rows.items()
                if k[0] == "tls"]
    adj_growth = max(r[0] for r in adj_rows) if adj_rows else None
    adj_asym = max(r[1] for r in adj_rows) if adj_rows else None
    quarter = res.get(("tls", A_LAYOUTS[0]), ({}, {}))[0]
    q_tls = quarter.get(("tls", "tls"), (math.nan,))[0]
    q_direct = quarter.get(("tls", "direct"), (math.nan,))[0]
    # The observed growth rate of B2-TLS (defaults): the energy factor per period over the first
    # two periods, gamma = ln(factor) / (2 period).
    return (render("plate_001", "stiffness", table="\n".join(lines),
                   direct_max=e(direct_max) if direct_max is not None else "n/a",
                   min_tls_b2=min(tls_b2), max_tls_b2=max(tls_b2), q_tls=q_tls, q_direct=q_direct,
                   factor=factor, factor_rate=math.log(factor) / 0.04,
                   p1_asym=e(p1_asym) if p1_asym is not None else "n/a",
                   p1_max=e(p1_max) if p1_max is not None else "n/a", own_text=own_text,
                   limit_text=limit_text, adj_asym=e(adj_asym) if adj_asym is not None else "n/a",
                   adj_growth=e(adj_growth) if adj_growth is not None else "n/a")
            + "\n" + a_adjoint(R))


# a_adjoint's variants of the mapping, on top of each basis.
ADJ_MAPPINGS = [("direct", ["method.mapping=direct"]), ("TLS, 2D defaults", ["method.mapping=tls"]),
                ("TLS, adjoint rate", ["method.mapping=tls", "method.tls_strain_rate=adjoint"])]
ADJ_BASES = [("P1", ["method.basis=linear"]), ("B2", ["method.basis=bspline", "method.degree=2"])]


def a_adjoint(R):
    """TLS with the strain rate the adjoint of its force (method.tls_strain_rate = "adjoint"):
    the plate at A = 0.05 m (sec_item3's amplitude) and A = 0.1 m (001's set-up) on 8-32 cells
    and the vortex at A = 0.1 and 1 rad on 32 and 64 cells, against the direct mapping and the
    2D default TLS."""
    specs, keys = [], []
    for basis, bs in ADJ_BASES:
        for label, ms in ADJ_MAPPINGS:
            for n in (8, 16, 32):
                specs.append(("plate_mms_2d", [f"grid.cells={n}", "mms.amplitude=0.05"] + bs + ms,
                              1, f"adj_plate05_{basis}_{label}_{n}"))
                keys.append(("plate05", basis, label, n))
                specs.append(("plate_mms_2d", [f"grid.cells={n}", "time.end=0.2", "mms.allow_unstable=true",
                                               "output.history_every=100"] + bs + ms,
                              1, f"adj_plate10_{basis}_{label}_{n}"))
                keys.append(("plate10", basis, label, n))
            for A in ("0.1", "1"):
                for n in (32, 64):
                    specs.append(("vortex_2d", [f"vortex.amplitude={A}", f"grid.cells={n}"] + bs + ms,
                                  1, f"adj_vortex_{A}_{basis}_{label}_{n}"))
                    keys.append((f"vortex{A}", basis, label, n))
    # B2 with the adjoint rate at A = 0.1 on 32 cells with dt halved: whether its growth there
    # depends on the time step.
    specs.append(("plate_mms_2d", ["grid.cells=32", "time.end=0.2", "mms.allow_unstable=true", "time.dt=5e-6",
                                   "output.history_every=200"] + ADJ_BASES[1][1] + ADJ_MAPPINGS[2][1],
                  1, "adj_plate10_B2_adjoint_32_dt2"))
    keys.append(("plate10 dt/2", "B2", ADJ_MAPPINGS[2][0], 32))
    res = dict(zip(keys, R.many(specs)))
    labels = [m for m, _ in ADJ_MAPPINGS]

    def cell(r, what):
        if r.get("status") != "ok":
            return f"stops at t = {fail_time(r.get('failure'))} s"
        return e(r["errors"].get(what))

    def table(case, grids, what):
        head = "| basis | cells | " + " | ".join(labels) + " |"
        out = [head, "|---|---|" + "---|" * len(labels)]
        for basis, _ in ADJ_BASES:
            for n in grids:
                out.append(f"| {basis} | {n} | "
                           + " | ".join(cell(res[(case, basis, m, n)], what) for m in labels) + " |")
        return "\n".join(out)

    def ok(case, basis, m, n):
        return res[(case, basis, m, n)].get("status") == "ok"

    def err(case, basis, m, n, what="stress_rms"):
        return res[(case, basis, m, n)]["errors"].get(what)

    # A = 0.05: the adjoint against the direct mapping and the default, in stress.
    beats = {}
    for basis, _ in ADJ_BASES:
        beats[basis] = [
            (n, err("plate05", basis, "direct", n) / err("plate05", basis, "TLS, adjoint rate", n),
             err("plate05", basis, "TLS, 2D defaults", n) / err("plate05", basis, "TLS, adjoint rate", n))
            for n in (8, 16, 32) if ok("plate05", basis, "TLS, adjoint rate", n)
            and ok("plate05", basis, "direct", n) and ok("plate05", basis, "TLS, 2D defaults", n)]
    wins = {basis: sum(a > 1.0 for _, a, _ in v) for basis, v in beats.items()}

    def rng(basis):
        v = [b for _, _, b in beats[basis]]
        return f"{min(v):.3g}-{max(v):.3g}" if v else "n/a"
    ratio_text = "; ".join(
        f"{basis}: direct / adjoint {', '.join(f'{a:.3g}' for _, a, _ in v)}, default / adjoint "
        f"{', '.join(f'{b:.3g}' for _, _, b in v)}" for basis, v in beats.items())
    # A = 0.1: where each finishes; the adjoint's error energy per period.
    fin10 = {(b, m): [n for n in (8, 16, 32) if ok("plate10", b, m, n)]
             for b, _ in ADJ_BASES for m in labels}
    growth = []
    for basis, _ in ADJ_BASES:
        for n in (8, 16, 32):
            q = quarter_energies(res[("plate10", basis, "TLS, adjoint rate", n)])
            qd = quarter_energies(res[("plate10", basis, "direct", n)])
            growth.append(f"| {basis} | {n} | {o(per_period(qd, False))} | {o(per_period(qd, True))} | "
                          f"{o(per_period(q, False))} | {o(per_period(q, True))} |")
    half = res[("plate10 dt/2", "B2", ADJ_MAPPINGS[2][0], 32)]
    full = res[("plate10", "B2", ADJ_MAPPINGS[2][0], 32)]
    half_text = (
        "with dt halved the B2 run on 32 cells "
        + (f"finishes with sigma RMS {e(half['errors'].get('stress_rms'))} Pa"
           if half.get("status") == "ok" else f"stops at t = {fail_time(half.get('failure'))} s")
        + f", its error's energy growing by {o(per_period(quarter_energies(half), True))} per "
        f"period over its last two periods (dt = 1e-5 s: {cell(full, 'stress_rms')} Pa, "
        f"{o(per_period(quarter_energies(full), True))}): the time step is not the cause")
    fin_v = {m: sum(ok(c, b, m, n) for c in ("vortex0.1", "vortex1") for b, _ in ADJ_BASES
                    for n in (32, 64)) for m in labels}
    cost = [(n, res[("plate10", "B2", "TLS, adjoint rate", n)].get("ns_per_particle_step"),
             res[("plate10", "B2", "direct", n)].get("ns_per_particle_step"))
            for n in (16, 32) if ok("plate10", "B2", "TLS, adjoint rate", n)]
    cost_text = "; ".join(f"{n} cells {a:.0f} against B2 direct's {d:.0f} ns per particle-step"
                          for n, a, d in cost if a and d) or "n/a"
    return render("plate_001", "adjoint",
                  plate05_stress=table("plate05", (8, 16, 32), "stress_rms"),
                  plate05_u=table("plate05", (8, 16, 32), "displacement_rms"),
                  ratio_text=ratio_text,
                  plate10_stress=table("plate10", (8, 16, 32), "stress_rms"),
                  growth_table="\n".join(growth),
                  vortex01_u=table("vortex0.1", (32, 64), "displacement_rms"),
                  vortex1_u=table("vortex1", (32, 64), "displacement_rms"),
                  fin10_b2_adjoint=(", ".join(str(n) for n in fin10[("B2", "TLS, adjoint rate")])
                                    or "no grid"),
                  fin10_b2_defaults=(", ".join(str(n) for n in fin10[("B2", "TLS, 2D defaults")])
                                     or "none"),
                  fin10_b2_direct=", ".join(str(n) for n in fin10[("B2", "direct")]) or "none",
                  half_text=half_text,
                  fin10_p1_adjoint=(", ".join(str(n) for n in fin10[("P1", "TLS, adjoint rate")])
                                    or "no grid"),
                  wins_p1=wins["P1"], wins_b2=wins["B2"], rng_p1=rng("P1"), rng_b2=rng("B2"),
                  fin_v_adjoint=fin_v["TLS, adjoint rate"],
                  fin_v_defaults=fin_v["TLS, 2D defaults"], fin_v_direct=fin_v["direct"],
                  cost_text=cost_text)


def sec_long(R, ctx):
    """--long: 001's plate at A = 0.1 m to T = 0.2 s, refined, with the study's own table."""
    out, rows = R.study("plate_mms_2d", "grid.cells=8,16,32,64",
                        "linear/direct, bspline2/direct, bspline2/tls, linear/tls, bspline2/mls",
                        ["time.end=0.2", "mms.allow_unstable=true"], name="plate_long")
    with open(os.path.join(out, "study.txt")) as f:
        table = f.read()
    figs = plot_study(out, os.path.join(ctx["figdir"], "plate_long"),
                      "displacement_rms,stress_rms", "plate_mms_2d, A = 0.1 m, T = 0.2 s",
                      energy=False)
    return ("Regenerated by `--long` in this report:\n\n```\n" + table + "```\n\n"
            + fig_md(ctx, figs, "plate at A = 0.1 m"))
