"""Powell-Sabin splines in the unified approach (D 7.3): method.solver = "unified" with
method.basis = "powell_sabin", on D 4.6.3's plate and on the column with a free surface of
"PS-MPM with partially filled elements", against PS-MPM with lumped, consistent and partially
lumped mass. Prose: templates/unified_ps.md."""
import csv
import os

from .common import e, fail_time, verdict_claim
from .template import render

# D 4.6.3's plate (sec_plate_463 in otm.py): the same set-up.
PLATE = ["mms.amplitude=0.005", "material.youngs_modulus=1e7", "material.density=1000",
         "material.poisson_ratio=0.3", "grid.cells=32", "particles.per_cell=4", "time.dt=5e-5",
         "time.end=3.5e-3", "method.scheme=usl"]
PS = ["method.basis=powell_sabin"]
UNIFIED = ["method.solver=unified"]
PARTIAL = ["method.mass=consistent", "method.partial_lumping=0.5"]
METHODS = [("PS-MPM, lumped", PS + ["method.mass=lumped"]),
           ("PS-MPM, consistent", PS + ["method.mass=consistent"]),
           ("PS-MPM, partial lumping 0.5", PS + PARTIAL),
           ("unified PS, lumped", UNIFIED + PS + ["method.mass=lumped"]),
           ("unified PS, consistent", UNIFIED + PS + ["method.mass=consistent"])]
# The column of ps_partial.py: tops and the fill of the cell row below the top.
TOPS = (1.0, 0.99, 0.975, 0.96)
FILLS = ("100 %", "80 %", "50 %", "20 %")


def final_kinetic(r):
    """The kinetic energy [J] in the last row of the run's history.csv (None without one)."""
    path = os.path.join(r["_dir"], "history.csv")
    if not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return float(rows[-1]["kinetic_energy"]) if rows else None


def outcome(r, key="stress_rms"):
    """The stress error and, in brackets, the kinetic energy at T; or where the run stopped."""
    if r.get("status") == "ok":
        return f"{e(r['errors'].get(key))} ({e(final_kinetic(r))} J)"
    return f"stops at t = {fail_time(r.get('failure'))} s"


def error_row(label, r):
    """A table row: the run's status, displacement RMS, stress RMS and relative L2 stress error."""
    ok = r.get("status") == "ok"
    er = r["errors"] if ok else {}
    status = "ok" if ok else f"stops at t = {fail_time(r.get('failure'))} s"
    return (f"| {label} | {status} | {e(er.get('displacement_rms'))} | "
            f"{e(er.get('stress_rms'))} | {e(er.get('stress_rel_l2'))} |")


