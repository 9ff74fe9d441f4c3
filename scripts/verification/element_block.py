"""The plane-strain compression test of a soil block (sec_element_block):
examples/element_block_2d.toml with each plastic law, its stress path from the platen's
reaction against the closed-form strength. Prose: templates/element_block.md."""
import csv
import math
import os

from .common import EX, fig_md
from .plots import pyplot, save_figure
from .template import render

C = 10e3           # [Pa] cohesion of the example
PHI = 30.0         # [deg] friction angle
SY = 60e3          # [Pa] von Mises yield stress of the von_mises runs
SPEED = 5e-3       # [m/s] the platen's speed; the block is 1 m high and wide
LAWS = [("mohr_coulomb", [], ""),
        ("drucker_prager, associated", ["material.model=drucker_prager",
                                        "material.dilatancy_angle=30"], ""),
        ("von_mises", ["material.model=von_mises"], "von")]


def mc_sigma1(sigma3):
    """sigma_1 at failure (compression positive) of Mohr-Coulomb in plane strain, sigma_zz
    intermediate; also the Drucker-Prager cone matched in plane strain with associated flow."""
    s = math.sin(math.radians(PHI))
    n = (1 + s) / (1 - s)
    return n * sigma3 + 2 * C * math.sqrt(n)


def path(r):
    """(axial strain [%], platen stress [Pa]) per history row, or None when the run stopped."""
    p = os.path.join(r["_dir"], "history.csv")
    if r.get("status") != "ok" or not os.path.exists(p):
        return None
    with open(p, newline="") as f:
        return [(100 * SPEED * float(x["time"]), -float(x["reaction_prescribed_y"]))
                for x in csv.DictReader(f)]


def plateau(pts):
    """The mean platen stress over the last third of the push (steady plastic flow)."""
    tail = pts[2 * len(pts) // 3:]
    return sum(p[1] for p in tail) / len(tail)


def sec_element_block(R, ctx):
    """Each law confined at p0 = 0 and 50 kPa: the platen's stress in steady plastic flow
    against the closed form, and the stress paths."""
    confinements = (0.0, 50e3)
    # von Mises reads yield_stress and refuses Mohr-Coulomb's cohesion and friction angle, which
    # the example sets: its runs read a copy with those replaced.
    with open(os.path.join(EX, "element_block_2d.toml")) as f:
        text = f.read()
    own = "cohesion = 10.0e3\nfriction_angle = 30.0\n"
    if own not in text:
        raise SystemExit("element_block.py: examples/element_block_2d.toml has changed its "
                         "[material] parameters; update LAWS")
    von = os.path.join(R.work, "element_block_von_mises")
    with open(von + ".toml", "w") as f:
        f.write(text.replace(own, f"yield_stress = {SY:g}\n"))
    specs, keys = [], []
    for label, sets, kind in LAWS:
        for p0 in confinements:
            conf = [f"pressure.right={p0:g}", f'initial.stress=["{-p0:g}", "{-p0:g}", "0"]',
                    f"initial.stress_zz={-p0:g}"]
            keys.append((label, p0))
            specs.append((von if kind == "von" else "element_block_2d", sets + conf, 0,
                          f"block_{label[:5]}_{p0:g}"))
    runs = dict(zip(keys, R.many(specs)))
    paths = {k: path(r) for k, r in runs.items()}
    t = ["| law | p0 [kPa] | closed form sigma_1 [kPa] | platen, steady flow [kPa] | difference |",
         "|---|---|---|---|---|"]
    for label, _, kind in LAWS:
        for p0 in confinements:
            exact = p0 + 2 * SY / math.sqrt(3) if kind == "von" else mc_sigma1(p0)
            pts = paths[(label, p0)]
            if pts is None:
                t.append(f"| {label} | {p0 / 1e3:g} | {exact / 1e3:.2f} | "
                         f"{runs[(label, p0)].get('status')} | - |")
                continue
            got = plateau(pts)
            t.append(f"| {label} | {p0 / 1e3:g} | {exact / 1e3:.2f} | {got / 1e3:.2f} | "
                     f"{100 * (got / exact - 1):+.2f} % |")
    figs = []
    plt = pyplot()
    if plt is not None:
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        for (label, _, kind), color in zip(LAWS, ("C0", "C1", "C2")):
            for p0, ls in zip(confinements, ("-", "--")):
                pts = paths.get((label, p0))
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] / 1e3 for p in pts], color=color, ls=ls,
                            lw=1.0, label=f"{label}, p0 = {p0 / 1e3:g} kPa")
                exact = p0 + 2 * SY / math.sqrt(3) if kind == "von" else mc_sigma1(p0)
                ax.axhline(exact / 1e3, color=color, ls=":", lw=0.8)
        ax.set_xlabel("axial strain [%]")
        ax.set_ylabel("platen stress sigma_1 [kPa]")
        ax.set_title("plane-strain compression of a soil block (dotted: closed forms)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="center right")
        fig.tight_layout()
        figs = save_figure(plt, fig, ctx, "element_block_paths")
    return render("element_block", "section", table="\n".join(t),
                  figures=fig_md(ctx, figs, "plane-strain compression: stress paths"))
