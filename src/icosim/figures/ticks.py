"""Tick locators for figures that are saved, not panned."""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import Locator

__all__ = ["InViewLocator"]


class InViewLocator(Locator):
    """The ticks of ``locator`` within the view of its axis, for a figure that is saved, not panned.

    Matplotlib's log locator also places the ticks of one decade (stride) beyond each end of the view,
    for panning; the axis makes a tick (lines, labels and their properties) for each and then draws
    only those in its view.  This locator leaves the others out: the same ticks are drawn.
    """

    #: slack at each end, as a fraction of the view in the axis's scale: wider than matplotlib's own
    #: (1e-10, ``Axis._update_ticks``), so that every tick matplotlib would draw is kept
    SLACK = 1e-6

    def __init__(self, locator):
        self.locator = locator

    def set_axis(self, axis):
        super().set_axis(axis)
        self.locator.set_axis(axis)

    def __call__(self):
        return self._in_view(self.locator(), *self.axis.get_view_interval())

    def tick_values(self, vmin, vmax):
        return self._in_view(self.locator.tick_values(vmin, vmax), vmin, vmax)

    def nonsingular(self, v0, v1):
        return self.locator.nonsingular(v0, v1)

    def view_limits(self, vmin, vmax):
        return self.locator.view_limits(vmin, vmax)

    def _in_view(self, locs, vmin, vmax):
        locs = np.asarray(locs)
        if self.axis is None or locs.size == 0:
            return locs
        with np.errstate(divide="ignore", invalid="ignore"):
            lo, hi = sorted(self.axis.get_transform().transform([vmin, vmax]))
            at = self.axis.get_transform().transform(locs)
        slack = self.SLACK * (hi - lo)
        return locs[~((at < lo - slack) | (at > hi + slack))]
