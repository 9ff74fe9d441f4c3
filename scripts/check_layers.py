#!/usr/bin/env python3
"""Checks that includes in src/ only go down the layers of docs/architecture.md.

Each folder of src/ belongs to one layer; a file may include project headers of its own layer
or of a lower one, never of a higher one. A folder that is not in LAYERS is an error too, so a
new folder has to be given its place. Exit 0 when the graph is clean, 1 with one line per upward
include (file:line, the include, both layers), 2 on usage errors.

Usage: python3 scripts/check_layers.py [--root REPO]
"""
import argparse
import pathlib
import re
import sys

# Lowest first (docs/architecture.md, "Layers").
LAYERS = [
    ("ground", ["core", "mpm"]),  # mpm/: the generated version header (build tree)
    ("model", ["grid", "particles", "material", "model"]),
    ("numerics", ["basis", "mapping", "scheme", "solver"]),
    ("set-up", ["setup", "benchmarks"]),
    ("output", ["io"]),
    ("driver", ["driver"]),
    ("commands", ["app"]),
]
LEVEL = {folder: (i, name) for i, (name, folders) in enumerate(LAYERS) for folder in folders}
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
            problems.append(f"{rel}: folder src/{folder} has no layer (add it to LAYERS in "
                            "scripts/check_layers.py and to docs/architecture.md)")
            continue
        level, name = LEVEL[folder]
        for lineno, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            if "@" in m.group(1):  # a configure_file placeholder (driver/stepper_kind.cpp.in)
                continue
            target = m.group(1).split("/")[0]
            if target not in LEVEL:
                problems.append(f"{rel}:{lineno}: includes \"{m.group(1)}\" from a folder with "
                                "no layer")
                continue
            tlevel, tname = LEVEL[target]
            if tlevel > level:
                problems.append(f"{rel}:{lineno}: includes \"{m.group(1)}\": {folder} ({name}) "
                                f"must not include {target} ({tname}), a higher layer")
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
        print(f"check_layers: {len(problems)} include(s) against the layers")
        return 1
    print("check_layers: every include goes down the layers")
    return 0


if __name__ == "__main__":
    sys.exit(main())
