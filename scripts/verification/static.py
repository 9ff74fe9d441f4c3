"""The sections of prose alone (no runs): the grid bases, MLS and IMLS in 2D, and traction on a
side in 2D with the custom problem. Their text is templates/bases.md, mls2d.md and
traction_2d.md."""
from .template import render


def sec_bases(R, ctx):
    """Grid bases (D 2.6.4, 3.1): what each basis is and what its unit tests check."""
    return render("bases", "section")


def sec_mls2d(R, ctx):
    """MLS and IMLS in 2D."""
    return render("mls2d", "section")


def sec_traction_2d(R, ctx):
    """Traction on a side in 2D and the custom problem."""
    return render("traction_2d", "section")
