"""The report's figures: plot_study (scripts/plot_study.py on a study) and the plots made here
with matplotlib (stress profiles, convergence, energy and conservation over time, the plate's
row and line profiles), written as figures/NAME.png and .svg without a date, so that a rerun
writes the same files. Without matplotlib they return no figures."""
import csv
import os
import subprocess
import sys

from .common import ROOT, SCRIPTS, last_frame


def plot_study(out, figdir, errors, title, energy=True):
    """Convergence, stress-profile and conservation plots of a study (scripts/plot_study.py).
    energy=False drops the energy-over-time plot (a body force doing work: not conserved)."""
    cmd = ["/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable,
           os.path.join(SCRIPTS, "plot_study.py"), os.path.join(out, "study.csv"),
           "--errors", errors, "--out", figdir, "--title", title]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        print(p.stderr, file=sys.stderr)
    paths = p.stdout.split()
    if not energy:
        for x in [x for x in paths if os.path.basename(x).startswith("conservation.")]:
            os.remove(x)
            paths.remove(x)
    return [os.path.relpath(x, ROOT) for x in paths]


def pyplot():
    """matplotlib.pyplot set up for reproducible figures, or None without matplotlib."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        plt.rcParams["svg.fonttype"] = "none"
        plt.rcParams["svg.hashsalt"] = "mpmlab"  # reproducible SVG ids
        return plt
    except ImportError:
        return None


def save_figure(plt, fig, ctx, name):
    """Writes figures/NAME.png and .svg (no date in the SVG); returns their paths."""
    paths = []
    os.makedirs(ctx["figdir"], exist_ok=True)
    for ext in ("png", "svg"):
        p = os.path.join(ctx["figdir"], f"{name}.{ext}")
        fig.savefig(p, dpi=120, metadata={"Date": None} if p.endswith(".svg") else None)
        paths.append(os.path.relpath(p, ROOT))
    plt.close(fig)
    return paths


def plot_profiles(ctx, name, runs, title, ylabel="stress [Pa]", xkey="x_1", key="stress_11"):
    """Final-time particle stress of several runs against the exact column of the first."""
    plt = pyplot()
    if plt is None:
        return []
    fig, ax = plt.subplots(figsize=(7.0, 4.5))
    exact_done = False
    for label, r in runs:
        parts = last_frame(r["_dir"])
        if not parts:
            continue
        parts.sort(key=lambda p: p[xkey])
        xs = [p[xkey] for p in parts]
        ax.plot(xs, [p[key] for p in parts], lw=1.0, label=label)
        if not exact_done and "stress_exact" in parts[0]:
            ax.plot(xs, [p["stress_exact"] for p in parts], "k--", lw=1.2, label="exact",
                    zorder=10)
            exact_done = True
    ax.set_xlabel("x [m]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(plt, fig, ctx, name)


def plot_convergence(ctx, name, series, title, ylabel):
    """Error against the number of nodes, several series {label: [(nodes, error), ...]}."""
    plt = pyplot()
    if plt is None:
        return []
    fig, ax = plt.subplots(figsize=(7.0, 4.8))
    markers = "osd^v<>ph*"
    for k, (label, pts) in enumerate(series.items()):
        pts = [(n, x) for n, x in pts if x is not None and x > 0]
        if pts:
            # Alternate solid lines with small filled markers and dashed lines with large open
            # ones, so that series lying on each other (MPM and OTM, BSMPM and unified on some
            # grids) stay visible.
            ax.loglog([n for n, _ in pts], [x for _, x in pts],
                      ("-" if k % 2 == 0 else "--") + markers[k % len(markers)], lw=1.0,
                      ms=4 if k % 2 == 0 else 8, mfc=None if k % 2 == 0 else "none",
                      label=label)
    ax.set_xlabel("nodes")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(plt, fig, ctx, name)


def plot_history(ctx, name, runs, title):
    """Relative change of total energy over time (history.csv) of several runs."""
    plt = pyplot()
    if plt is None:
        return []
    # Energy, and where history.csv has them the mapping's mass and momentum errors per step
    # (grid sums against particle sums; row 0 is the state before the first mapping).
    hist = []
    for label, r in runs:
        path = os.path.join(r["_dir"], "history.csv")
        if os.path.exists(path):
            with open(path, newline="") as f:
                hist.append((label, [{k: float(v) for k, v in row.items()}
                                     for row in csv.DictReader(f)]))
    per_step = bool(hist) and all("mass_error" in h[0] for _, h in hist)
    fig, axes = plt.subplots(1, 3 if per_step else 1, figsize=(15.0 if per_step else 6.5, 4.5))
    axes = list(axes) if per_step else [axes]
    floor = 1e-17  # exact zeros on a log axis
    for label, h in hist:
        t = [x["time"] for x in h]
        e0 = h[0]["total_energy"]
        axes[0].plot(t, [abs(x["total_energy"] - e0) / e0 for x in h], lw=1.0, label=label)
        if per_step:
            for ax, key in zip(axes[1:], ("mass_error", "momentum_error")):
                ax.plot(t[1:], [max(abs(x[key]), floor) for x in h[1:]], lw=1.0, label=label)
    ylabels = ["|E(t) - E(0)| / E(0)", "relative mass error of the mapping",
               "relative momentum error of the mapping"]
    for ax, yl in zip(axes, ylabels):
        ax.set_ylabel(yl)
        ax.set_xlabel("t [s]")
        ax.set_yscale("log")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title(title)
    fig.tight_layout()
    return save_figure(plt, fig, ctx, name)


def plot_plate_row(ctx, name, rows, title):
    """sigma_11 along one row of particles for several runs, with the exact stress."""
    plt = pyplot()
    if plt is None:
        return []
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13.0, 4.8))
    for k, (label, row) in enumerate(rows):
        xs = [p["x_1"] for p in row]
        line, = ax.plot(xs, [p["stress_11"] for p in row], lw=1.0, label=label)
        if k == 0:
            ax.plot(xs, [p["stress_exact_11"] for p in row], "k--", lw=1.2, label="exact",
                    zorder=10)
        if "P1" not in label:  # the right panel: the smooth methods' errors, P1's off scale
            ax2.plot(xs, [p["stress_11"] - p["stress_exact_11"] for p in row], lw=1.0,
                     label=label, color=line.get_color())
    ax.set_xlabel("x_1 [m]")
    ax.set_ylabel("sigma_11 [Pa]")
    ax.set_title(title)
    ax2.set_xlabel("x_1 [m]")
    ax2.set_ylabel("sigma_11 - exact [Pa]")
    ax2.set_title("error along the row (max-ent and B-splines)")
    for a in (ax, ax2):
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(plt, fig, ctx, name)


def plot_line_profiles(ctx, name, panels):
    """D Fig. 6.8: sigma_yy along X_1 = 0.5 m, one panel per mesh."""
    plt = pyplot()
    if plt is None:
        return []
    fig, axes = plt.subplots(1, len(panels), figsize=(6.0 * len(panels), 4.5), sharey=True)
    for ax, (title, runs) in zip(axes, panels):
        exact_done = False
        for label, pts in runs:
            if not pts:
                continue
            ax.plot([p[0] for p in pts], [p[1] for p in pts], ".", ms=3, label=label)
            if not exact_done:
                ax.plot([p[0] for p in pts], [p[2] for p in pts], "k-", lw=1.0, label="exact")
                exact_done = True
        ax.set_xlabel("X_2 [m] (material points nearest X_1 = 0.5 m)")
        ax.set_title(title)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("sigma_yy [Pa] at T = 0.015 s")
    fig.tight_layout()
    return save_figure(plt, fig, ctx, name)
