"""Accuracy per unit of cost (D 7.3): work-precision diagrams from `mpm study --work-precision`
on the 1D bar, the 2D plate and vortex and the 3D cube. Each method is refined with the time step
following the cell size (dt = CFL h / c, the same for every method); every run is timed alone,
the methods alternated in each round, the minimum of the rounds kept. Per problem and target
error: the cheapest method and the others' cost relative to it, and D 7.3's question (higher-order
BSMPM with the cubic-spline or TLS reconstruction against DDMPM). Prose:
templates/work_precision.md."""
import csv
import math
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor

from .common import EX, e, fig_md
from .plots import pyplot, save_figure
from .template import render

CFL = 0.1  # dt = CFL h / c: below every basis's lumped-mass limit (B-splines of degree 3: 0.33)
REPEATS = 2


def wave_speed(E, nu, rho, dim):
    """The P-wave speed [m/s] (1D: the bar's sqrt(E / rho))."""
    if dim == 1:
        return math.sqrt(E / rho)
    return math.sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho)


def matrix(bases, mappings, masses):
    return [f"{b}/{m}/{s}" for b in bases for m in mappings for s in masses]


BASES_1D = ["linear", "ugimp", "cpgimp", "cpdi", "ddmpm", "bspline2", "bspline3", "maxent"]
MAPPINGS = ["direct", "cubic_spline", "tls", "mls", "imls"]
MASSES = ["lumped", "consistent"]
# 2D and 3D: every basis with the direct mapping and both masses, and the reconstructions on the
# bases they are published with (P1, DDMPM and B-splines: D ch. 5-6; 001, 003).
BASES_2D = ["linear", "ugimp", "cpgimp", "cpdi", "cpdi2", "ddmpm", "bspline2", "bspline3",
            "maxent", "p1_triangles", "powell_sabin"]
RECON_2D = matrix(["linear", "ddmpm", "bspline2", "bspline3"], ["tls", "mls", "imls"],
                  ["lumped"]) + matrix(["linear", "ddmpm"], ["tls"], ["consistent"])
VORTEX = (matrix(["linear", "cpdi", "ddmpm", "bspline2", "bspline3", "maxent"], ["direct"],
                 ["lumped"]) + matrix(["bspline2"], ["direct"], ["consistent"])
          + matrix(["linear", "bspline2"], ["tls", "mls"], ["lumped"]))
# The cube without MLS and IMLS: in 3D their Gauss-point fits cost about 100 times the direct
# mapping's step (332 s against 2.7 s for B2 at 12 cells, one thread), beyond this report's time.
CUBE = (matrix(["linear", "ugimp", "cpdi", "ddmpm", "bspline2", "bspline3"], ["direct"],
               ["lumped"]) + matrix(["bspline2"], ["direct"], ["consistent"])
        + matrix(["linear", "bspline2"], ["tls"], ["lumped"]))
THREADS_2 = ["linear/direct/lumped", "ddmpm/direct/lumped", "bspline2/direct/lumped",
             "bspline3/direct/lumped", "bspline2/tls/lumped", "bspline3/tls/lumped"]

# (key, title, example, end, cells, (E, nu, rho, dim, length, cfl), error, methods, threads):
# dt = end / ceil(end c cells / (cfl length)), the largest step below cfl h / c that divides the
# end time. The end times are where the exact stress is largest (|sin(omega t)| = 1 for the bar,
# the plate and the cube; the vortex's largest turn, g(0.5 s) = A), so that the relative error
# is not a phase error divided by a passing zero. The vortex keeps its example's ratio (dt =
# 1e-3 s at 32 cells across 3 m: cfl 0.0125), the step its manufactured solution was set up
# with.
PROBLEMS = [
    ("bar", "1D vibrating bar, small deformation (D 5.4.1), T = 0.02535 s (3/4 period)",
     "vibrating_bar_small", 0.02535, [8, 16, 32, 64, 128],
     (7.0e6, 0.0, 2000.0, 1, 1.0, CFL), "stress_rel_l2", matrix(BASES_1D, MAPPINGS, MASSES),
     (1,)),
    ("plate", "2D plate, neo-Hookean manufactured solution (001; A = 0.1 m), T = 0.015 s",
     "plate_mms_2d", 0.015, [4, 8, 16, 32], (1e7, 0.3, 1000.0, 2, 1.0, CFL), "stress_rel_l2",
     matrix(BASES_2D, ["direct"], MASSES) + RECON_2D, (1, 2)),
    ("vortex", "2D generalized vortex (A = 1 rad), T = 0.5 s (the largest turn)", "vortex_2d",
     0.5, [16, 32, 64], (1000.0, 0.3, 1000.0, 2, 3.0, 0.0125), "stress_rel_l2", VORTEX, (1,)),
    ("cube", "3D cube, neo-Hookean manufactured solution (A = 0.05 m), T = 0.015 s",
     "cube_mms_3d", 0.015, [3, 6, 12], (1e7, 0.3, 1000.0, 3, 1.0, CFL), "stress_rel_l2", CUBE,
     (1, 2)),
]


