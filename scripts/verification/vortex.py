"""The generalized vortex (Kamojjala et al. 2015): an annulus turned by a radius-dependent angle,
a test of rotation and large shear, refined with the methods of VORTEX_METHODS, with the error
on the body's edge (sec_vortex). Prose: templates/vortex.md."""
import json
import math
import os
import re

from .common import col, e, fail_time, fig_md, last_frame, ls_order, num, o, pair_orders
from .plots import plot_study
from .template import render


VORTEX_METHODS = ("linear/direct, bspline2/direct, bspline3/direct, cpdi2/direct, linear/tls, "
                  "bspline2/tls, bspline2/mls, bspline2/imls, linear/direct/consistent, "
                  "bspline2/direct/consistent")
VORTEX_CELLS = (16, 32, 64, 128)


def vortex_failure(out, method, cells):
    """Why a run of a vortex study stopped: the failure of its summary.json, shortened to its
    first clause ("step N, t = T s: what")."""
    path = os.path.join(out, method.replace("/", "_"), f"grid.cells_{cells}", "summary.json")
    try:
        with open(path) as f:
            failure = json.load(f).get("failure", "")
    except OSError:
        return "no summary"
    m = re.match(r"step \d+, t = ([0-9.eE+-]+) s: (.*)", failure)
    if not m:
        return failure[:80]
    what = m.group(2)
    for cut in (": particle", " (", "; "):
        if cut in what:
            what = what[:what.index(cut)]
    return f"t = {m.group(1)} s: {what}"


def vortex_table(out, rows, labels, key):
    """One row per method: the error `key` per grid (or where the run stopped), the
    least-squares order over the finished grids when all finished, the pair orders."""
    t = ["| method | " + " | ".join(f"{c} cells" for c in VORTEX_CELLS) +
         " | order (fit) | pair orders |", "|---|" + "---|" * (len(VORTEX_CELLS) + 2)]
    for m in labels:
        rs = rows.get(m, [])
        es = [r.get(key) if r.get("status") == "ok" else None for r in rs]
        cells = [int(r["grid.cells"]) for r in rs]
        cellsx = [e(x) if x is not None else f"stopped ({vortex_failure(out, m, c)})"
                  for x, c in zip(es, cells)]
        hs = col(rs, "h")
        fit = ls_order(hs, es) if rs and all(x is not None for x in es) else None
        po = pair_orders(hs, es)[1:] if rs else []
        t.append(f"| {m} | " + " | ".join(cellsx) + f" | {o(fit)} | "
                 f"{', '.join(o(x) if x is not None else '-' for x in po)} |")
    return "\n".join(t)


def edge_split(run_dir, width):
    """(velocity RMS of the particles within `width` of either circle of the vortex annulus,
    the same of the others, their counts) from a run's last particle frame; None if absent."""
    parts = last_frame(run_dir)
    if not parts:
        return None
    edge, inner = [], []
    for p in parts:
        R = math.hypot(p["x0_1"], p["x0_2"])
        err = (p["v_1"] - p["v_exact_1"]) ** 2 + (p["v_2"] - p["v_exact_2"]) ** 2
        (edge if min(R - 0.75, 1.25 - R) < width else inner).append(err)
    rms = lambda xs: math.sqrt(sum(xs) / len(xs)) if xs else None
    return rms(edge), rms(inner), len(edge), len(inner)


def edge_text(out, method, cells=64):
    """The velocity error of `method`'s run on `cells` cells on the body's edge against its
    interior (edge_split), as text."""
    s = edge_split(os.path.join(out, method.replace("/", "_"), f"grid.cells_{cells}"),
                   3.0 / cells)
    if not s or s[0] is None or s[1] is None:
        return "not measured (no particle frame)"
    return f"{e(s[0])} m/s ({s[2]} particles) against {e(s[1])} m/s ({s[3]})"


