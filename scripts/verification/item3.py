"""With --long: the plate at A = 0.05 m with every mapping, completion and mass on 8-64 cells,
judged against the study's target (sec_item3), and what limits each reconstruction, one
input at a time (sec_item3_why). Prose: templates/item3.md, item3_why.md."""
import math
import os
import re
import subprocess
import time

from .common import EX, col, e, ls_order, o, pair_orders
from .template import render
from .vortex import vortex_failure


# The reconstruction study at A = 0.05 m: every mapping, completion and mass on 8-64 cells.
# Groups of (label, methods of `mpm study`, extra settings); the 2D default TLS completion is
# `auto` (= reduce). Combinations refused up front (ITEM3_REFUSED) are run once to quote the
# refusal.
ITEM3_CELLS = (8, 16, 32, 64)
ITEM3_GROUPS = [
    ("default", "linear/direct, bspline2/direct, linear/tls, bspline2/tls, linear/mls, "
     "bspline2/mls, linear/imls, bspline2/imls, linear/direct/consistent, "
     "bspline2/direct/consistent, linear/tls/consistent, linear/mls/consistent, "
     "bspline2/mls/consistent", []),
    ("TLS virtual", "linear/tls, bspline2/tls, linear/tls/consistent",
     ["method.tls_completion=virtual"]),
    ("TLS neighbour", "linear/tls, bspline2/tls, linear/tls/consistent",
     ["method.tls_completion=neighbour"]),
    ("conservative", "linear/mls, bspline2/mls, linear/imls, bspline2/imls, "
     "linear/mls/consistent, bspline2/mls/consistent", ["method.mls_conservative=true"]),
]
ITEM3_REFUSED = [("bspline2/tls/consistent", ["method.basis=bspline", "method.degree=2",
                                              "method.mapping=tls", "method.mass=consistent"]),
                 ("linear/imls/consistent", ["method.basis=linear", "method.mapping=imls",
                                             "method.mass=consistent"])]


