#!/usr/bin/python3
"""Work-precision diagrams of `mpm study --work-precision` (work_precision.csv): log-log error
against wall time (the minimum over the alternated rounds) and against particle-steps, one line
per method through its refinements, the successful runs only; the target errors of
work_precision.txt as dotted lines. Writes work_precision.png and .svg next to the CSV (or into
--out; --name sets the file name, --title the figure's title).

    /usr/bin/python3 scripts/plot_work_precision.py studies/plate_mms_2d/work_precision.csv

Needs matplotlib (Debian: python3-matplotlib; `bash scripts/deps.sh python3-matplotlib`).
"""
import argparse
import csv
import os
import sys
from collections import OrderedDict


def read(path):
    """(error column, {method: [(wall, particle-steps, error)]}) of the successful runs."""
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        error = header[7]  # method,<key>,cells,h,particles,steps,status,<error>,...
        methods = OrderedDict()
        for row in reader:
            r = dict(zip(header, row))
            methods.setdefault(r["method"], [])
            if r["status"] == "ok" and r[error]:
                methods[r["method"]].append((float(r["wall_seconds_min"]),
                                             float(r["particle_steps"]), float(r[error])))
    return error, methods


def targets_of(path):
    """The target errors listed in work_precision.txt beside the CSV, if it is there."""
    txt = os.path.join(os.path.dirname(os.path.abspath(path)), "work_precision.txt")
    out = []
    if os.path.exists(txt):
        with open(txt) as f:
            for line in f:
                if line.startswith("target ") and "<=" in line:
                    out.append(float(line.split("<=")[1].strip().rstrip(":")))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("--out", default=None, help="directory of the figures (default: the CSV's)")
    ap.add_argument("--name", default="work_precision", help="file name without extension")
    ap.add_argument("--title", default=None)
    a = ap.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit("plot_work_precision.py needs matplotlib (Debian: python3-matplotlib)")
    error, methods = read(a.csv)
    targets = targets_of(a.csv)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.2), sharey=True)
    markers = "os^vD<>ph*xP"
    for i, (name, pts) in enumerate(methods.items()):
        if not pts:
            continue
        pts.sort()
        style = dict(marker=markers[i % len(markers)], ms=4, lw=1.2,
                     ls="-" if i < 10 else "--", label=name)
        axes[0].loglog([p[0] for p in pts], [p[2] for p in pts], **style)
        axes[1].loglog([p[1] for p in pts], [p[2] for p in pts], **style)
    for ax, xlabel in zip(axes, ("wall time [s] (minimum of the rounds)", "particle-steps")):
        for t in targets:
            ax.axhline(t, color="0.6", ls=":", lw=0.8)
        ax.set_xlabel(xlabel)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel(error)
    axes[1].legend(fontsize=7, loc="best", ncol=2)
    if a.title:
        fig.suptitle(a.title)
    fig.tight_layout()
    out = a.out or os.path.dirname(os.path.abspath(a.csv))
    os.makedirs(out, exist_ok=True)
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(out, f"{a.name}.{ext}"), dpi=110)
    print(f"{a.name}.png and .svg in {out}")


if __name__ == "__main__":
    main()