def sec_vortex(R, ctx):
    """The generalized vortex, a rotation and shear test, refined."""
    labels = [m.strip() for m in VORTEX_METHODS.split(",")]
    refine = "grid.cells=" + ",".join(str(c) for c in VORTEX_CELLS)
    studies = {}
    for A in ("0.1", "1"):
        studies[A] = R.study("vortex_2d", refine, VORTEX_METHODS, [f"vortex.amplitude={A}"],
                             name=f"vortex_{A}")
    # The time step's share of the error: the finest B2 run again with half the step.
    half = R.run("vortex_2d", ["vortex.amplitude=0.1", "grid.cells=128", "time.dt=5e-4"], 0,
                 name="vortex_half_dt")
    full = next(r for r in studies["0.1"][1]["bspline2/direct"] if int(r["grid.cells"]) == 128)
    dt_ratio = (half.get("errors", {}).get("displacement_rms") or float("nan")) / \
        (full.get("displacement_rms") or float("nan"))
    # The particle layout: the grid's particles inside the annulus (a staircase along the
    # circles) against the rings that tile it, same methods and grids.
    stair_out, stair = R.study("vortex_2d", refine, "linear/direct, bspline2/direct",
                               ["vortex.amplitude=0.1", "vortex.seeding=cells"],
                               name="vortex_cells")
    # Consistent mass: the same B2 run on 32 cells with the nodes below a growing share of the
    # largest nodal mass left inactive (method.mass_tolerance, default 1e-10).
    tols = ("1e-10", "1e-4", "1e-2")
    cons = R.many([("vortex_2d", ["vortex.amplitude=0.1", "grid.cells=32",
                                  "method.basis=bspline", "method.degree=2",
                                  "method.mass=consistent", f"method.mass_tolerance={tol}"])
                   for tol in tols])
    cons_text = "; ".join(
        f"{tol}: " + ("runs to the end" if r.get("status") == "ok" else
                      f"stops at t = {fail_time(r.get('failure'))} s")
        for tol, r in zip(tols, cons))
    cons_cause = (
        "So the stop comes from the nodes on the body's edge that carry a tiny share of mass, "
        "through the nearly singular consistent mass matrix (as for the partially filled "
        "elements of the PS-MPM section)."
        if cons[0].get("status") != "ok" and cons[-1].get("status") == "ok" else
        "The nodes of tiny mass are therefore not shown to be the cause.")
    out01, rows01 = studies["0.1"]
    out1, rows1 = studies["1"]
    mls_mass = max((r.get("max_rel_mass_error") or 0.0) for r in rows01.get("bspline2/mls", []))
    figs = plot_study(out01, os.path.join(ctx["figdir"], "vortex"), "displacement_rms,stress_rms",
                      "vortex_2d, A = 0.1 rad, T = 1 s", energy=False)

    def fits(rows, m, key):
        rs = rows.get(m, [])
        es = [r.get(key) if r.get("status") == "ok" else None for r in rs]
        return ls_order(col(rs, "h"), es) if rs and all(x is not None for x in es) else None

    def finished(rows):
        return [m for m in labels if rows.get(m) and all(r.get("status") == "ok"
                                                         for r in rows[m])]

    b2_poly = fits(rows01, "bspline2/direct", "displacement_rms")
    b2_stair = fits(stair, "bspline2/direct", "displacement_rms")
    p1_poly = fits(rows01, "linear/direct", "velocity_rms_midstep")
    p1_stair = fits(stair, "linear/direct", "velocity_rms_midstep")
    stair_t = vortex_table(stair_out, stair, ["linear/direct", "bspline2/direct"],
                           "displacement_rms")
    stair_v = vortex_table(stair_out, stair, ["linear/direct", "bspline2/direct"],
                           "velocity_rms_midstep")
    ok01, ok1 = finished(rows01), finished(rows1)
    tls_ok = [f"{m} at A = {A}" for A, rows in (("0.1", rows01), ("1", rows1))
              for m in ("linear/tls", "bspline2/tls") if m in (ok01 if A == "0.1" else ok1)]
    tls_text = ("finishes every grid for " + ", ".join(tls_ok) if tls_ok else
                "does not finish every grid at either amplitude")
    return render("vortex", "section", refine=refine, VORTEX_METHODS=VORTEX_METHODS,
                  dt_ratio=num(dt_ratio),
                  u_table_01=vortex_table(out01, rows01, labels, "displacement_rms"),
                  v_table_01=vortex_table(out01, rows01, labels, "velocity_rms_midstep"),
                  stress_table_01=vortex_table(out01, rows01, labels, "stress_rms"),
                  u_table_1=vortex_table(out1, rows1, labels, "displacement_rms"),
                  stress_table_1=vortex_table(out1, rows1, labels, "stress_rms"),
                  ok01_list=", ".join(ok01) or "none", ok1_list=", ".join(ok1) or "none",
                  tls_text=tls_text, mls_mass=e(mls_mass), cons_text=cons_text,
                  cons_cause=cons_cause, stair_t=stair_t, stair_v=stair_v,
                  b2_poly=o(b2_poly) or "-", b2_stair=o(b2_stair) or "-",
                  p1_poly=o(p1_poly) or "-", p1_stair=o(p1_stair) or "-",
                  edge_poly=edge_text(out01, "bspline2/direct", 128),
                  edge_stair=edge_text(stair_out, "bspline2/direct", 128),
                  figures=fig_md(ctx, figs, "vortex_2d, A = 0.1 rad: convergence"))
