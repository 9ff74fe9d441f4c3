#!/usr/bin/python3
"""Convergence plots of an `mpm study` (study.csv): log-log error against h, one line per
method, with the least-squares order over the refinement printed in the legend. Writes
<stem>_<error>.png and .svg next to the CSV (or into --out).

    /usr/bin/python3 scripts/plot_study.py studies/plate_mms_2d/study.csv [--errors ...]

Needs matplotlib (Debian: python3-matplotlib; `bash scripts/deps.sh python3-matplotlib`).
"""
import argparse
import csv
import math
import os
import sys
from collections import OrderedDict

DEFAULT_ERRORS = ["displacement_rms", "velocity_rms", "stress_rms"]
LABELS = {
    "displacement_rms": "displacement RMS [m]",
    "velocity_rms": "velocity RMS [m/s]",
    "velocity_rms_scheme_time": "velocity RMS at the scheme's time [m/s]",
    "stress_rms": "stress RMS [Pa]",
    "stress_rel_l2": "relative L2 stress error [-]",
}


def fitted_order(hs, es):
    """Least-squares slope of log e against log h (the observed order over the series)."""
    pts = [(math.log(h), math.log(e)) for h, e in zip(hs, es) if h > 0 and e > 0]
    if len(pts) < 2:
        return float("nan")
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx > 0 else float("nan")


def read_study(path):
    methods = OrderedDict()
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            methods.setdefault(row["method"], []).append(row)
    return methods


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", help="study.csv written by mpm study")
    ap.add_argument("--errors", default=",".join(DEFAULT_ERRORS),
                    help="comma-separated error columns (default: %(default)s)")
    ap.add_argument("--out", help="output directory (default: the CSV's directory)")
    ap.add_argument("--title", default=None, help="figure title (default: the study directory)")
    args = ap.parse_args(argv)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        plt.rcParams["svg.fonttype"] = "none"  # text stays text in the SVG (searchable, editable)
    except ImportError:
        sys.exit("plot_study.py: matplotlib is missing; install it with "
                 "`bash scripts/deps.sh python3-matplotlib` (Debian package python3-matplotlib)")
    methods = read_study(args.csv)
    if not methods:
        sys.exit(f"plot_study.py: {args.csv} holds no runs")
    out = args.out or os.path.dirname(os.path.abspath(args.csv))
    os.makedirs(out, exist_ok=True)
    title = args.title or os.path.basename(os.path.dirname(os.path.abspath(args.csv)))
    written = []
    for err in [e.strip() for e in args.errors.split(",") if e.strip()]:
        fig, ax = plt.subplots(figsize=(6.0, 4.5))
        plotted = 0
        for name, rows in methods.items():
            if err not in rows[0]:
                sys.exit(f"plot_study.py: {args.csv} has no column '{err}'")
            pts = sorted((float(r["h"]), float(r[err])) for r in rows
                         if r["status"] == "ok" and r[err] not in ("", None))
            if not pts:
                continue
            hs, es = zip(*pts)
            order = fitted_order(hs, es)
            ax.loglog(hs, es, "o-", label=f"{name} (order {order:.2f})")
            plotted += 1
        if plotted == 0:
            plt.close(fig)
            continue
        ax.set_xlabel("h [m]")
        ax.set_ylabel(LABELS.get(err, err))
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        for ext in ("png", "svg"):
            path = os.path.join(out, f"convergence_{err}.{ext}")
            fig.savefig(path, dpi=120)
            written.append(path)
        plt.close(fig)
    for p in written:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
