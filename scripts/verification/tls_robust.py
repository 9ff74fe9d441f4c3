"""TLS on the grid's cells that survives free surfaces and sparse elements: the variants of the
study from which the 2D defaults were chosen, on the plate and the vortex (sec_tls_robust);
and MLS and IMLS with their conservative variant against 001's and 003's
(sec_mls_conservative). Prose: templates/tls_robust.md, mls_conservative.md."""
import math
import re

from .common import ROUNDOFF, e, fail_time, num, verdict_claim
from .template import render
from .vortex import VORTEX_CELLS


# TLS on the grid's cells: the variants of the study, (label, sets). "D's TLS" is
# the method as published and as mpmlab ran it before: virtual points, a limit that only refuses
# nearly singular fits, the plain stress fit over whole elements, no positivity.
TLS_BASE = ["method.mapping=tls"]
TLS_VARIANTS = [
    ("direct", ["method.mapping=direct"]),
    ("D's TLS", TLS_BASE + ["method.tls_completion=virtual", "method.tls_max_condition=1e8",
                            "method.tls_positivity=off", "method.tls_surface_stress=element",
                            "method.tls_cell_integrals=centres"]),
    ("default", TLS_BASE),
    ("centres", TLS_BASE + ["method.tls_cell_integrals=centres"]),
    ("virtual", TLS_BASE + ["method.tls_completion=virtual"]),
    ("limit 1e2", TLS_BASE + ["method.tls_max_condition=100"]),
    ("limit 1e8", TLS_BASE + ["method.tls_max_condition=1e8"]),
    ("no positivity", TLS_BASE + ["method.tls_positivity=off"]),
    ("element stress", TLS_BASE + ["method.tls_surface_stress=element"]),
]
TLS_BASES = {"P1": ["method.basis=linear"], "B2": ["method.basis=bspline", "method.degree=2"]}
# B-spline TLS (degree >= 2) with consistent mass in 2D and 3D is refused without this (the
# growing mode in sec_ps_partial); the runs that document it ask for it.
ALLOW_UNSTABLE = "method.allow_unstable=true"


def tls_cell(r, key):
    """A table cell: the run's error `key`, or where it stopped."""
    if r.get("status") == "ok":
        return e(r.get("errors", {}).get(key))
    return f"stops at t = {fail_time(r.get('failure'))} s"


