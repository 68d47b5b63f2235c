"""icosim.figures.save_figure: the files show what matplotlib draws, only with less repeated work."""

import io

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from PIL import Image  # noqa: E402

from icosim.figures import _in_view, _ticks_once, save_figure  # noqa: E402


def _figure():
    """A small grid like the project's: log axes (math tick labels), titles, labels, legends, a suptitle."""
    fig = Figure(figsize=(6, 4.5), layout="constrained")
    axes = fig.subplots(2, 2, sharex=True, sharey=True)
    H = np.geomspace(1e-5, 1e-2, 13)
    for n, ax in enumerate(axes.flat):
        for p in (1, 2, 3):
            ax.plot(H, (n + 1) * H**p, "o-", ms=3, label=f"k = {p - 1}: $p$ = {p:.2f}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"index {n + 1}; $\\mu$ = {0.001 * (n + 1):g} s", fontsize=9)
        ax.legend(loc="lower right", fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("macro-step size $H$ (s)")
    for ax in axes[:, 0]:
        ax.set_ylabel(r"NRMSE $\varepsilon_{glo}$")
    fig.suptitle("a convergence figure")
    fig.legend(handles=axes[0, 0].lines[:1], loc="outside lower center")
    return fig


def _pixels(data):
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGBA"))


def test_the_png_is_what_matplotlib_draws(tmp_path):
    fig = _figure()
    save_figure(fig, tmp_path / "a.png", tmp_path / "a.pdf", dpi=90)
    plain = io.BytesIO()
    _figure().savefig(plain, format="png", dpi=90)
    assert np.array_equal(_pixels((tmp_path / "a.png").read_bytes()), _pixels(plain.getvalue()))
    assert (tmp_path / "a.pdf").read_bytes().startswith(b"%PDF")


def test_one_draw_per_file_writes_the_files_of_matplotlibs_draw_before_each(tmp_path, monkeypatch):
    """The layout run before the PNG and no layout engine afterwards: each file is drawn once, and both files
    are those written when savefig draws the figure once more before each file (the layout engine, then its
    do-nothing placeholder)."""
    import icosim.figures as figures

    draws = []
    draw = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(self) or draw(self, renderer))
    fig = _figure()
    save_figure(fig, tmp_path / "a.png", tmp_path / "a.pdf", dpi=90)
    assert len(draws) == 2 and fig.get_layout_engine() is None
    monkeypatch.setattr(figures, "_lay_out", lambda fig: None)
    monkeypatch.setattr(figures, "_drop_layout_engine", lambda fig: fig.set_layout_engine("none"))
    plain = _figure()
    save_figure(plain, tmp_path / "b.png", tmp_path / "b.pdf", dpi=90)
    assert len(draws) == 6 and plain.get_layout_engine() is not None
    assert np.array_equal(_pixels((tmp_path / "a.png").read_bytes()), _pixels((tmp_path / "b.png").read_bytes()))
    assert (tmp_path / "a.pdf").read_bytes() == (tmp_path / "b.pdf").read_bytes()


def test_texts_measured_once_per_process_give_the_files_of_texts_measured_per_file(tmp_path, monkeypatch):
    """Two figures saved one after the other (the second measures its texts from the first's sizes): the
    same PNG pixels and PDF bytes as with matplotlib's measurement per renderer; matplotlib's function is
    back in place after each save."""
    import contextlib

    from matplotlib import text as mtext

    import icosim.figures as figures

    own = mtext._get_text_metrics_with_cache
    figures._TEXT_METRICS.clear()
    for n in range(2):
        save_figure(_figure(), tmp_path / f"a{n}.png", tmp_path / f"a{n}.pdf", dpi=90)
        assert mtext._get_text_metrics_with_cache is own
    assert any(figures._TEXT_METRICS.values())
    monkeypatch.setattr(figures, "_shared_text_metrics", contextlib.nullcontext)
    for n in range(2):
        save_figure(_figure(), tmp_path / f"b{n}.png", tmp_path / f"b{n}.pdf", dpi=90)
        assert np.array_equal(
            _pixels((tmp_path / f"a{n}.png").read_bytes()), _pixels((tmp_path / f"b{n}.png").read_bytes())
        )
        assert (tmp_path / f"a{n}.pdf").read_bytes() == (tmp_path / f"b{n}.pdf").read_bytes()


def test_a_matplotlib_without_the_tick_internals_draws_as_usual(tmp_path, monkeypatch):
    """The tick shortcuts stand in for private matplotlib methods: where one of them is missing (here: a
    name no matplotlib has), no axis is touched and the file is matplotlib's own drawing, not an error."""
    import icosim.figures as figures

    monkeypatch.setattr(figures, "_TICK_INTERNALS", (*figures._TICK_INTERNALS, "_a_method_no_matplotlib_has"))
    fig = _figure()
    with _ticks_once(fig):
        assert not any("_update_ticks" in vars(axis) for ax in fig.axes for axis in (ax.xaxis, ax.yaxis))
    save_figure(fig, tmp_path / "a.png", dpi=90)
    plain = io.BytesIO()
    _figure().savefig(plain, format="png", dpi=90)
    assert np.array_equal(_pixels((tmp_path / "a.png").read_bytes()), _pixels(plain.getvalue()))


def test_titles_and_labels_keep_their_place_at_another_resolution(tmp_path):
    """The PDF keeps the places the PNG's draw gave the titles and axis labels (in axes coordinates):
    the places matplotlib computes again at the PDF's resolution, to a fraction of a point."""
    fig = _figure()
    save_figure(fig, tmp_path / "a.png", tmp_path / "a.pdf", dpi=110)
    again = _figure()
    again.set_layout_engine("none")
    for ax, kept in zip(again.axes, fig.axes):
        ax.set_position(kept.get_position())
    again.set_dpi(72)
    FigureCanvasAgg(again).draw()
    fig.set_dpi(72)
    FigureCanvasAgg(fig).draw()
    for ax, kept in zip(again.axes, fig.axes):
        for text, same in [
            (ax.title, kept.title),
            (ax.xaxis.label, kept.xaxis.label),
            (ax.yaxis.label, kept.yaxis.label),
        ]:
            if text.get_text():
                a, b = text.get_window_extent(), same.get_window_extent()
                assert abs(a.x0 - b.x0) < 0.5 and abs(a.y0 - b.y0) < 0.5, (text.get_text(), a, b)


def test_saving_leaves_the_axes_as_matplotlib_made_them(tmp_path):
    fig = _figure()
    save_figure(fig, tmp_path / "a.png", tmp_path / "a.pdf")
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            assert not {"_update_ticks", "_get_ticklabel_bboxes", "get_majorticklocs", "get_minorticklocs"} & set(
                vars(axis)
            )


def test_ticks_outside_the_view_are_left_out_only_where_labels_do_not_depend_on_them():
    fig = _figure()
    FigureCanvasAgg(fig).draw()
    ax = fig.axes[0]
    lin = fig.add_subplot(3, 3, 9)
    lin.plot([0.1, 0.37], [2.0, 2.3])
    FigureCanvasAgg(fig).draw()
    for axis in (ax.xaxis, ax.yaxis, lin.xaxis, lin.yaxis):
        drawn = [t.get_loc() for t in axis._update_ticks()]
        labels = [t.label1.get_text() for t in axis._update_ticks()]
        major, minor = _in_view(axis)
        with _ticks_once(fig):
            assert [t.get_loc() for t in axis._update_ticks()] == drawn
            assert [t.label1.get_text() for t in axis._update_ticks()] == labels
        if axis in (lin.xaxis, lin.yaxis):  # plain numbers: every location kept
            assert np.array_equal(major(), axis.get_majorticklocs())
        else:  # log: the decades around the view left out, every drawn location kept
            kept, every = len(major()) + len(minor()), len(axis.get_majorticklocs()) + len(axis.get_minorticklocs())
            assert kept < every if axis is ax.xaxis else kept <= every
            assert set(drawn) <= set(major()) | set(minor())
