"""PS-MPM with partially filled elements (D 3.4.4, 7.2): a column whose top row is partly
filled, under gravity and under a pressure, with PS splines, P1 triangles, B-splines and TLS,
lumped, consistent and partially lumped mass (sec_ps_partial); with the probes of B2-TLS with
consistent mass that it runs (tls_consistent_probe) and the growing mode of that method under
a constant load, against the column's spectrum from scripts/column_modes.py (tls_flutter).
Prose: templates/ps_partial.md."""
import csv
import glob
import json
import math
import os
import subprocess
import sys

from .common import SCRIPTS, e, fail_time, verdict_claim
from .template import render
from .tls_robust import ALLOW_UNSTABLE, TLS_BASES


def sec_ps_partial(R, ctx):
    """D 3.4.4 and 7.2: PS-MPM with partially filled elements. The column of
    examples/custom_plate_2d.toml (rollers, fixed bottom, free top; 4 x 22 cells of 0.05 m) under
    ramped gravity and under a ramped pressure on its top face, its top at 1.0, 0.99, 0.975 and
    0.96 m: the cell row below the top filled to 100, 80, 50, 20 %. With partial lumping
    (method.partial_lumping = 0.5, D 7.2) for each basis with consistent mass, and TLS."""
    tops = (1.0, 0.99, 0.975, 0.96)
    fills = ("100 %", "80 %", "50 %", "20 %")
    lump = "method.partial_lumping=0.5"
    # (basis, mass, label, extra keys); mass "partial": consistent with partial lumping.
    methods = [("bspline", "lumped"), ("bspline", "consistent"), ("bspline", "partial"),
               ("p1_triangles", "lumped"), ("p1_triangles", "consistent"),
               ("p1_triangles", "partial"), ("powell_sabin", "lumped"),
               ("powell_sabin", "consistent"), ("powell_sabin", "partial"),
               ("bspline_tls", "lumped"), ("bspline_tls", "consistent"), ("bspline_tls", "partial"),
               ("linear_tls", "lumped"), ("linear_tls", "consistent"), ("linear_tls", "partial")]
    names = {"bspline": "B2 (rectangles)", "bspline_tls": "B2-TLS (rectangles)",
             "linear_tls": "P1-TLS (rectangles)"}
    mass_names = {"partial": "partial lumping 0.5"}

    def method_keys(b, m):
        keys = {"bspline_tls": ["method.basis=bspline", "method.mapping=tls"],
                "linear_tls": ["method.basis=linear", "method.mapping=tls"]}.get(
                    b, [f"method.basis={b}"])
        # B-spline TLS with consistent mass is refused unless asked for (the growing mode below).
        if b == "bspline_tls" and m != "lumped":
            keys.append(ALLOW_UNSTABLE)
        return keys + ([f"method.mass=consistent", lump] if m == "partial" else [f"method.mass={m}"])
    # The pressure case: uniaxial strain under p(t) = P min(t / T, 1) on the top face.
    pressure = ['loading.body_force=["0", "0"]', 'traction.top=["0", "-P*min(t/T, 1)"]',
                "constants.P=1e4",
                'exact.displacement=["0", "-P*min(t/T, 1)*y/(E*(1 - nu)/((1 + nu)*(1 - 2*nu)))"]',
                'exact.stress=["-P*min(t/T, 1)*nu/(1 - nu)", "-P*min(t/T, 1)", "0"]']
    cases = [("gravity (free top)", []), ("pressure on the top face", pressure)]
    common = ["particles.per_cell=4", "time.dt=1e-4", "method.degree=2"]
    specs, keys = [], []
    for ci, (_, extra) in enumerate(cases):
        for top in tops:
            for b, m in methods:
                keys.append((ci, top, b, m))
                specs.append(("custom_plate_2d", common + extra + [
                    f"body.max=[0.2, {top}]", f"constants.H={top}"] + method_keys(b, m), 0,
                    f"ps_partial_{ci}_{top}_{b}_{m}"))
    # The consistent PS mass and the explicit step: the full column at half the lumped-mass
    # limit (2.5e-4 s) and at 1e-4 s, to t = 0.2 s.
    for dt in ("2.5e-4", "1e-4"):
        keys.append(("dt", dt))
        specs.append(("custom_plate_2d", ["particles.per_cell=4", f"time.dt={dt}",
                                          "time.end=0.2", "method.basis=powell_sabin",
                                          "method.mass=consistent"], 0, f"ps_partial_dt_{dt}"))
    # TLS with consistent mass on the vortex (A = 0.1, 32 cells, B2 and P1; the section "Robust
    # TLS on the grid's cells" below stops B2 at t = 0.517 s), with and without partial lumping,
    # and the lumped-mass run for comparison.
    for tb in ("B2", "P1"):
        vortex = ["vortex.amplitude=0.1", "grid.cells=32", "method.mapping=tls"] + TLS_BASES[tb]
        for m in ("lumped", "consistent", "partial"):
            keys.append(("vortex", tb, m))
            specs.append(("vortex_2d", vortex + (["method.mass=consistent", lump] if m == "partial"
                                                 else [f"method.mass={m}"])
                          + ([ALLOW_UNSTABLE] if m != "lumped" and tb == "B2" else []), 0,
                          f"ps_partial_vortex_{tb}_{m}"))
    # The threshold: the gravity column with a 20 % top row, each basis, c = 0.25 .. 0.9.
    thresholds = ("0.25", "0.5", "0.75", "0.9")
    bases = ("bspline", "p1_triangles", "powell_sabin", "bspline_tls", "linear_tls")
    for b in bases:
        for c in thresholds:
            if c == "0.5":
                continue  # the table's runs
            keys.append(("threshold", b, c))
            specs.append(("custom_plate_2d", common + [f"body.max=[0.2, {tops[-1]}]",
                                                       f"constants.H={tops[-1]}"]
                          + [k for k in method_keys(b, "partial") if k != lump]
                          + [f"method.partial_lumping={c}"], 0, f"ps_partial_c_{b}_{c}"))
    # What stops B2-TLS with consistent mass (sec_tls_robust): the pressure case with the top row
    # full, every step in history.csv, at three time steps and three loads; lumped mass to 3 s;
    # P1-TLS with consistent mass.
    tls_cons = method_keys("bspline_tls", "consistent")
    probe = ["particles.per_cell=4", "method.degree=2", "output.history_every=1"] + pressure + [
        "body.max=[0.2, 1.0]", "constants.H=1.0"]
    probes = [(("probe", "dt", dt), probe + tls_cons + [f"time.dt={dt}"])
              for dt in ("1e-4", "5e-5", "2.5e-5")]
    probes += [(("probe", "P", P), probe + tls_cons + ["time.dt=1e-4", f"constants.P={P}"])
               for P in ("1.5e4", "2e4")]
    probes += [(("probe", "lumped"), probe + method_keys("bspline_tls", "lumped")
                + ["time.dt=1e-4", "time.end=3"]),
               (("probe", "p1"), probe + ["method.basis=linear", "method.mapping=tls",
                                         "method.mass=consistent", "time.dt=1e-4"])]
    # One TLS setting or the scheme changed at a time.
    switches = ("method.tls_cell_integrals=centres", "method.tls_surface_stress=element",
                "method.tls_positivity=off", "method.tls_completion=virtual",
                "method.tls_max_condition=1e8", "method.gauss_points=3", "method.tls_terms=3",
                "method.scheme=usl", "method.scheme=usf", "method.scheme=usavg")
    probes += [(("probe", "switch", sw), probe + tls_cons + ["time.dt=1e-4", sw])
               for sw in switches]
    for k, sets in probes:
        keys.append(k)
        specs.append(("custom_plate_2d", sets, 0, "ps_partial_" + "_".join(k)))
    # The same column with the load held after t0 (tls_flutter): whether a growing mode appears
    # at a constant load, every step in history.csv; one run ends before its stop with a frame
    # for the mode's shape.
    for k, (cells, load, m, end) in FROZEN.items():
        keys.append(("frozen",) + k)
        specs.append(("custom_plate_2d", frozen_keys(cells, load, m, end), 1 if end else 0,
                      "ps_partial_frozen_" + "_".join(str(x) for x in k)))
    res = dict(zip(keys, R.many(specs)))
    for b in bases:
        res[("threshold", b, "0.5")] = res[(0, tops[-1], b, "partial")]

    def cell(r):
        if r.get("status") == "ok":
            return e(r.get("errors", {}).get("stress_rms"))
        return f"stops at t = {fail_time(r.get('failure'))} s"
    tables = []
    for ci, (name, _) in enumerate(cases):
        t = [f"| {name} | " + " | ".join(f"top row {f}" for f in fills) + " |",
             "|---|" + "---|" * len(fills)]
        for b, m in methods:
            t.append(f"| {names.get(b, b)}, {mass_names.get(m, m)} | " +
                     " | ".join(cell(res[(ci, top, b, m)]) for top in tops) + " |")
        tables.append("\n".join(t))

    def stops(b, m, rows=tops[1:]):
        """Runs of basis b with mass m that stop, over both cases and the top rows `rows` (by
        default the partly filled ones)."""
        return sum(res[(ci, top, b, m)].get("status") != "ok"
                   for ci in range(len(cases)) for top in rows)

    def growth(b, m):
        """Worst partial-fill stress error over the full-row one, over both cases (None when a
        run stops)."""
        worst = None
        for ci in range(len(cases)):
            rs = [res[(ci, top, b, m)] for top in tops]
            if any(r.get("status") != "ok" for r in rs):
                return None
            es = [r["errors"]["stress_rms"] for r in rs]
            g = max(es[1:]) / es[0]
            worst = g if worst is None else max(worst, g)
        return worst
    n_partial = len(cases) * (len(tops) - 1)
    ps_stops = {m: stops("powell_sabin", m) for m in ("lumped", "consistent")}
    b2_stops = {m: stops("bspline", m) for m in ("lumped", "consistent")}
    ps_g = {m: growth("powell_sabin", m) for m in ("lumped", "consistent")}
    b2_g = {m: growth("bspline", m) for m in ("lumped", "consistent")}
    fragile = any(ps_stops[m] > b2_stops[m] for m in ps_stops) or any(
        ps_g[m] is not None and b2_g[m] is not None and ps_g[m] > 2 * b2_g[m] for m in ps_g)

    full_stops = [f"{cases[ci][0]} (t = {fail_time(r.get('failure'))} s)" for ci in range(len(cases))
                  for r in [res[(ci, tops[0], "powell_sabin", "consistent")]]
                  if r.get("status") != "ok"]
    def t_stop(r):
        t = fail_time(r.get("failure"))
        return float(t) if r.get("status") != "ok" and t != "?" else math.inf
    earlier = all(t_stop(res[(ci, top, "powell_sabin", "consistent")]) <
                  t_stop(res[(ci, tops[0], "powell_sabin", "consistent")])
                  for ci in range(len(cases)) for top in tops[1:])
    full_text = ("PS-MPM with consistent mass stops also with the top row full, in "
                 f"{' and '.join(full_stops)}: a free surface above full cells is enough"
                 + (", and every partial row makes it stop earlier" if earlier else "")
                 + ". " if full_stops else "")

    def gtext(g):
        return "a run stops" if g is None else f"worst partial / full {g:.1f}x"
    measured = "; ".join(
        f"PS {m}: {ps_stops[m]} of {n_partial} partial-fill runs stop, {gtext(ps_g[m])} "
        f"(B2 {m}: {b2_stops[m]} stop, {gtext(b2_g[m])})" for m in ("lumped", "consistent"))
    d1, d2 = res[("dt", "2.5e-4")], res[("dt", "1e-4")]
    dt_text = (f"At dt = 2.5e-4 s (half the lumped-mass limit that the run's stability check "
               f"uses, 4.8e-4 s) the full column (gravity) with consistent PS mass "
               f"{'runs to t = 0.2 s' if d1.get('status') == 'ok' else 'stops at t = ' + fail_time(d1.get('failure')) + ' s'}"
               f"; at 1e-4 s it {'runs to t = 0.2 s' if d2.get('status') == 'ok' else 'stops as well'}.")
    # Why the consistent PS runs of the tables stop (the first failure of each fill, gravity).
    reasons = []
    for top, fill in zip(tops, fills):
        r = res[(0, top, "powell_sabin", "consistent")]
        if r.get("status") != "ok":
            # The message up to its advice (after the first "; "), whole words only.
            reasons.append(f"{fill}: {(r.get('failure') or '?').split('; ')[0]}")
    why = ("The consistent PS runs (gravity) stop with: " + "; ".join(reasons) + "."
           if reasons else "")

    # Partial lumping: which runs finish, its error against lumped and consistent mass (where
    # consistent finishes), the most DOFs lumped, and conservation.
    n_all = len(cases) * len(tops)
    finish = {b: {m: n_all - stops(b, m, tops) for m in ("lumped", "consistent", "partial")}
              for b in bases}
    ratios_l, ratios_c, lumped_max, cons = [], [], 0, [0.0, 0.0]
    for b in bases:
        for ci in range(len(cases)):
            for top in tops:
                rp = res[(ci, top, b, "partial")]
                if rp.get("status") != "ok":
                    continue
                lumped_max = max(lumped_max, rp.get("method", {}).get("partially_lumped_dofs_max", 0))
                c = rp.get("conservation", {})
                cons[0] = max(cons[0], c.get("max_rel_mass_error", 0.0))
                cons[1] = max(cons[1], c.get("max_rel_momentum_error", 0.0))
                sp = rp["errors"]["stress_rms"]
                for other, out in (("lumped", ratios_l), ("consistent", ratios_c)):
                    ro = res[(ci, top, b, other)]
                    if ro.get("status") == "ok":
                        out.append(sp / ro["errors"]["stress_rms"])
    finish_rows = "\n".join(
        f"| {names.get(b, b)} | {finish[b]['lumped']} of {n_all} | {finish[b]['consistent']} of "
        f"{n_all} | {finish[b]['partial']} of {n_all} |" for b in bases)
    span = (lambda v: f"{min(v):.2f}-{max(v):.2f}" if v else "none")
    partial_ok = all(finish[b]["partial"] == n_all for b in bases)
    stopped_runs = [(b, ci, top, res[(ci, top, b, "partial")].get("failure") or "?")
                    for b in bases for ci in range(len(cases)) for top in tops
                    if res[(ci, top, b, "partial")].get("status") != "ok"]
    # Each failure up to its first particle ("...: particle N at x = (a, b)").
    stopped = [f"{names.get(b, b)}, {cases[ci][0]}, top row {fills[tops.index(top)]}: "
               f"{f.split('; particle')[0]}" for b, ci, top, f in stopped_runs]
    singular = sum("singular" in f for *_, f in stopped_runs)
    stopped_text = ("The partial-lumping runs that stop: " + "; ".join(stopped) + ". "
                    + (render("ps_partial", "singular", singular=singular)
                       if len(stopped_runs) > singular else "")
                    if stopped else "")
    # The smallest threshold tried at which every run of the direct mapping finishes.
    direct = [b for b in bases if not b.endswith("_tls")]
    enough = [c for c in thresholds
              if all(res[("threshold", b, c)].get("status") == "ok" for b in direct)]
    ps_ratio = [res[(ci, top, "powell_sabin", "partial")]["errors"]["stress_rms"] /
                res[(ci, top, "powell_sabin", "lumped")]["errors"]["stress_rms"]
                for ci in range(len(cases)) for top in tops
                if res[(ci, top, "powell_sabin", "partial")].get("status") == "ok"
                and res[(ci, top, "powell_sabin", "lumped")].get("status") == "ok"]
    ps_stable = finish["powell_sabin"]["partial"] == n_all and ps_ratio and max(ps_ratio) <= 2.0
    ps_measured = (f"PS with partial lumping 0.5: {finish['powell_sabin']['partial']} of {n_all} "
                   f"runs finish (consistent: {finish['powell_sabin']['consistent']}), stress error "
                   f"{span(ps_ratio)}x lumped PS's")
    full_ps_ok = all(res[(ci, tops[0], "powell_sabin", "partial")].get("status") == "ok"
                     for ci in range(len(cases)))
    full_cause = ("With partial lumping both full-row PS runs finish: what stopped them is in the "
                  "rows of the DOFs whose functions reach the empty row above the body, the rows "
                  "it lumps." if full_stops and full_ps_ok else
                  "What stops the full-row runs is not examined." if full_stops else "")
    sweep = "\n".join(
        f"| {names.get(b, b)} | " + " | ".join(
            cell(res[("threshold", b, c)]) + (
                f" ({res[('threshold', b, c)].get('method', {}).get('partially_lumped_dofs_max')} lumped)"
                if res[("threshold", b, c)].get("status") == "ok" else "")
            for c in thresholds) + " |" for b in bases)
    probe_text = tls_consistent_probe(res) + "\n\n" + tls_flutter(res)

    def vcell(r):
        if r.get("status") == "ok":
            return f"displacement RMS {e(r['errors'].get('displacement_rms'))} m"
        return f"stops at t = {fail_time(r.get('failure'))} s"
    vortex_text = "; ".join(
        f"{tb}, {mass_names.get(m, m + ' mass')}: {vcell(res[('vortex', tb, m)])}"
        for tb in ("B2", "P1") for m in ("lumped", "consistent", "partial"))
    # P1-TLS with consistent mass: the column runs that finish, and its error against lumped
    # P1-TLS where both finish.
    p1_ratio = [res[(ci, top, "linear_tls", m)]["errors"]["stress_rms"] /
                res[(ci, top, "linear_tls", "lumped")]["errors"]["stress_rms"]
                for m in ("partial",) for ci in range(len(cases)) for top in tops
                if res[(ci, top, "linear_tls", m)].get("status") == "ok"
                and res[(ci, top, "linear_tls", "lumped")].get("status") == "ok"]
    return render("ps_partial", "section", table_gravity=tables[0], table_pressure=tables[1],
                  dt_text=dt_text, why=why, measured=measured,
                  v_fragile=verdict_claim(fragile, measured), full_text=full_text,
                  full_cause=full_cause, n_all=n_all, finish_rows=finish_rows,
                  partial_text="every run finishes" if partial_ok else "not every run finishes",
                  ratios_l_span=span(ratios_l), ratios_c_span=span(ratios_c),
                  lumped_max=lumped_max, cons_mass=e(cons[0]), cons_momentum=e(cons[1]),
                  stopped_text=stopped_text, threshold_heads=" | c = ".join(thresholds),
                  threshold_rule="---|" * len(thresholds), sweep=sweep,
                  enough_text=("c = " + ", ".join(enough[:-1]) + " and " + enough[-1]
                               if len(enough) > 1 else "c = " + enough[0] if enough else "none"),
                  ps_measured=ps_measured, v_ps_stable=verdict_claim(ps_stable, ps_measured),
                  probe_text=probe_text, vortex_text=vortex_text,
                  p1_tls_consistent=finish["linear_tls"]["consistent"],
                  p1_tls_partial=finish["linear_tls"]["partial"], p1_ratio_span=span(p1_ratio))


