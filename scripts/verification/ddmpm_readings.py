"""D 2.6.4 leaves two things of DDMPM open, and D's tables one thing of the conservation
errors: how DDMPM's integrals over Omega are evaluated (method.ddmpm_integrals: the particles
or exact quadrature over the cells that hold them), and whether a table's error is the largest
over the steps or that of the final step (summary.json's max_rel_* and final_rel_*). Both
readings of each, on D's large bar and column, against D's figures. Prose:
templates/ddmpm_readings.md."""
import math

from .common import CLOSE_FACTOR, e, pub, reproduced, src, verdict_value
from .template import render

READINGS = ("particles", "quadrature")
MAPPINGS = {"direct": "direct", "CS": "cubic_spline", "TLS": "tls"}


def _score(verdicts):
    """(reproduced, close) counts of a list of verdicts."""
    return (sum(1 for v in verdicts if reproduced(v)),
            sum(1 for v in verdicts if v.startswith("close")))


def sec_ddmpm_readings(R, ctx):
    """DDMPM's integrals in both readings (large bar factors, column errors), and the column's
    and the bar's conservation errors in both measures."""
    dd = ["method.basis=ddmpm"]
    # Large bar: MPM (direct, lumped) is the base of D 5.4.1's reduction factors.
    large_specs = [("vibrating_bar_large", ["method.basis=linear"], 1)]
    large_keys = [None]
    for rd in READINGS:
        for mp in ("TLS", "CS"):
            for mass in ("lumped", "consistent"):
                large_keys.append((rd, mp, mass))
                large_specs.append(("vibrating_bar_large", dd + [
                    f"method.ddmpm_integrals={rd}", f"method.mapping={MAPPINGS[mp]}",
                    f"method.mass={mass}"], 1))
    column_keys, column_specs = [], []
    for rd in READINGS:
        for mp in MAPPINGS:
            column_keys.append((rd, mp))
            column_specs.append(("column_compaction", dd + [
                f"method.ddmpm_integrals={rd}", f"method.mapping={MAPPINGS[mp]}"], 0))
    # The conservation measures: the column with CS for the three bases of D Table 5.7.
    bases = {"MPM": ["method.basis=linear"], "DDMPM": dd,
             "DDMPM (quadrature)": dd + ["method.ddmpm_integrals=quadrature"],
             "BSMPM": ["method.basis=bspline", "method.degree=2"]}
    cons_specs = [("column_compaction", bases[b] + ["method.mapping=cubic_spline"], 0)
                  for b in bases]
    bar_specs = [("vibrating_bar_small", bases[b] + ["method.mapping=cubic_spline",
                                                     "grid.cells=40"], 0) for b in bases]
    res = R.many(large_specs + column_specs + cons_specs + bar_specs)
    n1, n2, n3 = len(large_specs), len(column_specs), len(cons_specs)
    large = dict(zip(large_keys, res[:n1]))
    column = dict(zip(column_keys, res[n1:n1 + n2]))
    cons = dict(zip(bases, res[n1 + n2:n1 + n2 + n3]))
    bar = dict(zip(bases, res[n1 + n2 + n3:]))

    base = large[None]["errors"].get("stress_rel_l2")
    rows, score = [], {}
    for rd in READINGS:
        verdicts = []
        cells = []
        for mp in ("TLS", "CS"):
            for mass in ("lumped", "consistent"):
                x = large[(rd, mp, mass)]["errors"].get("stress_rel_l2")
                f = base / x if base and x else None
                v = verdict_value(f, "large_factor_DDMPM_" + mp, factor=True)
                verdicts.append(v)
                cells.append(f"{f:.2f}x ({v.split(':')[0]})" if f else "-")
        col_direct = column[(rd, "direct")]["errors"].get("stress_rel_l2")
        col_tls = column[(rd, "TLS")]["errors"].get("stress_rel_l2")
        col_cs_mass = column[(rd, "CS")]["conservation"].get("max_rel_mass_error")
        for x, key in ((col_direct, "column_ddmpm_error"), (col_tls, "column_ddmpm_tls_error"),
                       (col_cs_mass, "column_cs_mass_DDMPM")):
            v = verdict_value(x, key, roundoff=key.endswith("mass_DDMPM"))
            verdicts.append(v)
            cells.append(f"{e(x, 3)} ({v.split(':')[0]})")
        score[rd] = _score(verdicts) + (len(verdicts),)
        rows.append(f"| {rd} | " + " | ".join(cells) + " |")
    published = ("| D | " + " | ".join(
        [f"{pub('large_factor_DDMPM_' + mp)}x" for mp in ("TLS", "CS") for _ in range(2)] +
        [e(pub("column_ddmpm_error"), 3), e(pub("column_ddmpm_tls_error"), 3),
         e(pub("column_cs_mass_DDMPM"), 3)]) + " |")
    rep = {rd: score[rd][0] + score[rd][1] for rd in READINGS}
    best = max(READINGS, key=lambda r: rep[r])
    other = [r for r in READINGS if r != best][0]
    which = (f"the {best} reading is reproduced or close (within a factor "
             f"{CLOSE_FACTOR:g}) for {rep[best]} of D's {score[best][2]} figures, the {other} "
             f"reading for {rep[other]}")
    # The column's direct-mapping DDMPM error: the one figure that sides with the other reading.
    col_direct = {rd: column[(rd, "direct")]["errors"].get("stress_rel_l2") for rd in READINGS}
    nearer = min(READINGS, key=lambda rd: abs(math.log(col_direct[rd] / pub("column_ddmpm_error")))
                 if col_direct[rd] else math.inf)

    # Conservation: the largest over the steps against the final step.
    crow = []
    for b in bases:
        c = cons[b]["conservation"]
        for key, label in (("momentum", "momentum"), ("mass", "mass")):
            pkey = f"column_cs_{key}_{b.split(' ')[0]}"
            mx, fin = c.get(f"max_rel_{key}_error"), c.get(f"final_rel_{key}_error")
            vmx, vfin = verdict_value(mx, pkey, True), verdict_value(fin, pkey, True)
            crow.append(f"| column, {b}-CS, {label} ({src(pkey)}) | {e(pub(pkey), 3)} | "
                        f"{e(mx, 3)} ({vmx.split(':')[0]}) | {e(fin, 3)} ({vfin.split(':')[0]}) |")
    for b in bases:
        c = bar[b]["conservation"]
        pkey = f"bar_cs_momentum_{b.split(' ')[0]}"
        mx, fin = c.get("max_rel_momentum_error"), c.get("final_rel_momentum_error")
        vmx, vfin = verdict_value(mx, pkey, True), verdict_value(fin, pkey, True)
        crow.append(f"| bar (40 cells), {b}-CS, momentum ({src(pkey)}) | {e(pub(pkey), 3)} | "
                    f"{e(mx, 3)} ({vmx.split(':')[0]}) | {e(fin, 3)} ({vfin.split(':')[0]}) |")
    # Which measure reproduces D where the other does not.
    final_only, max_only = [], []
    for b in bases:
        for key in ("momentum", "mass"):
            pkey = f"column_cs_{key}_{b.split(' ')[0]}"
            c = cons[b]["conservation"]
            vmx = verdict_value(c.get(f"max_rel_{key}_error"), pkey, True)
            vfin = verdict_value(c.get(f"final_rel_{key}_error"), pkey, True)
            if reproduced(vfin) and not reproduced(vmx):
                final_only.append(f"{b}-CS {key}")
            if reproduced(vmx) and not reproduced(vfin):
                max_only.append(f"{b}-CS {key}")
    ctx.update(ddmpm_readings_score=score)
    return render("ddmpm_readings", "section", table_rows="\n".join(rows),
                  published_row=published, which=which, conservation_rows="\n".join(crow),
                  nearer=nearer, subpoints=(
                      " D's Table 5.8 lowers that figure by adding subpoints to the particles "
                      "(Dhakal and Zhang), which suggests particle sums in D's plain DDMPM and a "
                      "finer quadrature where D reconstructs." if nearer == "particles" else ""),
                  col_direct_particles=e(col_direct["particles"], 3),
                  col_direct_quadrature=e(col_direct["quadrature"], 3),
                  col_direct_pub=e(pub("column_ddmpm_error"), 3),
                  final_only=", ".join(final_only) or "none",
                  max_only=", ".join(max_only) or "none")
