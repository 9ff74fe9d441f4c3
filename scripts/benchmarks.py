#!/usr/bin/python3
"""Regenerates the measured tables of BENCHMARKS.md.

Each table runs `mpm bench` (or `mpm run`) for its rows and prints a Markdown table. Variants
that are compared are alternated: every round runs each row once, the variants compared (a row
and its yardstick, one thread and two, ...) one right after the other, and a ratio is taken
between those neighbouring runs (so a change of the machine's load falls on both alike); a
table gives the median over the rounds of each figure and of each ratio, with their ranges.
Absolute ns figures depend on the machine and its load; every table ends with a line naming the
CPU, the cores and the load average before and after its runs, and a warning where the load
average exceeded the cores (other work shared them).

Tables (--table, repeatable; default: all of them):

  steps      one-thread step cost per dimension, problem, basis and mapping, against the
             yardstick (the hand-written reference kernel ../shared/tools/refkernel.cpp in 2D,
             scripts/refkernel3d.cpp in 3D, both built here with g++ -O3 -march=native -DNDEBUG)
  threads    one thread against two (`mpm bench --threads 1|2`)
  processes  one process against two MPI processes (`mpirun -n 2 mpm run`), and the
             communication model to 4,096 processes computed from the measured one-thread step
  memory     bytes per particle: counted by `mpm bench` and measured (peak resident memory)
  tls        the TLS mapping against the direct mapping at small and at large deformation, and
             TLS with the adjoint strain rate (method.tls_strain_rate) at large

Usage (from anywhere):

    /usr/bin/python3 scripts/benchmarks.py [--mpm build/mpm] [--table NAME]... [--rounds N]
        [--quick] [--update BENCHMARKS.md]

--update FILE replaces, in FILE, the text between the lines
`<!-- BEGIN benchmarks.py --table NAME -->` and `<!-- END benchmarks.py --table NAME -->` with
the new table (the other tables and the text around them stay as they are). --quick runs each
table on small problems and one round, to check that the script works; its figures are not the
page's. Python standard library only. Exits 0 on success, 1 when a run fails, 2 on usage errors.
"""

import argparse
import json
import math
import os
import pathlib
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
REFKERNEL_2D = ROOT.parent / "shared" / "tools" / "refkernel.cpp"
REFKERNEL_3D = ROOT / "scripts" / "refkernel3d.cpp"
TABLES = ("steps", "stages", "threads", "processes", "memory", "tls")

# Open MPI on one machine as scripts/mpi_check.py runs it (root allowed, shared memory).
MPIRUN_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
              "OMPI_MCA_rmaps_base_oversubscribe": "1",
              "OMPI_MCA_btl_vader_single_copy_mechanism": "none",
              "OMPI_MCA_btl": "self,vader", "OMPI_MCA_pml": "ob1"}


class Failure(Exception):
    pass


# ---------------------------------------------------------------------------------------------
# Running things


def run(cmd, env=None, cwd=None):
    full_env = dict(os.environ)
    full_env["OMP_WAIT_POLICY"] = "passive"
    full_env.update(env or {})
    r = subprocess.run(cmd, capture_output=True, text=True, env=full_env, cwd=cwd)
    if r.returncode != 0:
        raise Failure(f"{' '.join(map(str, cmd))} exited {r.returncode}:\n{r.stdout}{r.stderr}")
    return r.stdout


def number(pattern, text, what, group=1):
    m = re.search(pattern, text, re.MULTILINE)
    if not m:
        raise Failure(f"could not read {what} from:\n{text}")
    return float(m.group(group))


def parse_bench(out):
    """The figures `mpm bench` prints (src/app/main.cpp, cmd_bench)."""
    r = {
        "particles": int(number(r":\s*(\d+) particles,", out, "the particle count")),
        "cells": int(number(r"particles,\s*(\d+) cells", out, "the cell count")),
        "ns": number(r"^\s*([0-9.]+) ns per particle-step \(median", out, "ns per particle-step"),
        "bytes": number(r"([0-9.]+) bytes per particle \(particle state", out, "bytes"),
    }
    m = re.search(r"the steps after it ([0-9.]+) ns per particle-step", out)
    # The steps after the first (the first allocates and first touches the step's arrays, which
    # a long run pays once); with one step only, that step.
    r["ns_after_first"] = float(m.group(1)) if m else r["ns"]
    m = re.search(r"peak resident memory of a run ([0-9.]+) MB, ([0-9.]+) bytes per particle", out)
    r["peak_bytes"] = float(m.group(2)) if m else None
    m = re.search(r"(\d+) sort\(s\) per run[^;\n]*; sort buffers ([0-9.]+) bytes per particle", out)
    r["sorts"], r["sort_bytes"] = (int(m.group(1)), float(m.group(2))) if m else (None, None)
    # --stages: each stage's mean ns per particle-step, the rest and the whole step.
    m = re.search(r"stages \[ns per particle-step, mean of every step\]: basis ([0-9.]+), "
                  r"particles to grid ([0-9.]+), grid ([0-9.]+), grid to particles ([0-9.]+), "
                  r"other (-?[0-9.]+) \(of ([0-9.]+)\); the material laws ([0-9.]+)", out)
    r["stages"] = None if not m else dict(zip(
        ("basis", "to_grid", "grid", "to_particles", "other", "step", "material"),
        (float(g) for g in m.groups())))
    return r


