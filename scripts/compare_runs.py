#!/usr/bin/python3
"""Before/after comparison of mpm runs: proves a restructuring is behaviour-preserving.

A restructuring (refactoring, new dispatch, moved code, build changes) must leave every output
bit for bit as it was. This script runs the same set of configurations with two executables,
each into its own output tree, and compares the outputs bitwise:

  - particle frames (particles_*.csv, particles_*.vtu), particles.pvd, grid.vtu, history.csv,
    config.toml and any other file a run writes: byte-identical;
  - summary.json: identical after removing the timing fields (TIMING_FIELDS below);
  - exit code, stdout and stderr of every invocation: identical (input errors and failing runs
    must be rejected / fail the same way, with the same outputs);
  - checkpoint.bin: only with --checkpoints (its format may legitimately change);
  - config.toml: not with --skip-config, for a change that adds keys or changes a default's
    spelling (the echo of the effective configuration then differs on every run while the
    results must not).

With --rtol R the numbers in the outputs are compared to round-off instead of bitwise, for a
change that may alter the last bits (another instruction set, a vector kernel, a reordered
sum): every other character of a text (CSV, summary.json, .pvd, stdout, stderr, ASCII VTU) and
every integer array of a binary VTU must still match exactly, and two numbers a, b agree when
|a - b| <= R x scale or both are at most --atol in magnitude (default 1e-12: quantities that
are round-off themselves, such as conservation errors). The scale is the largest magnitude of
the field (CSV: the columns of one field's components, stress_11 ... stress_22, together) or of
the array (binary VTU), else of the pair (summary.json, an ASCII VTU, any other text). Each case
that agrees prints its largest relative difference and where it is. Some outputs move by more
than round-off under any such change, and differ here: the place of a maximum among equal
candidates (mls.worst_x), sums that cancel to round-off (a symmetric body's total momentum; set
--atol above them), and the states of runs that fail.

The configurations: every examples/*.toml (long ones shortened by a time.end override that is a
whole multiple of their time.dt); a 1D (mms_1d) and a 2D (plate_mms_2d, 8 x 8 cells) matrix of
every basis x mapping x scheme with lumped mass, plus consistent mass on a subset; further
method options, failing runs (each non-zero exit code) and input errors; checkpoint/restart
chains. --quick runs a reduced set (one scheme per basis x mapping) in well under a minute.

Usage (from anywhere; paths printed are relative to the work tree):

    /usr/bin/python3 scripts/compare_runs.py --before OLD/mpm --after NEW/mpm \
        [--work DIR] [--jobs N] [--quick] [--checkpoints] [--skip-config] [--rtol R [--atol A]]

Each executable runs with OMP_NUM_THREADS=1, OMP_WAIT_POLICY=passive, argv[0] = "mpm" and its
working directory at WORK/before or WORK/after, which hold identical copies of examples/, so
file names recorded in the outputs (config.toml origins, messages) are the same on both sides.
--work defaults to a new temporary directory, removed when everything is the same; with --work
DIR, DIR/before and DIR/after are replaced. Prints one line per case and a closing line
"N same, M differ"; exits 0 when every case is the same, 1 otherwise, 2 on usage errors.
"""

import argparse
import array
import concurrent.futures
import decimal
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

try:
    import tomllib  # Python >= 3.11
except ImportError:  # pragma: no cover
    tomllib = None

REPO = Path(__file__).resolve().parent.parent

# summary.json fields that are measurements (wall clock, memory), removed before comparing. They
# are the only non-deterministic fields of summary.json (make_summary and run_mpm in the
# sources): the wall time of the run, the step time per particle-step and the peak resident
# memory. Everything else (counts such as "sorts", errors, conservation, TLS/MLS totals, failure
# messages) must match bit for bit.
TIMING_FIELDS = ("wall_seconds", "ns_per_particle_step", "peak_memory_bytes")

# Files compared only with --checkpoints.
CHECKPOINT_FILES = ("checkpoint.bin",)

# Examples that take longer than about 5 s at full length: steps kept (time.end = steps * dt).
# None today: the slowest, plate_tls_2d (120 steps), takes 3.6 s alone on one core of the
# 2-core reference machine (Release build), about 7 s while the other runs share the cores.
EXAMPLE_STEPS = {}
QUICK_EXAMPLE_STEPS = 40  # --quick: every example at most this many steps

