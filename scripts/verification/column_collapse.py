"""The collapse of a granular column against the quasi-2D experiments of Lube et al. (2005)
(sec_column_collapse): examples/column_collapse_2d.toml at aspect ratios a = H0 / L0 from 0.5
to 8, the run-out and the final height against the experiments' fits, the deposits' profiles, the
run-out under grid refinement and with more particles and a stiffer material, and the schemes and
bases at a = 2. Prose: templates/column_collapse.md."""
import csv
import glob
import math
import os

from .common import fail_time, fig_md
from .plots import pyplot, save_figure
from .template import render

L0 = 0.2          # [m] the column's length (the example's body.max x)
G = 9.81          # [m/s^2]
RHO = 1800.0      # [kg/m^3] the example's density
E = 2.0e6         # [Pa] the example's Young's modulus
ASPECTS = (0.5, 1.0, 2.0, 4.0, 8.0)
CELLS = 20        # cells across L0 (h = L0 / 20 = 0.01 m) of the aspect-ratio runs
REFINE = (10, 20, 40)   # cells across L0 at a = A_CHECK
A_CHECK = 2.0     # the aspect ratio of the refinement, particle, stiffness and method checks
# A deposit's front: the x below which FRONT of its mass lies (the particles' masses sorted by
# x), and its extent, the same at EXTENT. A front read where a thickness falls through a
# threshold jumps with the thin layer ahead of the deposit's body, whose particles spread out as a
# loose cloud (their det F grows at the cone's apex); the mass's quantiles do not.
FRONT = 0.99
EXTENT = 0.999
WORDS = {2: "two", 3: "three", 4: "four"}
T_END = 4.5       # the runs end at T_END sqrt(H0 / g), rounded up to 0.05 s; the deposits are at
                  # rest from about 3.5-4.2 sqrt(H0 / g)
METHODS = [("MUSL, B-splines degree 2 (the example's)", []),
           ("USL, B-splines degree 2", ["method.scheme=usl"]),
           ("USF, B-splines degree 2", ["method.scheme=usf"]),
           ("MUSL, linear", ["method.basis=linear"])]

# Lube, Huppert, Sparks and Freundt (2005, Phys. Rev. E 72, 041301), quasi-2D collapses in a
# channel (sand, rice, sugar, couscous, silt), as quoted by Lagree, Staron and Popinet (2011,
# J. Fluid Mech. 686, their eqs. 3.1-3.2): (L_inf - L0) / L0 = 1.2 a for a < 1.8 and
# 1.9 a^(2/3) for a > 2.8 (between them the two fits do not meet); H_inf / L0 = a for a < 1.15
# (the column's top survives) and a^(2/5) above.
LUBE_A1, LUBE_A2 = 1.8, 2.8
LUBE_H = 1.15


def lube_runout(a):
    """(low, high) of Lube et al.'s run-out fits at a: one value below 1.8 and above 2.8, the
    two fits' values between, where the experiments change regime."""
    lin, power = 1.2 * a, 1.9 * a ** (2.0 / 3.0)
    if a < LUBE_A1:
        return lin, lin
    if a > LUBE_A2:
        return power, power
    return min(lin, power), max(lin, power)


def lube_height(a):
    """Lube et al.'s final height at the back wall, H_inf / L0."""
    return a if a < LUBE_H else a ** 0.4


def end_time(a):
    """[s] T_END sqrt(H0 / g) rounded up to 0.05 s."""
    return math.ceil(T_END * math.sqrt(a * L0 / G) / 0.05 - 1e-9) * 0.05


def sets(a, n, extra=()):
    """The overrides of a run at aspect ratio a on n cells across L0: the body, a grid long
    enough for three times Lube's run-out, the time step and the end."""
    h = L0 / n
    length = L0 * (2.0 + 3.0 * lube_runout(a)[1])
    cells = math.ceil(length / h - 1e-9)
    return [f"body.max=[{L0:g}, {a * L0:g}]", f"grid.max=[{cells * h:.10g}, {a * L0 + 2 * h:.10g}]",
            f"grid.cells={cells}", f"time.dt={1e-4 * CELLS / n:g}",
            f"time.end={end_time(a):.10g}"] + list(extra)


