"""The peers study's figure (icosim.figures.peers) draws the datasets as they are: per system a column, one line
per series with completed runs, at the runs' errors against their wall times (top) and doSteps (bottom)."""

import numpy as np
import pytest
from peers_data import dataset, run

from icosim.figures.peers import master_colour, peers_figure


def drawn(ax):
    """The axes' data lines (the levels' verticals carry no label)."""
    return [line for line in ax.lines if not line.get_label().startswith("_")]


def test_each_series_is_a_line_through_its_runs_and_a_run_without_an_error_is_not_drawn():
    rows = [run("Ecos", 1e-3, 4e-3, 0.05, 2000, 1000), run("Ecos", 5e-4, 2e-3, 0.09, 4000, 2000),
            run("icosim", 1e-2, 5e-4, 0.3, 400, 100, series="icosim"),
            run("FMPy", 1e-3, 0.0, 0.0, 0, 0, status="missing: fmpy (test)")]  # fmt: skip
    fig = peers_figure([dataset(rows), dataset(rows[:2])], title="t")
    axes = np.array(fig.axes[:4]).reshape(2, 2)
    top, bottom = axes[0, 0], axes[1, 0]
    assert len(drawn(top)) == 2 and len(drawn(axes[0, 1])) == 1  # Ecos and icosim; FMPy has no run
    ecos = next(line for line in drawn(top) if line.get_label() == "Ecos, fixed step")
    x, y = zip(*sorted(zip(ecos.get_xdata(), ecos.get_ydata())))
    assert x == pytest.approx([2e-3, 4e-3], rel=1e-12) and y == (0.09, 0.05)
    assert sorted(drawn(bottom)[0].get_ydata()) == [2000, 4000]
    assert len(top.lines) - len(drawn(top)) == 3  # the dataset's three error levels
    assert ecos.get_color() == master_colour("Ecos") != master_colour("icosim")
    assert top.xaxis_inverted()  # the smaller error to the right
