"""The driver of the full report: runs the sections in order and writes verification.md with
its header (templates/header.md), or with --only splices regenerated sections into the existing
report. The order of the sections is given by scripts/verify.py."""
import os
import re
import shutil
import sys
import time

from .common import ROOT, VERDICT_RULES
from .template import render


def full(R, args, steps):
    """The report into args.out (default docs/): every section of `steps`, [(label,
    function(R, ctx) -> Markdown)], in order; with args.only the named ones alone."""
    t0 = time.time()
    out = os.path.abspath(args.out or os.path.join(ROOT, "docs"))
    figdir = os.path.join(out, "figures")
    if not args.only:
        shutil.rmtree(figdir, ignore_errors=True)  # from scratch: no stale figures
    os.makedirs(figdir, exist_ok=True)
    # ctx collects the figures directory and the measured values that later sections (the
    # "Against the published figures" table) reuse.
    ctx = {"out": out, "figdir": figdir}
    parts = []
    if args.only:
        return regenerate_only(R, ctx, steps, args.only)
    for label, fn in steps:
        t = time.time()
        parts.append(fn(R, ctx))
        print(f"verify: {label} ({time.time() - t:.0f} s)", flush=True)
    wall = time.time() - t0
    cmd = "/usr/bin/python3 scripts/verify.py" + (" --long" if args.long else "")
    header = render("header", "header", cmd=cmd, wall=wall, jobs=args.jobs, cores=os.cpu_count(),
                    date=time.strftime('%Y-%m-%d', time.gmtime()), VERDICT_RULES=VERDICT_RULES)
    with open(os.path.join(out, "verification.md"), "w") as f:
        f.write(header + "\n".join(p.rstrip() + "\n" for p in parts))
    print(f"verify: wrote {os.path.join(out, 'verification.md')} in {wall:.0f} s")
    return 0


def splice_section(doc, text):
    """doc with the section whose heading is text's first line replaced by text: up to the
    heading of the same or a higher level that follows as many such headings as text has."""
    lines, new = doc.split("\n"), text.rstrip().split("\n")
    level = len(new[0]) - len(new[0].lstrip("#"))
    if level == 0 or new[0] not in lines:
        sys.exit(f"verify.py --only: the section heading {new[0]!r} is not in the report: "
                 "regenerate the whole report")
    heading = re.compile(r"^#{1,%d} " % level)
    own = sum(1 for line in new if heading.match(line))
    start = lines.index(new[0])
    seen, end = 0, len(lines)
    for k in range(start, len(lines)):
        if heading.match(lines[k]):
            seen += 1
            if seen > own:
                end = k
                break
    return "\n".join(lines[:start] + new + [""] + lines[end:])


def regenerate_only(R, ctx, steps, labels):
    """--only: the named sections computed afresh and put in place of theirs in the existing
    report, which then names them in its header (the rest stays from the last full run)."""
    path = os.path.join(ctx["out"], "verification.md")
    with open(path) as f:
        doc = f.read()
    chosen = [(label, fn) for label, fn in steps if label in labels]
    missing = [label for label in labels if label not in [c[0] for c in chosen]]
    if missing:
        sys.exit(f"verify.py --only: no section {missing}; the sections: "
                 + "; ".join(label for label, _ in steps))
    for label, fn in chosen:
        t = time.time()
        doc = splice_section(doc, fn(R, ctx))
        print(f"verify: {label} ({time.time() - t:.0f} s)", flush=True)
    note = "Sections regenerated alone since (`--only`): "
    today = time.strftime('%Y-%m-%d', time.gmtime())
    lines = doc.split("\n")
    old = [k for k, line in enumerate(lines) if line.startswith(note)]
    # One entry per section, with the date of its latest regeneration.
    entries = {}
    if old:
        for item in lines[old[0]][len(note):].rstrip(".").split("; "):
            label, _, date = item.rpartition(" (")
            entries[label] = date.rstrip(")")
    for label, _ in chosen:
        entries.pop(label, None)
        entries[label] = today
    done = "; ".join(f"{label} ({date})" for label, date in entries.items())
    if old:
        lines[old[0]] = note + done + "."
    else:
        at = next(k for k, line in enumerate(lines) if line.startswith("Measured with this"))
        lines[at:at] = [note + done + ".", ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))
    print(f"verify: updated {path}")
    return 0
