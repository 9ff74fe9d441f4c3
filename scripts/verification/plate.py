"""The plate in 2D: the axis-aligned vibration at small amplitude, refined (001, D 3.4.1;
sec_plate), and MPM against MPM-TLS on D's plate (D 6.3.1, Table 6.1, Fig. 6.8) on
rectangles and on triangles, with the completions and limits of TLS (sec_plate_tls). Prose:
templates/plate.md, plate_tls.md."""
import math
import os
import re

from .common import (ORDER_TOL, ROUNDOFF, col, e, fig_md, last_frame, o, pair_orders, pub, src,
                     verdict_claim, verdict_value)
from .plots import plot_line_profiles, plot_study
from .template import render


def sec_plate(R, ctx):
    """The plate at small amplitude (A = 1e-4 m), refined: P1 and quadratic B-splines."""
    methods = "linear/direct/lumped, bspline2/direct/consistent, bspline2/direct/lumped"
    out, rows = R.study("plate_mms_2d", "grid.cells=8,16,32", methods,
                        ["mms.amplitude=1e-4", "time.end=1e-3"], name="plate_small")
    po = {m: pair_orders(col(r, "h"), col(r, "displacement_rms"))[1:] for m, r in rows.items()}
    figs = plot_study(out, os.path.join(ctx["figdir"], "plate_small_amplitude"),
                      "displacement_rms,stress_rms", "plate_mms_2d, A = 1e-4 m, T = 1e-3 s",
                      energy=False)
    s = lambda m: ", ".join(o(x) for x in po[m])
    ok_p1 = all(x is not None and x >= 2 - ORDER_TOL for x in po["linear/direct/lumped"])
    ok_bs = all(x is not None and x >= 3 - ORDER_TOL for x in po["bspline2/direct/consistent"])
    return render("plate", "section", methods=methods, p1_orders=s('linear/direct/lumped'),
                  p1_verdict="reproduced" if ok_p1 else "differs",
                  b2_consistent_orders=s('bspline2/direct/consistent'),
                  b2_verdict="reproduced" if ok_bs else "differs",
                  b2_lumped_orders=s('bspline2/direct/lumped'),
                  figures=fig_md(ctx, figs, "plate at small amplitude: convergence"))