def sec_tls_robust(R, ctx):
    """TLS on the grid's cells that survives free surfaces and sparse elements;
    the 2D defaults chosen from this study."""
    plate = ["mms.amplitude=0.05", "time.end=0.02"]
    plate_cells = (8, 16, 32)
    plate_vars = [v for v in TLS_VARIANTS if v[0] != "element stress"]  # no free surface
    specs, keys = [], []
    for b, bs in TLS_BASES.items():
        for n in plate_cells:
            for label, sets in plate_vars:
                specs.append(("plate_mms_2d", plate + bs + [f"grid.cells={n}"] + sets, 0))
                keys.append(("plate", b, n, label))
    vortex_cells = (32, 64)
    for A in ("0.1", "1"):
        for b, bs in TLS_BASES.items():
            for n in vortex_cells:
                for label, sets in TLS_VARIANTS:
                    specs.append(("vortex_2d", [f"vortex.amplitude={A}", f"grid.cells={n}"] + bs +
                                  sets, 0))
                    keys.append((f"vortex {A}", b, n, label))
    # Layouts: particles per cell (per direction 2, 3, 4) on the vortex at A = 1 (B2, 32 cells)
    # and the plate at A = 0.05 (P1, 16 cells).
    layout_vars = [v for v in TLS_VARIANTS if v[0] in ("direct", "D's TLS", "default")]
    for k in (2, 3, 4):
        for label, sets in layout_vars:
            specs.append(("vortex_2d", ["vortex.amplitude=1", "grid.cells=32",
                                        f"particles.per_cell={k}"] + TLS_BASES["B2"] + sets, 0))
            keys.append(("layout vortex", "B2", k, label))
            specs.append(("plate_mms_2d", plate + ["grid.cells=16", f"particles.per_cell={k}"] +
                          TLS_BASES["P1"] + sets, 0))
            keys.append(("layout plate", "P1", k, label))
    # Consistent mass on the free body: TLS's mass matrix with 2 and 3 Gauss points per
    # direction, and with the nodes of tiny mass left out.
    cons_specs = [("2 Gauss points", []), ("3 Gauss points", ["method.gauss_points=3"]),
                  ("2 Gauss points, mass_tolerance 1e-2", ["method.mass_tolerance=1e-2"])]
    for label, sets in cons_specs:
        specs.append(("vortex_2d", ["vortex.amplitude=0.1", "grid.cells=32", "method.mapping=tls",
                                    "method.mass=consistent", ALLOW_UNSTABLE] + TLS_BASES["B2"]
                      + sets, 0))
        keys.append(("consistent", "B2", 32, label))
    # Where B2-TLS does not beat B2 direct on the plate: the same runs with more particles per
    # cell (per direction 3, 4, 6: 9, 16, 36), which shrink the integration error that TLS
    # replaces but not the grid's approximation error.
    ppc_cells, ppc_k = (8, 16), (3, 4, 6)
    for n in ppc_cells:
        for k in ppc_k:
            for label, sets in layout_vars:
                if label == "D's TLS":
                    continue
                specs.append(("plate_mms_2d", plate + [f"grid.cells={n}",
                                                       f"particles.per_cell={k}"] +
                              TLS_BASES["B2"] + sets, 0))
                keys.append(("ppc plate", "B2", (n, k), label))
    runs = dict(zip(keys, R.many(specs)))

    def ppc_errs(n, label):
        rs = [runs[("ppc plate", "B2", (n, k), label)] for k in ppc_k]
        return [r.get("errors", {}).get("stress_rms") if r.get("status") == "ok" else None
                for r in rs]

    def spread(v):
        return max(v) / min(v) - 1.0 if all(x for x in v) else None

    counts = ", ".join(str(k * k) for k in ppc_k)
    d8, t8, d16, t16 = (ppc_errs(ppc_cells[0], "direct"), ppc_errs(ppc_cells[0], "default"),
                        ppc_errs(ppc_cells[1], "direct"), ppc_errs(ppc_cells[1], "default"))
    sp8 = spread(d8)
    ppc_text = (
        f"Where B2 does not gain: on {ppc_cells[0]} cells B2 direct's stress error with {counts} "
        f"particles per cell is {', '.join(e(x) for x in d8)} Pa"
        + (f" (within {100 * sp8:.0f} %)" if sp8 is not None else "")
        + render("tls_robust", "ppc_text", t8_errors=', '.join(e(x) for x in t8),
                 ppc_cells_1=ppc_cells[1], d16_errors=', '.join(e(x) for x in d16),
                 t16_errors=', '.join(e(x) for x in t16)))

    def table(case, cells, variants, key, what="cells"):
        head = f"| basis | {what} | " + " | ".join(v[0] for v in variants) + " |"
        rows = [head, "|" + "---|" * (len(variants) + 2)]
        for b in TLS_BASES:
            for n in cells:
                if (case, b, n, variants[0][0]) not in runs:
                    continue
                rows.append(f"| {b} | {n} | " + " | ".join(
                    tls_cell(runs[(case, b, n, v[0])], key) for v in variants) + " |")
        return "\n".join(rows)

    def finished(case, label, bases=TLS_BASES, cells=None):
        rs = [r for (c, b, n, lab), r in runs.items() if c == case and lab == label and
              b in bases and (cells is None or n in cells)]
        return sum(r.get("status") == "ok" for r in rs), len(rs)

    def err(case, b, n, label, key):
        r = runs[(case, b, n, label)]
        return r.get("errors", {}).get(key) if r.get("status") == "ok" else None

    def beats(case, b, cells, key):
        out = []
        for n in cells:
            t, d = err(case, b, n, "default", key), err(case, b, n, "direct", key)
            out.append(t is not None and d is not None and t < d)
        return out

    def ratios(case, b, cells, key):
        return ", ".join(num(err(case, b, n, "direct", key) / err(case, b, n, "default", key))
                         if err(case, b, n, "default", key) and err(case, b, n, "direct", key)
                         else "-" for n in cells)

    tls_labels = [v[0] for v in TLS_VARIANTS if v[0] != "direct"]
    all_cases = ("plate", "vortex 0.1", "vortex 1")
    fin = {lab: [finished(c, lab) for c in all_cases] for lab in tls_labels}
    fin_text = "; ".join(
        f"{lab}: {sum(f for f, _ in v)} of {sum(t for _, t in v)}" for lab, v in fin.items())
    # Runs the default does not finish, and whether the direct mapping of the basis does.
    default_fails = [(c, b, n, runs[(c, b, n, "direct")].get("status") == "ok")
                     for (c, b, n, lab), r in runs.items()
                     if lab == "default" and c in all_cases and r.get("status") != "ok"]
    if not default_fails:
        default_text = "every run"
    else:
        default_text = "every run but " + "; ".join(
            f"{b} on {n} cells of the " + {"plate": "plate", "vortex 0.1": "vortex at A = 0.1",
                                           "vortex 1": "vortex at A = 1"}[c] +
            (" (direct finishes)" if ok else
                                              " (the direct mapping stops too)")
            for c, b, n, ok in default_fails)
    mass = max((r.get("conservation", {}).get("max_rel_mass_error") or 0.0)
               for (c, b, n, lab), r in runs.items()
               if lab != "direct" and r.get("status") == "ok" and c != "consistent")
    mom = max((r.get("conservation", {}).get("max_rel_momentum_error") or 0.0)
              for (c, b, n, lab), r in runs.items()
              if lab != "direct" and r.get("status") == "ok" and c != "consistent")
    p1_beats = beats("plate", "P1", plate_cells, "stress_rms")
    b2_beats = beats("plate", "B2", plate_cells, "stress_rms")
    vortex_beats = {(A, b): beats(f"vortex {A}", b, vortex_cells, "displacement_rms")
                    for A in ("0.1", "1") for b in TLS_BASES}
    vortex_beaten = [f"{b} at A = {A}" for (A, b), v in vortex_beats.items() if any(v)]
    cons_text = "; ".join(
        f"{label}: " + ("runs to the end" if runs[("consistent", "B2", 32, label)].get("status")
                        == "ok" else
                        "stops at t = " + fail_time(runs[("consistent", "B2", 32, label)]
                                                    .get("failure")) + " s ("
                        + re.sub(r"^step \d+, t = [0-9.eE+-]+ s: ", "",
                                 runs[("consistent", "B2", 32, label)].get("failure") or "")
                        .split(";")[0].split(" at ")[0] + ")")
        for label, _ in cons_specs)
    layout_rows = ["| case | particles per cell | direct | D's TLS | default |", "|---|---|---|---|---|"]
    for case, key in (("layout vortex", "displacement_rms"), ("layout plate", "stress_rms")):
        b = "B2" if case == "layout vortex" else "P1"
        for k in (2, 3, 4):
            layout_rows.append(
                f"| {'vortex, A = 1, B2, 32 cells, u' if b == 'B2' else 'plate, A = 0.05, P1, 16 cells, sigma'}"
                f" | {k * k} | " + " | ".join(tls_cell(runs[(case, b, k, lab)], key)
                                            for lab in ("direct", "D's TLS", "default")) + " |")
    layout_t = "\n".join(layout_rows)
    layout_fin = finished("layout vortex", "default")[0] + finished("layout plate", "default")[0]
    layout_fin_d = finished("layout vortex", "D's TLS")[0] + finished("layout plate", "D's TLS")[0]

    def ratios_of(case, b, label):
        return ", ".join(num(err(case, b, n, "direct", "stress_rms") /
                             err(case, b, n, label, "stress_rms"))
                         if err(case, b, n, label, "stress_rms") and
                         err(case, b, n, "direct", "stress_rms") else "-" for n in plate_cells)

    b2d = [err("plate", "B2", n, "direct", "stress_rms") for n in plate_cells]
    b2t = [err("plate", "B2", n, "default", "stress_rms") for n in plate_cells]
    if None not in b2d and None not in b2t:
        od, ot = math.log2(b2d[-2] / b2d[-1]), math.log2(b2t[-2] / b2t[-1])
        b2_trend = (f"From {plate_cells[-2]} to {plate_cells[-1]} cells B2 direct's stress error "
                    f"falls at order {od:.2f} and B2-TLS's (default) at {ot:.2f}"
                    + (": TLS keeps converging where the direct mapping stalls." if ot > od + 0.5
                       else "."))
    else:
        b2_trend = ""

    def yes_all(v):
        return "every grid" if all(v) else ("no grid" if not any(v) else
                                            f"{sum(v)} of {len(v)} grids")

    return render("tls_robust", "section",
                  plate_stress_table=table("plate", plate_cells, plate_vars, "stress_rms"),
                  plate_u_table=table("plate", plate_cells, plate_vars, "displacement_rms"),
                  vortex01_u_table=table("vortex 0.1", vortex_cells, TLS_VARIANTS,
                                         "displacement_rms"),
                  vortex01_stress_table=table("vortex 0.1", vortex_cells, TLS_VARIANTS,
                                              "stress_rms"),
                  vortex1_u_table=table("vortex 1", vortex_cells, TLS_VARIANTS,
                                        "displacement_rms"),
                  fin_text=fin_text, default_text=default_text, mass=e(mass), mom=e(mom),
                  layout_fin=layout_fin, layout_fin_d=layout_fin_d, layout_t=layout_t,
                  p1_beats=yes_all(p1_beats),
                  p1_ratios=ratios('plate', 'P1', plate_cells, 'stress_rms'),
                  plate_cells_list=", ".join(str(n) for n in plate_cells),
                  b2_beats=yes_all(b2_beats),
                  b2_ratios=ratios("plate", "B2", plate_cells, "stress_rms"),
                  p1_centres=ratios_of("plate", "P1", "centres"),
                  b2_centres=ratios_of("plate", "B2", "centres"), b2_trend=b2_trend,
                  ppc_text=ppc_text, vortex_beaten_list=", ".join(vortex_beaten) or "no grid",
                  cons_text=cons_text)


