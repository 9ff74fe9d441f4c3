"""PS-MPM, Powell-Sabin splines on triangles (D 3.4): D Fig. 3.9's plate on right triangles,
refined (sec_ps_plate), on unstructured meshes read from Gmsh files (sec_ps_unstructured), and
why its stress error does not fall under refinement there (sec_ps_plateau). Prose:
templates/ps_plate.md, ps_unstructured.md, ps_plateau.md."""
import json
import os

from .common import col, e, fail_time, fig_md, o, pair_orders, verdict_claim
from .plots import plot_study
from .template import render


def sec_ps_plate(R, ctx):
    """D 3.4.1 / 3.4.4, Fig. 3.9: the plate with P1 and PS splines on triangles, refined."""
    methods = ("p1_triangles/direct/lumped, powell_sabin/direct/lumped, "
               "powell_sabin/direct/consistent, bspline2/direct/consistent")
    sets = ["mms.amplitude=0.05", "time.dt=5e-5", "time.end=0.016", "particles.per_cell=4",
            "method.triangles=right", "method.scheme=musl"]
    out, rows = R.study("plate_mms_2d", "grid.cells=8,16,32", methods, sets, name="ps_plate")
    labels = [m.strip() for m in methods.split(",")]
    t = ["| method | 8 cells | 16 cells | 32 cells | orders | status |", "|---|---|---|---|---|---|"]
    errs = {}
    for m in labels:
        rs = rows.get(m, [])
        es = [r.get("stress_rms") if r.get("status") == "ok" else None for r in rs]
        errs[m] = es
        po = pair_orders(col(rs, "h"), es)[1:] if rs else []
        t.append(f"| {m} | " + " | ".join(e(x) if x else "stopped" for x in es) +
                 f" | {', '.join(o(x) for x in po)} | "
                 f"{', '.join(sorted(set(r.get('status') or '?' for r in rs)))} |")
    figs = plot_study(out, os.path.join(ctx["figdir"], "ps_plate"), "displacement_rms,stress_rms",
                      "plate_mms_2d on triangles, A = 0.05 m, T = 0.016 s", energy=False)
    p1, psl, psc = (errs[labels[0]], errs[labels[1]], errs[labels[2]])
    better = [a / b for a, b in zip(p1, psc) if a and b]
    v_better = verdict_claim(len(better) == 3 and min(better) >= 2,
                             f"{min(better):.1f}x to {max(better):.1f}x" if better else "no runs")
    lumped_ok = all(x for x in psl) and psl[2] < psl[0]
    # A run of PS-MPM with consistent mass that stops: the same grid with half the step, to tell
    # an explicit-step instability (which a smaller step cures) from another cause.
    stops = []
    for r in rows.get(labels[2], []):
        if r.get("status") == "ok":
            continue
        cells = int(round(1.0 / r["h"]))
        half = R.run("plate_mms_2d", [x for x in sets if not x.startswith("time.dt")] +
                     ["time.dt=2.5e-5", f"grid.cells={cells}", "method.basis=powell_sabin",
                      "method.mass=consistent"], 0, name=f"ps_plate_half_dt_{cells}")
        first = json.load(open(os.path.join(out, "powell_sabin_direct_consistent",
                                            f"grid.cells_{cells}", "summary.json")))
        stops.append((cells, first.get("failure", "?"), half.get("status"),
                      half.get("failure", "")))
    stop_text = "".join(render("ps_plate", "stop", cells=c, failure=f1,
                               half="it runs to the end. " if st2 == "ok" else f"{f2}. ")
                        for c, f1, st2, f2 in stops)
    same_time = ""
    if stops and all(st2 != "ok" for _, _, st2, _ in stops):
        same_time = render("ps_plate", "same_time",
                           times=", ".join(f"{fail_time(f1)} and {fail_time(f2)} s"
                                           for _, f1, _, f2 in stops))
    return render("ps_plate", "section", methods=methods,
                  sets_list=" ".join("--set " + x for x in sets), table="\n".join(t),
                  better_text=f"{min(better):.1f}x to {max(better):.1f}x" if better else "no runs",
                  v_better=v_better, stop_text=stop_text, same_time=same_time,
                  lumped_errors=", ".join(e(x) if x else "stopped" for x in psl),
                  lumped_ok_text=("the error falls slowly under refinement" if lumped_ok
                                  else "the error does not fall under refinement"),
                  figures=fig_md(ctx, figs, "PS-MPM plate on triangles: convergence"))


