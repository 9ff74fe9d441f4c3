"""Two follow-ups of D ch. 5 with second, independent implementations: what limits lumped
BSMPM-TLS on the large-deformation bar (runs refined in time and space, at the published
amplitude and at 1/100 of it, against scripts/large_bar_check.py; sec_large_bar_lumping), and
D's conservative constant of TLS against element integrals from the particles' domains
(against scripts/tls_constant_check.py; sec_tls_constant). Prose:
templates/large_bar_lumping.md, tls_constant.md."""
import json
import math
import os
import subprocess
import sys

from .chapter5 import CH5_MAPPINGS, CH5_METHODS
from .common import ROOT, e, ls_order, o, ratio_range
from .template import render


LUMPING_COMBOS = [("MPM", "direct", "lumped"), ("BSMPM", "direct", "lumped"),
                  ("BSMPM", "TLS", "lumped"), ("BSMPM", "direct", "consistent"),
                  ("BSMPM", "TLS", "consistent")]


def sec_large_bar_lumping(R, ctx):
    """What limits lumped BSMPM-TLS on the large-deformation bar. mpmlab runs
    refined in time and space, at the published amplitude and at 1/100 of it, and the second,
    independent implementation scripts/large_bar_check.py (numpy, its own TL-FEM reference)."""
    large = ctx["ch5_large"]
    sets = lambda c: CH5_METHODS[c[0]] + [f"method.mapping={CH5_MAPPINGS[c[1]]}",
                                          f"method.mass={c[2]}"]
    cells = [10, 20, 40, 80]
    fine_dt = R.many([("vibrating_bar_large", sets(c) + ["time.dt=2.5e-5"], 0)
                      for c in LUMPING_COMBOS])
    jobs = [(c, n, v0) for v0 in ("0.8", "0.008") for c in LUMPING_COMBOS for n in cells]
    res = R.many([("vibrating_bar_large", sets(c) + [f"grid.cells={n}", "reference.dofs=960",
                                                     f"bar.v0={v0}"], 0) for c, n, v0 in jobs])
    space = {}
    for (c, n, v0), r in zip(jobs, res):
        space.setdefault((c, v0), []).append(r)
    err = lambda r: r["errors"].get("stress_rel_l2") if r["status"] == "ok" else None
    hs = [1.0 / n for n in cells]
    md = ["### What limits lumped BSMPM on the large-deformation bar (issue 22 item 6)\n"]
    fl, fc = ctx["large_factor_lumped"], ctx["large_factor_consistent"]
    md.append(render("large_bar_lumping", "intro", fl=fl, fc=fc))
    md.append(render("large_bar_lumping", "setup"))
    md.append("| method | mapping | mass | dt 1e-4 | dt 2.5e-5 | v0 | " +
              " | ".join(f"{n} cells" for n in cells) + " | order |")
    md.append("|---|---|---|---|---|---|" + "---|" * len(cells) + "---|")
    orders = {}
    for c, rdt in zip(LUMPING_COMBOS, fine_dt):
        for v0 in ("0.8", "0.008"):
            es = [err(r) for r in space[(c, v0)]]
            orders[(c, v0)] = ls_order(hs, es)
            head = (f"{e(err(large[c]))} | {e(err(rdt))}" if v0 == "0.8" else " | ")
            md.append(f"| {c[0]} | {c[1]} | {c[2]} | {head} | {v0} | "
                      + " | ".join(e(x) for x in es) + f" | {o(orders[(c, v0)]) or '-'} |")
    md.append("")

    # The second implementation: its MPM errors (all and interior particles), the n = 20 ratios
    # and the one-projection check.
    js = os.path.join(R.work, "large_bar_check.json")
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "large_bar_check.py"),
                    "--json", js], check=True, capture_output=True, text=True)
    with open(js) as f:
        sec = json.load(f)
    two = {(r["basis"], r["mass"], r["cells"]): r for r in sec["mpm"] if r["dt"] == 1e-4}
    proj = {(r["basis"], r["mode"], r["cells"]): r["error"] for r in sec["projection"]}
    ref = sec["reference"]
    ours = {("P1", "lumped"): ("MPM", "direct", "lumped"),
            ("B2", "lumped"): ("BSMPM", "direct", "lumped"),
            ("B2", "consistent"): ("BSMPM", "direct", "consistent")}
    md.append(render("large_bar_lumping", "second_implementation", ref_elements=ref[-1]['ne'],
                     ref_elements_coarser=ref[-2]['ne'],
                     ref_difference=e(ref[-2]['diff_to_finest'])))
    md.append("| basis | mass | " + " | ".join(f"{n} cells" for n in cells)
              + " | interior, 20 cells | P1/this (all, interior) | mpmlab, 20 cells |")
    md.append("|---|---|" + "---|" * len(cells) + "---|---|---|")
    base = two[("P1", "lumped", 20)]
    for b in ("P1", "B2"):
        for mass in ("lumped", "consistent"):
            r20 = two[(b, mass, 20)]
            mine = ours.get((b, mass))
            mv = err(space[(mine, "0.8")][cells.index(20)]) if mine else None
            md.append(f"| {b} | {mass} | " + " | ".join(e(two[(b, mass, n)]["e_all"]) for n in cells)
                      + f" | {e(r20['e_interior'])} | {base['e_all'] / r20['e_all']:.2f}, "
                      f"{base['e_interior'] / r20['e_interior']:.2f} | {e(mv)} |")
    md.append("")
    md.append(render("large_bar_lumping", "projection"))
    md.append("| cells | P1 lumped | P1 consistent | B2 lumped | (k h)^2 / 4 | B2 consistent | "
              "B2 lumped / consistent |")
    md.append("|---|---|---|---|---|---|---|")
    for n in cells:
        kh2 = (math.pi / n) ** 2 / 4
        md.append(f"| {n} | {e(proj[('P1', 'lumped', n)])} | {e(proj[('P1', 'consistent', n)])} | "
                  f"{e(proj[('B2', 'lumped', n)])} | {e(kh2)} | {e(proj[('B2', 'consistent', n)])} | "
                  f"{proj[('B2', 'lumped', n)] / proj[('B2', 'consistent', n)]:.1f} |")
    md.append("")

    # The conclusions, each from the numbers above.
    c_l, c_c = ("BSMPM", "TLS", "lumped"), ("BSMPM", "TLS", "consistent")
    dt_change = max(abs(err(rdt) / err(large[c]) - 1) for c, rdt in zip(LUMPING_COMBOS, fine_dt))
    small_l = err(space[(c_l, "0.008")][1])
    big_l = err(space[(c_l, "0.8")][1])
    small_c = err(space[(c_c, "0.008")][1])
    big_c = err(space[(c_c, "0.8")][1])
    agree = max(abs(err(space[(ours[k], "0.8")][cells.index(20)]) / two[k + (20,)]["e_all"] - 1)
                for k in ours)
    int_ratio = base["e_interior"] / two[("B2", "lumped", 20)]["e_interior"]
    all_ratio = base["e_all"] / two[("B2", "lumped", 20)]["e_all"]
    pl = [proj[("B2", "lumped", n)] for n in cells]
    pred = max(abs(pl[k] / ((math.pi / n) ** 2 / 4) - 1) for k, n in enumerate(cells))
    lump_over_cons = [proj[("B2", "lumped", n)] / proj[("B2", "consistent", n)] for n in cells]
    ref_change = max(abs(err(space[(c, "0.8")][cells.index(20)]) / err(large[c]) - 1)
                     for c in LUMPING_COMBOS)
    big_l_pairs = [math.log2(err(space[(c_l, "0.8")][k]) / err(space[(c_l, "0.8")][k + 1]))
                   for k in range(2)]
    floor = [max(err(space[(c, "0.8")][k]) for c in (c_l, c_c))
             / min(err(space[(c, "0.8")][k]) for c in (c_l, c_c)) for k in (2, 3)]
    lumped_maps = [err(large[("BSMPM", mp, "lumped")]) for mp in CH5_MAPPINGS]
    f_direct = err(large[("MPM", "direct", "lumped")]) / err(large[("BSMPM", "direct", "consistent")])
    md.append("What this shows:")
    md.append(render("large_bar_lumping", "not_time_step", dt_change_pct=100 * dt_change,
                     ref_change_pct=100 * ref_change, agree_pct=100 * agree))
    md.append(render("large_bar_lumping", "not_ends", int_ratio=int_ratio, all_ratio=all_ratio))
    md.append(render("large_bar_lumping", "not_large_deformation", small_l=e(small_l),
                     small_over_big=small_l / big_l, small_l_order=o(orders[(c_l, '0.008')]),
                     big_l_order_1=big_l_pairs[0], big_l_order_2=big_l_pairs[1],
                     small_c=e(small_c), big_c=e(big_c), floor_40=floor[0], floor_80=floor[1]))
    tc = [err(r) for r in space[(c_c, "0.008")]]
    dc = [err(r) for r in space[(("BSMPM", "direct", "consistent"), "0.008")]]
    if tc[-1] > 3 * dc[-1]:
        md.append(render("large_bar_lumping", "seen_on_the_way", tls_40=e(tc[-2]),
                         tls_80=e(tc[-1]), direct_80=e(dc[-1])))
    md.append(render("large_bar_lumping", "lumped_mass", pred_pct=100 * pred, lumped_20=e(pl[1]),
                     lumped_over_consistent=ratio_range(lump_over_cons),
                     lumped_min=e(min(lumped_maps)), lumped_max=e(max(lumped_maps)), fc=fc,
                     f_direct=f_direct, fl=fl))
    md.append("")
    md.append(render("large_bar_lumping", "derivation"))
    ctx.update(lumping_dt=dict(zip(LUMPING_COMBOS, fine_dt)), lumping_space=space,
               lumping_orders=orders, lumping_second=sec)
    return "\n".join(md) + "\n"