def sec_mls_conservative(R, ctx):
    """MLS and IMLS with method.mls_conservative against 001's and 003's."""
    m1 = "linear/mls, linear/imls, bspline2/mls"
    one = {c: R.study("mms_1d", "grid.cells=16,32,64", m1, [f"method.mls_conservative={c}"],
                      name=f"mls_cons_1d_{c}") for c in ("false", "true")}
    m2 = "bspline2/mls, bspline2/imls"
    two = {c: R.study("vortex_2d", "grid.cells=" + ",".join(str(x) for x in VORTEX_CELLS), m2,
                      ["vortex.amplitude=0.1", f"method.mls_conservative={c}"],
                      name=f"mls_cons_vortex_{c}") for c in ("false", "true")}

    def table(studies, methods):
        t = ["| method | variant | " + " | ".join(
            f"{int(r['grid.cells'])} cells" for r in studies["false"][1][methods[0]]) +
             " | largest relative mass / momentum error in a step |",
             "|---|---|" + "---|" * (len(studies["false"][1][methods[0]]) + 1)]
        for m in methods:
            for c, word in (("false", "published"), ("true", "conservative")):
                rs = studies[c][1].get(m, [])
                cells = [e(r.get("displacement_rms")) if r.get("status") == "ok" else "stopped"
                         for r in rs]
                mass = max((r.get("max_rel_mass_error") or 0.0) for r in rs) if rs else None
                mom = max((r.get("max_rel_momentum_error") or 0.0) for r in rs) if rs else None
                t.append(f"| {m} | {word} | " + " | ".join(cells) + f" | {e(mass)} / {e(mom)} |")
        return "\n".join(t)

    def worst(studies):
        return max((r.get("max_rel_mass_error") or 0.0, r.get("max_rel_momentum_error") or 0.0)
                   for rows in [studies["true"][1]] for rs in rows.values() for r in rs)

    w1, w2 = worst(one), worst(two)
    done = {c: sum(r.get("status") == "ok" for rs in two[c][1].values() for r in rs)
            for c in ("false", "true")}
    runs2 = sum(len(rs) for rs in two["false"][1].values())
    ok = max(w1 + w2) < ROUNDOFF
    return render("mls_conservative", "section",
                  table_1d=table(one, [m.strip() for m in m1.split(",")]),
                  table_vortex=table(two, [m.strip() for m in m2.split(",")]), ROUNDOFF=ROUNDOFF,
                  worst_mass=e(max(w1[0], w2[0])), worst_momentum=e(max(w1[1], w2[1])),
                  verdict=verdict_claim(ok, "above round-off"), done_conservative=done["true"],
                  runs2=runs2, done_published=done["false"])