def kinetic_growth(r):
    """The growth of a run that stops by an instability, from its history.csv (every step):
    (t1, rate) with t1 the first time the kinetic energy exceeds 10x its largest value over the
    first half of the run, and rate = ln(1e3) / (t2 - t1) [1/s], t2 the first time it exceeds
    1e4x that value (the energy's e-folding rate; the amplitude grows at half of it). None when
    the run finished or the history does not show both."""
    if r.get("status") == "ok":
        return None
    path = os.path.join(r["_dir"], "history.csv")
    if not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        h = [(float(x["time"]), float(x["kinetic_energy"])) for x in csv.DictReader(f)]
    if len(h) < 4:
        return None
    end = h[-1][0]
    base = max(k for t, k in h if t <= 0.5 * end)
    t1 = next((t for t, k in h if t > 0.5 * end and k > 10.0 * base), None)
    t2 = next((t for t, k in h if t > 0.5 * end and k > 1e4 * base), None)
    if t1 is None or t2 is None or not t2 > t1:
        return None
    return t1, math.log(1e3) / (t2 - t1)


# The column under a constant load (tls_flutter): key -> (cells across, load [Pa], method, end);
# method "tls" is B2-TLS with consistent mass; end None: t = 3 s; a negative load pulls.
FROZEN = {("b2tls", 4, 1000): (4, 1000, "tls", None), ("b2tls", 4, 1500): (4, 1500, "tls", None),
          ("b2tls", 4, 2000): (4, 2000, "tls", None), ("b2tls", 4, 4000): (4, 4000, "tls", None),
          ("b2tls", 4, -4000): (4, -4000, "tls", None), ("b2tls", 2, 2000): (2, 2000, "tls", None),
          ("b2tls", 2, 4000): (2, 4000, "tls", None), ("b2tls", 8, 100): (8, 100, "tls", None),
          ("b2tls", 8, 250): (8, 250, "tls", None),
          ("lumped", 4, 4000): (4, 4000, "lumped", None), ("p1", 4, 4000): (4, 4000, "p1", None),
          ("direct", 4, 4000): (4, 4000, "direct", None),
          ("lumped", 8, 4000): (8, 4000, "lumped", None), ("p1", 8, 4000): (8, 4000, "p1", None),
          ("shape", 4, 4000): (4, 4000, "tls", 0.95)}


