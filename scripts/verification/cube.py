"""Three dimensions: the vibrating cube (cube_mms_3d), observed orders at small amplitude and
errors at large amplitude, P1 and quadratic B-splines, lumped and consistent mass, with the
mappings' conservation (sec_cube). Prose: templates/cube.md."""
import os

from .common import ORDER_TOL, col, e, fig_md, o, pair_orders
from .plots import plot_study
from .template import render


def sec_cube(R, ctx):
    """The vibrating cube (cube_mms_3d): observed orders at small amplitude and the
    errors at large amplitude on 4-16 cells a side, P1 and quadratic B-splines, lumped and
    consistent mass, with the mappings' conservation."""
    # Consistent mass with conjugate gradients: the sparse LDL^T of the 3D matrix (18^3 DOFs
    # with 125 entries a row on 16 cells, factorised per velocity component) took about 5.7 s a
    # step there, CG about 0.85 s.
    lumped = "linear/direct/lumped, bspline2/direct/lumped"
    consistent = "bspline2/direct/consistent"
    small_sets = ["mms.amplitude=1e-4", "time.dt=1e-5", "time.end=1e-3"]
    out, small = R.study("cube_mms_3d", "grid.cells=4,8,16", lumped, small_sets,
                         name="cube_small")
    figs = plot_study(out, os.path.join(ctx["figdir"], "cube_small_amplitude"),
                      "displacement_rms,stress_rms", "cube_mms_3d, A = 1e-4 m, T = 1e-3 s",
                      energy=False)
    small.update(R.study("cube_mms_3d", "grid.cells=4,8,16", consistent,
                         small_sets + ["method.mass_solver=cg"], name="cube_small_cg")[1])
    _, large = R.study("cube_mms_3d", "grid.cells=4,8,16,32", lumped, [], name="cube_large")
    large.update(R.study("cube_mms_3d", "grid.cells=4,8", consistent,
                         ["method.mass_solver=cg"], name="cube_large_cg")[1])
    methods = lumped + ", " + consistent
    ms = [m.strip() for m in methods.split(",")]
    # The reconstructions at large amplitude, 27 particles per cell (3 per direction: with 2 the
    # squares of the quadratic Taylor basis are constant over an element's points and TLS
    # reduces to its 4 linear terms everywhere). MLS with its conservative variant,
    # whose support of 7^3 cells makes it about 120 times the direct step in 3D: 4 and 8 cells.
    recon = ("linear/direct/lumped, linear/tls/lumped, bspline2/direct/lumped, "
             "bspline2/tls/lumped")
    _, rec = R.study("cube_mms_3d", "grid.cells=4,8,16,32", recon, ["particles.per_cell=3"],
                     name="cube_recon")
    rec.update(R.study("cube_mms_3d", "grid.cells=4,8", "bspline2/mls/lumped",
                       ["particles.per_cell=3", "method.mls_conservative=true"],
                       name="cube_recon_mls")[1])
    rms = [m.strip() for m in recon.split(",")] + ["bspline2/mls/lumped"]

    def table(rows, keys, ms=ms):
        t = ["| method | cells | " + " | ".join(k for k, _ in keys) + " | mass | momentum |",
             "|---|---|" + "---|" * (len(keys) + 2)]
        for m in ms:
            rs = rows.get(m, [])
            po = {k: pair_orders(col(rs, "h"), col(rs, k)) for k, _ in keys}
            for i, r in enumerate(rs):
                cells = round(1.0 / r["h"]) if r.get("h") else "-"
                if r.get("status") != "ok":
                    t.append(f"| {m} | {cells} | " + " | ".join(r.get("status") or "-"
                                                                 for _ in keys) + " | | |")
                    continue
                vals = []
                for k, with_order in keys:
                    v = e(r.get(k))
                    if with_order and po[k][i] is not None:
                        v += f" ({o(po[k][i])})"
                    vals.append(v)
                t.append(f"| {m} | {cells} | " + " | ".join(vals) +
                         f" | {e(r.get('max_rel_mass_error'), 1)} | "
                         f"{e(r.get('max_rel_momentum_error'), 1)} |")
        return "\n".join(t)
    keys = [("displacement_rms", True), ("stress_rms", True)]
    so = {m: pair_orders(col(small.get(m, []), "h"), col(small.get(m, []), "displacement_rms"))[1:]
          for m in ms}
    ok_p1 = so["linear/direct/lumped"] and all(
        x is not None and x >= 2 - ORDER_TOL for x in so["linear/direct/lumped"])
    ok_bs = so["bspline2/direct/consistent"] and all(
        x is not None and x >= 3 - ORDER_TOL for x in so["bspline2/direct/consistent"])
    def orders(m):
        return ", ".join(o(x) for x in so[m])

    def stress_at(m, cells):
        for r in large.get(m, []):
            if r.get("h") and round(1.0 / r["h"]) == cells and r.get("status") == "ok":
                return r.get("stress_rms")
        return None
    p1, b2l, b2c = (stress_at(m, 8) for m in ms)
    p1_16, b2l_16 = stress_at(ms[0], 16), stress_at(ms[1], 16)
    p1_32, b2l_32 = stress_at(ms[0], 32), stress_at(ms[1], 32)

    def trend(a, b):
        return "grows" if b > a else "falls"
    if p1_32 and b2l_32 and p1_16 and b2l_16:
        verdict_32 = (f" From 16 to 32 cells P1's error {trend(p1_16, p1_32)} ({e(p1_16)} to "
                      f"{e(p1_32)} Pa) and the lumped B-splines' {trend(b2l_16, b2l_32)} "
                      f"({e(b2l_16)} to {e(b2l_32)} Pa)" +
                      (": with 8 particles per cell neither converges at this amplitude."
                       if p1_32 > p1_16 and b2l_32 > b2l_16 else "."))
    else:
        verdict_32 = " Some 32-cell runs stopped."
    if p1 and b2l and b2c and p1_16 and b2l_16:
        verdict = (
            render("cube", "stress_errors", p1_over_b2l=p1 / b2l, p1_over_b2c=p1 / b2c,
                   p1_trend='grows' if p1_16 > p1 else 'falls', p1=e(p1), p1_16=e(p1_16),
                   b2l_trend='grows' if b2l_16 > b2l else 'falls', b2l=e(b2l), b2l_16=e(b2l_16))
            + verdict_32)
    else:
        verdict = "Some runs at large amplitude stopped; no comparison is made."

    def rec_stress(m, cells):
        for r in rec.get(m, []):
            if r.get("h") and round(1.0 / r["h"]) == cells and r.get("status") == "ok":
                return r.get("stress_rms")
        return None
    parts = []
    for basis, name in (("linear", "P1"), ("bspline2", "quadratic B-splines")):
        ratios = []
        for cells in (4, 8, 16, 32):
            d, t = rec_stress(f"{basis}/direct/lumped", cells), rec_stress(f"{basis}/tls/lumped",
                                                                           cells)
            ratios.append(f"{d / t:.2f}" if d and t else "-")
        parts.append(f"{name}: {', '.join(ratios)}")
    rec_verdict = ("Stress error of the direct mapping over that of TLS on 4, 8, 16, 32 cells (above 1: "
                   "TLS is more accurate): " + "; ".join(parts) + ".")
    finished = all(r.get("status") == "ok" for m in rms for r in rec.get(m, []))
    finished_text = ("Every run finished." if finished else
                     "Not every run finished (the status is in the table).")
    return render("cube", "section", p1_orders=orders("linear/direct/lumped"),
                  p1_verdict="reproduced" if ok_p1 else "differs",
                  b2_consistent_orders=orders("bspline2/direct/consistent"),
                  b2_verdict="reproduced" if ok_bs else "differs",
                  b2_lumped_orders=orders("bspline2/direct/lumped"),
                  small_table=table(small, keys),
                  figures=fig_md(ctx, figs, "cube at small amplitude: convergence"),
                  large_table=table(large, keys), verdict=verdict, finished_text=finished_text,
                  rec_verdict=rec_verdict, rec_table=table(rec, keys, rms))
