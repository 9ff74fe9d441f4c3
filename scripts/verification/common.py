"""What every section uses: the repository's paths, the published figures (PUBLISHED) and the
rules that judge a measurement against them (VERDICT_RULES, verdict_*), the number formats of
the report (e, num, o), orders of convergence, and reading a run's particles.

The verdict column of the report follows VERDICT_RULES (templates/verdict_rules.md, filled with
the tolerances below)."""
import csv
import glob
import math
import os
import re

from .template import render

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPTS = os.path.join(ROOT, "scripts")
EX = os.path.join(ROOT, "examples")

# Published figures: key -> (source, value). Values are the documents' own numbers.
PUBLISHED = {
    "otm_bsmpm_order": ("D 4.6.1, Fig. 4.7", 3.0),
    "otm_p1_order": ("D 4.6.1, Fig. 4.7", 2.0),
    "otm_maxent_time_32": ("D Table 4.1", 16.22),
    "otm_maxent_time_512": ("D Table 4.1", 6.96),
    "otm_bsmpm_time_32": ("D Table 4.1", 1.00),
    "otm_p1_time_32": ("D Table 4.1", 1.12),
    "otm_unified_time_32": ("D Table 4.1", 1.23),
    "otm_unified_time_512": ("D Table 4.1", 1.15),
    "otm_p1_time_512": ("D Table 4.1", 1.04),
    "otm_otmmaxent_time_32": ("D Table 4.1", 26.04),
    "otm_otmmaxent_time_512": ("D Table 4.1", 9.07),
    "otm_bsmpm_time_512": ("D Table 4.1", 1.11),
    "bar_order_u": ("D 5.4.1, Fig. 5.9a", 2.0),
    "bar_order_v": ("D 5.4.1, Fig. 5.9a", 2.0),
    "bar_order_sigma": ("D 5.4.1, Fig. 5.9a", 1.0),
    "bar_direct_mass": ("D 5.4", 1e-15),
    "bar_tls_mass": ("D Table 5.3", 7.5e-15),
    "bar_tls_momentum": ("D Table 5.3", 2.1e-16),
    "bar_cs_mass_MPM": ("D Table 5.3", 2.3825e-12),
    "bar_cs_mass_DDMPM": ("D Table 5.3", 3.9211e-13),
    "bar_cs_mass_BSMPM": ("D Table 5.3", 7.3896e-15),
    "bar_cs_momentum_MPM": ("D Table 5.3", 3.7e-6),
    "bar_cs_momentum_DDMPM": ("D Table 5.3", 3.7e-6),
    "bar_cs_momentum_BSMPM": ("D Table 5.3", 1.8e-6),
    "bar_tls_u_factor": ("D Fig. 5.9a", 1.7),
    "bar_bstls_order_u": ("D Fig. 5.9c", 3.0),
    "bar_bstls_order_v": ("D Fig. 5.9c", 3.0),
    "bar_bstls_order_sigma": ("D Fig. 5.9c", 3.0),
    "large_tls_mass": ("D Table 5.5", 2.9e-14),
    "large_tls_momentum": ("D Table 5.5", 5.8e-15),
    "large_cs_mass_MPM": ("D Table 5.5", 8.21e-5),
    "large_cs_mass_DDMPM": ("D Table 5.5", 3.59e-5),
    "large_cs_mass_BSMPM": ("D Table 5.5", 7.39e-7),
    "large_factor_BSMPM_TLS": ("D 5.4.1", 9.9),
    "large_factor_DDMPM_TLS": ("D 5.4.1", 7.8),
    "large_factor_BSMPM_CS": ("D 5.4.1", 13.5),
    "large_factor_DDMPM_CS": ("D 5.4.1", 8.9),
    "column_bsmpm_factor": ("D 5.4.2, Table 5.6", 10.0),
    "column_mpm_crossings": ("D 5.4.2", 180),
    "column_ddmpm_error": ("D Table 5.6", 4.4555e-2),
    "column_tls_mass": ("D Table 5.7", 1.05e-12),
    "column_tls_momentum": ("D Table 5.7", 5.6e-13),
    "column_cs_mass_MPM": ("D Table 5.7", 3.08e-6),
    "column_cs_mass_DDMPM": ("D Table 5.7", 4.76e-7),
    "column_cs_mass_BSMPM": ("D Table 5.7", 1.51e-9),
    "column_cs_momentum_MPM": ("D Table 5.7", 3.5e-6),
    "column_cs_momentum_DDMPM": ("D Table 5.7", 2.0403e-6),
    "column_cs_momentum_BSMPM": ("D Table 5.7", 1.4039e-7),
    # D Table 5.8 gives DDMPM with 2 subpoints, 3.4086e-2, and its ratio to DDMPM-TLS, 4.9518.
    "column_ddmpm_tls_error": ("D Table 5.8", 3.4086e-2 / 4.9518),
    "tls2d_rms": ("D 6.2.1", 6.17e-3),
    "tls2d_integral": ("D 6.2.1", 6.66e-16),
    "tlstri_rms": ("D 6.2.2", 1.80e-3),
    "tls2d_order_1": ("D Fig. 6.6", 1.0),
    "tls2d_order_3": ("D Fig. 6.6", 2.0),
    "tls2d_order_6": ("D Fig. 6.6", 3.0),
    "mms_imls_order": ("003 Fig. 6", 2.0),
    "mms_cpdi_order": ("003 Fig. 5", 2.0),
    "plate_tls_mass": ("D Table 6.1", 7.3e-13),
}

