"""The strip footing against Prandtl (sec_footing): examples/footing_2d.toml, a rigid rough
footing pushed into weightless Tresca clay, per basis under refinement, with the load-settlement
curves. Prose: templates/footing.md."""
import csv
import math
import os

from .common import EX, fig_md
from .plots import pyplot, save_figure
from .template import render

PRANDTL = 2.0 + math.pi  # q_u / c_u, plane strain, weightless Tresca soil
C_U = 2000.0             # [Pa], the example's yield_stress / sqrt(3)
HALF_WIDTH = 0.5         # [m], B / 2 of the half model
SPEED = 0.01             # [m/s], the example's prescribed.velocity
SURFACE = 2.5            # [m], the soil's top
BASES = [("linear", ["method.basis=linear"]),
         ("uGIMP", ["method.basis=ugimp"]),
         ("CPDI", ["method.basis=cpdi"]),
         ("B-splines, degree 2", ["method.basis=bspline", "method.degree=2"])]
CELLS = (20, 40, 80)  # h = B / 4, B / 8, B / 16 over the 5 m grid
PHI_FRICTIONAL = 20.0  # [deg] the frictional soil's friction angle


def footing_box(label, h):
    """The box of the footing's DOFs: the grid nodes on the surface, or for the quadratic
    B-splines the two rows of control values at the cell middles around it."""
    if label.startswith("B-splines"):
        return [f"prescribed.min=[0, {SURFACE - 0.6 * h:g}]",
                f"prescribed.max=[{HALF_WIDTH:g}, {SURFACE + 0.6 * h:g}]"]
    return [f"prescribed.min=[0, {SURFACE:g}]", f"prescribed.max=[{HALF_WIDTH:g}, {SURFACE:g}]"]


def curve(r):
    """(settlement / B [%], q / c_u) per history row of a run, or None when it stopped."""
    path = os.path.join(r["_dir"], "history.csv")
    if r.get("status") != "ok" or not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return [(100.0 * SPEED * float(x["time"]) / (2 * HALF_WIDTH),
             -float(x["reaction_prescribed_y"]) / HALF_WIDTH / C_U) for x in rows]