def sec_tls_constant(R, ctx):
    """D's conservative constant of TLS and the element integrals from the particles' domains
    (method.tls_cell_integrals), in 1D with a second implementation."""
    cells = [10, 20, 40, 80]
    base = ["method.basis=bspline", "method.degree=2", "method.mass=consistent", "bar.v0=0.008",
            "reference.dofs=960"]
    variants = [("direct", ["method.mapping=direct"]),
                ("TLS, centres (D)", ["method.mapping=tls", "method.tls_cell_integrals=centres"]),
                ("TLS, domains", ["method.mapping=tls", "method.tls_cell_integrals=domains"])]
    jobs = [(lab, n) for lab, _ in variants for n in cells]
    res = R.many([("vibrating_bar_large", base + dict(variants)[lab] + [f"grid.cells={n}"], 0)
                  for lab, n in jobs])
    runs = dict(zip(jobs, res))
    err = lambda lab, n: (runs[(lab, n)]["errors"].get("stress_rel_l2")
                          if runs[(lab, n)]["status"] == "ok" else None)
    hs = [1.0 / n for n in cells]
    rows = ["| mapping | " + " | ".join(f"{n} cells" for n in cells)
            + " | order 40-80 | mass error | momentum error |",
            "|---|" + "---|" * len(cells) + "---|---|---|"]
    for lab, _ in variants:
        es = [err(lab, n) for n in cells]
        o4080 = ls_order(hs[2:], es[2:])
        cons = [runs[(lab, n)]["conservation"] for n in cells]
        rows.append(f"| {lab} | " + " | ".join(e(x) for x in es) + f" | {o(o4080) or '-'} | "
                    + e(max(c.get("max_rel_mass_error") or 0 for c in cons), 1) + " | "
                    + e(max(c.get("max_rel_momentum_error") or 0 for c in cons), 1) + " |")
    second = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "tls_constant_check.py"),
                             "--quick"], check=True, capture_output=True, text=True).stdout
    # Its tables, without the timing line.
    second = "\n".join(line for line in second.splitlines() if not line.startswith("Total"))
    cent80, dom80, dir80 = err("TLS, centres (D)", 80), err("TLS, domains", 80), err("direct", 80)
    stall = cent80 is not None and dir80 is not None and cent80 > 3 * dir80
    same = dom80 is not None and dir80 is not None and abs(dom80 / dir80 - 1) < 0.02
    md = ["### The conservative constant of TLS: element integrals from the particles' domains\n"]
    md.append(render("tls_constant", "domains"))
    md.append(render("tls_constant", "setup"))
    md += rows
    md.append("")
    md.append(render("tls_constant", "result",
                     centres_verb="stops converging" if stall else "converges",
                     centres_80=e(cent80), direct_80=e(dir80),
                     domains_verb="has the direct mapping's error" if same else "has",
                     domains_80=e(dom80)))
    md.append("```\n" + second.strip() + "\n```\n")
    md.append(render("tls_constant", "unseen_in_d"))
    ctx.update(tls_constant=runs)
    return "\n".join(md) + "\n"
