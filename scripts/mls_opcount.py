#!/usr/bin/env python3
"""Operation count of the MLS (001) and IMLS (003) mappings against their implementation
(issue 22 item 5: "MLS and IMLS within 1.5x of the operation count of their definition").

    /usr/bin/python3 scripts/mls_opcount.py [--mpm build/mpm] [--particles 40000]
                                            [--callgrind] [--time ROUNDS]

The layout is that of `mpm bench --dim 2` (plate, 3 x 3 particles per cell on n x n cells of the
unit square, n = round(sqrt(particles) / 3), 2 x 2 Gauss points per element, the published
quadratic-spline weight with dilation 2: support |x - x_p| < 3 l per direction, linear
polynomials). The script prints, per particle-step:

1. The support sizes, computed exactly for that layout (the rows are tensor products, so the
   entries of a row are n_x n_y): Gauss points, row entries (particles in a Gauss point's
   support), candidates scanned (particles of the cells that overlap the support box), and
   IMLS's nodal rows (003 eq. 31, linear weight). They equal the counts of the implementation
   (instrumented once: 137.63 entries and 186.10 candidates per particle-step at 40,401
   particles, 4 steps; the bench's small deformation moves a few particles).
2. The floating-point operations of each definition, phase by phase (below), counted as adds,
   subtractions, multiplications and divisions (abs, max and comparisons not counted; no fused
   multiply-adds: the default build targets SSE2), and those of the direct mapping.
3. --callgrind: the instructions the implementation executes (valgrind's callgrind, exact and
   noise-free; the difference of a 4-step and a 2-step run, so set-up is excluded), split into
   the mapping and the rest of the step, and the instructions per defined operation.
4. --time R: R alternating rounds of `mpm bench` (1 thread) of the three mappings, the ns per
   particle-step and the ratios to the direct step. With --callgrind as well: the time of each
   mapping per defined operation against the direct mapping's (the direct mapping's time taken
   as its share of the direct step's instructions; the rest of the step, common to all three,
   is subtracted from each step's time). Issue 22's target: at most 1.5.

Counting rules (2D, degree 1, m = 3 terms; per row entry unless stated):
  MLS (001 eq. 10-17)
    offset x_p - x_g                                    2
    weight w(r_x) w(r_y), r = |d| / (a l) (eq. 16-17)    2 x (1 + 3) + 1 = 9
    scaled offset s = d / l                             2
    moment matrix, lower triangle (eq. 10)              5 mul + 6 add = 11
    shape function w (c_0 + c_1 s_0 + c_2 s_1) (eq. 14) 5
    fields: rho (2), sigma (3 components, 6), b (4), rho v (4; rho_p v_p once per particle)  16
    per Gauss point: A c = e_1 by LDL^T (about 25), rho^ b^ (2)
  IMLS (003 eq. 7-17): offset, weight and scaled offset as MLS (13); Gram-Schmidt of
    [1, s_0, s_1] under <f, g> = sum w f g, one pass: <1,1> 1, <s_0,1> 2, p_1 1, <p_1,p_1> 3,
    <s_1,1> 2, <s_1,p_1> 3, p_2 3, <p_2,p_2> 3 = 18; shape function 5; fields at the Gauss points
    rho, sigma, b (12); momentum at the nodes instead: the nodal rows (linear weight 2 x 2 + 1,
    offset 2, scaled offset 2, Gram-Schmidt 18, shape 5, v 4 = 36 per entry). The
    implementation orthogonalises twice (two passes, a stability choice 003 does not make): the
    second pass projects p_1 on p_0 again (inner product 3, update 2) and p_2 on p_0 and p_1
    (2 x 5), 15 per entry, listed separately.
  Quadrature at each Gauss point (common to every Gauss-point mapping; P1: 4 nodes):
    N_i 4, grad N_i 8, mass 9, momentum 18, internal force 3 + 32, body force 18   = 92
  Direct mapping (D eq. 2.32, 2.45, per particle; the same sums with m_p for w_g rho):
    N_i 4, grad N_i 8, mass 8, momentum 18, internal force 4 + 32, body force 18     = 92
    Its functions (map_fused) also advance v_p by dt sum_i N_i a_i in the momentum pass (MUSL,
    kVelocityFirst; 18 operations that the MLS step does elsewhere), so the instructions of
    those functions are divided by 92 + 18 = 110.
"""
import argparse
import math
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Floating-point operations per row entry / per Gauss point / per particle (module docstring).
MLS_ENTRY = {"offset": 2, "weight": 9, "scaled offset": 2, "moment matrix": 11,
             "shape function": 5, "fields (rho, sigma, b, rho v)": 16}