def sec_footing(R, ctx):
    """Per basis and cell size: q / c_u at a settlement of 1.5 % of B against Prandtl's
    (2 + pi); B-splines with nu = 0.49 and with Mohr-Coulomb at phi = 0 (Tresca) beside."""
    specs, keys = [], []
    for label, sets in BASES:
        for n in CELLS:
            h = 5.0 / n
            keys.append((label, n))
            specs.append(("footing_2d", sets + footing_box(label, h) +
                          [f"grid.cells={n}", f"time.dt={2.5e-4 * 40 / n:g}"], 0,
                          f"footing_{label.split(',')[0]}_{n}"))
    b2 = BASES[-1][1] + footing_box(BASES[-1][0], 5.0 / 40)
    keys.append("nu49")
    specs.append(("footing_2d", b2 + ["material.poisson_ratio=0.49", "time.dt=1.25e-4"], 0,
                  "footing_nu49"))
    # At h = B/8: the smooth footing (its vertical velocity alone prescribed), and the
    # B-splines with TLS's mapping.
    variants = [("linear, smooth footing", BASES[0][1] + footing_box(BASES[0][0], 5.0 / 40) +
                 ['prescribed.components="y"']),
                ("B-splines, degree 2, smooth footing", b2 + ['prescribed.components="y"']),
                ("B-splines, degree 2, TLS", b2 + ["method.mapping=tls"])]
    for label, sets in variants:
        keys.append(label)
        specs.append(("footing_2d", sets, 0, "footing_" + label.replace(",", "")))
    # A frictional soil: Mohr-Coulomb, c = c_u, phi = 20 deg, psi = 0, pushed to 4 % of B, against
    # Prandtl's N_c = (N_q - 1) cot phi, N_q = exp(pi tan phi) tan^2(45 deg + phi / 2). The
    # example's von Mises parameter is replaced in a copy (a law refuses another's parameters).
    with open(os.path.join(EX, "footing_2d.toml")) as f:
        text = f.read()
    own = "model = \"von_mises\"\n"
    if own not in text or "yield_stress = " not in text:
        raise SystemExit("footing.py: examples/footing_2d.toml has changed its [material]; "
                         "update the frictional runs")
    lines = [x for x in text.replace(own, f"model = \"mohr_coulomb\"\ncohesion = {C_U:g}\n"
                                              f"friction_angle = {PHI_FRICTIONAL:g}\n").split("\n")
             if not x.startswith("yield_stress = ")]
    frictional = os.path.join(R.work, "footing_frictional")
    with open(frictional + ".toml", "w") as f:
        f.write("\n".join(lines))
    frictional_runs = [("linear", BASES[0][1] + footing_box(BASES[0][0], 5.0 / 40)),
                       ("B-splines, degree 2", b2)]
    for label, sets in frictional_runs:
        keys.append(("frictional", label))
        specs.append((frictional, sets + ["time.end=4"], 0, "footing_frictional_" + label[:6]))
    res = dict(zip(keys, R.many(specs)))
    curves = {k: curve(r) for k, r in res.items()}

    def final(k):
        c = curves.get(k)
        return c[-1][1] if c else None

    def cell(k):
        q = final(k)
        return f"{q:.3f} ({100 * (q / PRANDTL - 1):+.1f} %)" if q is not None else \
            res[k].get("status", "failed")
    t = ["| basis | h = B/4 | h = B/8 | h = B/16 |", "|---|---|---|---|"]
    for label, _ in BASES:
        t.append(f"| {label} | " + " | ".join(cell((label, n)) for n in CELLS) + " |")
    t2 = ["| run, h = B/8 | q / c_u |", "|---|---|"]
    t2.append(f"| linear, rough footing (above) | {cell((BASES[0][0], CELLS[1]))} |")
    t2.append(f"| B-splines, degree 2, rough footing, direct mapping (above) | "
              f"{cell((BASES[-1][0], CELLS[1]))} |")
    for label, _ in variants:
        t2.append(f"| {label} | {cell(label)} |")
    t2.append(f"| B-splines, degree 2, rough footing, nu = 0.49 | {cell('nu49')} |")
    tp = math.tan(math.radians(PHI_FRICTIONAL))
    n_q = math.exp(math.pi * tp) * math.tan(math.radians(45 + PHI_FRICTIONAL / 2)) ** 2
    n_c = (n_q - 1) / tp
    t3 = ["| basis, h = B/8 | q / c at 4 % of B | Prandtl's N_c | difference |",
          "|---|---|---|---|"]
    for label, _ in frictional_runs:
        q = final(("frictional", label))
        t3.append(f"| {label} | {q:.3f} | {n_c:.3f} | {100 * (q / n_c - 1):+.1f} % |"
                  if q is not None else
                  f"| {label} | {res[('frictional', label)].get('status')} | {n_c:.3f} | - |")

    figs = []
    plt = pyplot()
    if plt is not None:
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        for label, _ in BASES:
            c = curves.get((label, CELLS[1]))
            if c:
                ax.plot([p[0] for p in c], [p[1] for p in c], lw=1.2, label=f"{label}, h = B/8")
        c = curves.get((BASES[-1][0], CELLS[2]))
        if c:
            ax.plot([p[0] for p in c], [p[1] for p in c], "k--", lw=1.0,
                    label="B-splines, degree 2, h = B/16")
        ax.axhline(PRANDTL, color="grey", lw=1.0, ls=":", label="Prandtl, 2 + pi")
        ax.set_xlabel("settlement / B [%]")
        ax.set_ylabel("q / c_u")
        ax.set_title("rigid rough strip footing on Tresca clay (von Mises, plane strain)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        figs = save_figure(plt, fig, ctx, "footing_load_settlement")

    b2 = [final((BASES[-1][0], n)) for n in CELLS]
    lin = [final((BASES[0][0], n)) for n in CELLS]
    nu49 = final("nu49")
    if None in (*b2, *lin, nu49):
        text = "Some runs stopped, so the reading below is not made."
    else:
        # The locking reading holds when the B-splines' excess keeps most of itself from B/4 to
        # B/16 and a near-incompressible elasticity raises the plateau; otherwise the plain one.
        stays = (b2[2] - PRANDTL) > 0.75 * (b2[0] - PRANDTL)
        block = "reading" if stays and nu49 > b2[1] + 0.2 else "reading_converging"
        text = render("footing", block, b2_4=b2[0], b2_8=b2[1], b2_16=b2[2],
                      b2_pct=100 * (b2[2] / PRANDTL - 1), lin_4=lin[0], lin_8=lin[1],
                      lin_16=lin[2], lin_pct=100 * (lin[2] / PRANDTL - 1), nu49=nu49,
                      nu49_pct=100 * (nu49 / PRANDTL - 1),
                      lin_side="further above" if lin[2] > b2[2] else "below them",
                      lin_rate=math.sqrt(max(lin[2] - PRANDTL, 0.0) / (lin[0] - PRANDTL)))
    return render("footing", "section", table="\n".join(t), t2="\n".join(t2),
                  t3="\n".join(t3), phi=PHI_FRICTIONAL, text=text,
                  figures=fig_md(ctx, figs, "strip footing: load against settlement"))