class Runner:
    def __init__(self, args):
        self.mpm = str(pathlib.Path(args.mpm).resolve())
        self.quick = args.quick
        self.rounds = 1 if args.quick else args.rounds
        self.tmp = pathlib.Path(tempfile.mkdtemp(prefix="mpm_benchmarks_"))
        self.yardsticks = {}
        self.verbose = args.verbose

    def log(self, msg):
        if self.verbose:
            print(msg, file=sys.stderr, flush=True)

    def bench(self, args):
        out = run([self.mpm, "bench"] + [str(a) for a in args])
        r = parse_bench(out)
        self.log(f"  mpm bench {' '.join(map(str, args))}: {r['ns_after_first']:.1f} ns")
        return r

    def mpm_run(self, config, sets, threads, processes=1):
        """ns per particle-step of `mpm run` (summary.json, rank 0's stepping time per
        particle-step of the whole problem, the first step included) and its summary.json."""
        out = pathlib.Path(tempfile.mkdtemp(dir=self.tmp))
        cmd = [self.mpm, "run", str(ROOT / config), "--out", str(out / "o")]
        for s in sets:
            cmd += ["--set", s]
        env = {"OMP_NUM_THREADS": str(threads)}
        if processes > 1:
            env.update(MPIRUN_ENV)
            cmd = ["mpirun", "-n", str(processes), "--oversubscribe"] + cmd
        run(cmd, env=env)
        summary = json.loads((out / "o" / "summary.json").read_text())
        shutil.rmtree(out, ignore_errors=True)
        ns = float(summary["ns_per_particle_step"])
        self.log(f"  {processes} x mpm run {config} --set {' --set '.join(sets)}: {ns:.1f} ns")
        return ns, summary

    def yardstick(self, dim):
        """The yardstick's executable, built once (None where g++ or its source is missing)."""
        if dim in self.yardsticks:
            return self.yardsticks[dim]
        src = REFKERNEL_2D if dim == 2 else REFKERNEL_3D
        exe = self.tmp / f"refkernel{dim}d"
        if not src.exists() or not shutil.which("g++"):
            print(f"benchmarks.py: no yardstick in {dim}D ({src} or g++ missing)", file=sys.stderr)
            self.yardsticks[dim] = None
        else:
            run(["g++", "-O3", "-march=native", "-DNDEBUG", str(src), "-o", str(exe)])
            self.yardsticks[dim] = str(exe)
        return self.yardsticks[dim]

    def run_yardstick(self, dim, cells, steps):
        exe = self.yardstick(dim)
        if exe is None:
            return None
        per_cell = 9 if dim == 2 else 8
        out = run([exe, str(cells), str(per_cell), str(steps)])
        ns = number(r"ns_per_particle_step ([0-9.]+)", out, "the yardstick's figure")
        self.log(f"  yardstick {dim}D {cells} cells: {ns:.1f} ns")
        return ns


# ---------------------------------------------------------------------------------------------
# Formatting