IMLS_ENTRY = {"offset": 2, "weight": 9, "scaled offset": 2, "Gram-Schmidt": 18,
              "shape function": 5, "fields (rho, sigma, b)": 12}
IMLS_SECOND_PASS = 15
IMLS_NODE_ENTRY = 36
MLS_PER_GAUSS = 25 + 2
GAUSS_QUADRATURE = 92
DIRECT_PER_PARTICLE = 92
DIRECT_IN_ITS_FUNCTIONS = 92 + 18  # with the velocity advance of map_fused


def layout(particles):
    """Exact support counts per particle-step for mpm bench's 2D layout (rows are products)."""
    n = max(1, round(math.sqrt(particles) / 3))
    h = 1.0 / n
    g = 1.0 / math.sqrt(3.0)
    gx = [(i + 0.5 + s * 0.5 * g) * h for i in range(n) for s in (-1, 1)]
    px = [(j + (k + 0.5) / 3.0) * h for j in range(n) for k in range(3)]
    R = 3.0 * h  # 1.5 a l with a = 2

    def cells(x):
        lo = max(0, min(n - 1, math.floor((x - R) / h)))
        hi = max(0, min(n - 1, math.floor((x + R) / h)))
        return hi - lo + 1

    ent1 = sum(sum(1 for p in px if abs(p - x) < R) for x in gx)
    cand1 = sum(3 * cells(x) for x in gx)
    nodes1 = sum(sum(1 for p in px if abs(p - i * h) < h) for i in range(n + 1))
    N = (3 * n) ** 2
    return {"cells": n, "particles": N, "gauss": (2 * n) ** 2 / N, "entries": ent1 ** 2 / N,
            "candidates": cand1 ** 2 / N, "node entries": nodes1 ** 2 / N}


def defined_ops(L):
    e, g = L["entries"], L["gauss"]
    mls = e * sum(MLS_ENTRY.values()) + g * (MLS_PER_GAUSS + GAUSS_QUADRATURE)
    imls = (e * sum(IMLS_ENTRY.values()) + L["node entries"] * IMLS_NODE_ENTRY
            + g * (2 + GAUSS_QUADRATURE))
    imls2 = imls + (e + L["node entries"]) * IMLS_SECOND_PASS
    return {"direct": DIRECT_PER_PARTICLE, "mls": mls, "imls": imls, "imls, two passes": imls2}


def bench_cmd(mpm, mapping, particles, steps):
    return [mpm, "bench", "--dim", "2", "--particles", str(particles), "--steps", str(steps),
            "--repeats", "1", "--threads", "1", "--basis", "linear", "--mapping", mapping]


# Self cost of the functions that belong to each mapping (callgrind_annotate names).
MAPPING_PATTERNS = {
    "direct": [r"DirectMapping::map_fused"],
    "mls": [r"MovingLeastSquares", r"mls_shape", r"SelfAdjointEigenSolver", r"tridiagonal",
            r"memmove|memcpy|memset", r"QuadraturePoints", r"assemble_", r"ShapeTables"],
}
MAPPING_PATTERNS["imls"] = MAPPING_PATTERNS["mls"]


def callgrind(mpm, mapping, particles):
    env = dict(os.environ, OMP_WAIT_POLICY="passive")  # no re-exec (src/app/main.cpp)
    costs = {}
    with tempfile.TemporaryDirectory() as tmp:
        for steps in (2, 4):
            out = os.path.join(tmp, f"cg.{steps}")
            subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}"]
                           + bench_cmd(mpm, mapping, particles, steps), env=env, check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            text = subprocess.run(["callgrind_annotate", "--threshold=100", out],
                                  capture_output=True, text=True, check=True).stdout
            total, mapped = 0, 0
            for line in text.splitlines():
                m = re.match(r"\s*([\d,]+) \([^)]*\)\s+(.*)", line)
                if not m:
                    continue
                ir, name = int(m.group(1).replace(",", "")), m.group(2)
                if "PROGRAM TOTALS" in name:
                    total = ir
                elif any(re.search(p, name) for p in MAPPING_PATTERNS[mapping]):
                    mapped += ir
            costs[steps] = (total, mapped)
    n = 2 * layout(particles)["particles"]
    return ((costs[4][0] - costs[2][0]) / n, (costs[4][1] - costs[2][1]) / n)


