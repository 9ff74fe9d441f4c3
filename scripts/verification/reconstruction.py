"""The reconstruction mappings (cubic spline, TLS) and the FEM reference, with D 6.2's TLS
reconstructions on rectangles and triangles measured by `mpm reconstruct` (D Fig. 6.6, 6.2.2).
Prose: templates/reconstruction.md."""
from .common import ROUNDOFF, e, ls_order, o, pub, src, verdict_order, verdict_value
from .template import render


def sec_reconstruction_intro(R, ctx):
    """The reconstruction mappings and the FEM reference, with D 6.2's reconstructions on
    rectangles (D Fig. 6.6) and triangles (D 6.2.2) by `mpm reconstruct`."""
    rms, integ = R.reconstruct(["--dim", "2", "--function", "sin(x)*cos(y)", "--upper", "5",
                                "--cells", "5", "--points", "inner:2x3", "--terms", "6",
                                "--error-points", "2"])
    fig66 = {}
    for terms in (1, 3, 6):
        for gp in ((5, 2) if terms == 6 else (5,)):
            errs = [R.reconstruct(["--dim", "2", "--function", "sin(x/10)*cos(y/10)",
                                   "--lower", "0", "--upper", "10", "--cells", str(n),
                                   "--points", "uniform:3", "--terms", str(terms),
                                   "--error-points", str(gp)])[0] for n in (4, 8, 16, 32)]
            fig66[(terms, gp)] = ls_order([1 / 4, 1 / 8, 1 / 16, 1 / 32], errs)
    v_rms = verdict_value(rms, "tls2d_rms")
    v_int = verdict_value(integ, "tls2d_integral", roundoff=True)
    # D 6.2.2 on triangles: D gives neither its 30-triangle mesh nor its point layout (300 points
    # in the text, 6 per element in Fig. 6.7's caption), so several readings, 5 seeds each.
    tri = {}
    for mesh, cells in (("right", 4), ("criss-cross", 3)):
        for pts in ("domain:300", "random:10"):
            runs = [R.reconstruct(["--dim", "2", "--function", "sin(x)*cos(y)", "--upper", "5",
                                   "--mesh", mesh, "--cells", str(cells), "--points", pts,
                                   "--terms", "6", "--seed", str(seed)]) for seed in range(1, 6)]
            tri[(mesh, pts)] = ([r[0] for r in runs], max(r[1] for r in runs))
    tri_best = min(min(v[0]) for v in tri.values())
    tri_int = max(v[1] for v in tri.values())
    tri_spread = max(max(v[0]) / min(v[0]) for v in tri.values())
    v_tri = verdict_value(tri_best, "tlstri_rms")
    v_tri_int = ("reproduced (round-off; D: \"machine precision\", no number)"
                 if tri_int < ROUNDOFF else f"differs: {e(tri_int, 1)}")
    tri_rows = "\n".join(
        f"| {mesh} {('4 x 4 squares, 32' if mesh == 'right' else '3 x 3 squares, 36')} "
        f"triangles | `{pts}` | {min(v[0]):.2e} - {max(v[0]):.2e} | {e(v[1], 1)} |"
        for (mesh, pts), v in tri.items())
    v66 = [verdict_order(fig66[(n, 5)], f"tls2d_order_{n}") for n in (1, 3, 6)]
    ctx["tls2d"] = (rms, integ, v_rms, v_int, fig66, v66)
    return render("reconstruction", "section", tls2d_rms_src=src('tls2d_rms'),
                  tls2d_rms_pub=pub('tls2d_rms'), rms=rms, v_rms=v_rms,
                  tls2d_integral_pub=pub('tls2d_integral'), integ=e(integ, 1), v_int=v_int,
                  tls2d_order_1_pub=pub('tls2d_order_1'), order_1_term=o(fig66[(1, 5)]),
                  v66_1=v66[0], tls2d_order_3_pub=pub('tls2d_order_3'),
                  order_3_terms=o(fig66[(3, 5)]), v66_3=v66[1],
                  tls2d_order_6_pub=pub('tls2d_order_6'), order_6_terms=o(fig66[(6, 5)]),
                  v66_6=v66[2], tlstri_rms_src=src('tlstri_rms'), tlstri_rms_pub=pub('tlstri_rms'),
                  tri_best=tri_best, v_tri=v_tri, tri_int=e(tri_int, 1), v_tri_int=v_tri_int,
                  tri_rows=tri_rows, tri_over_published=tri_best / pub('tlstri_rms'),
                  tri_spread=tri_spread, order_6_terms_2x2=o(fig66[(6, 2)]))
