"""Figure builders: they take datasets and draw, never recompute.

Every builder returns a :class:`matplotlib.figure.Figure` (no global pyplot
state), so callers choose how to save it; :func:`save_figure` writes PNG and
PDF atomically.  The builders live in one module per part (:mod:`.stability`,
:mod:`.convergence`, :mod:`.pendulum`, :mod:`.pendulum_trade`, :mod:`.schemes`);
importing this package loads none of them.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from ..io.netcdf import atomic_path

__all__ = ["save_figure"]


def save_figure(fig, *paths, dpi: int = 110):
    """Write ``fig`` to each path; the format follows the suffix (``.png``, ``.pdf``).

    Only matplotlib's public API.  The first file lays the figure out (constrained layout, if the
    figure uses it; for a PNG before the draw that writes it, :func:`_lay_out`) and places the axis
    labels beside their tick labels; both are in figure or axes coordinates, so they are kept for the
    other files instead of computed again.  ``fig`` has no layout engine afterwards
    (:func:`_drop_layout_engine`) and its axis labels stay where the first file put them
    (:func:`_keep_axis_labels`; those without text from before the first draw).  Its log axes make ticks only within their view (:func:`_ticks_in_view`).
    The files show what matplotlib draws (``tests/figures/test_figures.py``); a PNG's pixels are compressed
    with :data:`PNG_ZLIB`.
    """
    _ticks_in_view(fig)
    fig.set_dpi(dpi)  # the first file is drawn at the figure's own resolution: positions read from it hold
    for i, path in enumerate(paths):
        fmt = Path(path).suffix.lstrip(".").lower()
        with atomic_path(path) as tmp:
            if i == 0 and fmt == "png":
                _lay_out(fig)
                _keep_axis_labels(fig, without_text=True)
            fig.savefig(tmp, format=fmt, dpi=dpi, metadata=_metadata(fmt), **_encoding(fmt))
        if i == 0:
            _drop_layout_engine(fig)
            _keep_axis_labels(fig)


def _ticks_in_view(fig):
    """Give every log axis of ``fig`` :class:`.ticks.InViewLocator` s (once: shared axes share their locators)."""
    from matplotlib.ticker import LogLocator

    from .ticks import InViewLocator

    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for get, put in (
                (axis.get_major_locator, axis.set_major_locator),
                (axis.get_minor_locator, axis.set_minor_locator),
            ):
                if isinstance(get(), LogLocator):
                    put(InViewLocator(get()))


def _lay_out(fig):
    """Run ``fig``'s layout engine once, as matplotlib's ``Figure.draw`` does, and leave it without one.

    ``savefig`` of a figure with a layout engine draws the figure twice: once (to no output) only to
    run the engine, then to write the file.  Run here, for a PNG (the renderer the engine measures
    text with is the same Agg renderer at the same resolution), the engine's work is the same and
    the file is drawn once.
    """
    engine = fig.get_layout_engine()
    if engine is not None and fig.axes:
        with contextlib.suppress(ValueError):  # as Figure.draw: a layout that cannot be made is left out
            engine.execute(fig)
    _drop_layout_engine(fig)


def _drop_layout_engine(fig):
    """Leave ``fig`` without a layout engine: laid out by the first file, it needs none.

    With any engine, even matplotlib's do-nothing placeholder (``set_layout_engine("none")``),
    ``savefig`` draws the whole figure once before the draw that writes the file, only to run
    the engine.  ``set_layout_engine(None)`` removes the engine where the rcParams ask for no
    automatic layout (set so here); then ``savefig`` draws once.
    """
    import matplotlib as mpl

    with mpl.rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        fig.set_layout_engine(None)


def _keep_axis_labels(fig, without_text=False):
    """Keep every axis label where the last draw put it (:meth:`matplotlib.axis.Axis.set_label_coords`).

    Matplotlib places the labels on each draw from the bounding boxes of the tick labels (every tick
    label of the axis measured again); once drawn, their place in axes coordinates does not change
    with the resolution, so the next file uses it as it is.  With ``without_text``, before the first
    draw (once laid out), only the labels without text, as the inner panels of a grid have: they draw
    nothing wherever they are, so their axes' tick labels need not be measured for them.
    """
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            label = axis.label
            if without_text and label.get_text():
                continue
            x, y = ax.transAxes.inverted().transform(label.get_transform().transform(label.get_position()))
            axis.set_label_coords(x, y)


#: zlib settings of the PNGs (level 4, the default strategy): on the project's figures the files are 9 % smaller
#: than with Pillow's defaults (level 6, filtered strategy) and written in four fifths of the time; the pixels are the same.
PNG_ZLIB = {"compress_level": 4, "compress_type": 0}


def _encoding(fmt):
    return {"pil_kwargs": dict(PNG_ZLIB)} if fmt == "png" else {}


def _metadata(fmt):
    from ..version import package_version

    if fmt == "pdf":  # no creation date: identical inputs give identical files
        return {"Creator": f"icosim {package_version()}", "CreationDate": None}
    if fmt == "png":
        return {"Software": f"icosim {package_version()}"}
    return None