def timing(mpm, particles, rounds):
    ns = {m: [] for m in ("direct", "mls", "imls")}
    env = dict(os.environ, OMP_WAIT_POLICY="passive")
    for _ in range(rounds):
        for m in ns:
            cmd = bench_cmd(mpm, m, particles, 10)
            cmd[cmd.index("--repeats") + 1] = "2"
            out = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env).stdout
            ns[m].append(float(re.search(r"([\d.]+) ns per particle-step", out).group(1)))
    return ns


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mpm", default=os.path.join(ROOT, "build", "mpm"))
    ap.add_argument("--particles", type=int, default=40000)
    ap.add_argument("--callgrind", action="store_true")
    ap.add_argument("--time", type=int, default=0, metavar="ROUNDS")
    a = ap.parse_args()
    L = layout(a.particles)
    print(f"Layout of `mpm bench --dim 2 --particles {a.particles}`: {L['cells']} x {L['cells']} "
          f"cells, {L['particles']} particles. Per particle-step: {L['gauss']:.3f} Gauss points, "
          f"{L['entries']:.2f} row entries, {L['candidates']:.2f} candidates scanned, "
          f"{L['node entries']:.2f} IMLS nodal entries.\n")
    print("| definition | per entry | per particle-step |\n|---|---|---|")
    for k, v in MLS_ENTRY.items():
        print(f"| MLS {k} | {v} | {v * L['entries']:.0f} |")
    for k, v in IMLS_ENTRY.items():
        print(f"| IMLS {k} | {v} | {v * L['entries']:.0f} |")
    ops = defined_ops(L)
    print()
    print("| mapping | defined operations per particle-step |\n|---|---|")
    for k, v in ops.items():
        print(f"| {k} | {v:.0f} |")
    ins = {}
    if a.callgrind:
        print("\n| mapping | instructions per particle-step (step / mapping) "
              "| mapping instructions per defined operation |\n|---|---|---|")
        for m in ("direct", "mls", "imls"):
            total, mapped = callgrind(a.mpm, m, a.particles)
            ins[m] = (total, mapped)
            per = DIRECT_IN_ITS_FUNCTIONS if m == "direct" else ops[m]
            print(f"| {m} | {total:.0f} / {mapped:.0f} | {mapped / per:.2f} |")
    if a.time:
        ns = timing(a.mpm, a.particles, a.time)
        print("\n| mapping | ns per particle-step (rounds) | best / direct's best |\n|---|---|---|")
        for m, v in ns.items():
            print(f"| {m} | {', '.join(f'{x:.1f}' for x in v)} | {min(v) / min(ns['direct']):.1f} |")
    if ins and a.time:
        # The time of the direct mapping: its share of the direct step's instructions (both
        # parts run scalar code at a similar rate); the rest of the step is common to the three
        # mappings, so a mapping's time is its step's best time less that rest.
        best = {m: min(v) for m, v in ns.items()}
        t_map = best["direct"] * ins["direct"][1] / ins["direct"][0]
        rest = best["direct"] - t_map
        ref = t_map / DIRECT_IN_ITS_FUNCTIONS
        print("\n| mapping | mapping time [ns per particle-step] | defined operations "
              "| ns per defined operation | / the direct mapping's |\n|---|---|---|---|---|")
        print(f"| direct | {t_map:.1f} (instruction share) | {DIRECT_IN_ITS_FUNCTIONS} "
              f"| {ref:.3f} | 1 |")
        for m in ("mls", "imls", "imls, two passes"):
            t = best[m.split(",")[0]] - rest
            print(f"| {m} | {t:.0f} | {ops[m]:.0f} | {t / ops[m]:.3f} | {t / ops[m] / ref:.2f} |")


if __name__ == "__main__":
    sys.exit(main())
