"""The vertical cut in Tresca clay against limit analysis (sec_vertical_cut):
examples/vertical_cut_2d.toml at several stability numbers gamma H / c_u and cell sizes, the
cut's displacement and kinetic energy once gravity is on. Prose: templates/vertical_cut.md."""
import csv
import glob
import os

from .common import fig_md
from .plots import pyplot, save_figure
from .template import render

H = 5.0              # [m] the cut's height
GAMMA = 20e3         # [N/m^3] unit weight rho g of the example
# gamma H_c / c_u of a vertical cut in Tresca soil: the static (lower) bound of Kammoun et al.
# (2010, IJNAMG 34) and the best kinematic (upper) bound they compare it with.
LOWER, UPPER = 3.7752, 3.7776
NUMBERS = (3.6, 3.8, 4.0, 4.2, 4.4, 5.0)
CELLS = (20, 40, 80)  # h = 1, 0.5, 0.25 m over the 20 m grid
END = 3.0             # [s] gravity is ramped to full over the first second, then held
FALLEN = 0.02         # a cut has fallen when its face has moved more than this fraction of H


def final_state(r):
    """(largest horizontal displacement at the end [m], largest kinetic energy [J/m]), or None
    when the run stopped."""
    if r.get("status") != "ok":
        return None
    frames = sorted(glob.glob(os.path.join(r["_dir"], "particles_*.csv")))
    with open(frames[-1], newline="") as f:
        u = max(abs(float(x["u_1"])) for x in csv.DictReader(f))
    with open(os.path.join(r["_dir"], "history.csv"), newline="") as f:
        ke = max(float(x["kinetic_energy"]) for x in csv.DictReader(f))
    return u, ke


def sec_vertical_cut(R, ctx):
    specs, keys = [], []
    for n in CELLS:
        for N in NUMBERS:
            keys.append((n, N))
            specs.append(("vertical_cut_2d",
                          [f"grid.cells={n}", f"time.dt={2e-4 * 40 / n:g}", f"time.end={END:g}",
                           f"material.cohesion={GAMMA * H / N:.10g}"], 1,
                          f"vertical_cut_{n}_{N:g}"))
    res = {k: final_state(r) for k, r in zip(keys, R.many(specs))}

    def cell(k):
        s = res[k]
        return "stopped" if s is None else f"{100 * s[0] / H:.2f} % ({s[1]:.3g} J/m)"
    t = ["| gamma H / c_u | " + " | ".join(f"h = {20 / n:g} m" for n in CELLS) + " |",
         "|---|" + "---|" * len(CELLS)]
    for N in NUMBERS:
        t.append(f"| {N:g} | " + " | ".join(cell((n, N)) for n in CELLS) + " |")
    # Per cell size: the largest number that stands below the smallest that falls.
    brackets, rows = {}, []
    for n in CELLS:
        stands = [N for N in NUMBERS if res[(n, N)] and res[(n, N)][0] < FALLEN * H]
        falls = [N for N in NUMBERS if res[(n, N)] and res[(n, N)][0] >= FALLEN * H]
        lo, hi = (max(stands) if stands else None), (min(falls) if falls else None)
        brackets[n] = (lo, hi)
        consistent = lo is not None and hi is not None and lo < hi and \
            all(N <= lo for N in stands) and all(N >= hi for N in falls)
        rows.append(f"| {20 / n:g} m | {lo if lo is not None else '-'} | "
                    f"{hi if hi is not None else '-'} | "
                    f"{'' if consistent else 'not monotone in gamma H / c_u'} |")
    t2 = ["| h | stands at gamma H / c_u up to | falls from | |", "|---|---|---|---|"] + rows

    figs = []
    plt = pyplot()
    if plt is not None:
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        for n, style in zip(CELLS, ("o:", "s--", "^-")):
            pts = [(N, 100 * res[(n, N)][0] / H) for N in NUMBERS if res[(n, N)]]
            ax.semilogy([p[0] for p in pts], [p[1] for p in pts], style, lw=1.2,
                        label=f"h = {20 / n:g} m (H / h = {H * n / 20:g})")
        ax.axvspan(LOWER, UPPER, color="grey", alpha=0.5, label="limit analysis, 3.775-3.778")
        ax.axhline(100 * FALLEN, color="k", lw=0.8, ls=":", label=f"{100 * FALLEN:g} % of H")
        ax.set_xlabel("gamma H / c_u")
        ax.set_ylabel(f"largest horizontal displacement at t = {END:g} s / H [%]")
        ax.set_title("vertical cut in Tresca clay (B-splines, degree 2, MUSL)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        figs = save_figure(plt, fig, ctx, "vertical_cut_displacement")

    lo, hi = brackets[CELLS[-1]]
    h = 20 / CELLS[-1]
    if lo is None or hi is None:
        text = render("vertical_cut", "unread", h=h)
    else:
        pct = dict(h=h, lo=lo, hi=hi, lo_pct=100 * (lo / UPPER - 1),
                   hi_pct=100 * (hi / LOWER - 1))
        if lo >= UPPER:
            read = [brackets[n] for n in CELLS if None not in brackets[n]]
            falling = all(b[0] <= a[0] and b[1] <= a[1] for a, b in zip(read, read[1:])) and \
                read[-1] != read[0]
            text = render("vertical_cut", "above", **pct,
                          brackets=", ".join(f"[{brackets[n][0]:g}, {brackets[n][1]:g}] at h = "
                                             f"{20 / n:g} m" for n in CELLS
                                             if None not in brackets[n]),
                          trend="they come down as h falls" if falling else
                          "they do not come down as h falls")
        elif hi <= LOWER:
            text = render("vertical_cut", "below", **pct)
        else:
            text = render("vertical_cut", "contains", **pct)
    return render("vertical_cut", "section", table="\n".join(t), t2="\n".join(t2), text=text,
                  end=END, fallen=100 * FALLEN,
                  figures=fig_md(ctx, figs, "vertical cut: displacement against gamma H / c_u"))