def sec_item3(R, ctx):
    """The plate at A = 0.05 m (T = 0.02 s) on 8-64 cells, P1 and B2, every
    mapping and completion, lumped and consistent mass: which runs finish, their errors and
    orders, conservation (about 40 minutes on 2 cores: behind --long)."""
    base = ["mms.amplitude=0.05", "time.end=0.02"]
    refine = "grid.cells=" + ",".join(str(c) for c in ITEM3_CELLS)
    studies = [(label, R.study("plate_mms_2d", refine, methods, base + sets,
                               name=f"item3_{label.replace(' ', '_')}"))
               for label, methods, sets in ITEM3_GROUPS]
    # The runs' own times (one thread each), summed: the cost of the study on one core.
    run_time = sum(r.get("wall_seconds") or 0.0 for _, (_, rows) in studies
                   for rs in rows.values() for r in rs)
    refused = []
    for m, sets in ITEM3_REFUSED:
        cmd = [R.mpm, "run", os.path.join(EX, "plate_mms_2d.toml"), "-q", "--out",
               R._dir("item3_refused")]
        for x in base + sets + ["time.end=1e-5"]:
            cmd += ["--set", x]
        p = subprocess.run(cmd, capture_output=True, text=True, env=R.env)
        msg = p.stderr.strip().split("\n")[-1] if p.returncode != 0 else "not refused"
        msg = re.sub(r"^mpm: error: ", "", msg)
        refused.append((m, msg.split(": ", 1)[-1].split(" (")[0]))

    def rows_of():
        for label, (out, rows) in studies:
            for m, rs in rows.items():
                yield label, m, out, rs

    def table(key):
        t = ["| method | variant | " + " | ".join(f"{c} cells" for c in ITEM3_CELLS) +
             " | order (fit) | pair orders |", "|---|---|" + "---|" * (len(ITEM3_CELLS) + 2)]
        for label, m, out, rs in rows_of():
            es = [r.get(key) if r.get("status") == "ok" else None for r in rs]
            cells = [int(r["grid.cells"]) for r in rs]
            cx = [e(x) if x is not None else f"stopped ({vortex_failure(out, m, c)})"
                  for x, c in zip(es, cells)]
            hs = col(rs, "h")
            fit = ls_order(hs, es) if all(x is not None for x in es) else None
            po = pair_orders(hs, es)[1:]
            t.append(f"| {m} | {label} | " + " | ".join(cx) + f" | {o(fit)} | "
                     + ", ".join(o(x) if x is not None else "-" for x in po) + " |")
        return "\n".join(t)

    finished = total = 0
    cons = ["| method | variant | runs that finish | largest relative mass error in a step | "
            "largest relative momentum error in a step |", "|---|---|---|---|---|"]
    worst_conservative = 0.0
    for label, m, out, rs in rows_of():
        ok = [r for r in rs if r.get("status") == "ok"]
        finished += len(ok)
        total += len(rs)
        mass = max((r.get("max_rel_mass_error") or 0.0 for r in rs), default=None)
        mom = max((r.get("max_rel_momentum_error") or 0.0 for r in rs), default=None)
        if "/mls" not in m and "/imls" not in m or label == "conservative":
            worst_conservative = max(worst_conservative, mass or 0.0, mom or 0.0)
        cons.append(f"| {m} | {label} | {len(ok)} of {len(rs)} | {e(mass)} | {e(mom)} |")
    # B2 direct against the best reconstruction of its basis in stress, grid by grid.
    def stress(label, m):
        for lb, mm, _, rs in rows_of():
            if lb == label and mm == m:
                return [r.get("stress_rms") if r.get("status") == "ok" else None for r in rs]
        return [None] * len(ITEM3_CELLS)

    def ratios(direct, other):
        return " | ".join(f"{a / b:.2f}" if a and b else "-" for a, b in zip(direct, other))

    def last_order(v):
        h = [1.0 / c for c in ITEM3_CELLS]
        po = pair_orders(h, v)
        return po[-1]

    beat, beats_all, keeps = [], [], []
    stall = {}
    for basis, d in (("P1", "linear"), ("B2", "bspline2")):
        ref = stress("default", f"{d}/direct")
        stall[basis] = last_order(ref)
        for label, m in (("default", f"{d}/tls"), ("TLS virtual", f"{d}/tls"),
                         ("TLS neighbour", f"{d}/tls"), ("default", f"{d}/mls"),
                         ("conservative", f"{d}/mls"), ("default", f"{d}/imls"),
                         ("conservative", f"{d}/imls")):
            v = stress(label, m)
            beat.append(f"| {basis} | {m} ({label}) | {ratios(ref, v)} | {o(last_order(v))} |")
            name = f"{m} ({label})"
            if all(a and b and a > b for a, b in zip(ref, v)):
                beats_all.append(name)
            lo = last_order(v)
            if lo is not None and lo >= 1.0:
                keeps.append(name)
    both = [m for m in beats_all if m in keeps]
    c1, c2 = ITEM3_CELLS[-2], ITEM3_CELLS[-1]
    target = render("item3", "target", c1=c1, c2=c2, stall_b2=o(stall['B2']),
                    stall_p1=o(stall['P1']), beats_all_list=', '.join(beats_all) or 'none',
                    keeps_list=', '.join(keeps) or 'none', both_list=', '.join(both) or 'none')
    return render("item3", "section", cells_list=", ".join(str(c) for c in ITEM3_CELLS),
                  refine=refine, run_time=run_time, run_minutes=run_time / 2 / 60,
                  finished=finished, total=total,
                  refused_list="\n".join(f"- `{m}`: {why}" for m, why in refused),
                  table_stress_rms=table("stress_rms"),
                  table_displacement_rms=table("displacement_rms"),
                  table_velocity=table("velocity_rms_scheme_time"), cons_table="\n".join(cons),
                  worst_conservative=e(worst_conservative),
                  cells_heads=" | ".join(f"{c} cells" for c in ITEM3_CELLS),
                  cells_rule="---|" * (len(ITEM3_CELLS) + 1), beat_table="\n".join(beat),
                  target=target)


# The study's target at 9 particles per cell (finish every run, beat the direct mapping of the
# basis in stress on every grid, keep converging where B2 direct stalls) is met by no
# reconstruction (sec_item3). What limits each: TLS from 32 to 64 cells (the time step, the
# particles per cell), B2-TLS and MLS / IMLS on 8 and 16 cells (the particles per cell, MLS's
# weight support). The direct mapping is rerun beside each change of the particles, so that
# "beats the direct mapping" is judged under it.
ITEM3_WHY_TLS = "linear/direct, bspline2/direct, linear/tls, bspline2/tls"
ITEM3_WHY_MLS = "linear/mls, bspline2/mls, linear/imls, bspline2/imls"