def frozen_keys(cells, load, method, end):
    """The column of sec_ps_partial (top row full) under p(t) = P min(t, t0) / T on its top face
    with P = +-1e4 Pa and t0 = |load| / 1e4 s: the pressure of the probe runs, held at `load`
    after t0 (negative: tension), to t = 3 s (or `end`), every step in history.csv."""
    P, t0 = math.copysign(1e4, load), abs(load) / 1e4
    m = {"tls": ["method.basis=bspline", "method.mapping=tls", "method.mass=consistent",
                 ALLOW_UNSTABLE],
         "lumped": ["method.basis=bspline", "method.mapping=tls", "method.mass=lumped"],
         "p1": ["method.basis=linear", "method.mapping=tls", "method.mass=consistent"],
         "direct": ["method.basis=bspline", "method.mass=consistent"]}[method]
    return ["particles.per_cell=4", "method.degree=2", "output.history_every=1",
            'loading.body_force=["0", "0"]', 'traction.top=["0", "-P*min(t, t0)/T"]',
            f"constants.P={P:g}", f"constants.t0={t0:g}", "body.max=[0.2, 1.0]", "constants.H=1.0",
            'exact.displacement=["0", "-P*min(t, t0)/T*y/(E*(1 - nu)/((1 + nu)*(1 - 2*nu)))"]',
            'exact.stress=["-P*min(t, t0)/T*nu/(1 - nu)", "-P*min(t, t0)/T", "0"]',
            f"grid.cells={cells}", f"time.dt={'5e-5' if cells >= 8 else '1e-4'}",
            f"time.end={end or 3}"] + m