def dts(cells, material, end):
    E, nu, rho, dim, length, cfl = material
    c = wave_speed(E, nu, rho, dim)
    return [repr(end / math.ceil(end * c * n / (cfl * length))) for n in cells]


def accepted(R, example, sets, cells, dt, methods):
    """The methods set-up accepts, and those it refuses (exit code 2), from one step of each at
    the coarsest resolution."""
    def probe(m):
        out = R._dir("wp_probe")
        p = subprocess.run([R.mpm, "study", os.path.join(EX, example + ".toml"), "--refine",
                            f"grid.cells={cells}", "--methods", m, "--out", out, "-j", "1",
                            "--set", f"time.dt={dt}", "--set", f"time.end={dt}",
                            "--set", "output.frames=0", "--set", "output.vtk=false"]
                           + [a for s in sets if not s.startswith("time.end=")
                              for a in ("--set", s)],
                           capture_output=True, text=True, env=R.env)
        return p.returncode != 2
    with ThreadPoolExecutor(max_workers=R.jobs) as ex:
        ok = list(ex.map(probe, methods))
    return ([m for m, k in zip(methods, ok) if k], [m for m, k in zip(methods, ok) if not k])


def work_precision(R, example, sets, cells, dt, methods, error, threads):
    """`mpm study --work-precision`; returns {method: [row dicts, coarse to fine]}."""
    out = R._dir(f"wp_{example}_{threads}")
    cmd = [R.mpm, "study", os.path.join(EX, example + ".toml"),
           "--refine", "grid.cells=" + ",".join(str(c) for c in cells),
           "--refine", "time.dt=" + ",".join(dt), "--methods", ", ".join(methods),
           "--work-precision", "--error", error, "--repeats", str(REPEATS),
           "--threads", str(threads), "--out", out] + [a for s in sets for a in ("--set", s)]
    p = subprocess.run(cmd, capture_output=True, text=True, env=R.env)
    path = os.path.join(out, "work_precision.csv")
    if not os.path.exists(path):
        raise RuntimeError(f"mpm study --work-precision failed: {p.stderr.strip()[-400:]}")
    rows = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            rows.setdefault(r["method"], []).append(r)
    return rows


def err_of(r, error):
    return float(r[error]) if r["status"] == "ok" and r[error] else None


def cheapest(rows, error, target):
    """{method: (wall, particle-steps, cells)} of the run where each method reaches target: its
    coarsest refinement from which on every run's error is at or below it (mpm's rule)."""
    best = {}
    for m, rs in rows.items():
        first = None
        for r in reversed(rs):
            if not (err_of(r, error) or math.inf) <= target:
                break
            first = r
        if first is not None:
            best[m] = (float(first["wall_seconds_min"]), float(first["particle_steps"]),
                       first["grid.cells"])
    return best


def targets_for(rows, error):
    """Targets on the 1-2-5 series between the third smallest error reached (so that at least
    three methods reach every target) and the median error of the coarsest runs; the smallest
    three, where the methods part."""
    finest = sorted(min(x for x in (err_of(r, error) for r in rs) if x is not None)
                    for rs in rows.values() if any(err_of(r, error) for r in rs))
    coarsest = sorted(err_of(rs[0], error) for rs in rows.values() if err_of(rs[0], error))
    if len(finest) < 3 or not coarsest:
        return []
    lo, hi = finest[2], coarsest[len(coarsest) // 2]
    ts = [m * 10.0 ** k for k in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)
          for m in (1, 2, 5) if lo <= m * 10.0 ** k <= hi]
    return sorted(ts)[:3][::-1]


def plot(ctx, name, title, rows, error, highlight):
    plt = pyplot()
    if plt is None:
        return []
    fig, axes = plt.subplots(1, 2, figsize=(12.5, 5.2), sharey=True)
    markers = "os^vD<>ph*"
    for m, rs in rows.items():
        pts = sorted((float(r["wall_seconds_min"]), float(r["particle_steps"]), err_of(r, error))
                     for r in rs if err_of(r, error))
        if not pts:
            continue
        if m in highlight:
            i = highlight.index(m)
            style = dict(marker=markers[i % len(markers)], ms=4, lw=1.4, label=m, zorder=3)
        else:
            style = dict(color="0.8", lw=0.7, zorder=1)
        axes[0].loglog([p[0] for p in pts], [p[2] for p in pts], **style)
        axes[1].loglog([p[1] for p in pts], [p[2] for p in pts], **style)
    axes[0].set_xlabel("wall time [s], one thread (minimum of the alternated rounds)")
    axes[1].set_xlabel("particle-steps")
    axes[0].set_ylabel(error)
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=7, loc="best")
    fig.suptitle(title + " (grey: the other methods)", fontsize=10)
    fig.tight_layout()
    return save_figure(plt, fig, ctx, name)


