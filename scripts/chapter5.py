#!/usr/bin/env python3
"""Regenerates the chapter-5 tables of docs/verification.md (D 5.4: vibrating bar small and
large deformation, column compaction) from fresh runs of build/mpm. Prints Markdown.

    python3 scripts/chapter5.py > /tmp/ch5.md     (about a minute on 2 cores)
"""
import json
import math
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MPM = os.path.join(ROOT, "build", "mpm")
TMP = tempfile.mkdtemp(prefix="mpm_ch5_")


def run(example, sets):
    name = example + "_" + "_".join(s.replace("=", "-").replace(".", "") for s in sets)
    out = os.path.join(TMP, name)
    cmd = [MPM, "run", os.path.join(ROOT, "examples", example + ".toml"), "-q", "--out", out,
           "--set", "output.csv=false", "--set", "output.vtk=false", "--set", "output.frames=0"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=False, capture_output=True)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


METHODS = {  # label: settings
    "MPM": ["method.basis=linear"],
    "DDMPM": ["method.basis=ddmpm"],
    "BSMPM": ["method.basis=bspline", "method.degree=2"],
}
MAPPINGS = {"direct": "direct", "CS": "cubic_spline", "TLS": "tls"}


def fmt(x):
    return "-" if x is None else f"{x:.3e}"


def order(e0, e1, h0, h1):
    if e0 is None or e1 is None or e0 <= 0 or e1 <= 0:
        return "-"
    return f"{math.log(e0 / e1) / math.log(h0 / h1):.2f}"


def pool_map(fn, items):
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as ex:
        return list(ex.map(fn, items))


def small_bar():
    print("### Vibrating bar, small deformation, set 2 (D 5.4.1, Fig. 5.9-5.11)\n")
    cells = [5, 10, 20, 40]
    combos = []
    for m in METHODS:
        for mp in MAPPINGS:
            for mass in ["lumped", "consistent"]:
                combos.append((m, mp, mass))
    jobs = [(c, n) for c in combos for n in cells]
    res = pool_map(lambda j: run("vibrating_bar_small", METHODS[j[0][0]] + [
        f"method.mapping={MAPPINGS[j[0][1]]}", f"method.mass={j[0][2]}", f"grid.cells={j[1]}"]),
        jobs)
    table = {}
    for (c, n), r in zip(jobs, res):
        table.setdefault(c, []).append(r)
    print("Errors at 40 cells and least-squares orders over 5-40 cells (12 PPC, MUSL).\n")
    print("| method | mapping | mass | displacement_rms | order | velocity_rms_midstep | order "
          "| stress_rms [Pa] | order | stress_rms_interior | order | status |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for c in combos:
        rs = table[c]
        def col(key):
            vals = [r["errors"].get(key) for r in rs]
            hs = [r["h"] for r in rs]
            if any(v is None or v <= 0 for v in vals):
                return fmt(vals[-1]), "-"
            lx = [math.log(h) for h in hs]
            ly = [math.log(v) for v in vals]
            n = len(lx)
            sx, sy = sum(lx), sum(ly)
            sxx = sum(x * x for x in lx)
            sxy = sum(x * y for x, y in zip(lx, ly))
            return fmt(vals[-1]), f"{(n * sxy - sx * sy) / (n * sxx - sx * sx):.2f}"
        status = ",".join(sorted(set(r["status"] for r in rs)))
        cells_out = []
        for key in ["displacement_rms", "velocity_rms_midstep", "stress_rms",
                    "stress_rms_interior"]:
            cells_out += list(col(key))
        print(f"| {c[0]} | {c[1]} | {c[2]} | " + " | ".join(cells_out) + f" | {status} |")
    print()
    print("Conservation at 40 cells, lumped mass (D Table 5.3).\n")
    print("| method | mapping | mass error | momentum error |")
    print("|---|---|---|---|")
    for m in METHODS:
        for mp in ["CS", "TLS"]:
            r = table[(m, mp, "lumped")][-1]
            cons = r["conservation"]
            print(f"| {m} | {mp} | {fmt(cons['max_rel_mass_error'])} | "
                  f"{fmt(cons['max_rel_momentum_error'])} |")
    print()


def large_bar():
    print("### Vibrating bar, large deformation (D 5.4.1, Fig. 5.12-5.13, Table 5.5)\n")
    print("20 cells, 8 PPC, dt = 1e-4 s, T = 0.1 s, MUSL; relative L2 stress error against the "
          "ULFEM reference (120 nodes) at the particles' material positions.\n")
    combos = [(m, mp, mass) for mass in ["lumped", "consistent"] for m in METHODS
              for mp in MAPPINGS]
    res = pool_map(lambda c: run("vibrating_bar_large", METHODS[c[0]] + [
        f"method.mapping={MAPPINGS[c[1]]}", f"method.mass={c[2]}"]), combos)
    # Reduction factors relative to standard MPM (P1, direct mapping, lumped mass), as in D.
    base = [r["errors"]["stress_rel_l2"] for c, r in zip(combos, res)
            if c == ("MPM", "direct", "lumped")][0]
    print("| method | mapping | mass | stress_rel_l2 | MPM (lumped) error / this | mass error | "
          "momentum error | crossings | status |")
    print("|---|---|---|---|---|---|---|---|---|")
    for c, r in zip(combos, res):
        e = r["errors"]["stress_rel_l2"]
        ratio = "-" if e is None else f"{base / e:.1f}"
        cons = r["conservation"]
        print(f"| {c[0]} | {c[1]} | {c[2]} | {fmt(e)} | {ratio} | "
              f"{fmt(cons['max_rel_mass_error'])} | {fmt(cons['max_rel_momentum_error'])} | "
              f"{r['grid_crossings']} | {r['status']} |")
    print()


def column():
    print("### Column compaction (D 5.4.2, Fig. 5.14, Table 5.7)\n")
    combos = [(m, mp) for m in METHODS for mp in MAPPINGS]
    res = pool_map(lambda c: run("column_compaction", METHODS[c[0]] + [
        f"method.mapping={MAPPINGS[c[1]]}"]), combos)
    print("50 cells, 20 PPC, dt = 1e-4 s, T = 0.5 s, MUSL, lumped mass.\n")
    print("| method | mapping | stress_rel_l2 | mass error | momentum error | crossings | status |")
    print("|---|---|---|---|---|---|---|")
    for c, r in zip(combos, res):
        cons = r["conservation"]
        print(f"| {c[0]} | {c[1]} | {fmt(r['errors']['stress_rel_l2'])} | "
              f"{fmt(cons['max_rel_mass_error'])} | {fmt(cons['max_rel_momentum_error'])} | "
              f"{r['grid_crossings']} | {r['status']} |")
    print()


if __name__ == "__main__":
    if not os.path.exists(MPM):
        sys.exit("build/mpm not found: run bash scripts/test.sh first")
    small_bar()
    large_bar()
    column()
