#!/usr/bin/python3
"""Verification report: regenerates docs/verification.md and docs/figures/ from fresh runs of
build/mpm, with the published figures beside the measured ones and a computed verdict.

    /usr/bin/python3 scripts/verify.py            full report into docs/ (1-3 min on 2 cores)
    /usr/bin/python3 scripts/verify.py --quick    coarse convergence guard (CI): prints each
                                                  observed order against its threshold, writes
                                                  nothing into docs/, exits 1 if one is below
    build/mpm verify [--quick] [--out DIR]        the same, through the command line

Every number in the report that comes from a run is computed from summary.json, study.csv,
particle CSVs or `mpm reconstruct` output. The published figures are data in PUBLISHED (value
and source); the verdict column follows the rules of VERDICT_RULES. Prose explaining a
difference is printed only when the verdict it explains is "differs".

This file is the command line and the order of the report's sections. The sections are in the
package scripts/verification/, one module per section or group of related sections, with their
prose in Markdown templates in scripts/verification/templates/ (the mechanism:
verification/template.py). Beside them: common.py (PUBLISHED, VERDICT_RULES, the verdicts and
number formats), runner.py (running build/mpm), plots.py, quick.py (--quick) and report.py (the
header, writing the report, --only).

Needs only the Python standard library; the plots need matplotlib (Debian: python3-matplotlib,
which /usr/bin/python3 sees). --quick needs no matplotlib.
"""
import argparse
import os
import shutil
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # the package beside this file, however the script is started

from verification import (bases, chapter5, column_collapse, cube, ddmpm_readings,  # noqa: E402
                          dimensions, element_block, footing, item3, large_bar, massmatrix,
                          mesh_boundaries, mms, otm, plate, plate_001, ps_mpm, ps_partial,
                          reconstruction, small_bar, static, tls_robust, unified_ps,
                          vertical_cut, vortex, work_precision)
from verification.common import ROOT  # noqa: E402
from verification.quick import quick  # noqa: E402
from verification.report import full  # noqa: E402
from verification.runner import Runner  # noqa: E402

# The report's sections in order: (label, function(R, ctx) -> Markdown). The label names the
# section in the progress lines and for --only.
SECTIONS = [
    ("small-deformation bar", small_bar.sec_small_bar),
    ("bases", static.sec_bases),
    ("grid crossing", bases.sec_crossing),
    ("column (bases)", bases.sec_column_bases),
    ("traction bar", bases.sec_traction),
    ("boundary error", small_bar.sec_boundary),
    ("reconstructions", reconstruction.sec_reconstruction_intro),
    ("chapter 5 tables", chapter5.sec_chapter5),
    ("against the published figures", chapter5.sec_against_published),
    ("DDMPM's integrals and D's conservation measure", ddmpm_readings.sec_ddmpm_readings),
    ("consistency across dimensions", dimensions.sec_dimensions),
    ("lumped BSMPM on the large bar", large_bar.sec_large_bar_lumping),
    ("the conservative constant of TLS", large_bar.sec_tls_constant),
    ("mms_1d", mms.sec_mms),
    ("bar of D 4.6.1", otm.sec_bar_461),
    ("traction bar of D 4.6.2", otm.sec_traction_462),
    ("plate of D 4.6.3", otm.sec_plate_463),
    ("B-spline mass matrices (004 4.6-4.7)", massmatrix.sec_massmatrix),
    ("2D MLS", static.sec_mls2d),
    ("plate", plate.sec_plate),
    ("plate TLS", plate.sec_plate_tls),
    ("PS-MPM plate (D Fig. 3.9)", ps_mpm.sec_ps_plate),
    ("PS-MPM on unstructured meshes (D Fig. 3.9)", ps_mpm.sec_ps_unstructured),
    ("PS-MPM's stress plateau under refinement", ps_mpm.sec_ps_plateau),
    ("PS-MPM with partially filled elements", ps_partial.sec_ps_partial),
    ("Powell-Sabin splines in the unified approach", unified_ps.sec_unified_ps),
    ("conditions and loads on mesh boundaries", mesh_boundaries.sec_mesh_boundaries),
    ("generalized vortex", vortex.sec_vortex),
    ("robust TLS on the grid's cells", tls_robust.sec_tls_robust),
    ("conservative MLS and IMLS", tls_robust.sec_mls_conservative),
    ("001 long study", plate_001.sec_001),
    ("2D traction and custom", static.sec_traction_2d),
    ("3D cube", cube.sec_cube),
    ("accuracy per unit of cost", work_precision.sec_work_precision),
    ("plane-strain compression of a soil block", element_block.sec_element_block),
    ("strip footing", footing.sec_footing),
    ("vertical cut", vertical_cut.sec_vertical_cut),
    ("granular column collapse", column_collapse.sec_column_collapse),
]
# Appended with --long (hours).
LONG_SECTIONS = [
    ("001 long study (--long)", plate_001.sec_long),
    ("item 3 study at A = 0.05 (--long)", item3.sec_item3),
    ("item 3: one input at a time (--long)", item3.sec_item3_why),
]


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="coarse convergence guard: print orders against thresholds, exit 1 "
                         "if one is below (writes nothing into docs/)")
    ap.add_argument("--threshold-scale", type=float, default=1.0,
                    help="multiply the --quick thresholds (a test uses 10 to prove the guard "
                         "can fail)")
    ap.add_argument("--long", action="store_true",
                    help="also run the 001 plate study at A = 0.1 m, T = 0.2 s, and issue 22 "
                         "item 3's study at A = 0.05 m with every mapping, completion and mass "
                         "(hours)")
    ap.add_argument("--out", help="report directory (default: docs/ of the repository)")
    ap.add_argument("--mpm", default=os.path.join(ROOT, "build", "mpm"),
                    help="the mpm executable (default: %(default)s)")
    ap.add_argument("--jobs", "-j", type=int, default=2, help="parallel runs (default 2)")
    ap.add_argument("--keep", action="store_true", help="keep the run directories")
    ap.add_argument("--only", action="append", metavar="SECTION",
                    help="regenerate only this section of the existing report (its label in "
                         "the progress lines, e.g. \"PS-MPM with partially filled elements\"; "
                         "repeatable); its figures are written afresh, the others kept")
    args = ap.parse_args(argv)
    if not os.path.exists(args.mpm):
        sys.exit(f"verify.py: {args.mpm} not found: build first (bash scripts/build.sh)")
    work = tempfile.mkdtemp(prefix="mpm_verify_")
    R = Runner(os.path.abspath(args.mpm), max(1, args.jobs), work)
    try:
        if args.quick:
            return quick(R, args.threshold_scale)
        return full(R, args, SECTIONS + (LONG_SECTIONS if args.long else []))
    finally:
        if args.keep:
            print(f"verify: run directories kept in {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
