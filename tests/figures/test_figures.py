"""icosim.figures.save_figure: the files show what matplotlib draws, only with less repeated work (public API only)."""

import io

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from PIL import Image  # noqa: E402

from icosim.figures import save_figure  # noqa: E402


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


def test_labels_keep_their_place_at_another_resolution(tmp_path):
    """The PDF keeps the places the PNG's draw gave the axis labels (in axes coordinates): the places
    matplotlib computes again at the PDF's resolution, to a fraction of a point (the titles it places itself)."""
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


def test_a_log_axis_makes_only_the_ticks_in_its_view(tmp_path):
    """Saved, a log axis from 2e-6 to 3e-3 makes one tick per decade 1e-5 ... 1e-3 and one minor tick at each
    m * 10^e (m = 2 ... 9) inside the view (counted here from the definition), and draws those matplotlib draws."""
    fig = Figure(figsize=(4, 3))
    ax = fig.subplots()
    ax.plot([2e-6, 3e-3], [1, 2])
    ax.set_xscale("log")
    ax.set_xlim(2e-6, 3e-3)
    plain = io.BytesIO()
    fig.savefig(plain, format="png", dpi=90)
    save_figure(fig, tmp_path / "a.png", dpi=90)
    minor = [m * 10.0**e for e in range(-6, -2) for m in range(2, 10) if 2e-6 <= m * 10.0**e <= 3e-3]
    np.testing.assert_allclose(ax.xaxis.get_majorticklocs(), [1e-5, 1e-4, 1e-3])
    np.testing.assert_allclose(ax.xaxis.get_minorticklocs(), minor)
    assert np.array_equal(_pixels((tmp_path / "a.png").read_bytes()), _pixels(plain.getvalue()))
