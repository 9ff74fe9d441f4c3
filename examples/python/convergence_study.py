"""A convergence study from Python: three methods on the 1D manufactured solution, their errors
and observed orders, and a log-log plot.

The problem is examples/mms_1d.toml: a bar of 1 m with fixed ends under the body force that makes
u(X, t) = A sin(pi X) sin(c pi t) exact (003's manufactured solution, amplitude A = 0.1 m, so
that particles cross cells). 003 reports (its Figs. 4-6) that MPM with linear functions does not
converge on this problem (the grid-crossing error), that CPDI is second order on the coarse grids
and then stalls, and that MPM with the IMLS reconstruction is second order.

Run from the repository (after the README's set-up command):

    PYTHONPATH=build /usr/bin/python3 examples/python/convergence_study.py --out runs/py_study

``--quick`` runs three refinements instead of five (what CI runs). The script checks what it
shows and exits 1 when an order is off.
"""
import argparse
import pathlib
import sys

import mpmlab

ROOT = pathlib.Path(__file__).resolve().parents[2]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="runs/py_convergence_study", help="output directory")
parser.add_argument("--quick", action="store_true", help="three refinements (CI)")
args = parser.parse_args()
out = pathlib.Path(args.out)

# 1. The configuration, checked as `mpm run` checks it; set() takes what --set takes.
cfg = mpmlab.Config.from_file(ROOT / "examples" / "mms_1d.toml")
cfg.set("time.end", 0.01)  # half the example's period: the exact stress is largest here

# 2. The study: the refined key with its values, coarse to fine, and the methods, labelled as
#    `mpm study --methods` labels them. The time step stays 1e-5 s, well below every grid's limit.
cells = [8, 16, 32] if args.quick else [8, 16, 32, 64, 128]
methods = ["linear/direct", "cpdi/direct", "linear/imls"]
rows = mpmlab.study(cfg, {"grid.cells": cells}, methods=methods, out=out, overwrite=True,
                    frame=False)

# 3. The rows: one per run, with every error norm and its observed order against the method's
#    previous refinement (what study.txt prints).
print(f"{'method':>16} {'cells':>6} {'stress_rms [Pa]':>16} {'order':>6}")
for r in rows:
    order = r["order_stress_rms"]
    print(f"{r['method']:>16} {r['grid.cells']:>6} {r['stress_rms']:>16.4e} "
          f"{'' if order is None else f'{order:6.2f}'}")

# 4. A plot of the errors against the cell size.
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, ax = plt.subplots(figsize=(5, 4))
for m in methods:
    mine = [r for r in rows if r["method"] == m]
    ax.loglog([r["h"] for r in mine], [r["stress_rms"] for r in mine], "o-", label=m)
ax.set_xlabel("h [m]")
ax.set_ylabel("RMS stress error at T [Pa]")
ax.legend()
ax.grid(True, which="both", lw=0.3)
fig.tight_layout()
fig.savefig(out / "convergence.png", dpi=120)
print(f"plot: {out / 'convergence.png'}")

# 5. What the study shows, checked: every run finished; on the finest pair MPM with IMLS
#    converges at about second order (1.89 from 64 to 128 cells, 2.11 from 16 to 32), where
#    linear MPM does not converge (its error grows).
last = {m: [r for r in rows if r["method"] == m][-1] for m in methods}
problems = [f"{r['method']} at {r['grid.cells']} cells: {r['status']}" for r in rows
            if r["status"] != "ok"]
if last["linear/imls"]["order_stress_rms"] < 1.7:
    problems.append(f"IMLS order {last['linear/imls']['order_stress_rms']:.2f} < 1.7")
if last["linear/direct"]["order_stress_rms"] > 0.5:
    problems.append(f"linear order {last['linear/direct']['order_stress_rms']:.2f} > 0.5")
if problems:
    print("unexpected: " + "; ".join(problems))
    sys.exit(1)
