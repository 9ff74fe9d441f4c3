"""B-spline mass matrices (004 4.6-4.7): condition numbers, CG iterations and p-multigrid
V-cycles against 004's Tables 4.2-4.4, the matrices of MPM's regular particles, and the time
to solution of each solver (`mpm massmatrix`). Prose: templates/massmatrix.md."""
import math
from concurrent.futures import ThreadPoolExecutor

from .common import FACTOR_TOL, verdict_claim
from .runner import massmatrix
from .template import render


def sec_massmatrix(R, ctx):
    """004 4.6-4.7: condition numbers, CG iterations and p-multigrid V-cycles (Tables 4.2-4.4)."""
    cells = "8,16,32,64,128"
    specs = [["--cells", cells], ["--cells", cells, "--boundary", "free"],
             ["--cells", "8,16,32,64", "--no-coarse-correction"],
             ["--cells", "8,16,32,64", "--boundary", "free", "--no-coarse-correction"]]
    with ThreadPoolExecutor(max_workers=R.jobs) as ex:
        res = list(ex.map(lambda a: massmatrix(R.mpm, R.env, a), specs))
    (dr, t_d), (fr, t_f), (dn, _), (fn, _) = res
    # Beyond 004: the MPM matrices of regular particles (1D bar: N per cell; 2D plate: N x N),
    # 1/h = 16, and the time to solution of each solver as the grid grows (Gauss points).
    part_specs = [(1, n, ["--dim", "1", "--cells", "16", "--particles", str(n)])
                  for n in (1, 2, 4, 12, 25)]
    part_specs += [(2, n, ["--cells", "16", "--particles", str(n)]) for n in (1, 2, 3, 4, 5)]
    time_spec = ["--cells", "32,64,128,256", "--degrees", "2,3", "--max-cycles", "300",
                 "--matrix-free"]
    with ThreadPoolExecutor(max_workers=R.jobs) as ex:
        pres = list(ex.map(lambda a: massmatrix(R.mpm, R.env, a[2] + ["--max-iterations", "20000",
                                                                     "--max-cycles", "1000"]),
                           part_specs))
        tres, _ = massmatrix(R.mpm, R.env, time_spec)
    degrees, hs = [1, 2, 3, 4, 5], [8, 16, 32, 64, 128]

    def table(rows, key, pub_key, fmt_):
        t = ["| p | " + " | ".join(f"1/h = {h}" for h in hs) + " |", "|---" * (len(hs) + 1) + "|"]
        for p in degrees:
            cs = []
            for h in hs:
                r = rows.get((p, h))
                if not r:
                    cs.append("-")
                    continue
                ok = key == "kappa" or r[key.replace("iterations", "converged").replace(
                    "cycles", "converged")]
                c = fmt_(r[key]) if ok else "failed"
                if r.get(pub_key) is not None:
                    c += f" ({fmt_(r[pub_key])})"
                cs.append(c)
            t.append(f"| {p} | " + " | ".join(cs) + " |")
        return "\n".join(t)

    def within(rows, key, pub_key):
        n = ok = 0
        worst = (1.0, None)
        for (p, h), r in rows.items():
            if r.get(pub_key) is None or not r.get(key):
                continue
            n += 1
            f = r[key] / r[pub_key]
            ok += 1 / FACTOR_TOL <= f <= FACTOR_TOL
            if abs(math.log(f)) > abs(math.log(worst[0])):
                worst = (f, (p, h))
        return ok, n, worst

    g = lambda x: f"{x:.3g}"
    i = lambda x: f"{x:.0f}"
    kd, kf = within(dr, "kappa", "kappa_published"), within(fr, "kappa", "kappa_published")
    cd, cf = within(dr, "cg_iterations", "cg_published"), within(fr, "cg_iterations", "cg_published")
    vd, vf = within(dr, "pmg_cycles", "pmg_published"), within(fr, "pmg_cycles", "pmg_published")
    ratios = [dr[(p + 1, 64)]["kappa"] / dr[(p, 64)]["kappa"] for p in degrees[:-1]]
    v_kappa = verdict_claim(kd[0] == kd[1], f"{kd[0]} of {kd[1]} within {FACTOR_TOL}x")
    v_ratio = verdict_claim(all(6.0 <= x <= 10.0 for x in ratios),
                            "ratios " + ", ".join(f"{x:.2f}" for x in ratios))
    flat = [dr[(p, 64)]["kappa"] / dr[(p, 16)]["kappa"] for p in degrees]
    v_flat = verdict_claim(all(1 / FACTOR_TOL <= x <= FACTOR_TOL for x in flat),
                           "kappa(1/64) / kappa(1/16) = " + ", ".join(f"{x:.2f}" for x in flat))
    grows = lambda rows: all(rows[(p + 1, h)]["cg_iterations"] > rows[(p, h)]["cg_iterations"]
                             for p in degrees[:-1] for h in hs[1:])
    v_cg_trend = verdict_claim(grows(dr) and grows(fr), "not monotone in p")
    v_cg = verdict_claim(cd[0] == cd[1] or cf[0] == cf[1],
                         f"{cd[0]} of {cd[1]} (eliminated), {cf[0]} of {cf[1]} (free) within "
                         f"{FACTOR_TOL}x")
    noinc = lambda rows: all(rows[(p, 64)]["pmg_cycles"] <= rows[(p, 16)]["pmg_cycles"]
                             for p in degrees)
    v_v_trend = verdict_claim(noinc(dr) and noinc(fr), "cycles grow from 1/h = 16 to 64")
    v_v = verdict_claim(vd[0] == vd[1] or vf[0] == vf[1],
                        f"{vd[0]} of {vd[1]} (eliminated), {vf[0]} of {vf[1]} (free) within "
                        f"{FACTOR_TOL}x")
    fewer = all(fr[(p, h)]["pmg_cycles"] < fr[(p, h)]["cg_iterations"] for p in degrees[1:]
                for h in hs[1:])
    v_fewer = verdict_claim(fewer, "not in every case")
    same = lambda a, b: (sum(a[k]["pmg_cycles"] == b[k]["pmg_cycles"] for k in b), len(b))
    sd, sf = same(dr, dn), same(fr, fn)
    bound_ok = all(r["cg_iterations"] <= r["cg_bound"] for r in list(dr.values()) + list(fr.values()))
    err = max(max(r["cg_error"] / r["kappa"], r["pmg_error"] / r["kappa"])
              for r in list(dr.values()) + list(fr.values()))

    def span(rows, key, pub, ps):
        f = [rows[(p, h)][key] / rows[(p, h)][pub] for p in ps for h in hs
             if rows.get((p, h)) and rows[(p, h)].get(pub)]
        return f"{min(f):.2f}x to {max(f):.2f}x" if f else "-"

    if sd[0] == sd[1] and sf[0] == sf[1]:
        smoother_text = render("massmatrix", "smoother_text")
    else:
        smoother_text = "the coarse correction changes the count in the other entries."
    pt = ["| dim | particles per cell | " + " | ".join(f"p = {p}: kappa / CG / V-cycles"
                                                     for p in degrees) + " |",
          "|---|---|" + "---|" * len(degrees)]
    singular_cases, failed_iter = [], []
    for (dim, n, _), (rows, _) in zip(part_specs, pres):
        cs = []
        for p in degrees:
            r = rows.get((p, 16))
            if not r:
                cs.append("-")
                continue
            k = "singular" if r["singular"] else f"{r['kappa']:.3g}"
            c = f"{r['cg_iterations']:.0f}" if r["cg_converged"] else "failed"
            v = f"{r['pmg_cycles']:.0f}" if r["pmg_converged"] else "failed"
            if r["singular"]:
                singular_cases.append((dim, n, p))
            elif not (r["cg_converged"] and r["pmg_converged"]):
                failed_iter.append((dim, n, p))
            cs.append(f"{k} / {c} / {v}")
        pt.append(f"| {dim} | {n ** dim} | " + " | ".join(cs) + " |")
    tt = ["| p | 1/h | unknowns | direct [ms] | CG [ms] | CG, matrix-free [ms] | p-multigrid [ms] |",
          "|---|---|---|---|---|---|---|"]
    for (p, h), r in sorted(tres.items()):
        tt.append(f"| {p} | {h} | {r['unknowns']:.0f} | {1e3 * r['direct_seconds']:.3g} | "
                  f"{1e3 * r['cg_seconds']:.3g} | {1e3 * r['cg_free_seconds']:.3g} | "
                  f"{1e3 * r['pmg_seconds']:.3g}"
                  + ("" if r["pmg_converged"] else " (failed)") + " |")
    free_same = all(abs(r["cg_free_iterations"] - r["cg_iterations"]) <= 1
                    and r["cg_free_difference"] < 1e-6 for r in tres.values())
    cross = [h for (p, h), r in sorted(tres.items()) if p == 2 and r["cg_seconds"] < r["direct_seconds"]]
    return render("massmatrix", "section", t_d=t_d, t_f=t_f,
                  kappa_eliminated=table(dr, "kappa", "kappa_published", g),
                  kappa_free=table(fr, "kappa", "kappa_published", g),
                  cg_eliminated=table(dr, "cg_iterations", "cg_published", i),
                  cg_free=table(fr, "cg_iterations", "cg_published", i),
                  pmg_eliminated=table(dr, "pmg_cycles", "pmg_published", i),
                  pmg_free=table(fr, "pmg_cycles", "pmg_published", i), FACTOR_TOL=FACTOR_TOL,
                  kd_ok=kd[0], kd_n=kd[1], kf_ok=kf[0], kf_n=kf[1], v_kappa=v_kappa,
                  ratios_list=", ".join(f"{x:.2f}" for x in ratios), v_ratio=v_ratio,
                  flat_list=", ".join(f"{x:.2f}" for x in flat), v_flat=v_flat,
                  v_cg_trend=v_cg_trend, cd_worst=cd[2][0], cd_worst_at=cd[2][1],
                  cf_worst=cf[2][0], cf_worst_at=cf[2][1], v_cg=v_cg, v_v_trend=v_v_trend,
                  vd_worst=vd[2][0], vd_worst_at=vd[2][1], vf_worst=vf[2][0], vf_worst_at=vf[2][1],
                  v_v=v_v, v_fewer=v_fewer, bound_ok="true" if bound_ok else "false", err=err,
                  sd_same=sd[0], sd_n=sd[1], sf_same=sf[0], sf_n=sf[1],
                  smoother_text=smoother_text,
                  pmg_span_free=span(fr, "pmg_cycles", "pmg_published", [3, 4, 5]),
                  pmg_span_eliminated=span(dr, "pmg_cycles", "pmg_published", [3, 4, 5]),
                  cg_span_eliminated_low=span(dr, "cg_iterations", "cg_published", [1, 2, 3]),
                  cg_span_free_low=span(fr, "cg_iterations", "cg_published", [1, 2, 3]),
                  cg_span_eliminated_high=span(dr, "cg_iterations", "cg_published", [4, 5]),
                  cg_span_free_high=span(fr, "cg_iterations", "cg_published", [4, 5]),
                  particle_table="\n".join(pt),
                  singular_list=", ".join(str(c) for c in singular_cases) or "none",
                  failed_list=", ".join(str(c) for c in failed_iter) or "none",
                  time_table="\n".join(tt), crossover=cross[0] if cross else "-",
                  free_same="true" if free_same else "false")