def summary_rows(rows, error, targets, threads):
    """One table row per target: cheapest, runner-up, P1, best B-spline reconstruction, DDMPM."""
    out, answers = [], []
    for t in targets:
        best = cheapest(rows, error, t)
        if not best:
            out.append(f"| {t:g} | {threads} | none reached | | | | |")
            continue
        order = sorted(best.items(), key=lambda kv: kv[1][0])
        (m0, (w0, ps0, c0)) = order[0]

        def rel(pred):
            cand = [(m, v) for m, v in order if pred(m)]
            if not cand:
                return "not reached", None
            m, v = cand[0]
            return f"{m} {v[0] / w0:.3g}x", v[0]
        second = f"{order[1][0]} {order[1][1][0] / w0:.3g}x" if len(order) > 1 else "-"
        p1, _ = rel(lambda m: m.startswith("linear/direct"))
        bs_txt, bs = rel(lambda m: m.startswith("bspline") and
                         m.split("/")[1] in ("cubic_spline", "tls"))
        dd_txt, dd = rel(lambda m: m.startswith("ddmpm"))
        out.append(f"| {t:g} | {threads} | {m0} ({c0} cells, {w0:.3g} s, {ps0:.3g} "
                   f"particle-steps) | {second} | {p1} | {bs_txt} | {dd_txt} |")
        if bs is not None or dd is not None:
            answers.append((t, bs, dd))
    return out, answers


def sec_work_precision(R, ctx):
    """The work-precision diagrams and the cheapest method per problem and target."""
    blocks, counts, d73 = [], [], []
    for key, title, example, end, cells, material, error, methods, threads in PROBLEMS:
        sets = [f"time.end={end}"]
        dt = dts(cells, material, end)
        ok, refused = accepted(R, example, sets, cells[0], dt[0], methods)
        counts.append(f"{title}: {len(ok)} methods"
                      + (f" ({len(refused)} refused by set-up: {', '.join(refused)})"
                         if refused else ""))
        rows_by_threads = {}
        for th in threads:
            ms = ok if th == 1 else [m for m in THREADS_2 if m in ok]
            rows_by_threads[th] = work_precision(R, example, sets, cells, dt, ms, error, th)
        rows = rows_by_threads[1]
        targets = targets_for(rows, error)
        table = []
        highlight = []
        for th, rs in rows_by_threads.items():
            lines, answers = summary_rows(rs, error, targets, th)
            table += lines
            if th == 1:
                d73 += [(title, t, bs, dd) for t, bs, dd in answers]
        for t in targets:
            for m, _ in sorted(cheapest(rows, error, t).items(), key=lambda kv: kv[1][0])[:3]:
                if m not in highlight:
                    highlight.append(m)
        for m in ("linear/direct/lumped", "ddmpm/direct/lumped", "bspline2/direct/lumped"):
            if m in rows and m not in highlight:
                highlight.append(m)
        figs = plot(ctx, f"work_precision_{key}", title, rows, error, highlight[:9])
        failed = sorted({m for m, rs in rows.items() for r in rs if r["status"] != "ok"})
        blocks.append(render(
            "work_precision", "problem", title=title, example=example,
            cells=", ".join(str(c) for c in cells),
            dt=", ".join(f"{float(x):.4g}" for x in dt), error=error,
            table="\n".join(table),
            failed=", ".join(failed) if failed else "none",
            figures=fig_md(ctx, figs, f"work-precision, {title}")))
    d73_rows = []
    for title, t, bs, dd in d73:
        if bs is None and dd is None:
            continue
        verdict = ("B-spline with CS/TLS cheaper" if bs is not None and (dd is None or bs < dd)
                   else "DDMPM cheaper" if dd is not None else "-")
        ratio = (f"{dd / bs:.3g}" if bs is not None and dd is not None else
                 "DDMPM did not reach it" if bs is not None else "the B-splines with CS/TLS "
                 "did not reach it")
        d73_rows.append(f"| {title} | {t:g} | {e(bs)} | {e(dd)} | {ratio} | {verdict} |")
    ctx.update(work_precision=d73)
    return render("work_precision", "section", problems="\n".join(blocks),
                  counts="\n".join(f"- {c}" for c in counts), cfl=CFL, repeats=REPEATS,
                  d73_rows="\n".join(d73_rows))