def med(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def fmt_ns(values):
    values = [v for v in values if v is not None]
    if not values:
        return "-"
    m = statistics.median(values)
    digits = 0 if m >= 1000 else 1
    if len(values) == 1:
        return f"{m:,.{digits}f}"
    return f"{m:,.{digits}f} ({min(values):,.{digits}f}-{max(values):,.{digits}f})"


def fmt_ratio(values, bold=False):
    values = [v for v in values if v is not None]
    if not values:
        return "-"
    m = f"{statistics.median(values):.2f}"
    if bold:
        m = f"**{m}**"
    if len(values) == 1:
        return m
    return f"{m} ({min(values):.2f}-{max(values):.2f})"


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def cpu_name():
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


class Measured:
    """The machine and its load around one table's runs."""

    def __enter__(self):
        self.load0 = os.getloadavg()[0]
        self.t0 = time.monotonic()
        return self

    def __exit__(self, *exc):
        self.load1 = os.getloadavg()[0]
        self.seconds = time.monotonic() - self.t0

    def line(self, runner, what):
        return (f"Measured on {cpu_name()}, {os.cpu_count()} cores; {what}; "
                f"load average {self.load0:.2f} before and {self.load1:.2f} after the runs "
                f"({self.seconds:.0f} s).")


def rounds_text(runner):
    n = runner.rounds
    return f"{n} round{'s' if n != 1 else ''}, each running every row once, one after the other"


# ---------------------------------------------------------------------------------------------
# Tables


def table_steps(rn):
    """One thread, MUSL, lumped mass: ns per particle-step of the steps after the first, and
    the ratio to a run of the yardstick of the same dimension (1D: the 2D one) made just before
    the row's."""
    q = rn.quick
    n2, n3 = (40000, 13824) if q else (1000000, 262144)
    n_recon = 10000 if q else 100000
    steps = 4 if q else 6
    common = ["--threads", 1, "--steps", steps, "--repeats", 1, "--scheme", "musl"]
    b2 = ["--basis", "bspline", "--degree", 2]
    # (dimension, problem, basis, mapping, bench options); options None: the yardstick.
    rows = [
        (1, "vibrating bar", "linear", "direct",
         ["--dim", 1, "--particles", n2, "--basis", "linear"]),
        (1, "vibrating bar", "B-spline 2", "direct", ["--dim", 1, "--particles", n2] + b2),
        (2, "yardstick", "B-spline 2", "direct", None),
        (2, "refkernel", "B-spline 2", "direct",
         ["--dim", 2, "--particles", n2, "--problem", "refkernel"] + b2),
        (2, "plate", "linear", "direct", ["--dim", 2, "--particles", n2, "--basis", "linear"]),
        (2, "plate", "B-spline 2", "direct", ["--dim", 2, "--particles", n2] + b2),
        (2, "plate, particles shuffled, method.sort = never", "B-spline 2", "direct",
         ["--dim", 2, "--particles", n2, "--shuffle", "--sort", "never"] + b2),
        (2, "plate, particles shuffled, method.sort = auto", "B-spline 2", "direct",
         ["--dim", 2, "--particles", n2, "--shuffle", "--sort", "auto"] + b2),
        (2, "plate", "B-spline 3", "direct",
         ["--dim", 2, "--particles", n2, "--basis", "bspline", "--degree", 3]),
        (2, "plate", "uGIMP", "direct", ["--dim", 2, "--particles", n2, "--basis", "ugimp"]),
        (2, "plate", "CPDI", "direct", ["--dim", 2, "--particles", n2, "--basis", "cpdi"]),
        (2, "plate", "DDMPM", "direct", ["--dim", 2, "--particles", n2, "--basis", "ddmpm"]),
        (2, "plate", "P1 triangles", "direct",
         ["--dim", 2, "--particles", n2, "--basis", "p1_triangles"]),
        (2, "plate", "Powell-Sabin", "direct",
         ["--dim", 2, "--particles", n2, "--basis", "powell_sabin"]),
        (2, "plate", "linear", "TLS",
         ["--dim", 2, "--particles", n2, "--basis", "linear", "--mapping", "tls"]),
        (2, "plate", "B-spline 2", "TLS",
         ["--dim", 2, "--particles", n2, "--mapping", "tls"] + b2),
        (2, "plate", "B-spline 2", "MLS",
         ["--dim", 2, "--particles", n_recon, "--mapping", "mls"] + b2),
        (2, "plate", "B-spline 2", "IMLS",
         ["--dim", 2, "--particles", n_recon, "--mapping", "imls"] + b2),
        (3, "yardstick", "B-spline 2", "direct", None),
        (3, "refkernel", "B-spline 2", "direct",
         ["--dim", 3, "--particles", n3, "--problem", "refkernel"] + b2),
        (3, "cube", "linear", "direct", ["--dim", 3, "--particles", n3, "--basis", "linear"]),
        (3, "cube", "B-spline 2", "direct", ["--dim", 3, "--particles", n3] + b2),
        (3, "cube", "B-spline 2", "TLS",
         ["--dim", 3, "--particles", 1728 if q else 110592, "--per-cell", 3, "--mapping", "tls"]
         + b2),
    ]
    # The yardsticks' grids: those of mpm's refkernel problem of the same size.
    cells = {2: round(n2 ** 0.5 / 3), 3: round(n3 ** (1 / 3) / 2)}
    ns = {i: [] for i in range(len(rows))}
    ratio = {i: [] for i in range(len(rows))}
    particles = {}
    yard_rows = {dim: i for i, (dim, _, _, _, opts) in enumerate(rows) if opts is None}
    for r in range(rn.rounds):
        rn.log(f"steps: round {r + 1}")
        for i, (dim, problem, basis, mapping, opts) in enumerate(rows):
            if opts is None:
                continue
            # Each row right after a run of its yardstick: the pair sees the same load.
            ydim = 2 if dim == 1 else dim
            y = rn.run_yardstick(ydim, cells[ydim], steps - 1)
            b = rn.bench(opts + common)
            particles[i] = b["particles"]
            ns[i].append(b["ns_after_first"])
            ratio[i].append(b["ns_after_first"] / y if y else None)
            if ydim in yard_rows:
                ns[yard_rows[ydim]].append(y)
                particles[yard_rows[ydim]] = cells[ydim] ** ydim * (9 if ydim == 2 else 8)
    out = []
    for i, (dim, problem, basis, mapping, opts) in enumerate(rows):
        name = "**yardstick**" if opts is None else (
            "refkernel problem" if problem == "refkernel" else problem)
        out.append([f"{dim}D", name, basis, mapping, f"{particles[i]:,}", fmt_ns(ns[i]),
                    "1" if opts is None else fmt_ratio(ratio[i], bold=(problem == "refkernel"))])
    return table(["dim", "problem", "basis", "mapping", "particles",
                  "ns per particle-step", "/ yardstick"], out), \
        (f"one thread, {steps} steps a run (the {steps - 1} after the first timed), each row's "
         f"run right after one of its yardstick; {rounds_text(rn)}")


def table_stages(rn):
    """One thread, MUSL, lumped mass: where the step's time goes (`mpm bench --stages`), each
    stage's mean ns per particle-step over every step of the run, median over the rounds."""
    q = rn.quick
    n2, n3 = (40000, 13824) if q else (1000000, 262144)
    steps = 4 if q else 6
    common = ["--threads", 1, "--steps", steps, "--repeats", 1, "--scheme", "musl", "--stages"]
    b2 = ["--basis", "bspline", "--degree", 2]
    rows = [
        ("2D refkernel problem", "B-spline 2", ["--dim", 2, "--particles", n2, "--problem",
                                                "refkernel"] + b2),
        ("2D plate", "B-spline 2", ["--dim", 2, "--particles", n2] + b2),
        ("2D plate", "linear", ["--dim", 2, "--particles", n2, "--basis", "linear"]),
        ("3D refkernel problem", "B-spline 2", ["--dim", 3, "--particles", n3, "--problem",
                                                "refkernel"] + b2),
        ("3D cube", "B-spline 2", ["--dim", 3, "--particles", n3] + b2),
    ]
    keys = ("basis", "to_grid", "grid", "gather", "material", "other", "step")
    got = {i: {k: [] for k in keys} for i in range(len(rows))}
    particles = {}
    for r in range(rn.rounds):
        rn.log(f"stages: round {r + 1}")
        for i, (_, _, opts) in enumerate(rows):
            b = rn.bench(opts + common)
            st = b["stages"]
            if st is None:
                raise Failure("mpm bench --stages printed no stages line")
            particles[i] = b["particles"]
            st["gather"] = st["to_particles"] - st["material"]
            for k in keys:
                got[i][k].append(st[k])
    out = []
    for i, (problem, basis, _) in enumerate(rows):
        # The stages' medians; the step's range over the rounds shows the machine's spread.
        cells = [f"{med(got[i][k]):,.1f}" for k in keys[:-1]] + [fmt_ns(got[i]["step"])]
        step = med(got[i]["step"])
        share = (f"{100 * med(got[i]['to_grid']) / step:.0f} / "
                 f"{100 * (med(got[i]['gather']) + med(got[i]['material'])) / step:.0f} %")
        out.append([problem, basis, f"{particles[i]:,}"] + cells[:-1] + [f"**{cells[-1]}**",
                                                                         share])
    return table(["problem", "basis", "particles", "basis (stencils)", "particles to grid",
                  "grid", "grid to particles", "material laws", "other", "step",
                  "to grid / to particles"], out), \
        (f"one thread, {steps} steps a run (every step timed, the first included); "
         f"{rounds_text(rn)}")


def table_threads(rn):
    q = rn.quick
    n2, n3 = (40000, 13824) if q else (1000000, 262144)
    steps = 4 if q else 6
    b2 = ["--basis", "bspline", "--degree", 2]
    small = 50 if q else 200
    rows = [
        ("1D vibrating bar, linear", ["--dim", 1, "--particles", n2, "--basis", "linear"]),
        ("2D refkernel problem, B-spline 2", ["--dim", 2, "--particles", n2,
                                              "--problem", "refkernel"] + b2),
        ("2D plate, B-spline 2", ["--dim", 2, "--particles", n2] + b2),
        ("2D plate, linear, TLS", ["--dim", 2, "--particles", n2, "--basis", "linear",
                                   "--mapping", "tls"]),
        ("3D cube, B-spline 2", ["--dim", 3, "--particles", n3] + b2),
        ("3D refkernel problem, B-spline 2", ["--dim", 3, "--particles", n3,
                                              "--problem", "refkernel"] + b2),
        # Small problems: where a second thread starts to pay (driver/run.hpp sizes the threads
        # of `mpm run` by them).
        ("1D vibrating bar, linear", ["--dim", 1, "--particles", 16000 // (4 if q else 1),
                                      "--basis", "linear", "--steps", small]),
        ("1D vibrating bar, linear", ["--dim", 1, "--particles", 128000 // (4 if q else 1),
                                      "--basis", "linear", "--steps", small]),
        ("2D plate, B-spline 2", ["--dim", 2, "--particles", 4000, "--steps", small] + b2),
        ("2D plate, B-spline 2", ["--dim", 2, "--particles", 16000, "--steps", small] + b2),
    ]
    common = ["--repeats", 1, "--scheme", "musl"]
    rows = [(name, opts if "--steps" in opts else opts + ["--steps", steps])
            for name, opts in rows]
    one = {i: [] for i in range(len(rows))}
    two = {i: [] for i in range(len(rows))}
    particles = {}
    for r in range(rn.rounds):
        rn.log(f"threads: round {r + 1}")
        for i, (_, opts) in enumerate(rows):
            a = rn.bench(opts + common + ["--threads", 1])
            b = rn.bench(opts + common + ["--threads", 2])
            one[i].append(a["ns_after_first"])
            two[i].append(b["ns_after_first"])
            particles[i] = a["particles"]
    out = []
    for i, (name, _) in enumerate(rows):
        out.append([name, f"{particles[i]:,}", fmt_ns(one[i]), fmt_ns(two[i]),
                    fmt_ratio([x / y for x, y in zip(one[i], two[i])], bold=True)])
    return table(["problem", "particles", "1 thread [ns per particle-step]", "2 threads",
                  "speed-up (1 thread / 2 threads)"], out), \
        (f"MUSL, direct mapping unless named, {steps} steps a run ({small} for the four smallest "
         f"problems; the steps after the first timed), one and two threads alternating; "
         f"{rounds_text(rn)}")


# The communication model (BENCHMARKS.md, "Processes"): a cluster's alpha [s] and beta [B/s].
ALPHA, BETA = 2e-6, 10e9


def sig(x):
    """Three significant digits, without an exponent."""
    return f"{x:,.0f}" if x >= 100 else f"{float(f'{x:.3g}'):g}"


def model_rows(ns2, ns3, shm):
    """Predicted parallel efficiency of the decomposition (direct mapping, MUSL, quadratic
    B-splines: p = 2 layers of shared DOFs), per step, for slabs and for blocks:
      compute      particles per process x one-thread ns per particle-step;
      halo         two exchanges a step, alpha a message, the shared DOFs' 1 + 2 Dim doubles a
                   step over beta. Slabs: both neighbours (four where a slab is one cell layer:
                   the stencils reach two slabs each side), p (n + p)^(Dim - 1) DOFs each.
                   Blocks of b cells a side: the 3^Dim - 1 blocks around one, a face p (b + p)^(Dim
                   - 1) DOFs, an edge p^2 (b + p), a corner p^Dim (the intersections of the DOF
                   boxes, state/dof_sharing.hpp);
      collectives  14 reductions of a few values on a fixed tree, log2(N) alpha each, one
                   all-gather of each process's DOF range and box (2 + 2 Dim values),
                   log2(N) alpha + 8 (2 + 2 Dim) N / beta, and the migration's message to each
                   neighbour, alpha each;
      efficiency   compute / (compute + halo + collectives),
    with a cluster's alpha and beta (ALPHA, BETA) and with those measured here between two
    processes over shared memory (`shm`: alpha [s], beta [B/s], from `mpm bench --messages`)."""
    p = 2
    cases = [("2D, 4,096^2 cells, 9 particles a cell", 2, 4096, 9, ns2,
              [(64, None), (1024, None), (4096, None), (4096, 64), (16384, 128)]),
             ("3D, 512^3 cells, 8 particles a cell", 3, 512, 8, ns3,
              [(64, None), (512, None), (512, 8), (4096, 16), (32768, 32)])]

    def cost(dim, n, procs, per_axis, alpha, beta):
        if per_axis is None:  # slabs
            layers = n / procs
            neighbours = 2 if layers >= p else 4
            dofs = neighbours * p * (n + p) ** (dim - 1)
        else:
            b = n // per_axis
            neighbours = 3 ** dim - 1
            faces = 2 * dim * p * (b + p) ** (dim - 1)
            edges = (12 * p * p * (b + p)) if dim == 3 else 0
            corners = 2 ** dim * p ** dim
            dofs = faces + edges + corners
        halo = 2 * neighbours * alpha + 2 * dofs * (1 + 2 * dim) * 8 / beta
        lg = math.log2(procs)
        coll = 14 * lg * alpha + (lg * alpha + 8 * (2 + 2 * dim) * procs / beta) + \
            neighbours * alpha
        return halo, coll

    out = []
    for name, dim, n, per_cell, ns, counts in cases:
        total = n ** dim * per_cell
        for i, (procs, per_axis) in enumerate(counts):
            compute = total / procs * ns * 1e-9
            halo, coll = cost(dim, n, procs, per_axis, ALPHA, BETA)
            eff = compute / (compute + halo + coll)
            h2, c2 = cost(dim, n, procs, per_axis, *shm)
            eff_shm = compute / (compute + h2 + c2)
            label = f"{name}, {total / 1e6:,.0f} M particles ({ns:,.0f} ns per particle-step)" \
                if i == 0 else ""
            shape = "slabs" if per_axis is None else \
                " x ".join([str(per_axis)] * dim) + f" blocks of {n // per_axis}^{dim} cells"
            out.append([label, f"{procs:,}", shape, f"{total / procs / 1e6:,.3g} M",
                        sig(compute * 1e3), sig(halo * 1e3), sig(coll * 1e3),
                        f"**{eff:.3f}**", f"{eff_shm:.3f}"])
    return table(["problem", "processes", "decomposition", "particles per process",
                  "compute [ms per step]", "halo [ms]", "collectives [ms]",
                  "predicted efficiency (cluster)", "with this machine's shared memory"], out)


def messages(rn):
    """alpha [s] and beta [B/s] between two processes over shared memory (`mpm bench
    --messages` under mpirun)."""
    env = dict(MPIRUN_ENV)
    env["OMP_NUM_THREADS"] = "1"
    out = run(["mpirun", "-n", "2", rn.mpm, "bench", "--messages", "--repeats", "5"], env=env)
    alpha = number(r"alpha = ([0-9.]+) us", out, "alpha of mpm bench --messages") * 1e-6
    beta = number(r"beta = ([0-9.]+) GB/s", out, "beta of mpm bench --messages") * 1e9
    rn.log(f"  mpm bench --messages: alpha {alpha * 1e6:.2f} us, beta {beta / 1e9:.2f} GB/s")
    return alpha, beta


def table_processes(rn):
    if not shutil.which("mpirun"):
        raise Failure("mpirun not found: the processes table needs Open MPI")
    q = rn.quick
    off = ["output.frames=0", "output.csv=false", "output.vtk=false"]
    problems = [
        ("2D plate, B-spline 2", "examples/plate_mms_2d.toml",
         [f"grid.cells={50 if q else 200}", "time.end=4e-4"] + off),
        ("3D cube, B-spline 2", "examples/cube_mms_3d.toml",
         [f"grid.cells={12 if q else 36}", "time.dt=1e-5", "time.end=2e-4"] + off),
    ]
    variants = [(1, 1), (1, 2), (2, 1)]  # (processes, threads each)
    figs = {(i, v): [] for i in range(len(problems)) for v in variants}
    peak = {(i, v): [] for i in range(len(problems)) for v in variants}
    particles = {}
    costs = []  # (alpha, beta) of each round
    for r in range(rn.rounds):
        rn.log(f"processes: round {r + 1}")
        costs.append(messages(rn))
        for i, (_, config, sets) in enumerate(problems):
            for procs, threads in variants:
                ns, summary = rn.mpm_run(config, sets, threads, procs)
                figs[(i, (procs, threads))].append(ns)
                particles[i] = int(summary["particles"])
                mpi = summary.get("mpi") or {}
                per_process = mpi.get("peak_memory_bytes_per_process") or \
                    [summary.get("peak_memory_bytes")]
                if None not in per_process:
                    peak[(i, (procs, threads))].append(max(per_process) / 1e6)
    out = []
    for i, (name, _, _) in enumerate(problems):
        a, b, c = (figs[(i, v)] for v in variants)
        m1, m2 = med(peak[(i, (1, 1))]), med(peak[(i, (2, 1))])
        memory = f"{m1:,.0f} / {m2:,.0f}" if m1 and m2 else "-"
        out.append([name, f"{particles[i]:,}", fmt_ns(a), fmt_ns(b), fmt_ns(c),
                    fmt_ratio([x / z for x, z in zip(a, c)], bold=True),
                    fmt_ratio([y / z for y, z in zip(b, c)]), memory])
    measured = table(["problem", "particles", "1 process, 1 thread [ns per particle-step]",
                      "1 process, 2 threads", "2 processes, 1 thread each",
                      "speed-up of 2 processes", "2 threads / 2 processes",
                      "peak memory per process [MB], 1 / 2 processes"], out)
    alphas, betas = [c[0] for c in costs], [c[1] for c in costs]
    shm = (med(alphas), med(betas))
    model = model_rows(med(figs[(0, (1, 1))]), med(figs[(1, (1, 1))]), shm)
    model += (f"\n\nThis machine's shared memory, `mpirun -n 2 build/mpm bench --messages "
              f"--repeats 5` once a round: alpha = {shm[0] * 1e6:.2f} us a message "
              f"({min(alphas) * 1e6:.2f}-{max(alphas) * 1e6:.2f}), beta = {shm[1] / 1e9:.2f} GB/s "
              f"({min(betas) / 1e9:.2f}-{max(betas) / 1e9:.2f}), medians of the rounds, with the "
              f"measured runs' Open MPI settings (`MPIRUN_ENV`: shared memory without a single-"
              f"copy mechanism, so a large message is copied twice; two processes alone, where "
              f"many processes of one node share its memory bandwidth). The "
              f"cluster: alpha = {ALPHA * 1e6:g} us, beta = {BETA / 1e9:g} GB/s.")
    what = (f"2D 40 steps, 3D 20 steps (`ns_per_particle_step` of rank 0's summary.json, the "
            f"first step included), the three variants alternating; {rounds_text(rn)}")
    return measured, what, model


def table_memory(rn):
    q = rn.quick
    n2, n3 = (40000, 13824) if q else (1000000, 1000000)
    b2 = ["--basis", "bspline", "--degree", 2]
    rows = [
        ("1D vibrating bar", "linear, direct",
         ["--dim", 1, "--particles", n2, "--basis", "linear"]),
        ("2D plate", "linear, direct", ["--dim", 2, "--particles", n2, "--basis", "linear"]),
        ("2D plate", "B-spline 2, direct", ["--dim", 2, "--particles", n2] + b2),
        ("2D plate", "linear, TLS", ["--dim", 2, "--particles", n2, "--basis", "linear",
                                     "--mapping", "tls"]),
        ("3D cube", "linear, direct", ["--dim", 3, "--particles", n3, "--basis", "linear"]),
        ("3D cube", "B-spline 2, direct", ["--dim", 3, "--particles", n3] + b2),
    ]
    out = []
    for name, method, opts in rows:
        b = rn.bench(opts + ["--steps", 3, "--repeats", 1, "--threads", 1])
        sort = "-" if b["sort_bytes"] is None else f"{b['sort_bytes']:.1f}"
        sorts = "-" if b["sorts"] is None else str(b["sorts"])
        peak = "-" if b["peak_bytes"] is None else f"**{b['peak_bytes']:,.1f}**"
        out.append([name, method, f"{b['particles']:,}", f"{b['bytes']:,.1f}", sort, sorts,
                    peak])
    return table(["problem", "basis, mapping", "particles",
                  "counted: state, stencil, grid share [bytes per particle]",
                  "counted: sort buffers", "re-sorts in the run",
                  "measured: peak resident memory / particles"], out), \
        "one thread, 3 steps, one run a row"


def table_tls(rn):
    q = rn.quick
    n = 10000 if q else 100000
    steps = 10 if q else 30
    end = "2e-3" if q else "1e-2"
    bases = [("linear (P1)", ["--basis", "linear"], "method.basis=linear"),
             ("B-spline 2", ["--basis", "bspline", "--degree", 2], "method.basis=bspline")]
    small_variants = ("direct", "tls")
    large_variants = ("direct", "tls", "adjoint")
    small = {(i, m): [] for i in range(len(bases)) for m in small_variants}
    large = {(i, m): [] for i in range(len(bases)) for m in large_variants}
    npart = {}
    off = ["output.frames=0", "output.csv=false", "output.vtk=false", "grid.cells=32",
           f"time.end={end}"]
    mapping = {"direct": ["method.mapping=direct"], "tls": ["method.mapping=tls"],
               "adjoint": ["method.mapping=tls", "method.tls_strain_rate=adjoint"]}
    for r in range(rn.rounds):
        rn.log(f"tls: round {r + 1}")
        for i, (_, opts, key) in enumerate(bases):
            for m in small_variants:
                b = rn.bench(["--dim", 2, "--particles", n, "--steps", steps, "--repeats", 1,
                              "--threads", 1, "--mapping", m] + opts)
                small[(i, m)].append(b["ns_after_first"])
                npart["small"] = b["particles"]
            for m in large_variants:
                ns, summary = rn.mpm_run("examples/plate_mms_2d.toml",
                                         off + [key] + mapping[m], threads=1)
                large[(i, m)].append(ns)
                npart["large"] = int(summary["particles"])
    out = []
    for i, (name, _, _) in enumerate(bases):
        d, t = small[(i, "direct")], small[(i, "tls")]
        out.append([name, "small (A = 1e-3 m)", f"{npart['small']:,}", fmt_ns(d), fmt_ns(t),
                    fmt_ratio([y / x for x, y in zip(d, t)], bold=True), "-", "-"])
        d, t, a = large[(i, "direct")], large[(i, "tls")], large[(i, "adjoint")]
        out.append([name, "large (A = 0.1 m)", f"{npart['large']:,}", fmt_ns(d), fmt_ns(t),
                    fmt_ratio([y / x for x, y in zip(d, t)], bold=True), fmt_ns(a),
                    fmt_ratio([y / x for x, y in zip(d, a)])])
    return table(["basis", "deformation", "particles", "direct [ns per particle-step]", "TLS",
                  "TLS / direct", "TLS, adjoint rate", "adjoint / direct"], out), \
        (f"one thread, MUSL, the variants alternating; small: `mpm bench`, {steps} steps (the "
         f"{steps - 1} after the first timed); large: `mpm run`, {end} s (the first step "
         f"included); {rounds_text(rn)}")


# ---------------------------------------------------------------------------------------------


def render(name, rn):
    with Measured() as m:
        result = {"steps": table_steps, "stages": table_stages, "threads": table_threads,
                  "processes": table_processes,
                  "memory": table_memory, "tls": table_tls}[name](rn)
    text = result[0] + "\n\n" + m.line(rn, result[1])
    # The 1-minute load average counts this table's own runs (one thread, or two): above the
    # cores, other work shared them.
    load, cores = max(m.load0, m.load1), os.cpu_count() or 1
    if name in ("threads", "processes") and load > cores + 0.5:
        text += (" **The second core was not free:** other work kept the machine busy during "
                 "these runs, so the speed-ups measure that contention, not mpm's scaling; "
                 "regenerate the table on an idle machine.")
    elif name != "memory" and load > cores:
        text += (" **Measured under load:** other work shared the cores, so the absolute ns "
                 "figures are inflated and vary between rounds; the ratios, taken between "
                 "neighbouring runs, are what compares.")
    if len(result) > 2:  # the processes' model, computed from the measured one-thread step
        text += ("\n\nModel (computed, not measured; the formulas: `model_rows` in "
                 "scripts/benchmarks.py):\n\n" + result[2])
    return text


def update(path, name, text):
    begin = f"<!-- BEGIN benchmarks.py --table {name} -->"
    end = f"<!-- END benchmarks.py --table {name} -->"
    doc = path.read_text()
    i, j = doc.find(begin), doc.find(end)
    if i < 0 or j < i:
        raise Failure(f"{path} has no block {begin} ... {end}")
    path.write_text(doc[:i + len(begin)] + "\n" + text + "\n" + doc[j:])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mpm", default=str(ROOT / "build" / "mpm"),
                    help="the mpm executable (default: build/mpm of this tree)")
    ap.add_argument("--table", action="append", choices=TABLES + ("all",),
                    help="a table to regenerate (repeatable; default: all)")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of alternated runs (default 3)")
    ap.add_argument("--quick", action="store_true",
                    help="small problems, one round: checks the script, not the page's figures")
    ap.add_argument("--update", metavar="FILE",
                    help="replace the tables' blocks in FILE (e.g. BENCHMARKS.md)")
    ap.add_argument("-v", "--verbose", action="store_true", help="print each run's figure")
    args = ap.parse_args()
    if not os.access(args.mpm, os.X_OK):
        ap.error(f"{args.mpm} is not an executable (--mpm)")
    if args.rounds < 1:
        ap.error("--rounds must be at least 1")
    names = TABLES if not args.table or "all" in args.table else tuple(dict.fromkeys(args.table))
    rn = Runner(args)
    try:
        for name in names:
            t0 = time.monotonic()
            text = render(name, rn)
            print(f"## {name}\n\n{text}\n", flush=True)
            rn.log(f"{name}: {time.monotonic() - t0:.0f} s")
            if args.update:
                update(pathlib.Path(args.update), name, text)
    except Failure as e:
        print(f"benchmarks.py: {e}", file=sys.stderr)
        return 1
    finally:
        shutil.rmtree(rn.tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