FACTOR_TOL = 1.25   # a value is reproduced within this factor of the published one
CLOSE_FACTOR = 2.0  # ... and close (same size, not the same number) within this factor
ORDER_TOL = 0.3     # an order is reproduced within this distance of the published one
CLOSE_ORDER = 0.6   # ... and close within this distance
ROUNDOFF = 1e-11    # relative conservation errors below this are round-off (accumulated
                    # over the thousands of steps of a run)
VERDICT_RULES = render("verdict_rules", "rules", FACTOR_TOL=FACTOR_TOL, ORDER_TOL=ORDER_TOL,
                       ROUNDOFF=ROUNDOFF, CLOSE_FACTOR=CLOSE_FACTOR, CLOSE_ORDER=CLOSE_ORDER)


def e(x, d=2):
    """Compact scientific notation (None -> '-')."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{d}e}"


def num(x):
    """A measured or published number in a verdict: 3 significant digits."""
    if x is None or not math.isfinite(x):
        return "-"
    return f"{x:.3g}" if 1e-2 <= abs(x) < 1e4 else f"{x:.2e}"


def pub(key):
    """The published value of PUBLISHED[key]."""
    return PUBLISHED[key][1]


def src(key):
    """The source (document, section) of PUBLISHED[key]."""
    return PUBLISHED[key][0]


def verdict_value(measured, key, roundoff=False, factor=False):
    """factor: the value is an error-reduction factor (published > 1). Then *close* also needs
    the measured reduction to be at least half the published one on a log scale
    (log measured >= log published / 2): a factor of 1.0 against a published 1.7 is no
    reduction at all, although it lies within CLOSE_FACTOR."""
    p = pub(key)
    if measured is None:
        return f"differs: no measurement (run failed) vs published {num(p)}"
    if measured > 0 and 1 / FACTOR_TOL <= measured / p <= FACTOR_TOL:
        return "reproduced"
    if roundoff and measured < ROUNDOFF and p < ROUNDOFF:
        return "reproduced (both round-off)"
    close = measured > 0 and 1 / CLOSE_FACTOR <= measured / p <= CLOSE_FACTOR
    if factor and p > 1 and close:
        close = math.log(measured) >= 0.5 * math.log(p)
    word = "close" if close else "differs"
    return f"{word}: measured {num(measured)} vs published {num(p)}"


def verdict_order(measured, key):
    """An observed order against the published PUBLISHED[key] (ORDER_TOL, CLOSE_ORDER)."""
    p = pub(key)
    if measured is None or not math.isfinite(measured):
        return f"differs: no order measured vs published {p:.1f}"
    if abs(measured - p) <= ORDER_TOL:
        return "reproduced"
    word = "close" if abs(measured - p) <= CLOSE_ORDER else "differs"
    return f"{word}: measured {measured:.2f} vs published {p:.1f}"


def verdict_claim(ok, measured_text):
    """A qualitative claim: reproduced when ok, else what was measured."""
    return "reproduced" if ok else f"differs: measured {measured_text}"


def reproduced(v):
    """Whether a verdict says reproduced."""
    return v.startswith("reproduced")


def ratio_range(xs):
    """'7' or '6-7' for a list of ratios (rounded)."""
    lo, hi = round(min(xs)), round(max(xs))
    return f"{lo}" if lo == hi else f"{lo}-{hi}"


def ls_order(hs, es):
    """Least-squares slope of log e against log h over the series (None if undefined)."""
    pts = [(math.log(h), math.log(x)) for h, x in zip(hs, es)
           if h and x is not None and h > 0 and x > 0]
    if len(pts) < 2 or len(pts) < len(hs):
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx > 0 else None


def pair_orders(hs, es):
    """Observed orders between successive sizes (None first and where undefined)."""
    out = [None]
    for k in range(1, len(hs)):
        a, b = es[k - 1], es[k]
        out.append(math.log(a / b) / math.log(hs[k - 1] / hs[k])
                   if a and b and a > 0 and b > 0 else None)
    return out


def o(x):
    """An order with two decimals ('' for None)."""
    return "" if x is None else f"{x:.2f}"


def col(rows, key):
    """The column `key` of study rows."""
    return [r.get(key) for r in rows]


def last_frame(run_dir):
    """The particles of a run's last particles_*.csv as dicts of floats (None without one)."""
    files = sorted(glob.glob(os.path.join(run_dir, "particles_*.csv")))
    if not files:
        return None
    with open(files[-1], newline="") as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def total_variation(parts, key):
    """Total variation of `key` over the particles sorted by initial position x0_1."""
    ps = sorted(parts, key=lambda r: r["x0_1"])
    return sum(abs(ps[k][key] - ps[k - 1][key]) for k in range(1, len(ps)))


def fail_time(failure):
    """The time t of a failure message "step N, t = T s: ..." ("?" when absent)."""
    m = re.search(r"t = ([0-9.eE+-]+) s", failure or "")
    return m.group(1) if m else "?"


def fig_md(ctx, paths, caption, ext=".png"):
    """Markdown image links relative to the report (PNG shown, SVG alongside), each captioned
    with `caption` and what the file shows (from its name)."""
    what = {"convergence_": "convergence of ", "stress_profile": "stress at the final time "
            "(finest run of each method)", "conservation_mapping": "the mapping's relative mass "
            "and momentum errors in every step (finest run of each method)",
            "conservation": "total energy over time (finest run of each method)"}
    out = []
    for p in (p for p in paths if p.endswith(ext)):
        stem = os.path.splitext(os.path.basename(p))[0]
        label = next((v + stem[len(k):] if k.endswith("_") else v for k, v in what.items()
                      if stem.startswith(k)), "")
        rel = os.path.relpath(os.path.join(ROOT, p), ctx["out"])
        out.append(f"![{caption}{': ' + label if label else ''}]({rel})")
    return "\n".join(out) + "\n" if out else ""
