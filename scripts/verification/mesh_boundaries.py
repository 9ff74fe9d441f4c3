"""Conditions and loads on the named boundaries of a mesh file: an inclined block on a roller
under a pressure, P1 and PS splines, with its static error taken apart (sec_mesh_boundaries).
Prose: templates/mesh_boundaries.md."""
from .common import e
from .template import render


def sec_mesh_boundaries(R, ctx):
    """Conditions and loads on the named boundaries of a mesh file: the block of
    examples/incline_pressure_2d.toml on a 30-degree incline (a roller along the inclined base,
    a pressure raised smoothly on its top) against its quasi-static solution; what its error is
    made of (the load's rise time, the particles per triangle, the same block not turned, a
    smaller load)."""
    ex = "incline_pressure_2d"
    methods = [("p1_triangles", "lumped"), ("p1_triangles", "consistent"),
               ("powell_sabin", "lumped")]
    rises = (0.5, 1.0, 2.0)
    checks = [("PS, lumped, 24 per triangle", ["method.basis=powell_sabin",
                                               "particles.per_triangle=24"]),
              ("PS, lumped, 54 per triangle", ["method.basis=powell_sabin",
                                               "particles.per_triangle=54"]),
              ("P1, lumped, the block not turned (`incline_0.msh`, a = 0)",
               ["constants.a=0", "grid.mesh=meshes/incline_0.msh"]),
              ("P1, lumped, p0 = 100 Pa", ["constants.p0=100"]),
              ("P1, lumped, p0 = 10 Pa", ["constants.p0=10"])]
    specs, keys = [], []
    for b, m in methods:
        for T in rises:
            keys.append((b, m, T))
            specs.append((ex, [f"method.basis={b}", f"method.mass={m}", f"constants.T={T}",
                               f"time.end={T + 0.1:g}"], 0, f"incline_{b}_{m}_{T:g}"))
    for k, (label, sets) in enumerate(checks):
        keys.append(("check", k))
        specs.append((ex, sets, 0, f"incline_check_{k}"))
    res = dict(zip(keys, R.many(specs)))

    def err(r, key="stress_rel_l2"):
        return r.get("errors", {}).get(key) if r.get("status") == "ok" else None

    def crossings(r):
        return r.get("conservation", {}).get("grid_crossings", r.get("grid_crossings"))
    t = ["| basis | mass | stress, relative L2: T = 0.5 s | T = 1 s | T = 2 s | displacement "
         "RMS [m] (T = 0.5 s) | mass | momentum |", "|---|---|---|---|---|---|---|---|"]
    for b, m in methods:
        r0 = res[(b, m, rises[0])]
        cons = r0.get("conservation", {})
        t.append(f"| {b} | {m} | " + " | ".join(
            e(err(res[(b, m, T)])) if err(res[(b, m, T)]) else res[(b, m, T)].get("status")
            for T in rises) + f" | {e(err(r0, 'displacement_rms'))} | "
            f"{e(cons.get('max_rel_mass_error'), 1)} | "
            f"{e(cons.get('max_rel_momentum_error'), 1)} |")
    t2 = ["| run (T = 0.5 s) | stress, relative L2 | grid crossings |", "|---|---|---|"]
    base_p1 = res[("p1_triangles", "lumped", rises[0])]
    base_ps = res[("powell_sabin", "lumped", rises[0])]
    t2.append(f"| P1, lumped (the example) | {e(err(base_p1))} | {crossings(base_p1)} |")
    t2.append(f"| PS, lumped, 6 per triangle (the example) | {e(err(base_ps))} | "
              f"{crossings(base_ps)} |")
    for k, (label, _) in enumerate(checks):
        r = res[("check", k)]
        t2.append(f"| {label} | {e(err(r)) if err(r) else r.get('status')} | {crossings(r)} |")

    def spread(b, m):
        v = [err(res[(b, m, T)]) for T in rises]
        return (min(v), max(v)) if all(v) else (None, None)
    p1 = spread("p1_triangles", "lumped")
    ps = spread("powell_sabin", "lumped")
    ps24, ps54 = err(res[("check", 0)]), err(res[("check", 1)])
    flat, small, tiny = err(res[("check", 2)]), err(res[("check", 3)]), err(res[("check", 4)])
    if None in (*p1, *ps, ps24, ps54, flat, small, tiny) or not err(base_ps):
        text = "Some runs stopped, so the reading below is not made."
    else:
        text = render("mesh_boundaries", "static_error", p1_0=p1[0], p1_1=p1[1], ps_0=ps[0],
                      ps_1=ps[1], ps_error=e(err(base_ps)), ps24=e(ps24), ps54=e(ps54),
                      flat=e(flat), p1_error=e(err(base_p1)),
                      small_load_crossings=crossings(res[('check', 3)]),
                      base_crossings=crossings(base_p1), small=e(small), tiny=e(tiny),
                      tiny_pct=tiny * 100)
    return render("mesh_boundaries", "section", table="\n".join(t), t2="\n".join(t2), text=text)