def tls_flutter(res):
    """The paragraph on the growing mode of B2-TLS with consistent mass under a constant load
    (FROZEN runs of sec_ps_partial), with the column's spectrum from scripts/column_modes.py."""
    import numpy as np  # python3-numpy comes with python3-matplotlib (scripts/deps.sh)

    def history(r):
        with open(os.path.join(r["_dir"], "history.csv"), newline="") as f:
            return np.array([(float(x["time"]), float(x["kinetic_energy"]))
                             for x in csv.DictReader(f)])

    def outcome(k):
        r, (_, load, _, _) = res[("frozen",) + k], FROZEN[k]
        if r.get("status") != "ok":
            return f"stops at t = {fail_time(r.get('failure'))} s", None
        h = history(r)
        t0 = abs(load) / 1e4
        after = h[(h[:, 0] >= t0 + 0.05) & (h[:, 0] <= t0 + 0.55), 1].max()
        last = h[h[:, 0] >= h[-1, 0] - 0.5, 1].max()
        g = last / after
        return f"kinetic energy x{g:.2f}" if g < 10 else f"kinetic energy x{g:,.0f}", g
    grids = ((2, (2000, 4000)), (4, (1000, 1500, 2000, 4000, -4000)), (8, (100, 250)))
    rows = []
    for cells, loads in grids:
        for load in loads:
            text, _ = outcome(("b2tls", cells, load))
            rows.append(f"| {cells} ({0.2 / cells:g} m) | {load:+d} | {text} |")
    def bracket(cells):
        """'a and b': the largest load (compression) that did not grow (x < 10) and the
        smallest that did, on this grid; 'below a' or 'above b' when one is missing."""
        loads = [l for c, ls in grids if c == cells for l in ls if l > 0]
        grew = {l: (lambda g: g is None or g >= 10)(outcome(("b2tls", cells, l))[1]) for l in loads}
        calm = [l for l in loads if not grew[l]]
        bad = [l for l in loads if grew[l]]
        if calm and bad:
            return f"{max(calm):,} and {min(bad):,}"
        return f"below {min(bad):,}" if bad else f"above {max(calm):,}"
    controls = [(name, outcome((key, 4, 4000))[0]) for key, name in
                (("lumped", "B2-TLS, lumped mass"), ("p1", "P1-TLS, consistent mass"),
                 ("direct", "B2, direct mapping, consistent mass"))]
    controls8 = [(name, outcome((key, 8, 4000))[0]) for key, name in
                 (("lumped", "B2-TLS, lumped mass"), ("p1", "P1-TLS, consistent mass"))]
    # The controls keep their energy (within 10 %) over the 3 s.
    calm = all((lambda g: g is not None and g < 1.1)(outcome((key, cells, 4000))[1])
               for key, cells in (("lumped", 4), ("p1", 4), ("direct", 4), ("lumped", 8),
                                  ("p1", 8)))
    calm_text = ("lumped mass, P1 and the direct mapping keep their energy at 4,000 Pa" if calm
                 else "not every control keeps its energy (above)")
    neutral = ("the direct mapping with the same consistent matrix stays neutral here"
               if (lambda g: g is not None and g < 1.1)(outcome(("direct", 4, 4000))[1])
               else "the direct mapping with the same consistent matrix grows here too (above)")
    # The growing oscillation: the kinetic energy of the 4,000 Pa run over the 0.2 s before the
    # last 0.03 s of the run, its log detrended; the mode's frequency is half the energy's.
    grow = res[("frozen", "b2tls", 4, 4000)]
    h = history(grow)
    end = h[-1, 0]
    w = h[(h[:, 0] >= end - 0.23) & (h[:, 0] <= end - 0.03)]
    slope, icpt = np.polyfit(w[:, 0], np.log(w[:, 1]), 1)
    resid = np.log(w[:, 1]) - (slope * w[:, 0] + icpt)
    dt = w[1, 0] - w[0, 0]
    spec = np.abs(np.fft.rfft(resid * np.hanning(len(resid))))
    freq = np.fft.rfftfreq(len(resid), dt)
    band = freq > 100.0
    f_ke = freq[band][np.argmax(spec[band])]
    shape = res[("frozen", "shape", 4, 4000)]
    frames = sorted(glob.glob(os.path.join(shape["_dir"], "particles_*.csv")))
    spec_json = os.path.join(shape["_dir"], "column_modes.json")
    subprocess.run([sys.executable, os.path.join(SCRIPTS, "column_modes.py"), "--modes", "2",
                    "--compare", frames[-1], "--json", spec_json], capture_output=True, check=True)
    with open(spec_json) as f:
        cm = json.load(f)
    cons, lump = cm["consistent"], cm["lumped"]
    top = cons["highest"][0]
    fr = cons["frame"]
    ch = cm["c_P"] / cm["h"] / (2 * math.pi)  # c_P / h in Hz
    # Where the grown mode is: the particle speeds per cell row of the frame.
    with open(frames[-1], newline="") as f:
        pts = [(float(x["x0_2"]), math.hypot(float(x["v_1"]), float(x["v_2"])))
               for x in csv.DictReader(f)]
    rms_row = {}
    for y, v in pts:
        rms_row.setdefault(int(y / 0.05), []).append(v * v)
    rms_row = {j: math.sqrt(sum(v) / len(v)) for j, v in rms_row.items()}
    peak = max(rms_row, key=rms_row.get)
    where = (f"its particle speeds are largest in cell row {peak + 1} of {len(rms_row)} from "
             f"the base, RMS {rms_row[peak]:.2g} m/s, and {rms_row[max(rms_row)]:.2g} m/s in the "
             f"top row")
    corners = (", a pair of modes at the two top corners"
               if all(m["top_corners"] > 0.5 for m in cons["highest"][:2]) else "")
    mode_rows = "\n".join(f"| {m['hz']:.1f} | {m['hz'] / ch:.2f} | {m['share']:.3f} |"
                           for m in fr["modes"][:3])
    return render("ps_partial", "flutter", rows="\n".join(rows),
                  controls_list="; ".join(f"{n}: {t}" for n, t in controls),
                  controls8_list="; ".join(f"{n}: {t}" for n, t in controls8),
                  bracket_2=bracket(2), bracket_4=bracket(4), bracket_8=bracket(8),
                  calm_text=calm_text, f_ke=f_ke, slope=slope, f_amplitude=f_ke / 2,
                  slope_pct=100 * slope / 2 / (np.pi * f_ke), neutral=neutral, top_hz=top['hz'],
                  top_ratio=top['hz'] / ch, corners=corners,
                  lumped_top_hz=lump['highest'][0]['hz'],
                  lumped_top_ratio=lump['highest'][0]['hz'] / ch, fr_fit=fr['fit'],
                  above_half_pct=100 * fr['above_half'], where=where, mode_rows=mode_rows,
                  low_modes_min=min(m['hz'] for m in fr['modes'][:3]),
                  low_modes_max=max(m['hz'] for m in fr['modes'][:3]))