def sec_unified_ps(R, ctx):
    """The plate and the column, PS-MPM against unified PS."""
    plate_methods = METHODS + [("unified (B-splines, p = 2), consistent",
                                UNIFIED + ["method.basis=bspline", "method.degree=2",
                                           "method.mass=consistent"])]
    specs = [("plate_mms_2d", PLATE + sets, 0) for _, sets in plate_methods]
    # The column: PS-MPM on the grid of 4 x 22 cells of 0.05 m whose top row is partly filled;
    # the unified approach's triangles are the body's own (its nodes discretise the body only,
    # D 4.4), so its grid is the body: 4 x 20 cells, 0.05 m wide and top / 20 high.
    common = ["particles.per_cell=4", "time.dt=1e-4"]
    for top in TOPS:
        at = [f"body.max=[0.2, {top}]", f"constants.H={top}"]
        for label, sets in METHODS:
            grid = ([f"grid.max=[0.2, {top}]", "grid.cells_y=20"]
                    if label.startswith("unified") else [])
            specs.append(("custom_plate_2d", common + at + grid + sets, 0))
    # Four times the particles (particles.per_cell = 8: 32 per triangle), top row full and 20 %.
    dense_methods = [METHODS[0], METHODS[2], METHODS[4]]
    dense_tops = (TOPS[0], TOPS[-1])
    for top in dense_tops:
        at = [f"body.max=[0.2, {top}]", f"constants.H={top}"]
        for label, sets in dense_methods:
            grid = ([f"grid.max=[0.2, {top}]", "grid.cells_y=20"]
                    if label.startswith("unified") else [])
            specs.append(("custom_plate_2d", ["particles.per_cell=8", "time.dt=1e-4"] + at + grid
                          + sets, 0))
    # The plate on 8 x 8 cells with 8, 32 and 128 particles per triangle: PS-MPM and unified PS,
    # consistent mass (the particles' quadrature error, "Why the stress error of PS-MPM does not
    # fall under refinement here").
    ppt = [("4", 8), ("8", 32), ("16", 128)]
    ppt_methods = [METHODS[1], METHODS[4]]
    for per_cell, _ in ppt:
        for _, sets in ppt_methods:
            specs.append(("plate_mms_2d", [x for x in PLATE if not x.startswith(("grid.cells",
                                                                             "particles.per"))]
                          + ["grid.cells=8", f"particles.per_cell={per_cell}"] + sets, 0))
    # D Fig. 3.9's plate on the unstructured mesh (the example: 8 divisions, 24 particles per
    # triangle, consistent mass, t = 0.016 s): PS-MPM and unified PS.
    mesh_methods = [("PS-MPM, consistent", []), ("unified PS, consistent", UNIFIED)]
    for _, sets in mesh_methods:
        specs.append(("plate_ps_unstructured_2d", sets, 0))
    runs = R.many(specs)
    n_plate, n_column = len(plate_methods), len(TOPS) * len(METHODS)
    plate_runs = runs[:n_plate]
    column_runs = runs[n_plate:n_plate + n_column]
    n_dense = len(dense_methods) * len(dense_tops)
    dense_runs = runs[n_plate + n_column:n_plate + n_column + n_dense]
    ppt_runs = runs[n_plate + n_column + n_dense:-len(mesh_methods)]
    trow = []
    for mi, (label, _) in enumerate(ppt_methods):
        cells = []
        for pi in range(len(ppt)):
            r = ppt_runs[pi * len(ppt_methods) + mi]
            cells.append(e(r["errors"].get("stress_rel_l2")) if r.get("status") == "ok" else
                         f"stops at t = {fail_time(r.get('failure'))} s")
        trow.append(f"| {label} | " + " | ".join(cells) + " |")
    mrow = [error_row(label, r) for (label, _), r in zip(mesh_methods,
                                                          runs[-len(mesh_methods):])]
    drow = []
    for mi, (label, _) in enumerate(dense_methods):
        drow.append(f"| {label} | " + " | ".join(
            outcome(dense_runs[ti * len(dense_methods) + mi]) for ti in range(len(dense_tops)))
            + " |")
    prow = [error_row(label, r) for (label, _), r in zip(plate_methods, plate_runs)]
    crow, table = [], {}
    for mi, (label, _) in enumerate(METHODS):
        cells = []
        for ti in range(len(TOPS)):
            r = column_runs[ti * len(METHODS) + mi]
            table[(label, ti)] = r
            cells.append(outcome(r))
        crow.append(f"| {label} | " + " | ".join(cells) + " |")
    # D 7.3's suggestion read as a rule fixed before the runs: unified PS with consistent mass
    # runs to the end at every fill, and its stress error is at most that of PS-MPM with partial
    # lumping at each fill.
    def err(label, ti):
        r = table[(label, ti)]
        return r["errors"].get("stress_rms") if r.get("status") == "ok" else None
    uni = [err("unified PS, consistent", ti) for ti in range(len(TOPS))]
    part = [err("PS-MPM, partial lumping 0.5", ti) for ti in range(len(TOPS))]
    runs_all = all(u is not None for u in uni)
    not_worse = runs_all and all(p is None or u <= p for u, p in zip(uni, part))
    cons_stops = sum(1 for ti in range(len(TOPS)) if err("PS-MPM, consistent", ti) is None)
    measured = ", ".join(f"{f}: {e(u)} against {e(p)}" for f, u, p in zip(FILLS, uni, part))
    runs_measured = (f"unified PS, consistent runs at {sum(u is not None for u in uni)} of "
                     f"{len(TOPS)} fills; PS-MPM, consistent stops at {cons_stops}")
    verdict = verdict_claim(not_worse, measured)
    verdict_runs = verdict_claim(runs_all, runs_measured)
    ctx.update(unified_ps_column=dict(zip(FILLS, uni)))
    return render("unified_ps", "section", plate_rows="\n".join(prow),
                  column_rows="\n".join(crow), verdict=verdict, verdict_runs=verdict_runs,
                  measured=measured, runs_measured=runs_measured, dense_rows="\n".join(drow),
                  mesh_rows="\n".join(mrow), ppt_rows="\n".join(trow),
                  fills=" | ".join(FILLS), rule="|".join("---" for _ in FILLS))
