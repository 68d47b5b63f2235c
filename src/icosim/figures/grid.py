"""A grid of panels laid out once, in inches, instead of by a layout engine.

Constrained layout measures every tick label of every panel (its solver is most of the CPU of
writing a many-panel figure).  The figures drawn on a regular grid know their margins beforehand:
their labels have fixed font sizes, so the space they need is fixed in inches, whatever the figure's
size.  :class:`Margins` holds that space; :func:`grid_axes` places the panels in what is left.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Margins", "grid_axes", "PANEL_TITLE"]

#: Keywords of ``Axes.set_title`` for a panel without tick labels on top: a title given its height is not
#: moved above such labels, so matplotlib does not measure the axis for it on every draw.
PANEL_TITLE = {"y": 1.0}


@dataclass(frozen=True)
class Margins:
    """Space in inches: around the grid (``left`` ... ``top``) and between its panels (``wspace``, ``hspace``)."""

    left: float
    right: float
    bottom: float
    top: float
    wspace: float
    hspace: float

    def check(self, width: float, height: float, nrows: int, ncols: int):
        """Raise if the panels of an ``nrows`` x ``ncols`` grid get no room in a ``width`` x ``height`` figure."""
        free_w = width - self.left - self.right - (ncols - 1) * self.wspace
        free_h = height - self.bottom - self.top - (nrows - 1) * self.hspace
        if free_w <= 0 or free_h <= 0:
            raise ValueError(
                f"a {width:g} x {height:g} in figure leaves no room for {nrows} x {ncols} panels with {self}"
            )
        return free_w / ncols, free_h / nrows


def grid_axes(fig, nrows: int, ncols: int, margins: Margins, **subplot_kw):
    """``nrows`` x ``ncols`` axes of ``fig`` (an array, as ``Figure.subplots(squeeze=False)``) within ``margins``."""
    width, height = fig.get_size_inches()
    panel_w, panel_h = margins.check(width, height, nrows, ncols)
    gridspec = {
        "left": margins.left / width,
        "right": 1 - margins.right / width,
        "bottom": margins.bottom / height,
        "top": 1 - margins.top / height,
        # matplotlib's gaps are fractions of a panel's width and height
        "wspace": margins.wspace / panel_w,
        "hspace": margins.hspace / panel_h,
    }
    return fig.subplots(nrows, ncols, squeeze=False, gridspec_kw=gridspec, **subplot_kw)
