"""The grid bases on the 1D benchmarks: the vibrating bar with grid crossing (D 3.4.2, Fig. 3.7),
the column under compaction (D 5.4.2, Table 5.6) and the bar with a dynamic traction (D
4.6.2), each run with every basis and judged by the claim D makes about it. Prose:
templates/crossing.md, column_bases.md, traction.md (the bases themselves: static.py)."""
from .common import (e, fig_md, last_frame, pub, reproduced, src, total_variation, verdict_claim,
                     verdict_value)
from .plots import plot_profiles
from .template import render


def sec_crossing(R, ctx):
    """The bar with grid crossing (Table 3.1 set 1, D 3.4.2, Fig. 3.7) with every basis: the
    total variation of the final stress against the exact one."""
    bases = [("linear (MPM)", ["method.basis=linear"]),
             ("bspline p=2 (BSMPM)", ["method.basis=bspline", "method.degree=2"]),
             ("ugimp", ["method.basis=ugimp"]), ("cpgimp", ["method.basis=cpgimp"]),
             ("cpdi", ["method.basis=cpdi"]), ("ddmpm", ["method.basis=ddmpm"])]
    res = R.many([("vibrating_bar_crossing", s, 1) for _, s in bases])
    t = ["| basis | stress_rms [Pa] | stress_rel_l2 | velocity_rms_midstep [m/s] | TV / TV_exact "
         "| grid crossings | status |", "|---|---|---|---|---|---|---|"]
    tv = {}
    tv_exact = None
    for (label, _), r in zip(bases, res):
        parts = last_frame(r["_dir"])
        if parts:
            tv_exact = total_variation(parts, "stress_exact")
            tv[label] = total_variation(parts, "stress_11") / tv_exact
        er = r["errors"]
        t.append(f"| {label} | {er.get('stress_rms', 0):.4g} | {e(er.get('stress_rel_l2'))} | "
                 f"{e(er.get('velocity_rms_midstep'))} | {tv.get(label, float('nan')):.2f} | "
                 f"{r.get('grid_crossings', '-')} | {r['status']} |")
    mpm, bs = res[0]["errors"], res[1]["errors"]
    ratio = mpm["stress_rms"] / bs["stress_rms"]
    ok = tv["linear (MPM)"] > 2 and abs(tv["bspline p=2 (BSMPM)"] - 1) < 0.1
    v = verdict_claim(ok, f"TV ratios {tv['linear (MPM)']:.1f} (MPM), "
                      f"{tv['bspline p=2 (BSMPM)']:.2f} (BSMPM)")
    figs = plot_profiles(ctx, "crossing_stress_profile",
                         [("MPM (P1)", res[0]), ("BSMPM (p=2)", res[1])],
                         "vibrating bar with grid crossing, stress at T = 1e-3 s")
    return render("crossing", "section", tv_exact=tv_exact, table="\n".join(t), v=v, ratio=ratio,
                  figures=fig_md(ctx, figs, "stress of the grid-crossing bar at the final time"))


def sec_column_bases(R, ctx):
    """The column under compaction (D 5.4.2, Table 5.6) with every basis, against D's figures."""
    bases = [("linear (MPM)", ["method.basis=linear"]), ("ddmpm", ["method.basis=ddmpm"]),
             ("ugimp", ["method.basis=ugimp"]), ("cpgimp", ["method.basis=cpgimp"]),
             ("cpdi", ["method.basis=cpdi"]),
             ("bspline p=2 (BSMPM)", ["method.basis=bspline", "method.degree=2"]),
             ("bspline p=3", ["method.basis=bspline", "method.degree=3"])]
    res = R.many([("column_compaction", s, 1) for _, s in bases])
    t = ["| basis | stress_rel_l2 | grid crossings | status |", "|---|---|---|---|"]
    for (label, _), r in zip(bases, res):
        t.append(f"| {label} | {e(r['errors'].get('stress_rel_l2'))} | "
                 f"{r.get('grid_crossings', '-')} | {r['status']} |")
    mpm, dd, bs = (res[0]["errors"]["stress_rel_l2"], res[1]["errors"]["stress_rel_l2"],
                   res[5]["errors"]["stress_rel_l2"])
    cross = res[0]["grid_crossings"]
    v1 = verdict_value(mpm / bs, "column_bsmpm_factor", factor=True)
    v2 = verdict_value(cross, "column_mpm_crossings")
    v3 = verdict_value(dd, "column_ddmpm_error")
    figs = plot_profiles(ctx, "column_stress_profile",
                         [("MPM (P1)", res[0]), ("DDMPM", res[1]), ("BSMPM (p=2)", res[5])],
                         "column compaction, stress at T = 0.5 s")
    why = ""
    if not reproduced(v3):
        why = render("column_bases", "why")
    ctx["column_bases"] = res
    return render("column_bases", "section", table="\n".join(t),
                  column_bsmpm_factor_src=src('column_bsmpm_factor'),
                  column_bsmpm_factor_pub=pub('column_bsmpm_factor'), mpm_over_bs=mpm / bs, v1=v1,
                  column_mpm_crossings_src=src('column_mpm_crossings'),
                  column_mpm_crossings_pub=pub('column_mpm_crossings'), cross=cross, v2=v2,
                  column_ddmpm_error_src=src('column_ddmpm_error'),
                  column_ddmpm_error_pub=pub('column_ddmpm_error'), dd=e(dd, 3), v3=v3, why=why,
                  figures=fig_md(ctx, figs, "column compaction stress at the final time"))


def sec_traction(R, ctx):
    """The bar with a dynamic traction (D 4.6.2) with P1, BSMPM, CPDI and uGIMP: is BSMPM
    unstable with 81 nodes, as D reports?"""
    bases = [("linear (MPM)", ["method.basis=linear"]),
             ("bspline p=2 (BSMPM)", ["method.basis=bspline", "method.degree=2"]),
             ("cpdi", ["method.basis=cpdi"]), ("ugimp", ["method.basis=ugimp"])]
    res = R.many([("traction_bar", s, 1) for _, s in bases])
    t = ["| basis | stress_rel_l2 | displacement_rms [m] | grid crossings | status |",
         "|---|---|---|---|---|"]
    for (label, _), r in zip(bases, res):
        t.append(f"| {label} | {e(r['errors'].get('stress_rel_l2'), 3)} | "
                 f"{e(r['errors'].get('displacement_rms'))} | {r.get('grid_crossings', '-')} | "
                 f"{r['status']} |")
    p1, bs = res[0], res[1]
    unstable = bs["status"] != "ok" or not bs["errors"].get("stress_rel_l2") or \
        bs["errors"]["stress_rel_l2"] > 10 * p1["errors"]["stress_rel_l2"]
    v = verdict_claim(unstable, f"BSMPM {bs['status']}, stress_rel_l2 "
                      f"{e(bs['errors'].get('stress_rel_l2'))} against P1's "
                      f"{e(p1['errors'].get('stress_rel_l2'))}")
    figs = plot_profiles(ctx, "traction_stress_profile",
                         [("MPM (P1)", res[0]), ("BSMPM (p=2)", res[1])],
                         "bar with a dynamic traction, stress at T = 0.4 s")
    why = "" if unstable else render("traction", "why")
    return render("traction", "section", table="\n".join(t), bs_status=bs['status'],
                  bs_error=e(bs['errors'].get('stress_rel_l2')), v=v, why=why,
                  figures=fig_md(ctx, figs, "traction bar stress at the final time"))
