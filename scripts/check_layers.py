#!/usr/bin/env python3
"""Checks that includes in src/ only go down the total order of folders of docs/architecture.md.

The folders of src/ are in one order, lowest first (LAYERS); a file may include project headers
of its own folder or of a lower one, never of a higher one (neither up nor sideways: no two
folders share a level, so no two can include each other). A folder that is not in LAYERS is an
error too, so a new folder has to be given its place. Exit 0 when the graph is clean, 1 with one
line per include against the order (file:line, the include, both folders), 2 on usage errors.

Usage: python3 scripts/check_layers.py [--root REPO]
"""
import argparse
import pathlib
import re
import sys

# Lowest first (docs/architecture.md, "Layers"), with what each holds.
LAYERS = [
    ("core", "types, errors and exit codes, processes, deterministic loops, input files"),
    ("mpm", "the build's generated headers (version, stepper units)"),
    ("grid", "the uniform grid, triangle meshes, grid quantities"),
    ("particles", "the particles' struct of arrays, material state, permutations"),
    ("material", "constitutive laws"),
    ("model", "a problem: body, loads, conditions, exact solution"),
    ("basis", "shape functions and their stencils, quadrature rules"),
    ("solver", "linear solvers and mass matrices"),
    ("state", "a run's state: model, grid and solver state, distribution; re-sorting"),
    ("parallel", "slabs, migration, ghosts, distributed multigrid"),
    ("mapping", "particle-to-grid mappings: direct and the reconstructions"),
    ("scheme", "the shared stages and the update schemes"),
    ("methods", "the method kinds (bases, mappings), OTM and the ULFEM reference"),
    ("setup", "configuration, keys, registry, settings"),
    ("benchmarks", "the built-in problems"),
    ("io", "output writers and checkpoints"),
    ("driver", "the run: time loop, outputs, steppers"),
    ("app", "the commands"),
    ("python", "the Python module's native part (pybind11)"),
]
LEVEL = {folder: i for i, (folder, _) in enumerate(LAYERS)}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def check(root: pathlib.Path) -> list[str]:
    src = root / "src"
    if not src.is_dir():
        raise SystemExit(f"check_layers: no src/ under {root}")
    problems = []
    for path in sorted(src.rglob("*")):
        if path.suffix not in (".hpp", ".cpp", ".in") or not path.is_file():
            continue
        rel = path.relative_to(root)
        folder = path.relative_to(src).parts[0]
        if folder not in LEVEL:
            problems.append(f"{rel}: folder src/{folder} has no place in the order (add it to "
                            "LAYERS in scripts/check_layers.py and to docs/architecture.md)")
            continue
        level = LEVEL[folder]
        for lineno, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            if "@" in m.group(1):  # a configure_file placeholder (driver/stepper_kind.cpp.in)
                continue
            target = m.group(1).split("/")[0]
            if target not in LEVEL:
                problems.append(f"{rel}:{lineno}: includes \"{m.group(1)}\" from a folder with "
                                "no place in the order")
                continue
            if LEVEL[target] > level:
                problems.append(f"{rel}:{lineno}: includes \"{m.group(1)}\": {folder} "
                                f"(level {level}) must not include {target} (level "
                                f"{LEVEL[target]}), a higher folder")
    return problems


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=str(pathlib.Path(__file__).resolve().parent.parent),
                    help="repository root (default: the one holding this script)")
    args = ap.parse_args()
    problems = check(pathlib.Path(args.root))
    for p in problems:
        print(p)
    if problems:
        print(f"check_layers: {len(problems)} include(s) against the order of folders")
        return 1
    print("check_layers: every include goes down the order of folders")
    return 0


if __name__ == "__main__":
    sys.exit(main())