def frames(run_dir):
    """The particle frames of a run as [(x, y, mass, volume) lists], in time order."""
    out = []
    for path in sorted(glob.glob(os.path.join(run_dir, "particles_*.csv"))):
        with open(path, newline="") as f:
            out.append([(float(r["x_1"]), float(r["x_2"]), float(r["mass"]),
                         float(r["volume"])) for r in csv.DictReader(f)])
    return out


def surface(parts, h, spacing):
    """The deposit's height per cell column [k h, (k + 1) h): its highest particle's y plus half
    the particles' initial spacing (0 where the column is empty)."""
    n = int(max(p[0] for p in parts) / h) + 3
    top = [0.0] * n
    for x, y, _, _ in parts:
        k = int(x / h)
        top[k] = max(top[k], y + 0.5 * spacing)
    return top


def quantile(parts, q):
    """The x below which the fraction q of the particles' mass lies."""
    ps = sorted(parts)
    total, acc = sum(p[2] for p in ps), 0.0
    for x, _, m, _ in ps:
        acc += m
        if acc >= q * total:
            return x
    return ps[-1][0]


def measure(r, a, n, ppc=2):
    """{runout, extent, height, moved, ke, swell, loose, profile} of a run: the run-out
    (L_inf - L0) / L0 at the FRONT and at the EXTENT quantile, the height at the back wall
    H_inf / L0, the front's move over the last frame interval / h, the final kinetic energy / its
    peak, the deposit's volume / its initial volume (the particles' det F V0 over their m / rho0),
    the median det F of the particles beyond the front, the deposit's height per column / L0;
    None when the run stopped."""
    if r.get("status") != "ok":
        return None
    h = L0 / n
    fr = frames(r["_dir"])
    top = surface(fr[-1], h, h / ppc)
    x_front = quantile(fr[-1], FRONT)
    with open(os.path.join(r["_dir"], "history.csv"), newline="") as f:
        ke = [float(x["kinetic_energy"]) for x in csv.DictReader(f)]
    beyond = sorted(p[3] * RHO / p[2] for p in fr[-1] if p[0] > x_front)
    return {"runout": (x_front - L0) / L0, "extent": (quantile(fr[-1], EXTENT) - L0) / L0,
            "swell": sum(p[3] for p in fr[-1]) / sum(p[2] / RHO for p in fr[-1]),
            "loose": beyond[len(beyond) // 2] if beyond else 1.0,
            "height": top[0] / L0, "moved": abs(x_front - quantile(fr[-2], FRONT)) / h,
            "ke": ke[-1] / max(ke),
            "profile": [((k + 0.5) * h / L0, v / L0) for k, v in enumerate(top)]}


def fnum(x, d=2):
    return "-" if x is None else f"{x:.{d}f}"


def pct(m, ref):
    return f"{100 * (m / ref - 1):+.0f} %"


def sec_column_collapse(R, ctx):
    specs, keys = [], []

    def add(key, a, n, extra=(), name=None):
        keys.append(key)
        specs.append(("column_collapse_2d", sets(a, n, extra), 8, name or f"column_{key}"))
    # The longest runs first, so that the two workers end together.
    add(("a", ASPECTS[-1]), ASPECTS[-1], CELLS, name=f"column_a{ASPECTS[-1]:g}")
    add(("n", REFINE[-1]), A_CHECK, REFINE[-1], name=f"column_n{REFINE[-1]}")
    for a in ASPECTS[:-1]:
        add(("a", a), a, CELLS, name=f"column_a{a:g}")
    add("stiff", A_CHECK, CELLS, [f"material.youngs_modulus={2 * E:g}", f"time.dt={0.5e-4:g}"])
    add("ppc3", A_CHECK, CELLS, ["particles.per_cell=3"])
    for label, extra in METHODS[1:]:
        add(("m", label), A_CHECK, CELLS, extra, name="column_" + label.split(",")[0])
    add(("n", REFINE[0]), A_CHECK, REFINE[0], name=f"column_n{REFINE[0]}")
    res, why_failed = {}, {}
    for key, r in zip(keys, R.many(specs)):
        n = key[1] if key[0] == "n" else CELLS
        a = key[1] if key[0] == "a" else A_CHECK
        res[key] = measure(r, a, n, 3 if key == "ppc3" else 2)
        if res[key] is None:
            msg = r.get("failure") or "no summary"
            why_failed[key] = f"stopped at t = {fail_time(msg)} s: " + msg.split(": ", 1)[-1]
    for alias in (("n", CELLS), ("m", METHODS[0][0])):
        res[alias] = res[("a", A_CHECK)]
        if ("a", A_CHECK) in why_failed:
            why_failed[alias] = why_failed[("a", A_CHECK)]
    lo2, hi2 = lube_runout(A_CHECK)

    def cells(key, fields):
        m = res[key]
        if m is None:
            return why_failed[key] + " |" * (len(fields) - 1)
        return " | ".join(fnum(m[f]) for f in fields)

    # (a) Run-out and final height per aspect ratio against Lube et al.
    rows = ["| a = H0 / L0 | (L_inf - L0) / L0 | Lube et al. | mpmlab / Lube | extent (99.9 %) "
            "| H_inf / L0 | Lube et al. | mpmlab / Lube | front's last move / h | "
            "final / peak kinetic energy | volume / initial: deposit, beyond the front |",
            "|---" * 11 + "|"]
    over, hdev = [], []
    for a in ASPECTS:
        m = res[("a", a)]
        lo, hi = lube_runout(a)
        law = f"{lo:.2f}" if lo == hi else f"{lo:.2f}-{hi:.2f}"
        if m is None:
            rows.append(f"| {a:g} | {why_failed[('a', a)]} | {law} | | | | {lube_height(a):.2f} "
                        "| | | | |")
            continue
        ratio = f"{m['runout'] / hi:.2f}" if lo == hi else \
            f"{m['runout'] / hi:.2f}-{m['runout'] / lo:.2f}"
        over.append((a, m["runout"] / hi))
        hdev.append((a, m["height"] / lube_height(a)))
        rows.append(f"| {a:g} | {m['runout']:.2f} | {law} | {ratio} | {m['extent']:.2f} | "
                    f"{m['height']:.2f} | {lube_height(a):.2f} | "
                    f"{m['height'] / lube_height(a):.2f} | {m['moved']:.2f} | {m['ke']:.1e} | "
                    f"{m['swell']:.2f}, {m['loose']:.1f} |")

    # (c) Refinement, particles, stiffness at a = A_CHECK.
    conv = [(n, res[("n", n)]) for n in REFINE]
    rows_c = [f"| run at a = {A_CHECK:g} | (L_inf - L0) / L0 | extent (99.9 %) | H_inf / L0 |",
              "|---|---|---|---|"]
    fields = ("runout", "extent", "height")
    for n, m in conv:
        rows_c.append(f"| h = L0 / {n}, 2 x 2 particles per cell | {cells(('n', n), fields)} |")
    for key, label in (("ppc3", f"h = L0 / {CELLS}, 3 x 3 particles per cell"),
                       ("stiff", f"h = L0 / {CELLS}, E = {2 * E / 1e6:g} MPa (twice)")):
        rows_c.append(f"| {label} | {cells(key, fields)} |")
    ok = [m for _, m in conv if m]
    if len(ok) == len(REFINE):
        body = [m["runout"] for m in ok]
        thin = [m["extent"] for m in ok]
        spread = max(body) - min(body)
        steps = [b - a for a, b in zip(body, body[1:])]
        agree = (f"the {WORDS.get(len(body), len(body))} grids agree within {spread:.2f} "
                 f"({100 * spread / body[-1]:.0f} % of the finest)") \
            if spread <= 0.1 * body[-1] else \
            ("it still changes by " + ", ".join(f"{d:+.2f}" for d in steps) + " per halving of h")
        gap = body[-1] - hi2
        trend = (f"From the coarsest to the finest grid it changes by {body[-1] - body[0]:+.2f}, "
                 f"against a distance of {gap:.2f} from the finest to the experiments' upper fit."
                 if gap > 0 else "On the finest grid it lies within the experiments' range.")
        conv_text = render("column_collapse", "refined", body=", ".join(f"{v:.2f}" for v in body),
                           thin=", ".join(f"{v:.2f}" for v in thin), agree=agree, trend=trend,
                           hs=", ".join(f"L0 / {n}" for n in REFINE), hi=hi2, a=A_CHECK,
                           over=pct(body[-1], hi2),
                           thin_trend="grows" if thin[0] < thin[1] < thin[2] else
                           "does not grow monotonically")
    else:
        conv_text = render("column_collapse", "unread")
    base = res[("a", A_CHECK)]
    checks = []
    for key, what in (("ppc3", "3 x 3 particles per cell move the run-out"),
                      ("stiff", "twice the stiffness moves it")):
        m = res[key]
        if m and base:
            checks.append(f"{what} by {m['runout'] - base['runout']:+.2f} "
                          f"({100 * (m['runout'] / base['runout'] - 1):+.1f} %)")
    check_text = " and ".join(checks) if checks else "the checks did not run"

    # (d) Schemes and bases at a = A_CHECK.
    rows_m = ["| scheme, basis | (L_inf - L0) / L0 | extent (99.9 %) | H_inf / L0 |",
              "|---|---|---|---|"]
    meth = []
    for label, _ in METHODS:
        m = res[("m", label)]
        rows_m.append(f"| {label} | {cells(('m', label), fields)} |")
        if m:
            meth.append((abs(m["runout"] - hi2), label, m["runout"]))
    meth.sort()
    if meth:
        meth_text = render("column_collapse", "methods", best=meth[0][1],
                           best_runout=meth[0][2], worst=meth[-1][1], worst_runout=meth[-1][2],
                           law=f"{lo2:.2f}" if lo2 == hi2 else f"{lo2:.2f}-{hi2:.2f}", a=A_CHECK,
                           all_above="every scheme and basis tried runs out further than the "
                           "experiments" if all(v > hi2 for _, _, v in meth) else
                           "not every scheme and basis runs out further than the experiments")
    else:
        meth_text = render("column_collapse", "unread")
    # Every run at a = A_CHECK that finished: refinement, particles, stiffness, schemes, bases.
    variants = [("n", n) for n in REFINE] + ["ppc3", "stiff"] + [("m", l) for l, _ in METHODS[1:]]
    done = [res[k]["runout"] for k in variants if res[k]]
    stopped = [k for k in variants if res[k] is None]
    names = {"ppc3": "3 x 3 particles per cell", "stiff": "twice the stiffness"}

    def name(k):
        return names[k] if k in names else f"h = L0 / {k[1]}" if k[0] == "n" else k[1]
    stop_note = "" if not stopped else render(
        "column_collapse", "stopped",
        runs="; ".join(f"{name(k)} ({why_failed[k]})" for k in stopped))
    if done and min(done) > hi2:
        why = render("column_collapse", "why_persists", n=len(done), vmin=min(done),
                     vmax=max(done), hi=hi2, a=A_CHECK, stop_note=stop_note)
    else:
        why = render("column_collapse", "why_mixed", n=len(done), hi=hi2, a=A_CHECK,
                     vmin=min(done, default=float("nan")), vmax=max(done, default=float("nan")),
                     stop_note=stop_note)

    # Figures.
    figs = []
    plt = pyplot()
    if plt is not None:
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10.0, 4.3))
        grid_a = [0.3 + 0.01 * k for k in range(900)]
        for lo_a, hi_a, style in ((0.3, LUBE_A1, "k-"), (LUBE_A2, 9.5, "k-")):
            xs = [x for x in grid_a if lo_a <= x <= hi_a]
            ax1.loglog(xs, [lube_runout(x)[0] for x in xs], style, lw=1.2)
        xs = [x for x in grid_a if LUBE_A1 <= x <= LUBE_A2]
        ax1.fill_between(xs, [lube_runout(x)[0] for x in xs], [lube_runout(x)[1] for x in xs],
                         color="grey", alpha=0.4, lw=0,
                         label="Lube et al. 2005: 1.2 a, 1.9 a^(2/3) (between: both fits)")
        ax1.plot([], [], "k-", label="Lube et al. 2005 fits")
        pts = [(a, res[("a", a)]) for a in ASPECTS if res[("a", a)]]
        ax1.loglog([a for a, _ in pts], [m["runout"] for _, m in pts], "o", color="C3",
                   label=f"mpmlab, h = L0 / {CELLS} (MUSL, B2)")
        ax1.loglog([a for a, _ in pts], [m["extent"] for _, m in pts], "o", color="C3", mfc="none",
                   label="mpmlab, the extent (99.9 % of the mass)")
        for n, mk in zip(REFINE, ("v", None, "^")):
            if mk and res[("n", n)]:
                ax1.loglog([A_CHECK], [res[("n", n)]["runout"]], mk, color="C0", ms=5,
                           label=f"h = L0 / {n}")
        ax1.set_xlabel("a = H0 / L0")
        ax1.set_ylabel("(L_inf - L0) / L0")
        ax1.grid(True, which="both", alpha=0.3)
        ax1.legend(fontsize=7)
        xs1 = [x for x in grid_a if x < LUBE_H]
        xs2 = [x for x in grid_a if x >= LUBE_H]
        ax2.loglog(xs1, [lube_height(x) for x in xs1], "k-", lw=1.2,
                   label="Lube et al. 2005: a, a^(2/5)")
        ax2.loglog(xs2, [lube_height(x) for x in xs2], "k-", lw=1.2)
        ax2.loglog([a for a, _ in pts], [m["height"] for _, m in pts], "o", color="C3",
                   label="mpmlab")
        ax2.set_xlabel("a = H0 / L0")
        ax2.set_ylabel("H_inf / L0 (at the back wall)")
        ax2.grid(True, which="both", alpha=0.3)
        ax2.legend(fontsize=7)
        fig.suptitle("granular column collapse, plane strain: mpmlab against Lube et al. (2005)")
        fig.tight_layout()
        figs += save_figure(plt, fig, ctx, "column_collapse_runout")

        fig, ax = plt.subplots(figsize=(9.0, 4.0))
        for k, a in enumerate(ASPECTS):
            m = res[("a", a)]
            if not m:
                continue
            ax.plot([p[0] for p in m["profile"]], [p[1] for p in m["profile"]], "-",
                    color=f"C{k}", lw=1.2, label=f"a = {a:g}")
            lo_a, hi_a = lube_runout(a)
            ax.axvspan(1 + lo_a - 0.02, 1 + hi_a + 0.02, color=f"C{k}", alpha=0.35, lw=0)
        ax.set_xlabel("x / L0")
        ax.set_ylabel("deposit's height / L0")
        ax.set_title("final deposits (h = L0 / 20); the bars: Lube et al.'s fronts 1 + "
                     "(L_inf - L0) / L0", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        figs += save_figure(plt, fig, ctx, "column_collapse_profiles")

    # Verdict: the ratio to Lube's fits, below and above the regime change.
    low = [(a, r) for a, r in over if a < LUBE_A1]
    high = [(a, r) for a, r in over if a >= LUBE_A1]
    verdict = render("column_collapse", "verdict",
                     low=", ".join(f"{r:.2f}" for _, r in low) or "-",
                     low_a=", ".join(f"{a:g}" for a, _ in low) or "-",
                     high=", ".join(f"{r:.2f}" for _, r in high) or "-",
                     high_a=", ".join(f"{a:g}" for a, _ in high) or "-",
                     hmin=min((r for _, r in hdev), default=float("nan")),
                     hmax=max((r for _, r in hdev), default=float("nan")),
                     kemin=min((res[("a", a)]["ke"] for a in ASPECTS if res[("a", a)]),
                               default=float("nan")),
                     kemax=max((res[("a", a)]["ke"] for a in ASPECTS if res[("a", a)]),
                               default=float("nan")),
                     moved=max((res[("a", a)]["moved"] for a in ASPECTS if res[("a", a)]),
                               default=float("nan")),
                     swell=", ".join(f"{res[('a', a)]['swell']:.2f}" for a in ASPECTS
                                     if res[("a", a)]),
                     loose=", ".join(f"{res[('a', a)]['loose']:.1f}" for a in ASPECTS
                                     if res[("a", a)]),
                     swell_a=", ".join(f"{a:g}" for a in ASPECTS if res[("a", a)]))
    block = "low_over" if any(r > 1.1 for _, r in low) else \
        "low_within" if all(0.9 <= r <= 1.1 for _, r in low) else "low_under"
    low_note = render("column_collapse", block, low=", ".join(f"{r:.2f}" for _, r in low) or "-",
                      low_a=", ".join(f"{a:g}" for a, _ in low) or "-")
    return render("column_collapse", "section", low_note=low_note, table="\n".join(rows),
                  table_c="\n".join(rows_c), table_m="\n".join(rows_m), conv=conv_text,
                  checks=check_text, methods=meth_text, verdict=verdict, why=why, cells=CELLS,
                  t_end=T_END, front=100 * FRONT, extent=100 * EXTENT, a_check=A_CHECK,
                  figures=fig_md(ctx, figs, "granular column collapse"))