def sec_ps_unstructured(R, ctx):
    """D 3.4.4, Fig. 3.6 and 3.9: the plate on unstructured triangulations read from Gmsh files
    (examples/meshes/plate_unstructured_{8,16,32}.msh, scripts/plate_mesh.cpp), P1 and PS
    splines, lumped and consistent mass; the particles per triangle of PS-MPM."""
    meshes = (8, 16, 32)
    base = ["mms.amplitude=0.05", "time.dt=2e-5", "time.end=0.016", "method.scheme=musl"]
    methods = [("p1_triangles", "lumped"), ("p1_triangles", "consistent"),
               ("powell_sabin", "lumped"), ("powell_sabin", "consistent")]
    seedings = [("particles.per_cell = 4", ["particles.per_triangle=0", "particles.per_cell=4"]),
                ("6 per triangle", ["particles.per_triangle=6"]),
                ("12 per triangle", ["particles.per_triangle=12"]),
                ("24 per triangle", ["particles.per_triangle=24"])]

    def mesh_sets(n):
        return [f"grid.mesh=meshes/plate_unstructured_{n}.msh", f"grid.cells={n}"]
    specs, keys = [], []
    for n in meshes:
        for b, m in methods:
            keys.append(("main", b, m, n))
            specs.append(("plate_ps_unstructured_2d", base + mesh_sets(n) + [
                "particles.per_triangle=24", f"method.basis={b}", f"method.mass={m}"], 0,
                f"ps_unstructured_{b}_{m}_{n}"))
        for label, seed in seedings[:3]:
            keys.append(("seed", label, n))
            specs.append(("plate_ps_unstructured_2d", base + mesh_sets(n) + seed + [
                "method.basis=powell_sabin", "method.mass=consistent"], 0,
                f"ps_unstructured_seed_{seedings.index((label, seed))}_{n}"))
    res = dict(zip(keys, R.many(specs)))

    def err(r):
        return r.get("errors", {}).get("stress_rms") if r.get("status") == "ok" else None
    hs = [1.0 / n for n in meshes]
    t = ["| method (24 particles per triangle) | mesh 8 (184 triangles) | mesh 16 (676) | "
         "mesh 32 (2658) | orders |", "|---|---|---|---|---|"]
    errs = {}
    for b, m in methods:
        es = [err(res[("main", b, m, n)]) for n in meshes]
        errs[(b, m)] = es
        t.append(f"| {b}, {m} | " + " | ".join(e(x) if x else "stopped" for x in es) +
                 f" | {', '.join(o(x) for x in pair_orders(hs, es)[1:])} |")
    t2 = ["| PS-MPM, consistent mass | mesh 8 | mesh 16 | mesh 32 |", "|---|---|---|---|"]
    for label, _ in seedings:
        rs = [res[("seed", label, n)] if label != "24 per triangle" else
              res[("main", "powell_sabin", "consistent", n)] for n in meshes]
        t2.append(f"| {label} | " + " | ".join(
            e(err(r)) if err(r) else f"stops at t = {fail_time(r.get('failure'))} s" for r in rs)
            + " |")
    ps = errs[("powell_sabin", "consistent")]
    p1 = [min(a, b) if a and b else None for a, b in
          zip(errs[("p1_triangles", "lumped")], errs[("p1_triangles", "consistent")])]
    better = [a / b for a, b in zip(p1, ps) if a and b]
    ok = len(better) == len(meshes) and min(better) >= 2
    few_stop = all(res[("seed", seedings[0][0], n)].get("status") != "ok" for n in meshes)
    # The structured 32-cell PS-MPM run of sec_ps_plate (right triangles, dt = 5e-5 s), with 24
    # particles per triangle instead of 16 per square.
    st = R.run("plate_mms_2d", ["mms.amplitude=0.05", "time.dt=5e-5", "time.end=0.016",
                                "method.triangles=right", "method.scheme=musl", "grid.cells=32",
                                "particles.per_triangle=24", "method.basis=powell_sabin",
                                "method.mass=consistent"], 0, name="ps_plate_32_per_triangle_24")
    structured_text = (f"it runs to the end, stress RMS {e(err(st))}" if st.get("status") == "ok"
                       else f"it stops as well ({st.get('failure', '?')[:160]})")
    ps_orders = [x for x in pair_orders(hs, ps)[1:] if x is not None]
    conv_text = (render("ps_unstructured", "conv_text",
                        ps_orders=', '.join(o(x) for x in ps_orders))
                 if ps_orders and max(ps_orders) < 0.5 else
                 f"PS-MPM's observed orders: {', '.join(o(x) for x in ps_orders)}.")
    lumped = [a / b for a, b in zip(errs[("powell_sabin", "lumped")], ps) if a and b]
    lumped_text = (f"{min(lumped):.1f}x to {max(lumped):.1f}x" if lumped else "not comparable to")
    better_text = f"{min(better):.1f}x to {max(better):.1f}x" if better else "no runs"
    return render("ps_unstructured", "section", table="\n".join(t), conv_text=conv_text,
                  better_text=better_text, v_better=verdict_claim(ok, better_text),
                  t2="\n".join(t2),
                  few_text=render("ps_unstructured", "few_stop") + " " if few_stop else "",
                  structured_text=structured_text, lumped_text=lumped_text)