def sec_plate_tls(R, ctx):
    """MPM against MPM-TLS on D's plate (D 6.3.1, Table 6.1), the completions of sparse
    elements at A = 0.1 m, then the same on triangles (sec_plate_tls_triangles)."""
    combos = [("P1", "direct", ["method.basis=linear", "method.mapping=direct"]),
              ("P1", "TLS (6 terms)", ["method.basis=linear", "method.mapping=tls"]),
              ("B-spline p=2", "direct", ["method.basis=bspline", "method.degree=2",
                                          "method.mapping=direct"]),
              ("B-spline p=2", "TLS (6 terms)", ["method.basis=bspline", "method.degree=2",
                                                 "method.mapping=tls"])]
    res = R.many([("plate_tls_2d", s, 1) for _, _, s in combos])
    t = ["| basis | mapping | u [m] | v [m/s] | sigma [Pa] | mass | momentum | run time / P1 "
         "direct | status |", "|---|---|---|---|---|---|---|---|---|"]
    t0 = res[0].get("wall_seconds")
    for (b, m, _), r in zip(combos, res):
        er, cn = r["errors"], r["conservation"]
        t.append(f"| {b} | {m} | {e(er.get('displacement_rms'))} | "
                 f"{er.get('velocity_rms', float('nan')):.3g} | {e(er.get('stress_rms'))} | "
                 f"{e(cn.get('max_rel_mass_error'), 1)} | "
                 f"{e(cn.get('max_rel_momentum_error'), 1)} | "
                 f"{r['wall_seconds'] / t0 if t0 and r.get('wall_seconds') else float('nan'):.1f} | "
                 f"{r['status']} |")
    p1, tl = res[0]["errors"], res[1]["errors"]
    fu, fv, fs = (p1["displacement_rms"] / tl["displacement_rms"],
                  p1["velocity_rms"] / tl["velocity_rms"], p1["stress_rms"] / tl["stress_rms"])
    v_imp = verdict_claim(fu >= 2 and fs >= 2, f"{fu:.1f}x (u), {fs:.1f}x (stress)")
    mass = max(r["conservation"]["max_rel_mass_error"] for r in res)
    v_mass = verdict_value(mass, "plate_tls_mass", True)
    bs_better = res[2]["errors"]["displacement_rms"] < res[3]["errors"]["displacement_rms"]
    # A = 0.1 m: completions of the fragile sparse elements (P1, 16 cells, 9 PPC).
    comp = ["reduce", "virtual", "neighbour"]
    fr = []
    for tend in ("5e-3", "1e-3"):
        base = ["grid.cells=16", "particles.per_cell=3", "mms.amplitude=0.1",
                "time.dt=1e-5", f"time.end={tend}", "method.basis=linear"]
        fr.append(R.many([("plate_tls_2d", base + ["method.mapping=direct"], 0)] +
                         [("plate_tls_2d", base + ["method.mapping=tls",
                                                   f"method.tls_completion={c}"], 0)
                          for c in comp]))

    def vdesc(r):
        if r["status"] != "ok":
            return f"failed at step {r.get('steps', '?')}"
        return f"{r['errors'].get('velocity_rms', float('nan')):.3g} m/s"
    long_t = ["| T | direct | TLS reduce | TLS virtual | TLS neighbour |", "|---|---|---|---|---|"]
    for tend, rs in zip(("5e-3 s", "1e-3 s"), fr):
        long_t.append(f"| {tend} | " + " | ".join(vdesc(r) for r in rs) + " |")
    return (render("plate_tls", "section", table="\n".join(t), fu=fu, fv=fv, fs=fs, v_imp=v_imp,
                   plate_tls_mass_src=src("plate_tls_mass"),
                   plate_tls_mass_pub=e(pub("plate_tls_mass"), 1), mass=e(mass, 1), v_mass=v_mass,
                   bs_better_text=("already more accurate than" if bs_better
                                   else "less accurate than"),
                   completion_table="\n".join(long_t))
            + sec_plate_tls_triangles(R, ctx, res[0], res[1]))


# examples/plate_tls_2d.toml names the rectangles' completion (virtual); auto is the default,
# reduce on triangles.
TRI = ["method.basis=p1_triangles", "grid.cells=23", "particles.per_triangle=24",
       "method.triangles=right", "method.tls_completion=auto"]


def line_profile(run, x0=0.5, key="stress_22"):
    """Final-frame particles of the column nearest the material line X_1 = x0: (X_2, value,
    exact) sorted by X_2, and the RMS error of `key` over them."""
    parts = last_frame(run["_dir"]) or []
    if not parts:
        return [], None
    dmin = min(abs(p["x0_1"] - x0) for p in parts)
    col_ = sorted((p for p in parts if abs(p["x0_1"] - x0) <= dmin + 1e-9),
                  key=lambda p: p["x0_2"])
    pts = [(p["x0_2"], p[key], p[key.replace("stress_", "stress_exact_")]) for p in col_]
    rms = math.sqrt(sum((v - x) ** 2 for _, v, x in pts) / len(pts)) if pts else None
    return pts, rms


