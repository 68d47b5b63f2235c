"""Figure builders: they take datasets and draw, never recompute.

Every builder returns a :class:`matplotlib.figure.Figure` (no global pyplot
state), so callers choose how to save it; :func:`save_figure` writes PNG and
PDF atomically.  The builders live in one module per part (:mod:`.stability`,
:mod:`.convergence`, :mod:`.pendulum`, :mod:`.pendulum_trade`, :mod:`.schemes`);
importing this package loads none of them.
"""

from __future__ import annotations

import contextlib
import functools
from pathlib import Path

import numpy as np

from ..io.netcdf import atomic_path

__all__ = ["save_figure"]


def save_figure(fig, *paths, dpi: int = 110):
    """Write ``fig`` to each path; the format follows the suffix (``.png``, ``.pdf``).

    The first file lays the figure out (constrained layout, if the figure uses it; for a PNG before
    the draw that writes it, :func:`_lay_out`) and places the
    titles and axis labels beside their tick labels; both are in figure or axes coordinates, so they
    are kept for the other files instead of computed again (for a figure with many panels, the
    slowest part of saving).  ``fig`` has no layout engine afterwards (:func:`_drop_layout_engine`)
    and its titles and axis labels stay where the first file put them.  Within each file an axis's ticks are computed
    once per state (:func:`_ticks_once`), texts are measured once per process (:func:`_shared_text_metrics`),
    and mathematical text (log-scale tick labels, symbols in
    labels) is typeset once per process, not once per file (:func:`_share_mathtext`).  The files
    show what matplotlib draws without these shortcuts (``tests/figures/test_figures.py``); a PNG's pixels are
    compressed with :data:`PNG_ZLIB`.
    """
    _share_mathtext()
    fig.set_dpi(dpi)  # the first file is drawn at the figure's own resolution: positions read from it hold
    for i, path in enumerate(paths):
        fmt = Path(path).suffix.lstrip(".").lower()
        with atomic_path(path) as tmp, _ticks_once(fig), _shared_text_metrics():
            if i == 0 and fmt == "png":
                _lay_out(fig)
            fig.savefig(tmp, format=fmt, dpi=dpi, metadata=_metadata(fmt), **_encoding(fmt))
        if i == 0:
            _drop_layout_engine(fig)
            _keep_decorations(fig)


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
    the engine.  Without one it draws once.  The private attribute is checked before use; a
    matplotlib without it gets the placeholder (the same file, one draw more).
    """
    fig.set_layout_engine("none")
    from matplotlib.layout_engine import PlaceHolderLayoutEngine

    if isinstance(getattr(fig, "_layout_engine", None), PlaceHolderLayoutEngine):
        fig._layout_engine = None


def _keep_decorations(fig):
    """Keep every axes' title and axis labels where the last draw put them.

    Matplotlib places them on each draw from the bounding boxes of the tick labels (every tick
    label of the axis measured again); once drawn, their place in axes coordinates does not
    change with the resolution, so the next file uses it as it is.
    """
    for ax in fig.axes:
        if hasattr(ax, "_autotitlepos"):
            ax._autotitlepos = False  # placed by the last draw (matplotlib moves it only above top tick labels)
        for axis in (ax.xaxis, ax.yaxis):
            if not getattr(axis, "_autolabelpos", False):
                continue
            label = axis.label
            if label.get_text():
                x, y = ax.transAxes.inverted().transform(label.get_transform().transform(label.get_position()))
                axis.set_label_coords(x, y)
            else:
                axis._autolabelpos = False  # nothing to place


#: The matplotlib methods :func:`_ticks_once` stands in for (private: checked before each use).
_TICK_INTERNALS = ("_update_ticks", "_get_ticklabel_bboxes", "get_majorticklocs", "get_minorticklocs")


@contextlib.contextmanager
def _ticks_once(fig):
    """Within one save, compute each axis's ticks once for each state it is drawn in.

    Matplotlib updates an axis's ticks (locations, labels, their positions) each time something
    asks for them: the layout, the title's and the axis label's placement, each spine's extent,
    the draw itself, ten or more times per axis and draw, every time with the same result as
    long as the view limits, the panel's box and the resolution are the same.  Here the result
    is kept for that state and computed again when any of them changes (the layout moving a
    panel, the PDF's resolution).
    """
    patched = []
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            if not all(callable(getattr(axis, name, None)) for name in _TICK_INTERNALS):
                continue  # a matplotlib whose internals differ: its own ticks, every time
            axis._update_ticks, axis._get_ticklabel_bboxes = _memoised(axis)
            axis.get_majorticklocs, axis.get_minorticklocs = _in_view(axis)
            patched.append(axis)
    try:
        yield
    finally:
        for axis in patched:
            del axis._update_ticks, axis._get_ticklabel_bboxes, axis.get_majorticklocs, axis.get_minorticklocs


def _memoised(axis):
    """``axis``'s tick update and tick-label extents, each computed once per state (see :func:`_ticks_once`)."""
    update, extents = axis._update_ticks, axis._get_ticklabel_bboxes
    ticks = {}  # state -> the ticks drawn in it (a new list whenever the state changes)
    boxes = []  # [(ticks, renderer, extents)] of the last call

    def update_ticks():
        state = (tuple(axis.get_view_interval()), tuple(axis.axes.bbox.bounds), axis.axes.figure.dpi)
        if state not in ticks:
            ticks.clear()
            ticks[state] = update()
        return ticks[state]

    def ticklabel_bboxes(drawn, renderer=None):
        if not (boxes and boxes[0][0] is drawn and boxes[0][1] is renderer):
            boxes[:] = [(drawn, renderer, extents(drawn, renderer))]
        return boxes[0][2]

    return update_ticks, ticklabel_bboxes


def _in_view(axis):
    """``axis``'s major and minor tick locations without those outside its view, where its labels do not
    depend on them (log and empty labels).

    A log axis's locator also returns the decades around the view (a quarter of the ticks of a
    four-decade axis); matplotlib makes a tick (five artists) for each and then draws only those in
    view.  Other labels (plain numbers) take their precision from every location: left as they are.
    """
    from matplotlib.ticker import LogFormatter, NullFormatter

    def trimmed(get, ticker):
        def locations():
            locs = np.asarray(get())
            if not isinstance(ticker.formatter, (LogFormatter, NullFormatter)) or locs.size == 0:
                return locs
            transform = axis.get_transform()
            lo, hi = sorted(transform.transform(axis.get_view_interval()))
            slack = (hi - lo) * 1e-6  # wider than matplotlib's own test (1e-10): every tick it draws stays
            with np.errstate(invalid="ignore", divide="ignore"):
                t = transform.transform(locs)
            return locs[~((t < lo - slack) | (t > hi + slack))]

        return locations

    return trimmed(axis.get_majorticklocs, axis.major), trimmed(axis.get_minorticklocs, axis.minor)


#: Text sizes measured by :func:`_shared_text_metrics`, for the text settings (rcParams) they were measured with.
_TEXT_METRICS: dict = {}
#: The rcParams a text's measured size may depend on besides its string, font and resolution.
_TEXT_SETTINGS = ("font.", "text.", "mathtext.", "pdf.", "ps.", "svg.")


@contextlib.contextmanager
def _shared_text_metrics():
    """Within one save, measure each text once per process, output kind and resolution.

    Matplotlib keeps a text's measured size per renderer, and each file has a new renderer, so
    every figure measures its texts again (tick labels, legend entries, titles: the same strings
    in every figure of a job).  The size depends only on the string, the font, the math mode, the
    resolution, the kind of renderer and the text settings, so one cache keyed by those serves
    every renderer.  Matplotlib's own function again after the save; left as it is where
    matplotlib's internals differ.
    """
    import matplotlib as mpl
    from matplotlib import text as mtext

    measure = getattr(mtext, "_get_text_metrics_with_cache", None)
    if not callable(measure):
        yield
        return
    settings = tuple(sorted((k, repr(v)) for k, v in mpl.rcParams.items() if k.startswith(_TEXT_SETTINGS)))
    if settings not in _TEXT_METRICS:
        _TEXT_METRICS.clear()
        _TEXT_METRICS[settings] = {}
    sizes = _TEXT_METRICS[settings]

    def shared(renderer, text, fontprop, ismath, dpi):
        key = (type(renderer), getattr(renderer, "dpi", None), text, fontprop.copy(), ismath, dpi)
        size = sizes.get(key)
        if size is None:
            if len(sizes) >= 65536:  # a bound on the memory of a long process
                sizes.clear()
            size = sizes[key] = measure(renderer, text, fontprop, ismath, dpi)
        return size

    mtext._get_text_metrics_with_cache = shared
    try:
        yield
    finally:
        mtext._get_text_metrics_with_cache = measure


@functools.cache
def _share_mathtext():
    """Typeset each piece of mathematical text once per process instead of once per renderer.

    Matplotlib keeps the last 50 typeset strings, keyed by the renderer's parser too (each file has
    its own), so a figure with more distinct strings than that (log tick labels, legend entries with
    ``$p$``) typesets each of them again on every draw and every file.  The typesetting depends only on the string, resolution,
    font and output kind, never on the renderer, so one cache keyed by those serves every
    renderer.  Left as it is where matplotlib's internals differ.
    """
    from matplotlib.mathtext import MathTextParser

    uncached = getattr(MathTextParser._parse_cached, "__wrapped__", None)
    if uncached is None:
        return
    parsers = {}

    @functools.lru_cache(maxsize=4096)
    def shared(output_type, *args):
        return uncached(parsers[output_type], *args)

    def _parse_cached(self, *args):
        parsers.setdefault(self._output_type, self)
        return shared(self._output_type, *args)

    MathTextParser._parse_cached = _parse_cached


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
