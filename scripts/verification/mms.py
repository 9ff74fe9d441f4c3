"""MLS and IMLS (001, 003) on the 1D neo-Hookean manufactured solution, refined, with the
orders against 003 Figs. 5-6 (sec_mms). Prose: templates/mms.md; the MLS and IMLS of 2D are
prose only (static.py)."""
import os

from .common import (ORDER_TOL, col, e, fig_md, ls_order, o, pair_orders, pub, src, verdict_claim,
                     verdict_order)
from .plots import plot_study
from .template import render


def stopped_text(stopped):
    """A sentence on the runs of a table that stopped (exit code and cells), or nothing."""
    if not stopped:
        return ""
    runs = ", ".join(f"{h} at {int(r['cells'])} cells" for h, r in stopped)
    return render("mms", "stopped", runs=runs)


def sec_mms(R, ctx):
    """MLS and IMLS against the direct mapping on mms_1d (003 Figs. 5-6), refined."""
    methods = ["linear/direct", "cpdi/direct", "bspline2/direct", "linear/imls",
               "bspline2/imls", "linear/mls", "bspline2/mls"]
    heads = ["MPM", "CPDI", "BSMPM (p=2)", "MPM+IMLS", "BSMPM+IMLS", "MPM+MLS", "BSMPM+MLS"]
    out, rows = R.study("mms_1d", "grid.cells=8,16,32,64,128", ", ".join(methods), name="mms")
    _, small = R.study("mms_1d", "grid.cells=8,16,32,64,128", "linear/direct",
                       ["mms.amplitude=1e-4"], name="mms_small")
    t = ["| cells | " + " | ".join(heads) + " |", "|---" * (len(heads) + 1) + "|"]
    po = {m: pair_orders(col(rows[m], "h"), col(rows[m], "displacement_rms")) for m in methods}
    for i in range(5):
        cells = [f"{e(rows[m][i]['displacement_rms'])}"
                 + (f" ({o(po[m][i])})" if po[m][i] is not None else "")
                 + ("" if rows[m][i]["status"] == "ok" else " failed") for m in methods]
        t.append(f"| {int(rows[methods[0]][i]['cells'])} | " + " | ".join(cells) + " |")
    mpm_o = ls_order(col(rows["linear/direct"], "h"), col(rows["linear/direct"], "displacement_rms"))
    cp = po["cpdi/direct"]
    # Orders between runs that finished (a run stopped by method.conservation_limit has none).
    im = [x for x in po["linear/imls"][1:] if x is not None]
    stopped = [(h, rows[m][i]) for m, h in zip(methods, heads) for i in range(5)
               if rows[m][i]["status"] != "ok"]
    small_o = ls_order(col(list(small.values())[0], "h"),
                       col(list(small.values())[0], "displacement_rms"))
    v_mpm = verdict_claim(mpm_o is None or mpm_o < 0.5, f"order {o(mpm_o)}")
    v_cp1 = verdict_order(cp[1], "mms_cpdi_order")
    v_cp2 = verdict_claim(cp[-1] is not None and cp[-1] < cp[1] - 0.5,
                          f"last order {o(cp[-1])} against first {o(cp[1])}")
    v_im = verdict_claim(all(x is not None and x >= pub("mms_imls_order") - ORDER_TOL for x in im),
                         "orders " + ", ".join(o(x) for x in im))
    bs_stall = po["bspline2/direct"][-1]
    mls_keep = [po[m][-1] for m in ("linear/mls", "bspline2/mls")]
    figs = plot_study(out, os.path.join(ctx["figdir"], "mms_1d"), "displacement_rms",
                      "mms_1d (003), A = 0.1 m", energy=False)
    return render("mms", "section", methods_list=', '.join(methods), table="\n".join(t),
                  mpm_o=o(mpm_o), v_mpm=v_mpm, mms_cpdi_order_src=src('mms_cpdi_order'),
                  cp_first=o(cp[1]), v_cp1=v_cp1, cp_orders=", ".join(o(x) for x in cp[1:]),
                  v_cp2=v_cp2, mms_imls_order_src=src('mms_imls_order'),
                  imls_threshold=pub('mms_imls_order') - ORDER_TOL,
                  im_orders=", ".join(o(x) for x in im), v_im=v_im,
                  stopped_note=stopped_text(stopped),
                  bspline_orders=", ".join(o(x) for x in po["bspline2/direct"][1:]),
                  bs_stall=o(bs_stall), mls_p1_last=o(mls_keep[0]), mls_b2_last=o(mls_keep[1]),
                  small_o=o(small_o), figures=fig_md(ctx, figs, "mms_1d convergence"))