BASES_1D = ["linear", "ugimp", "cpgimp", "cpdi", "ddmpm"] + [f"bspline{k}" for k in range(1, 6)]
BASES_2D = ["linear", "ugimp", "cpgimp", "cpdi", "cpdi2", "ddmpm"] + [
    f"bspline{k}" for k in range(1, 6)
]
MAPPINGS_1D = ["direct", "cubic_spline", "tls", "mls", "imls"]
MAPPINGS_2D = ["direct", "tls", "mls", "imls"]
SCHEMES = ["usl", "usf", "musl", "usavg"]

# The matrix problems: example, time.dt (None: the example's), steps (default, --quick), further
# overrides. Long enough for particles to cross cells (grid_crossings > 0 in summary.json):
# mms_1d moves them by up to 0.06 m = 0.95 h in 200 steps, the 8 x 8 plate with dt = 5e-5 s by
# up to 0.08 m = 0.65 h in 60 steps.
MATRIX_1D = ("mms_1d", None, (200, 60), ["output.frames=2"])
MATRIX_2D = ("plate_mms_2d", "5e-05", (60, 20), ["grid.cells=8", "output.frames=2"])

ENV = dict(os.environ, OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive", LC_ALL="C")
RUN_TIMEOUT_S = 600


def example_dt(name):
    """time.dt of examples/NAME.toml, as written (a string)."""
    text = (REPO / "examples" / f"{name}.toml").read_text()
    if tomllib is not None:
        return repr(float(tomllib.loads(text)["time"]["dt"]))
    section = None
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line.startswith("["):
            section = line.strip("[]").strip()
        elif section == "time" and line.split("=", 1)[0].strip() == "dt":
            return line.split("=", 1)[1].strip()
    raise SystemExit(f"compare_runs: no time.dt in examples/{name}.toml")


def end_after(name, steps, dt=None):
    """time.end = steps * time.dt (default: the example's), in decimal: a whole multiple."""
    end = decimal.Decimal(dt or example_dt(name)) * steps
    return repr(float(end))


def basis_sets(basis):
    if basis.startswith("bspline"):
        return ["method.basis=bspline", f"method.degree={basis[len('bspline'):]}"]
    return [f"method.basis={basis}"]


def sets(values):
    args = []
    for v in values:
        args += ["--set", v]
    return args


class Case:
    """A named sequence of steps writing under the case directory WORK/SIDE/NAME: ("mpm",
    [args...]), an invocation in WORK/SIDE with outputs in NAME/..., or ("snapshot", src, dst),
    a copy of NAME/src to NAME/dst. The whole case directory is compared."""

    def __init__(self, name, steps):
        self.name = name
        self.steps = steps


def run_case(name, config, overrides):
    args = ["run", config, "--out", f"{name}/out", "--quiet"] + sets(overrides)
    return Case(name, [("mpm", args)])


def build_cases(quick):
    cases = []
    examples = sorted(p.stem for p in (REPO / "examples").glob("*.toml"))

    # 1. Every example (long ones shortened; every frame series still written).
    for ex in examples:
        over = []
        steps = QUICK_EXAMPLE_STEPS if quick else EXAMPLE_STEPS.get(ex)
        if steps is not None:
            over = [f"time.end={end_after(ex, steps)}", "output.frames=4"]
        cases.append(run_case(f"ex/{ex}", f"examples/{ex}.toml", over))

    # 2. basis x mapping x scheme (x mass) in 1D and 2D.
    def matrix_base(spec, quick):
        ex, dt, steps, extra = spec
        n = steps[1] if quick else steps[0]
        return extra + ([f"time.dt={dt}"] if dt else []) + [f"time.end={end_after(ex, n, dt)}"]

    for dim, bases, mappings, spec in (
        (1, BASES_1D, MAPPINGS_1D, MATRIX_1D),
        (2, BASES_2D, MAPPINGS_2D, MATRIX_2D),
    ):
        ex, base = spec[0], matrix_base(spec, quick)
        for i, basis in enumerate(bases):
            for j, mapping in enumerate(mappings):
                rotated = SCHEMES[(i + j) % len(SCHEMES)]  # one scheme, all schemes covered
                combos = [(rotated, "lumped")] if quick else (
                    [(s, "lumped") for s in SCHEMES] + [(rotated, "consistent")])
                for scheme, mass in combos:
                    over = base + basis_sets(basis) + [f"method.mapping={mapping}",
                                                       f"method.scheme={scheme}",
                                                       f"method.mass={mass}"]
                    cases.append(run_case(f"{dim}d/{basis}-{mapping}-{scheme}-{mass}",
                                          f"examples/{ex}.toml", over))
    if not quick:
        # Consistent mass with every scheme on two representative combinations.
        for dim, spec, basis, mapping in ((1, MATRIX_1D, "bspline2", "tls"),
                                          (2, MATRIX_2D, "linear", "direct")):
            ex = spec[0]
            for scheme in SCHEMES:
                name = f"{dim}d/{basis}-{mapping}-{scheme}-consistent"
                if any(c.name == name for c in cases):
                    continue
                over = matrix_base(spec, quick) + basis_sets(basis) + [
                    f"method.mapping={mapping}", f"method.scheme={scheme}",
                    "method.mass=consistent"]
                cases.append(run_case(name, f"examples/{ex}.toml", over))

    # Further options, failing runs and input errors (short runs).
    e1 = f"time.end={end_after('mms_1d', 60)}"
    e2 = f"time.end={end_after('plate_mms_2d', 12)}"
    p2 = ["grid.cells=8", "output.frames=2", e2]
    extras = [
        ("extra/1d-tls-reduce", "mms_1d",
         [e1, "method.mapping=tls", "method.tls_completion=reduce"]),
        ("extra/1d-tls-neighbour-2terms", "mms_1d",
         [e1, "method.mapping=tls", "method.tls_completion=neighbour", "method.tls_terms=2"]),
        ("extra/1d-mls2-gauss3", "mms_1d",
         [e1, "method.mapping=mls", "method.mls_degree=2", "method.gauss_points=3",
          "method.mls_dilation=2.5"]),
        ("extra/1d-imls2", "mms_1d", [e1, "method.mapping=imls", "method.mls_degree=2"]),
        ("extra/1d-ulfem", "vibrating_bar_large",
         [f"time.end={end_after('vibrating_bar_large', 100)}", "method.solver=ulfem"]),
        ("extra/1d-history-csv-only", "traction_bar",
         [f"time.end={end_after('traction_bar', 200)}", "output.vtk=false",
          "output.history_every=7", "output.frames=3"]),
        ("extra/1d-vtk-only", "column_compaction",
         [f"time.end={end_after('column_compaction', 200)}", "output.csv=false",
          "output.frames=0"]),
        ("extra/2d-tls-reduce-3terms", "plate_mms_2d",
         p2 + ["method.mapping=tls", "method.tls_completion=reduce", "method.tls_terms=3"]),
        ("extra/2d-tls-neighbour", "plate_mms_2d",
         p2 + ["method.mapping=tls", "method.tls_completion=neighbour", "method.basis=cpdi2"]),
        ("extra/2d-mls2", "plate_mms_2d", p2 + ["method.mapping=mls", "method.mls_degree=2"]),
        ("extra/2d-sort-never", "plate_mms_2d", p2 + ["method.sort=never"]),
        ("extra/2d-custom-pressure-cells_y", "custom_plate_2d",
         [f"time.end={end_after('custom_plate_2d', 60)}", "grid.cells_y=12",
          'pressure.top="1e3*min(t/0.01, 1)"', 'traction.top=["1e2*t", "0"]',
          "boundary.right=free", "method.basis=ugimp"]),
        # Failing runs: each failure exit code (README), outputs up to the failure included.
        ("fail/3-nonfinite-2d", "plate_mms_2d",
         ["mms.amplitude=2", f"time.end={end_after('plate_mms_2d', 200)}", "output.frames=4"]),
        ("fail/4-left-grid", "custom_bar",
         ['loading.body_force="1e5"', f"time.end={end_after('custom_bar', 500)}"]),
        ("fail/5-det-f", "custom_bar",
         ['initial.velocity="-20000*x"', "material.model=elastic_1d_large",
          f"time.end={end_after('custom_bar', 100)}"]),
        ("fail/6-tls-none", "mms_1d",
         [f"time.end={end_after('mms_1d', 50)}", "method.mapping=tls",
          "method.tls_completion=none"]),
        # Input errors: rejected before the first step, identically.
        ("input/unknown-key", "mms_1d", ["grid.cell=3"]),
        ("input/out-of-range", "mms_1d", ["method.degree=6"]),
        ("input/bad-choice", "mms_1d", ["method.basis=quadratic"]),
        ("input/cubic_spline-2d", "plate_mms_2d", p2 + ["method.mapping=cubic_spline"]),
        ("input/cpdi2-1d", "mms_1d", [e1, "method.basis=cpdi2"]),
        ("input/imls-consistent", "mms_1d", [e1, "method.mapping=imls", "method.mass=consistent"]),
        ("input/bad-expression", "custom_bar", ['initial.velocity="sin(x"']),
        ("input/unstable-dt", "mms_1d", ["time.dt=1e-3", "time.end=0.01"]),
    ]
    if quick:
        extras = [e for e in extras if not e[0].startswith("extra/")]
    for name, ex, over in extras:
        cases.append(run_case(name, f"examples/{ex}.toml", over))

    # 3. Checkpoint and restart chains: the first leg is kept as a snapshot, the second leg
    # continues into the same folder (or another one with --out), a mismatching restart is
    # rejected.
    def restart_case(name, ex, over, first, every, second, config_again=False, other_out=False,
                     reject=False):
        leg1 = over + [f"time.end={end_after(ex, first)}", f"output.checkpoint_every={every}",
                       "output.frames=4"]
        first_leg = ["run", f"examples/{ex}.toml", "--out", f"{name}/out", "--quiet"] + sets(leg1)
        steps = [("mpm", first_leg), ("snapshot", "out", "leg1")]
        args = ["run"] + ([f"examples/{ex}.toml"] + sets(over) if config_again else [])
        args += ["--restart", f"{name}/out/checkpoint.bin", "--quiet",
                 "--set", f"time.end={end_after(ex, second)}"]
        if other_out:
            args += ["--out", f"{name}/out2"]
        steps.append(("mpm", args))
        if reject:
            steps.append(("mpm", ["run", "--restart", f"{name}/out/checkpoint.bin", "--quiet",
                                  "--set", "grid.cells=10", "--out", f"{name}/rejected"]))
        return Case(name, steps)

    cases.append(restart_case("restart/1d-bspline2-tls-consistent", "mms_1d",
                              ["method.basis=bspline", "method.mapping=tls",
                               "method.mass=consistent"],
                              40, 20, 80, reject=True))
    cases.append(restart_case("restart/2d-cpdi2-mls-usf", "plate_mms_2d",
                              ["grid.cells=8", "method.basis=cpdi2", "method.mapping=mls",
                               "method.scheme=usf"], 20, 10, 30))
    if not quick:
        # Restart from a checkpoint before the end of the first leg (steps 40..50 run again).
        cases.append(restart_case("restart/1d-large-ulfem-ref-config-again", "vibrating_bar_large",
                                  ["method.basis=cpdi", "method.mapping=cubic_spline"],
                                  50, 20, 100, config_again=True, other_out=True))
        cases.append(restart_case("restart/2d-bspline3-direct-usavg", "plate_mms_2d",
                                  ["grid.cells=8", "method.basis=bspline", "method.degree=3",
                                   "method.scheme=usavg"], 20, 10, 40, other_out=True))
    return cases


class Outcome:
    def __init__(self):
        self.results = []  # per "mpm" step: (returncode, stdout bytes, stderr bytes)
        self.seconds = 0.0


def execute(binary, side_root, case):
    """Runs one case with one executable; returns an Outcome."""
    out = Outcome()
    t0 = time.monotonic()
    case_dir = side_root / case.name
    for step in case.steps:
        if step[0] == "snapshot":
            src, dst = case_dir / step[1], case_dir / step[2]
            if src.is_dir():
                shutil.copytree(src, dst)
            continue
        try:
            p = subprocess.run(["mpm"] + step[1], executable=binary, cwd=side_root, env=ENV,
                               stdin=subprocess.DEVNULL, capture_output=True,
                               timeout=RUN_TIMEOUT_S)
            out.results.append((p.returncode, p.stdout, p.stderr))
        except subprocess.TimeoutExpired as e:
            out.results.append((f"timeout after {RUN_TIMEOUT_S} s", e.stdout or b"",
                                e.stderr or b""))
        except OSError as e:
            out.results.append((f"cannot execute: {e.strerror}", b"", b""))
    out.seconds = time.monotonic() - t0
    return out


def short(b, n=120):
    s = b.decode("utf-8", "replace") if isinstance(b, bytes) else str(b)
    return repr(s if len(s) <= n else s[:n] + "...")


def excerpts(x, y, before=30, after=60):
    """The two strings around their first differing character."""
    x, y = (v.decode("utf-8", "replace") for v in (x, y))
    k = next((i for i, (a, b) in enumerate(zip(x, y)) if a != b), min(len(x), len(y)))
    lo = max(0, k - before)

    def cut(v):
        return repr(("..." if lo else "") + v[lo:k + after] + ("..." if len(v) > k + after else ""))

    return f"before {cut(x)} | after {cut(y)}"


def first_line_difference(a, b, csv=False):
    la, lb = a.split(b"\n"), b.split(b"\n")
    for k in range(max(len(la), len(lb))):
        x = la[k] if k < len(la) else None
        y = lb[k] if k < len(lb) else None
        if x == y:
            continue
        if x is None or y is None:
            side, text = ("after", y) if x is None else ("before", x)
            return f"line {k + 1}: only {side} has it: {short(text)}"
        if csv and k > 0:
            header = la[0].split(b",")
            fx, fy = x.split(b","), y.split(b",")
            for c in range(min(len(fx), len(fy))):
                if fx[c] != fy[c]:
                    col = header[c].decode("utf-8", "replace") if c < len(header) else f"#{c + 1}"
                    return (f"line {k + 1}, column {col}: before {short(fx[c])} | "
                            f"after {short(fy[c])}")
        return f"line {k + 1}: {excerpts(x, y)}"
    return "no line differs (line endings?)"


def bytes_difference(a, b):
    n = min(len(a), len(b))
    k = next((i for i in range(n) if a[i] != b[i]), n)
    return f"byte {k} differs (sizes {len(a)} and {len(b)})"


def load_summary(data):
    """summary.json as nested (key, value) pair lists, numbers kept as their exact text."""
    return json.loads(data, object_pairs_hook=lambda pairs: ("{}", pairs),
                      parse_float=lambda s: ("num", s), parse_int=lambda s: ("num", s),
                      parse_constant=lambda s: ("num", s))


def first_json_difference(a, b, path="", agree=None):
    if isinstance(a, tuple) and isinstance(b, tuple) and a[0] == b[0] == "{}":
        ka, kb = [k for k, _ in a[1]], [k for k, _ in b[1]]
        if ka != kb:
            return f"{path or 'top level'}: keys {ka} | {kb}"
        for (k, va), (_, vb) in zip(a[1], b[1]):
            d = first_json_difference(va, vb, f"{path}.{k}" if path else k, agree)
            if d:
                return d
        return None
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (va, vb) in enumerate(zip(a, b)):
            d = first_json_difference(va, vb, f"{path}[{i}]", agree)
            if d:
                return d
        return None
    if (agree is not None and isinstance(a, tuple) and isinstance(b, tuple)
            and a[0] == b[0] == "num"):
        u, v = float(a[1]), float(b[1])
        return agree.check(u, v, max(abs(u), abs(v)), path)
    if isinstance(a, str) and isinstance(b, str) and agree is not None:
        return text_within(path, a.encode(), b.encode(), agree)
    if a != b:
        fmt = lambda v: v[1] if isinstance(v, tuple) and v[0] == "num" else json.dumps(v)
        return f"{path}: before {short(fmt(a))} | after {short(fmt(b))}"
    return None


# --rtol / --atol (None: bitwise), and per case the largest relative difference accepted.
RTOL = None
ATOL = 1e-12
NUMBER = re.compile(rb"[-+]?(?:(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?|inf|nan)")


class Agreement:
    """The largest relative difference accepted so far, and where."""

    def __init__(self):
        self.largest, self.where = 0.0, ""

    def check(self, a, b, scale, where):
        """None when a and b agree to RTOL x scale (or are both at round-off level), else a
        description."""
        if a == b or (math.isnan(a) and math.isnan(b)):
            return None
        if max(abs(a), abs(b)) <= ATOL:
            return None
        rel = abs(a - b) / scale if scale > 0 and math.isfinite(scale) else math.inf
        if not rel <= RTOL:
            return f"{where}: before {a!r} | after {b!r} (relative difference {rel:.3g} > {RTOL:g})"
        if rel > self.largest:
            self.largest, self.where = rel, where
        return None


def split_numbers(text):
    """The text with every number replaced by a mark, and the numbers."""
    nums = []

    def take(m):
        nums.append(float(m.group(0)))
        return b"\x01"
    return NUMBER.sub(take, text), nums


def text_within(rel, a, b, agree, csv=False):
    """Texts that differ in their numbers only, by at most RTOL: the numbers of a CSV column
    against the column's largest magnitude, the others against the pair's."""
    la, lb = a.split(b"\n"), b.split(b"\n")
    if len(la) != len(lb):
        return f"{rel}: {len(la)} | {len(lb)} lines"
    rows = []
    for k, (x, y) in enumerate(zip(la, lb)):
        fx, fy = (x.split(b","), y.split(b",")) if csv and k > 0 else ([x], [y])
        if len(fx) != len(fy):
            return f"{rel}: line {k + 1}: {len(fx)} | {len(fy)} fields"
        row = []
        for c, (u, v) in enumerate(zip(fx, fy)):
            tu, nu = split_numbers(u)
            tv, nv = split_numbers(v)
            if tu != tv or len(nu) != len(nv):
                return f"{rel}: line {k + 1}: {excerpts(x, y)}"
            row.append((c, nu, nv))
        rows.append((k, row))
    # A CSV column's scale: the components of one field (stress_11 ... stress_22, u_1, u_2)
    # share the field's largest magnitude, since a component that is zero by symmetry differs
    # at the round-off of the others.
    field = []
    if csv:
        field = [re.sub(r"_\d+$", "", n.decode("utf-8", "replace")) for n in la[0].split(b",")]
    field_of = lambda c: field[c] if c < len(field) else str(c)
    scale = {}
    if csv:
        for _, row in rows[1:]:
            for c, nu, nv in row:
                f = field_of(c)
                scale[f] = max([scale.get(f, 0.0)] + [abs(t) for t in nu + nv if math.isfinite(t)])
    for k, row in rows:
        for c, nu, nv in row:
            for u, v in zip(nu, nv):
                sc = scale[field_of(c)] if csv and k > 0 else max(abs(u), abs(v))
                col = f", column {field_of(c)}" + (f" ({la[0].split(b',')[c].decode()})"
                                                   if c < len(field) else "") if csv else ""
                d = agree.check(u, v, sc, f"{rel}: line {k + 1}{col}")
                if d:
                    return d
    return None


VTU_ARRAY = re.compile(rb'<DataArray type="(\w+)" Name="([^"]*)"[^>]*format="appended" offset="(\d+)"')
VTU_TYPES = {b"Float64": "d", b"Int64": "q", b"UInt8": "B"}


def vtu_within(rel, a, b, agree):
    """Binary VTU files (raw appended data, UInt64 headers: io/output.cpp): the same XML, the
    same integer arrays, and each Float64 array within RTOL of its largest magnitude."""
    marker = b'<AppendedData encoding="raw">\n   _'
    ia, ib = a.find(marker), b.find(marker)
    if ia < 0 or ib < 0:
        return text_within(rel, a, b, agree)
    d = text_within(rel, a[:ia], b[:ib], agree)
    if d:
        return d
    ra, rb = a[ia + len(marker):], b[ib + len(marker):]
    for m in VTU_ARRAY.finditer(a[:ia]):
        kind, name, off = m.group(1), m.group(2).decode(), int(m.group(3))
        code = VTU_TYPES.get(kind)
        if code is None:
            return f"{rel}: array {name} of type {kind.decode()} (not compared numerically)"
        values = []
        for raw in (ra, rb):
            n = int.from_bytes(raw[off:off + 8], "little")
            v = array.array(code)
            v.frombytes(raw[off + 8:off + 8 + n])
            values.append(v)
        va, vb = values
        if len(va) != len(vb):
            return f"{rel}: array {name}: {len(va)} | {len(vb)} values"
        if code != "d":
            if va != vb:
                return f"{rel}: integer array {name} differs"
            continue
        scale = max([abs(t) for t in va if math.isfinite(t)] +
                    [abs(t) for t in vb if math.isfinite(t)] + [0.0])
        for k, (u, v) in enumerate(zip(va, vb)):
            d = agree.check(u, v, scale, f"{rel}: array {name}, value {k}")
            if d:
                return d
    return None


def compare_file(rel, a, b, agree=None):
    """None if the files match (bitwise, or to RTOL when set), else a description of the
    first difference."""
    name = rel.name
    if name == "summary.json":
        try:
            ja, jb = load_summary(a), load_summary(b)
        except ValueError:
            ja = jb = None
        if ja is not None and ja[0] == jb[0] == "{}":
            strip = lambda j: ("{}", [(k, v) for k, v in j[1] if k not in TIMING_FIELDS])
            d = first_json_difference(strip(ja), strip(jb), agree=agree)
            return None if d is None else f"{rel}: {d}"
    if a == b:
        return None
    if name in CHECKPOINT_FILES:
        return f"{rel}: {bytes_difference(a, b)}"
    if agree is not None and name.endswith(".vtu"):
        return vtu_within(rel, a, b, agree)
    if b"\0" in a[:4096] or b"\0" in b[:4096]:
        return f"{rel}: {bytes_difference(a, b)}"
    if agree is not None:
        return text_within(rel, a, b, agree, csv=name.endswith(".csv"))
    return f"{rel}: {first_line_difference(a, b, csv=name.endswith('.csv'))}"


def file_order(rel):
    """Frames in time order first, then the other files by name."""
    return (0 if rel.name.startswith("particles_") else 1, str(rel))


SKIP_CONFIG = False  # --skip-config


def compare_trees(before, after, rel_root, checkpoints, agree=None):
    def files(root):
        if not root.is_dir():
            return set()
        # .mpm.lock: the output directory's lock (io::DirectoryLock), holding the run's pid.
        return {p.relative_to(root) for p in root.rglob("*")
                if (p.is_file() or p.is_symlink()) and p.name != ".mpm.lock"}

    fa, fb = files(before), files(after)
    for only, side in ((fa - fb, "before"), (fb - fa, "after")):
        if only:
            first = sorted(only, key=file_order)[0]
            return (f"{rel_root / first}: only in {side} ({len(only)} file(s) missing on the "
                    "other side)")
    for rel in sorted(fa, key=file_order):
        if rel.name in CHECKPOINT_FILES and not checkpoints:
            continue
        if SKIP_CONFIG and rel.name == "config.toml":
            continue
        d = compare_file(rel_root / rel, (before / rel).read_bytes(), (after / rel).read_bytes(),
                         agree)
        if d:
            return d
    return None


def compare_case(case, ob, oa, work, checkpoints, agree=None):
    """None if the case is the same (bitwise, or to RTOL with `agree`), else the first
    difference."""
    for k, ((rb, sob, seb), (ra, soa, sea)) in enumerate(zip(ob.results, oa.results), 1):
        step = f" (invocation {k})" if len(ob.results) > 1 else ""
        if rb != ra:
            return f"exit code {rb} | {ra}{step}; stderr before {short(seb)} | after {short(sea)}"
        for what, x, y in (("stderr", seb, sea), ("stdout", sob, soa)):
            if x == y:
                continue
            if agree is None:
                return f"{what}{step}: {first_line_difference(x, y)}"
            d = text_within(f"{what}{step}", x, y, agree)
            if d:
                return d
    return compare_trees(work / "before" / case.name, work / "after" / case.name,
                         Path(case.name), checkpoints, agree)


def exit_summary(outcome):
    codes = [str(r[0]) for r in outcome.results]
    return "exit " + ",".join(codes)


def executable(parser, path):
    p = Path(path)
    if not p.is_file() or not os.access(p, os.X_OK):
        parser.error(f"not an executable file: {path}")
    return str(p.resolve())


def main():
    parser = argparse.ArgumentParser(
        description="Run the same configurations with two mpm executables and compare the "
        "outputs bitwise, or their numbers to --rtol (timings in summary.json excepted).")
    parser.add_argument("--before", required=True, help="reference mpm executable")
    parser.add_argument("--after", required=True, help="mpm executable under test")
    parser.add_argument("--work", help="work directory (default: a new temporary directory)")
    parser.add_argument("--jobs", type=int, default=2, help="parallel runs (default 2)")
    parser.add_argument("--quick", action="store_true",
                        help="reduced set: one scheme per basis x mapping, short examples")
    parser.add_argument("--checkpoints", action="store_true",
                        help="also compare checkpoint.bin files bytewise")
    parser.add_argument("--skip-config", action="store_true",
                        help="do not compare config.toml (a change that adds keys)")
    parser.add_argument("--rtol", type=float,
                        help="compare the numbers to this relative tolerance instead of bitwise "
                        "(the rest of every text exactly)")
    parser.add_argument("--atol", type=float, default=1e-12,
                        help="with --rtol: numbers both at most this in magnitude agree "
                        "(default 1e-12)")
    args = parser.parse_args()
    global SKIP_CONFIG, RTOL, ATOL
    SKIP_CONFIG = args.skip_config
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    if args.rtol is not None and not 0.0 < args.rtol < 1.0:
        parser.error("--rtol must lie in (0, 1)")
    if args.atol < 0.0:
        parser.error("--atol must not be negative")
    RTOL, ATOL = args.rtol, args.atol
    before = executable(parser, args.before)
    after = executable(parser, args.after)

    if args.work:
        work = Path(args.work)
        if work.exists() and not work.is_dir():
            parser.error(f"--work is not a directory: {args.work}")
        work.mkdir(parents=True, exist_ok=True)
        temporary = False
    else:
        work = Path(tempfile.mkdtemp(prefix="compare_runs."))
        temporary = True
    work = work.resolve()

    cases = build_cases(args.quick)
    for side in ("before", "after"):
        root = work / side
        if root.exists():
            shutil.rmtree(root)
        shutil.copytree(REPO / "examples", root / "examples")

    print(f"compare_runs: {len(cases)} cases, {args.jobs} job(s), before {args.before}, "
          f"after {args.after}", flush=True)
    t0 = time.monotonic()
    same = differ = 0
    slowest = (0.0, "")
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [(c, pool.submit(execute, before, work / "before", c),
                    pool.submit(execute, after, work / "after", c)) for c in cases]
        for case, fb, fa in futures:
            ob, oa = fb.result(), fa.result()
            slowest = max(slowest, (max(ob.seconds, oa.seconds), case.name))
            agree = Agreement() if RTOL is not None else None
            diff = compare_case(case, ob, oa, work, args.checkpoints, agree)
            if diff is None:
                same += 1
                close = ""
                if agree is not None and agree.largest > 0.0:
                    close = f"; largest relative difference {agree.largest:.2g} at {agree.where}"
                print(f"same     {case.name} ({exit_summary(ob)}{close})", flush=True)
            else:
                differ += 1
                print(f"DIFFERS  {case.name}: {diff}", flush=True)
    elapsed = time.monotonic() - t0
    print(f"{elapsed:.1f} s (slowest case {slowest[1]}: {slowest[0]:.1f} s per executable)")
    if temporary and differ == 0:
        shutil.rmtree(work, ignore_errors=True)
    else:
        kept = args.work if args.work else str(work)
        print(f"outputs kept in {os.path.join(kept, 'before')} and {os.path.join(kept, 'after')}")
    print(f"{same} same, {differ} differ")
    return 0 if differ == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
