"""Consistency across dimensions: where a method is a tensor product, the y-uniform 2D run of
examples/bar_uniaxial_strain.toml is the 1D run row by row and the z-uniform 3D run the 2D run
layer by layer. The rows of the questions this raises (DDMPM's weight, quadratic TLS, B-splines of
high degree), from the final particle CSVs of `mpm run`. The same checks over every basis,
mapping and mass are in CI (tests/methods/test_dimension_consistency.cpp). Prose:
templates/dimensions.md."""
import csv
import glob
import os

from .common import e
from .template import render

EXAMPLE = "bar_uniaxial_strain"
ROUNDOFF = 1e-11  # the largest difference of a tensor-product method is round-off below this


def dim_sets(dim, traction=False):
    """The --set of the bar in `dim` dimensions (the example is the 1D bar); `traction`: at
    rest, loaded by a ramped traction on its free end."""
    load = []
    if traction:
        load = ["initial.velocity=0" if dim == 1 else
                "initial.velocity=[" + ", ".join(['"0"'] * dim) + "]",
                "traction.right=-40*t" if dim == 1 else
                'traction.right=["-40*t"' + ', "0"' * (dim - 1) + "]"]
    if dim == 1:
        return load
    z = ", 0.0" if dim == 3 else ""
    zt = ", 0.3" if dim == 3 else ""
    v = ', "0"' * (dim - 1)
    sets = [f"grid.dimension={dim}", f"grid.min=[0.0, 0.0{z}]", f"grid.max=[1.0, 0.3{zt}]",
            f"body.min=[0.0, 0.0{z}]", f"body.max=[0.8, 0.3{zt}]",
            f'initial.velocity=["0.1*sin(pi*x/1.6)"{v}]', "boundary.bottom=roller",
            "boundary.top=roller"]
    if dim == 3:
        sets += ["boundary.back=roller", "boundary.front=roller"]
    return sets + load


def final_particles(run):
    """The last particle CSV of a run as {column: [values]} by particle id, the order of the
    seeding (x fastest; the run re-sorts them by cell); None if the run failed."""
    files = sorted(glob.glob(os.path.join(run["_dir"], "particles_*.csv")))
    if run.get("status") != "ok" or not files:
        return None
    with open(files[-1], newline="") as f:
        rows = sorted(csv.DictReader(f), key=lambda r: int(r["id"]))  # seeding order
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def difference(lo, hi, dim_lo):
    """The largest difference of the higher-dimensional run's particles from their
    lower-dimensional counterparts (particle k holds particle k mod n), relative to each field's
    scale, over the lower dimension's velocity, displacement and stress components."""
    n = len(lo["id"])
    worst = 0.0
    comps = [str(a + 1) for a in range(dim_lo)]
    groups = [[f"v_{a}" for a in comps], [f"u_{a}" for a in comps],
              [f"stress_{a}{b}" for a in comps for b in comps]]
    for group in groups:  # one scale per field: its largest component in the lower dimension
        scale = max(abs(x) for name in group for x in lo[name]) or 1.0
        for name in group:
            for k, x in enumerate(hi[name]):
                worst = max(worst, abs(x - lo[name][k % n]) / scale)
    # The out-of-plane velocity of the higher dimension.
    vscale = max(abs(x) for a in comps for x in lo[f"v_{a}"]) or 1.0
    worst = max(worst, max(abs(x) for x in hi[f"v_{dim_lo + 1}"]) / vscale)
    return worst