def tls_consistent_probe(res):
    """The paragraph on what stops B2-TLS with consistent mass on the column (sec_ps_partial's
    probe runs)."""
    dts = ("1e-4", "5e-5", "2.5e-5")
    loads = (("1e4", res[("probe", "dt", "1e-4")]), ("1.5e4", res[("probe", "P", "1.5e4")]),
             ("2e4", res[("probe", "P", "2e4")]))
    runs = [(f"dt = {dt} s, P = 1e4 Pa", res[("probe", "dt", dt)]) for dt in dts] + [
        (f"dt = 1e-4 s, P = {P} Pa", r) for P, r in loads[1:]]
    rows = []
    for label, r in runs:
        g = kinetic_growth(r)
        rows.append(f"| {label} | "
                    + ("runs to T | | |" if r.get("status") == "ok" else
                       f"{fail_time(r.get('failure'))} s | "
                       + (f"{g[0]:.4g} s | {g[1]:.0f} |" if g else "not measured | |")))
    growth = [kinetic_growth(res[("probe", "dt", dt)]) for dt in dts]
    rates = [g[1] for g in growth if g]
    same_rate = len(rates) == len(dts) and max(rates) <= 1.25 * min(rates)
    onset_load = [float(P) * g[0] for P, r in loads for g in [kinetic_growth(r)] if g]
    lumped, p1 = res[("probe", "lumped")], res[("probe", "p1")]
    switched = [r for k, r in res.items() if k[:2] == ("probe", "switch")]
    t_sw = [float(fail_time(r.get("failure"))) for r in switched
            if r.get("status") != "ok" and fail_time(r.get("failure")) != "?"]
    switch_text = (render("ps_partial", "probe_switch", min_t_sw=min(t_sw), max_t_sw=max(t_sw))
                   if len(t_sw) == len(switched) else
                   f"of the runs with one TLS setting or the scheme switched, "
                   f"{len(switched) - len(t_sw)} of {len(switched)} finish")
    rate_text = (render("ps_partial", "probe_rate", min_rates=min(rates), max_rates=max(rates))
                 if same_rate else
                 f"the growth rates ({', '.join(f'{x:.0f}' for x in rates)} per second) do not "
                 f"show one rate for every step")
    load_text = (f"It sets in at a load, not a time: P t / T = {min(onset_load):.0f}-"
                 f"{max(onset_load):.0f} Pa for P = 1e4, 1.5e4 and 2e4 Pa (under a constant load, "
                 f"below, it grows above a threshold load)"
                 if len(onset_load) == len(loads) and max(onset_load) <= 1.25 * min(onset_load)
                 else "The loads at which it sets in differ")
    return render("ps_partial", "probe", rows="\n".join(rows), rate_text=rate_text,
                  load_text=load_text,
                  lumped_text=("runs to t = 3 s" if lumped.get("status") == "ok"
                               else "stops at t = " + fail_time(lumped.get("failure")) + " s"),
                  p1_text=("runs to T" if p1.get("status") == "ok"
                           else "stops at t = " + fail_time(p1.get("failure")) + " s"),
                  switch_text=switch_text)