def sec_plate_tls_triangles(R, ctx, rect_mpm, rect_tls):
    """D 6.3.1 on triangles: Table 6.1, Fig. 6.8 and the runs with 12 and 16 particles per
    triangle that stop in D, with the completions and limits of TLS on triangles."""
    tri_mpm, tri_tls = R.many([("plate_tls_2d", TRI + ["method.mapping=direct"], 1),
                               ("plate_tls_2d", TRI + ["method.mapping=tls"], 1)])
    rows = [("MPM", "rectangular", rect_mpm, "7.2100e-13", "8.7421e-13", "1.9854e-13"),
            ("MPM-TLS", "rectangular", rect_tls, "7.3351e-13", "8.1654e-11", "4.7041e-11"),
            ("MPM", "triangular", tri_mpm, "3.3253e-13", "1.0270e-12", "1.7689e-11"),
            ("MPM-TLS", "triangular", tri_tls, "3.3265e-13", "6.9142e-13", "7.7780e-12")]
    t61 = ["| method | mesh | mass (D) | mass (ours) | Q_x, Q_y absolute (D) | momentum relative "
           "(ours) | sigma_yy RMS on X_1 = 0.5 [Pa] | status |", "|---|---|---|---|---|---|---|---|"]
    profiles = {}
    for m, mesh, r, dm, dqx, dqy in rows:
        pts, rms = line_profile(r)
        profiles[(m, mesh)] = pts
        cn = r["conservation"]
        t61.append(f"| {m} | {mesh} | {dm} | {e(cn.get('max_rel_mass_error'), 1)} | {dqx}, {dqy} | "
                   f"{e(cn.get('max_rel_momentum_error'), 1)} | {e(rms)} | {r['status']} |")
    worst = max(max(r["conservation"].get("max_rel_mass_error", 1.0),
                    r["conservation"].get("max_rel_momentum_error", 1.0)) for _, _, r, *_ in rows)
    v_cons = verdict_claim(worst < ROUNDOFF, f"largest {worst:.1e}")
    _, rms_rm = line_profile(rect_mpm)
    _, rms_rt = line_profile(rect_tls)
    _, rms_tm = line_profile(tri_mpm)
    _, rms_tt = line_profile(tri_tls)
    imp = (rms_tm / rms_tt if rms_tm and rms_tt else 0.0,
           rms_rm / rms_rt if rms_rm and rms_rt else 0.0)
    v_imp = verdict_claim(min(imp) >= 2, f"{imp[1]:.1f}x (rectangles), {imp[0]:.1f}x (triangles)")
    fig = plot_line_profiles(ctx, "plate_tls_fig68", [
        ("rectangles: 32 x 32, 25 per element", [("MPM", profiles[("MPM", "rectangular")]),
                                                 ("MPM-TLS", profiles[("MPM-TLS", "rectangular")])]),
        ("triangles: 1058, 24 per triangle", [("MPM", profiles[("MPM", "triangular")]),
                                              ("MPM-TLS", profiles[("MPM-TLS", "triangular")])])])
    tls_tri = tri_tls.get("tls", {})

    # The runs that stop in D (12, 16 per triangle) and the choice of completion and limit.
    cols = [("direct", ["method.mapping=direct"]),
            ("none", ["method.mapping=tls", "method.tls_completion=none",
                      "method.tls_triangle_max_condition=1e8"])]
    for lim in ("1e8", "1e2", "1e1"):
        for c in ("reduce", "graded"):
            cols.append((f"{c}, {lim}", ["method.mapping=tls", f"method.tls_completion={c}",
                                         f"method.tls_triangle_max_condition={lim}"]))
    cases = [("right", "0.05", 12), ("right", "0.05", 16), ("right", "0.05", 24),
             ("right", "0.1", 12), ("right", "0.1", 24), ("criss_cross", "0.1", 12)]
    specs = []
    for pat, amp, n in cases:
        base = ["method.basis=p1_triangles", "grid.cells=23", f"particles.per_triangle={n}",
                f"mms.amplitude={amp}", f"method.triangles={pat}"]
        specs += [("plate_tls_2d", base + c, 0) for _, c in cols]
    runs = R.many(specs)

    def cell(r):
        if r["status"] != "ok":
            why = "rank" if r.get("exit_code") == 6 else "non-finite" if r.get(
                "exit_code") == 3 else f"exit {r.get('exit_code')}"
            return f"stops at step {r.get('steps', '?')} ({why})"
        return e(r["errors"].get("stress_rms"))
    st = ["| mesh | A [m] | per triangle | " + " | ".join(c for c, _ in cols) + " |",
          "|---|---|---|" + "---|" * len(cols)]
    for k, (pat, amp, n) in enumerate(cases):
        rs = runs[k * len(cols):(k + 1) * len(cols)]
        st.append(f"| {pat.replace('_', '-')} | {amp} | {n} | " +
                  " | ".join(cell(r) for r in rs) + " |")
    def err(r):
        return r["errors"].get("stress_rms") if r["status"] == "ok" else None
    table = [runs[k * len(cols):(k + 1) * len(cols)] for k in range(len(cases))]
    limited = [r for rs in table for r in rs[4:]]  # the limits 1e2 and 1e1
    finished = all(r["status"] == "ok" for r in limited)
    # reduce alone (columns 4 and 6): the default's completion
    reduce_finished = all(rs[i]["status"] == "ok" for rs in table for i in (4, 6))
    graded_stops = [f"{cases[k][0].replace('_', '-')}, A = {cases[k][1]}, {cases[k][2]}"
                    for k, rs in enumerate(table) if any(rs[i]["status"] != "ok" for i in (5, 7))]
    stops12 = table[0][1]["status"] != "ok"
    stops16 = table[1][1]["status"] != "ok"
    v_12 = verdict_claim(stops12, "stops" if stops12 else "runs")
    v_16 = verdict_claim(stops16, "stops" if stops16 else "runs")
    # reduce against graded at the same limit, and the limits against each other (0.5 %: equal).
    pairs = [(err(rs[i]), err(rs[i + 1])) for rs in table for i in (4, 6)]
    reduce_wins = sum(1 for a, b in pairs if a is not None and b is not None and a <= 1.005 * b)
    strict = [(err(rs[6]), err(rs[4])) for rs in table]
    strict_wins = sum(1 for a, b in strict if a is not None and b is not None and a <= 1.005 * b)
    gains = [err(rs[0]) / err(rs[6]) for rs in table if err(rs[0]) and err(rs[6])]
    with open(os.path.join(tri_tls["_dir"], "config.toml")) as f:
        lim = re.search(r"^tls_triangle_max_condition\s*=\s*([0-9.eE+-]+)", f.read(), re.M)
    default_limit = float(lim.group(1)) if lim else float("nan")
    return render("plate_tls", "triangles", table61="\n".join(t61), worst=worst, v_cons=v_cons,
                  gain_rectangles=imp[1], gain_triangles=imp[0], v_imp=v_imp,
                  stops12_text="stops" if stops12 else "runs", v_12=v_12,
                  stops16_text="stops" if stops16 else "runs", v_16=v_16,
                  figures=fig_md(ctx, fig, "D Fig. 6.8: sigma_yy of the material points nearest "
                                 "X_1 = 0.5 m at T = 0.015 s, rectangles (left) and triangles "
                                 "(right), MPM and MPM-TLS against the exact solution."),
                  tri_element_fits=tls_tri.get('element_fits'), tri_reduced=tls_tri.get('reduced'),
                  tri_min_terms=tls_tri.get('min_terms'),
                  tri_max_condition=e(tls_tri.get('max_condition')),
                  tri_completion=tls_tri.get('completion'), stop_table="\n".join(st),
                  finish_text=("every run finishes" if finished
                               else "every run of `reduce` finishes" if reduce_finished
                               else "NOT every run of `reduce` finishes"),
                  graded_text=("" if finished
                               else " (`graded` stops with a non-finite stress in: "
                               + "; ".join(graded_stops) + ")"),
                  reduce_wins=reduce_wins, n_pairs=len(pairs), strict_wins=strict_wins,
                  n_strict=len(strict), min_gains=min(gains), max_gains=max(gains),
                  default_limit=default_limit)
