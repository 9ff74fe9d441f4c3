"""`verify.py --quick`: the coarse convergence guard of the test suite. Each check is a short
refinement study whose least-squares order must reach its threshold; prints one line per check
and returns 1 (GUARD FAILED) when one is below. Writes nothing into docs/ and needs no
matplotlib."""
import time

from .common import col, ls_order


QUICK_CHECKS = [
    # (label, example, refine, methods, sets, error column, threshold on the LS order)
    ("vibrating bar, P1 direct lumped, u (published 2)", "vibrating_bar_small",
     "grid.cells=5,10,20", "linear/direct/lumped", [], "displacement_rms", 1.8),
    ("vibrating bar, BSMPM-TLS consistent, u (published 3)", "vibrating_bar_small",
     "grid.cells=5,10,20", "bspline2/tls/consistent", [], "displacement_rms", 2.5),
    ("mms_1d, MPM+IMLS, u (published 2)", "mms_1d", "grid.cells=16,32,64", "linear/imls", [],
     "displacement_rms", 1.8),
    ("plate_mms_2d, A = 1e-4, P1 lumped, u (expected 2)", "plate_mms_2d", "grid.cells=8,16",
     "linear/direct/lumped", ["mms.amplitude=1e-4", "time.end=1e-3"], "displacement_rms", 1.8),
]


def quick(runner, scale):
    """The checks of QUICK_CHECKS with thresholds times `scale`; 0 when all pass, else 1."""
    t0 = time.time()
    failed = 0
    print(f"verify --quick: observed orders (least squares over the sizes) against thresholds"
          f"{'' if scale == 1 else f' x {scale}'}")
    for label, example, refine, methods, sets, err, thr in QUICK_CHECKS:
        _, rows = runner.study(example, refine, methods, sets)
        rs = list(rows.values())[0]
        order = ls_order(col(rs, "h"), col(rs, err))
        bad = any(r["status"] != "ok" for r in rs)
        ok = order is not None and not bad and order >= thr * scale
        failed += not ok
        print(f"  {'ok  ' if ok else 'FAIL'} {label}: {refine}, order "
              f"{'-' if order is None else f'{order:.2f}'} >= {thr * scale:.2f}")
    print(f"verify --quick: {len(QUICK_CHECKS) - failed}/{len(QUICK_CHECKS)} passed in "
          f"{time.time() - t0:.1f} s")
    if failed:
        print(f"GUARD FAILED: {failed} observed order(s) below threshold")
        return 1
    return 0