def sec_ps_plateau(R, ctx):
    """Why the stress error of PS-MPM (consistent mass) on the unstructured meshes of
    sec_ps_unstructured does not fall under refinement: the same runs with 54 instead of 24
    particles per triangle, with half the time step, and at a tenth of the amplitude."""
    meshes = (8, 16, 32)
    base = ["time.dt=2e-5", "time.end=0.016", "method.scheme=musl", "method.basis=powell_sabin",
            "method.mass=consistent"]
    rows = [("A = 0.05 m, 24 per triangle (the section above)",
             ["mms.amplitude=0.05", "particles.per_triangle=24"], meshes),
            ("A = 0.05 m, 54 per triangle",
             ["mms.amplitude=0.05", "particles.per_triangle=54"], meshes),
            ("A = 0.05 m, 24 per triangle, dt = 1e-5 s",
             ["mms.amplitude=0.05", "particles.per_triangle=24", "time.dt=1e-5"], (16,)),
            ("A = 0.005 m, 24 per triangle",
             ["mms.amplitude=0.005", "particles.per_triangle=24"], meshes)]
    specs, keys = [], []
    for k, (label, sets, ns) in enumerate(rows):
        for n in ns:
            keys.append((k, n))
            specs.append(("plate_ps_unstructured_2d", base + sets + [
                f"grid.mesh=meshes/plate_unstructured_{n}.msh", f"grid.cells={n}"], 0,
                f"ps_plateau_{k}_{n}"))
    res = dict(zip(keys, R.many(specs)))

    def rel(k, n):
        r = res.get((k, n))
        if r is None or r.get("status") != "ok":
            return None
        return r.get("errors", {}).get("stress_rel_l2")

    def spread(k):
        return [rel(k, n) for n in meshes if rel(k, n)]
    t = ["| PS-MPM, consistent mass: stress error (relative L2) | mesh 8 | mesh 16 | mesh 32 |",
         "|---|---|---|---|"]
    for k, (label, _, ns) in enumerate(rows):
        cells = [(e(rel(k, n)) if rel(k, n) else "stopped") if n in ns else "" for n in meshes]
        t.append(f"| {label} | " + " | ".join(cells) + " |")
    ratios = [rel(0, n) / rel(1, n) for n in meshes if rel(0, n) and rel(1, n)]
    dt_change = (rel(2, 16) / rel(0, 16) - 1.0) * 100.0 if rel(2, 16) and rel(0, 16) else None
    if not ratios or dt_change is None or not spread(0) or not spread(3):
        text = "Some runs stopped, so the comparison below is not made."
    else:
        text = render("ps_plateau", "plateau", spread_min=min(spread(0)),
                      spread_max=max(spread(0)), spread_small_min=min(spread(3)),
                      spread_small_max=max(spread(3)), dt_change=dt_change, ratios_min=min(ratios),
                      ratios_max=max(ratios))
    return render("ps_plateau", "section", table="\n".join(t), text=text)