def sec_item3_why(R, ctx):
    """Why no reconstruction reaches the target at 9 particles per cell, shown
    by changing one input at a time (the time step, the particles per cell, MLS's weight
    support) on the plate at A = 0.05 m (behind --long: about 15 minutes on 2 cores)."""
    base = ["mms.amplitude=0.05", "time.end=0.02"]
    refine = "grid.cells=" + ",".join(str(c) for c in ITEM3_CELLS)
    coarse, fine = ITEM3_CELLS[:2], ITEM3_CELLS[-2:]
    fine_refine = "grid.cells=" + ",".join(str(c) for c in fine)
    coarse_refine = "grid.cells=" + ",".join(str(c) for c in coarse)
    cons = ["method.mls_conservative=true"]
    t0 = time.time()
    series = {
        "tls9": R.study("plate_mms_2d", refine, ITEM3_WHY_TLS, base, name="item3why_tls9"),
        "tls16": R.study("plate_mms_2d", refine, ITEM3_WHY_TLS, base + ["particles.per_cell=4"],
                         name="item3why_tls16"),
        "tls25": R.study("plate_mms_2d", fine_refine, "linear/tls, bspline2/tls",
                         base + ["particles.per_cell=5"], name="item3why_tls25"),
        "dt2": R.study("plate_mms_2d", fine_refine, "linear/tls, bspline2/tls",
                       base + ["time.dt=5e-6"], name="item3why_dt2"),
        "mls_a2": R.study("plate_mms_2d", coarse_refine, ITEM3_WHY_MLS, base + cons,
                          name="item3why_mls_a2"),
        "mls_a2p16": R.study("plate_mms_2d", coarse_refine, ITEM3_WHY_MLS,
                             base + cons + ["particles.per_cell=4"], name="item3why_mls_p16"),
        "mls_a1": R.study("plate_mms_2d", refine, ITEM3_WHY_MLS,
                          base + cons + ["method.mls_dilation=1"], name="item3why_mls_a1"),
    }
    wall = time.time() - t0
    run_time = sum(r.get("wall_seconds") or 0.0 for _, rows in series.values()
                   for rs in rows.values() for r in rs)
    finished = sum(1 for _, rows in series.values() for rs in rows.values() for r in rs
                   if r.get("status") == "ok")
    total = sum(len(rs) for _, rows in series.values() for rs in rows.values())

    def s(key, m):
        """Stress RMS by cell count (None where the run did not finish)."""
        return {int(r["grid.cells"]): (r.get("stress_rms") if r.get("status") == "ok" else None)
                for r in series[key][1].get(m, [])}

    def order(v, a, b):
        x, y = v.get(a), v.get(b)
        return math.log(x / y) / math.log(b / a) if x and y else None

    def cell(v, c):
        return e(v.get(c)) if v.get(c) is not None else "-"

    def change(a, b, c):
        """Relative change from a to b on c cells, in per cent (None where one is missing)."""
        return 100.0 * (b[c] / a[c] - 1.0) if a.get(c) and b.get(c) else None

    def pct(x):
        return "-" if x is None else f"{x:+.0f} %"

    def beats_and_keeps(ref, v):
        beats = all(ref.get(c) and v.get(c) and ref[c] > v[c] for c in ITEM3_CELLS)
        lo = order(v, *fine)
        return beats and lo is not None and lo >= 1.0

    bases = (("P1", "linear"), ("B2", "bspline2"))
    def stress_row(m, ppc, w):
        return (f"| {m} | {ppc} | " + " | ".join(cell(w, c) for c in ITEM3_CELLS) + " | "
                + ", ".join(o(order(w, a, b)) or "-" for a, b in zip(ITEM3_CELLS, ITEM3_CELLS[1:]))
                + " |")

    tls_rows, ratio_rows, met = [], [], {9: [], 16: []}
    for key, ppc in (("tls9", 9), ("tls16", 16)):
        for _, d in bases:
            ref, v = s(key, f"{d}/direct"), s(key, f"{d}/tls")
            tls_rows += [stress_row(f"{d}/direct", ppc, ref), stress_row(f"{d}/tls", ppc, v)]
            ratio_rows.append(f"| {d}/tls | {ppc} | " + " | ".join(
                f"{ref[c] / v[c]:.2f}" if ref.get(c) and v.get(c) else "-" for c in ITEM3_CELLS)
                + " |")
            if beats_and_keeps(ref, v):
                met[ppc].append(f"{d}/tls")
    tls_rows += [stress_row(f"{d}/tls", 25, s("tls25", f"{d}/tls")) for _, d in bases]
    dt_rows = []
    for _, d in bases:
        v9, v2 = s("tls9", f"{d}/tls"), s("dt2", f"{d}/tls")
        dt_rows.append(f"| {d}/tls | " + " | ".join(f"{cell(v9, c)} | {cell(v2, c)}"
                                                    for c in fine)
                       + f" | {o(order(v9, *fine))} | {o(order(v2, *fine))} |")
    dt_change = max((abs(change(s("tls9", f"{d}/tls"), s("dt2", f"{d}/tls"), c) or 0.0)
                     for _, d in bases for c in fine), default=0.0)
    # The floor at the finest grid and the last order, by particles per cell.
    floor = {d: [(ppc, s(key, f"{d}/tls").get(fine[1]), order(s(key, f"{d}/tls"), *fine))
                 for key, ppc in (("tls9", 9), ("tls16", 16), ("tls25", 25))]
             for _, d in bases}

    def floor_text(d):
        return "; ".join(f"{ppc} per cell {e(x)} Pa (order {o(lo)})" for ppc, x, lo in floor[d])

    # B2 on the coarse grids: which error moves with the particles.
    b2d = {c: change(s("tls9", "bspline2/direct"), s("tls16", "bspline2/direct"), c)
           for c in coarse}
    b2t = {c: change(s("tls9", "bspline2/tls"), s("tls16", "bspline2/tls"), c) for c in coarse}

    # MLS and IMLS on the coarse grids: the weight's support against the particles per cell.
    mls = [x.strip() for x in ITEM3_WHY_MLS.split(",")]
    mls_rows, ppc_moves, a1_gain = [], [], []
    for m in mls:
        d = m.split("/")[0]
        a2, p16, a1 = s("mls_a2", m), s("mls_a2p16", m), s("mls_a1", m)
        r9, r16 = s("tls9", f"{d}/direct"), s("tls16", f"{d}/direct")
        mls_rows.append(f"| {m} | " + " | ".join(
            f"{cell(a2, c)} | {cell(p16, c)} | {cell(a1, c)} | {cell(r9, c)} | {cell(r16, c)}"
            for c in coarse) + " |")
        ppc_moves += [abs(change(a2, p16, c) or 0.0) for c in coarse]
        a1_gain += [a2[c] / a1[c] for c in coarse if a2.get(c) and a1.get(c)]
    a1_rows, met_a1 = [], []
    for m in mls:
        d = m.split("/")[0]
        ref, v = s("tls9", f"{d}/direct"), s("mls_a1", m)
        a1_rows.append(f"| {m} | " + " | ".join(cell(v, c) for c in ITEM3_CELLS) + " | "
                       + " | ".join(f"{ref[c] / v[c]:.2f}" if ref.get(c) and v.get(c) else "-"
                                    for c in ITEM3_CELLS)
                       + f" | {o(order(v, *fine))} |")
        if beats_and_keeps(ref, v):
            met_a1.append(m)
    hdr = " | ".join(f"{c} cells" for c in ITEM3_CELLS)
    pairs = ", ".join(f"{a}-{b}" for a, b in zip(ITEM3_CELLS, ITEM3_CELLS[1:]))
    met_a1_text = (render("item3_why", "met_a1_text", met_a1_list=", ".join(met_a1),
                          fine_0=fine[0], fine_1=fine[1]) if met_a1
                   else "None of them meets the whole target with a = 1 either.")
    return render("item3_why", "section", finished=finished, total=total, run_time=run_time,
                  wall=wall, pairs=pairs, hdr=hdr, rule_cells_1="---|" * (len(ITEM3_CELLS) + 1),
                  tls_rows="\n".join(tls_rows), rule_cells="---|" * len(ITEM3_CELLS),
                  ratio_rows="\n".join(ratio_rows),
                  dt_heads=" | ".join(f"{c} cells, dt | {c} cells, dt / 2" for c in fine),
                  dt_rule="---|" * (2 * len(fine) + 2), dt_rows="\n".join(dt_rows),
                  dt_change=dt_change, fine_0=fine[0], fine_1=fine[1],
                  floor_p1=floor_text("linear"), floor_b2=floor_text("bspline2"),
                  b2d_coarse_0=pct(b2d[coarse[0]]), coarse_0=coarse[0],
                  b2d_coarse_1=pct(b2d[coarse[1]]), coarse_1=coarse[1],
                  b2t_coarse_0=pct(b2t[coarse[0]]), b2t_coarse_1=pct(b2t[coarse[1]]),
                  met_16=", ".join(met[16]) or "none", met_9=", ".join(met[9]) or "none",
                  mls_heads=" | ".join(f"{c} cells: a = 2 | a = 2, 16 per cell | a = 1 | direct | "
                                       "direct, 16 per cell" for c in coarse),
                  mls_rule="---|" * (5 * len(coarse)), mls_rows="\n".join(mls_rows),
                  ppc_moves_max=max(ppc_moves, default=0.0), a1_gain_min=min(a1_gain, default=0.0),
                  a1_gain_max=max(a1_gain, default=0.0),
                  a1_heads=" | ".join(f"direct / MLS, {c}" for c in ITEM3_CELLS),
                  a1_rule="---|" * (2 * len(ITEM3_CELLS) + 1), a1_rows="\n".join(a1_rows),
                  met_a1_text=met_a1_text)
