#!/usr/bin/python3
"""Convergence plots of an `mpm study` (study.csv): log-log error against h, one line per
method, with the least-squares order over the refinement printed in the legend. Writes
convergence_<error>.png and .svg next to the CSV (or into --out). From the run directories the
study keeps (<out>/<method>/<key>_<value>/), it also writes, for the finest successful run of
each method, stress_profile.png/.svg (1D: final particle stress against x with the exact
stress where the particle CSV has it) and conservation.png/.svg (history.csv: relative change
of the total energy over time; with a body force doing work it is not conserved exactly).

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


def finest_runs(csv_path, methods):
    """(method, run directory) of the finest successful run of each method, where kept."""
    root = os.path.dirname(os.path.abspath(csv_path))
    with open(csv_path, newline="") as f:
        key = next(csv.reader(f))[1]  # the refined key: method,<key>,cells,...
    found = []
    for name, rows in methods.items():
        ok = [r for r in rows if r["status"] == "ok"]
        if not ok:
            continue
        r = min(ok, key=lambda r: float(r["h"]))
        for sub in (name.replace("/", "_"), ""):
            d = os.path.join(root, sub, f"{key}_{r[key]}")
            if os.path.isdir(d):
                found.append((name, d))
                break
    return found


def read_rows(path):
    with open(path, newline="") as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def save(fig, out, stem):
    paths = []
    for ext in ("png", "svg"):
        path = os.path.join(out, f"{stem}.{ext}")
        fig.savefig(path, dpi=120, metadata={"Date": None} if path.endswith(".svg") else None)
        paths.append(path)
    return paths


def histories(runs):
    """(method, history.csv rows) of each run directory that has a history.csv."""
    for name, d in runs:
        path = os.path.join(d, "history.csv")
        if os.path.exists(path):
            yield name, read_rows(path)


def profile_and_history(plt, csv_path, methods, out, title):
    """Stress profile (1D) and conservation over time of the finest run of each method."""
    import glob
    runs = finest_runs(csv_path, methods)
    written = []
    # Final-time stress profile: 1D particle frames only (x_1 and stress_11, no x_2).
    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    exact = False
    plotted = 0
    for name, d in runs:
        frames = sorted(glob.glob(os.path.join(d, "particles_*.csv")))
        if not frames:
            continue
        parts = read_rows(frames[-1])
        if not parts or "stress_11" not in parts[0] or "x_2" in parts[0]:
            continue
        parts.sort(key=lambda p: p["x_1"])
        xs = [p["x_1"] for p in parts]
        ax.plot(xs, [p["stress_11"] for p in parts], lw=1.0, label=f"{name} (finest)")
        plotted += 1
        if not exact and "stress_exact" in parts[0]:
            ax.plot(xs, [p["stress_exact"] for p in parts], "k--", lw=1.0, label="exact")
            exact = True
    if plotted:
        ax.set_xlabel("x [m]")
        ax.set_ylabel("stress at the final time [Pa]")
        ax.set_title(title)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        written += save(fig, out, "stress_profile")
    plt.close(fig)
    # Conservation over time from history.csv: the total energy (the particle mass there is the
    # particle sum, constant by construction; the mapping's errors are plotted below).
    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    plotted = 0
    for name, h in histories(runs):
        if len(h) < 2 or not h[0].get("total_energy"):
            continue
        t = [x["time"] for x in h]
        e0 = h[0]["total_energy"]
        ax.plot(t, [abs(x["total_energy"] - e0) / abs(e0) for x in h], lw=1.0,
                label=f"{name} (finest)")
        plotted += 1
    if plotted:
        ax.set_ylabel("|E(t) - E(0)| / |E(0)|")
        ax.set_xlabel("t [s]")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"{title}: total energy over time", fontsize=9)
        fig.tight_layout()
        written += save(fig, out, "conservation")
    plt.close(fig)
    # The mapping's conservation errors per step (history.csv columns mass_error and
    # momentum_error: |sum_i m_i - sum_p m_p| / sum_p m_p and |sum_i q_i - sum_p m_p v_p| /
    # sum_p m_p |v_p| of the last step; D Tables 5.3, 5.5, 5.7 report their maxima).
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
    plotted = 0
    floor = 1e-17  # exact zeros on a log axis
    for name, h in histories(runs):
        h = h[1:]  # row 0 is the initial state, before any mapping
        if not h or "mass_error" not in h[0]:
            continue
        t = [x["time"] for x in h]
        for ax, key in zip(axes, ("mass_error", "momentum_error")):
            ax.plot(t, [max(abs(x[key]), floor) for x in h], lw=1.0, label=f"{name} (finest)")
        plotted += 1
    if plotted:
        for ax, what in zip(axes, ("mass", "momentum")):
            ax.set_ylabel(f"relative {what} error of the mapping")
            ax.set_xlabel("t [s]")
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
        fig.suptitle(f"{title}: grid against particle sums per step", fontsize=9)
        fig.tight_layout()
        written += save(fig, out, "conservation_mapping")
    plt.close(fig)
    return written


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
        plt.rcParams["svg.hashsalt"] = "mpmlab"  # reproducible SVG ids (regenerated files diff)
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
            fig.savefig(path, dpi=120, metadata={"Date": None} if path.endswith(".svg") else None)
            written.append(path)
        plt.close(fig)
    written += profile_and_history(plt, args.csv, methods, out, title)
    for p in written:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