def sec_dimensions(R, ctx):
    """The rows of the dimension-consistency questions, and consistent mass at a moving surface."""
    tls_same = ["method.tls_completion=reduce", "method.tls_max_condition=10",
                "method.tls_positivity=on", "method.tls_cell_integrals=domains",
                "method.tls_surface_stress=volume"]
    cases = [
        ("DDMPM, per-direction weight (default)", ["method.basis=ddmpm"], False),
        ("DDMPM, product weight", ["method.basis=ddmpm", "method.ddmpm_weight=product"], False),
        ("DDMPM, quadrature integrals", ["method.basis=ddmpm",
                                         "method.ddmpm_integrals=quadrature"], False),
        ("P1-TLS, quadratic (3 / 6 / 10 terms)", ["method.mapping=tls"] + tls_same, False),
        ("P1-TLS, linear (2 / 3 / 4 terms)", ["method.mapping=tls"] + tls_same, True),
        ("cubic B-splines, direct, nu = 0.3", ["method.basis=bspline", "method.degree=3"], False),
        ("cubic B-splines, direct, nu = 0", ["method.basis=bspline", "method.degree=3",
                                             "material.poisson_ratio=0"], False),
        ("end traction, quadratic B-spline TLS (linear terms), nu = 0",
         ["method.basis=bspline", "method.degree=2", "method.mapping=tls",
          "material.poisson_ratio=0", "traction"] + tls_same, True),
        ("end traction, quartic B-spline MLS, nu = 0 (2 Gauss points)",
         ["method.basis=bspline", "method.degree=4", "method.mapping=mls",
          "material.poisson_ratio=0", "traction"], False),
        ("end traction, quartic B-spline MLS, nu = 0 (3 Gauss points)",
         ["method.basis=bspline", "method.degree=4", "method.mapping=mls",
          "method.gauss_points=3", "material.poisson_ratio=0", "traction"], False),
    ]
    specs = []
    for _, sets, linear in cases:
        loaded = "traction" in sets
        sets = [x for x in sets if x != "traction"]
        for dim in (1, 2, 3):
            extra = [f"method.tls_terms={dim + 1}"] if linear else []
            specs.append((EXAMPLE, dim_sets(dim, loaded) + sets + extra, 1))
    res = R.many(specs)
    rows, measured = [], {}
    for i, (label, _, _) in enumerate(cases):
        p1, p2, p3 = (final_particles(r) for r in res[3 * i:3 * i + 3])
        d12 = difference(p1, p2, 1) if p1 and p2 else None
        d23 = difference(p2, p3, 2) if p2 and p3 else None
        measured[label] = (d12, d23)
        ok = d12 is not None and d23 is not None and max(d12, d23) < ROUNDOFF
        rows.append(f"| {label} | {e(d12)} | {e(d23)} | "
                    f"{'reduces (round-off)' if ok else 'does not reduce'} |")
    # Consistent mass at a moving free surface: the 1D bar in rigid translation.
    rigid = ["initial.velocity=0.1", "boundary.left=free", "body.min=0.2", "body.max=0.79",
             "time.end=1.0", "time.dt=1e-3", "method.mass=consistent"]
    translations = [("P1", ["method.basis=linear"]), ("uGIMP", ["method.basis=ugimp"]),
                    ("cpGIMP", ["method.basis=cpgimp"]), ("CPDI", ["method.basis=cpdi"]),
                    ("quadratic B-splines", ["method.basis=bspline", "method.degree=2"]),
                    ("P1, partial lumping 0.5", ["method.basis=linear",
                                                 "method.partial_lumping=0.5"]),
                    ("uGIMP, partial lumping 0.5", ["method.basis=ugimp",
                                                    "method.partial_lumping=0.5"])]
    tr = R.many([(EXAMPLE, rigid + sets, 1) for _, sets in translations])
    trows = []
    for (label, _), r in zip(translations, tr):
        if r.get("status") == "ok":
            outcome = "runs to t = 1 s"
        else:
            fail = r.get("failure", "")
            outcome = "stops: " + (fail.split(" at ")[0] if fail else "no summary")
        trows.append(f"| {label} | {outcome} |")
    ctx.update(dimension_rows=measured)
    return render("dimensions", "section", rows="\n".join(rows), roundoff=ROUNDOFF,
                  translation_rows="\n".join(trows))
