"""The verification report of scripts/verify.py, one module per section or group of related
sections. scripts/verify.py holds the command line and the order of the sections; each section
is a function sec_NAME(R, ctx) -> Markdown, where R is the Runner (runner.py) and ctx a dict
that carries the figures directory and the results that later sections reuse.

    common.py      paths, PUBLISHED, VERDICT_RULES and the verdicts, number formats e/num/o
    runner.py      Runner (mpm run, study, bench, reconstruct) and massmatrix
    plots.py       the figures
    template.py    the prose templates (the one template mechanism: read its docstring)
    report.py      the full report and its header, --only
    quick.py       --quick, the convergence guard of the test suite
    small_bar.py, static.py, bases.py, reconstruction.py, chapter5.py, large_bar.py, mms.py,
    otm.py, massmatrix.py, plate.py, ps_mpm.py, ps_partial.py, mesh_boundaries.py, vortex.py,
    tls_robust.py, plate_001.py, cube.py, item3.py
                   the sections, in the order of the report

The prose of a section is in templates/NAME.md beside these modules, Markdown with named
placeholders that the section fills with the numbers it computes (template.render). The
templates are data: nothing in them is evaluated.
"""
