"""The small-deformation vibrating bar (D 5.4.1, Table 3.1 set 2) with P1: orders against D
Fig. 5.9a, the mid-step velocity, the other update schemes, conservation (sec_small_bar); and
the end error of quadratic B-splines with lumped mass, all particles against interior ones (D
Fig. 5.10, sec_boundary). Prose: templates/small_bar.md, boundary.md."""
import math
import os

from .common import (col, e, fig_md, ls_order, o, pair_orders, pub, src, verdict_order,
                     verdict_value)
from .plots import plot_study
from .template import render


def sec_small_bar(R, ctx):
    """The small-deformation bar with P1 (MUSL, lumped), refined; the mid-step velocity with a
    smaller step, the other schemes at 40 cells, conservation."""
    out, rows = R.study("vibrating_bar_small", "grid.cells=5,10,20,40", name="small_bar")
    rs = list(rows.values())[0]
    hs = col(rs, "h")
    keys = ["displacement_rms", "velocity_rms_midstep", "velocity_rms", "stress_rms"]
    orders = {k: pair_orders(hs, col(rs, k)) for k in keys}
    t = ["| cells | displacement_rms | order | velocity_rms_midstep | order | velocity_rms (t = T) "
         "| stress_rms [Pa] | order |", "|---|---|---|---|---|---|---|---|"]
    for i, r in enumerate(rs):
        t.append(f"| {int(r['cells'])} | {e(r['displacement_rms'], 3)} | "
                 f"{o(orders['displacement_rms'][i])} | {e(r['velocity_rms_midstep'], 3)} | "
                 f"{o(orders['velocity_rms_midstep'][i])} | {e(r['velocity_rms'], 3)} | "
                 f"{r['stress_rms']:.4g} | {o(orders['stress_rms'][i])} |")
    lsu = ls_order(hs, col(rs, "displacement_rms"))
    lsv = ls_order(hs, col(rs, "velocity_rms_midstep"))
    lss = ls_order(hs, col(rs, "stress_rms"))
    vu, vv, vs = (verdict_order(lsu, "bar_order_u"), verdict_order(lsv, "bar_order_v"),
                  verdict_order(lss, "bar_order_sigma"))
    ctx["small_bar"] = rs
    # dt = 1e-8 s: the mid-step velocity without its O(dt^2) start-up floor.
    _, fine = R.study("vibrating_bar_small", "grid.cells=5,10,20,40", sets=["time.dt=1e-8"],
                      name="small_bar_dt")
    fr = list(fine.values())[0]
    fo = pair_orders(col(fr, "h"), col(fr, "velocity_rms_midstep"))[1:]
    same_u = all(abs(a["displacement_rms"] / b["displacement_rms"] - 1) < 1e-2 and
                 abs(a["stress_rms"] / b["stress_rms"] - 1) < 1e-2 for a, b in zip(rs, fr))
    # The other schemes at 40 cells.
    sch = R.many([("vibrating_bar_small", ["grid.cells=40", f"method.scheme={s}"], 0)
                  for s in ("usl", "usf", "usavg")])
    usl = sch[0]["errors"]
    musl = rs[-1]
    digits = min(-math.log10(max(abs(usl[k] / musl[k] - 1), 1e-16))
                 for k in ("displacement_rms", "velocity_rms", "stress_rms"))
    mass, mom = musl["max_rel_mass_error"], musl["max_rel_momentum_error"]
    figs = plot_study(out, os.path.join(ctx["figdir"], "vibrating_bar_small"),
                      "displacement_rms,velocity_rms_midstep,stress_rms",
                      "vibrating bar, small deformation, P1 (MUSL, lumped)")
    ctx["readme_fig"] = [p for p in figs if p.endswith("convergence_displacement_rms.png")]
    stall = rs[-1]["velocity_rms"]
    mid_note = (", below 2 because of a second," if orders["velocity_rms_midstep"][-1] < 1.8
                else "; finer grids would meet a second,")
    md = render("small_bar", "section", table="\n".join(t), lsu=o(lsu), vu=vu, lsv=o(lsv), vv=vv,
                lss=o(lss), vs=vs, stall=e(stall, 1),
                mid_last_order=o(orders['velocity_rms_midstep'][-1]), mid_note=mid_note,
                fine_dt_orders=", ".join(o(x) for x in fo),
                fine_dt_error=e(fr[-1]['velocity_rms_midstep']),
                spatial_text=("unchanged to 1 % (spatial errors)" if same_u
                              else "changed (see the runs)"),
                usl_digits=int(digits), v_musl=e(musl['velocity_rms_scheme_time']),
                v_usl=e(sch[0]['errors'].get('velocity_rms_scheme_time')),
                v_usf=e(sch[1]['errors'].get('velocity_rms_scheme_time')),
                v_usavg=e(sch[2]['errors'].get('velocity_rms_scheme_time')), mass=e(mass, 1),
                mom=e(mom, 1), bar_direct_mass_pub=e(pub('bar_direct_mass'), 0),
                bar_direct_mass_src=src('bar_direct_mass'),
                mass_verdict=verdict_value(mass, 'bar_direct_mass', roundoff=True),
                figures=fig_md(ctx, figs, "small-deformation bar"))
    return md


def sec_boundary(R, ctx):
    """Quadratic B-splines with lumped mass on the same bar: all particles against those
    outside the p end cells (D Fig. 5.10)."""
    out, rows = R.study("vibrating_bar_small", "grid.cells=5,10,20,40",
                        sets=["method.basis=bspline", "method.degree=2"], name="boundary")
    rs = list(rows.values())[0]
    hs = col(rs, "h")
    t = ["| cells | displacement_rms | interior | velocity_rms_scheme_time | interior | "
         "stress_rms [Pa] | interior [Pa] |", "|---|---|---|---|---|---|---|"]
    for r in rs:
        t.append(f"| {int(r['cells'])} | {e(r['displacement_rms'])} | "
                 f"{e(r['displacement_rms_interior'])} | {e(r['velocity_rms_scheme_time'])} | "
                 f"{e(r['velocity_rms_scheme_time_interior'])} | {r['stress_rms']:.4g} | "
                 f"{r['stress_rms_interior']:.3g} |")
    s_all = ls_order(hs, col(rs, "stress_rms"))
    s_int = pair_orders(hs, col(rs, "stress_rms_interior"))[-1]
    mpm40 = ctx["small_bar"][-1]["stress_rms"]
    below = mpm40 / rs[-1]["stress_rms_interior"]
    v_int = col(rs, "velocity_rms_scheme_time_interior")
    v_all = col(rs, "velocity_rms_scheme_time")
    grows = v_all[-1] > v_all[0]
    figs = plot_study(out, os.path.join(ctx["figdir"], "boundary_bsmpm_lumped"),
                      "stress_rms,stress_rms_interior",
                      "vibrating bar, BSMPM (p=2) lumped: all vs interior particles")
    return render("boundary", "section", table="\n".join(t), s_all=o(s_all),
                  grows_text="grows" if grows else "does not grow", s_int=o(s_int), below=below,
                  min_v_int=e(min(v_int)), max_v_int=e(max(v_int)),
                  figures=fig_md(ctx, figs,
                                 "BSMPM lumped: all-particle against interior stress error"))
