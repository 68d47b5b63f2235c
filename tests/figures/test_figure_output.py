"""What the figure and report jobs write: the same pixels however the datasets are read and the files encoded."""

import io

import numpy as np
import pytest

pytest.importorskip("matplotlib")
xr = pytest.importorskip("xarray")

from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from PIL import Image  # noqa: E402

from icosim.figures.pendulum import DRAWN_VARIABLES, PANELS, error_figure, pendulum_figure  # noqa: E402
from icosim.io.netcdf import open_dataset, open_variables, write_netcdf  # noqa: E402
from icosim.report.html import compact_png  # noqa: E402


def _run(t, scale, **attrs):
    """A pendulum run (or reference) over ``t``: smooth curves, one per panel, and a variable not drawn."""
    data = {name: ("t", scale * np.sin((n + 1) * t) + 1e-3 * n) for n, (name, _) in enumerate(PANELS)}
    data["g_cax_corrector"] = ("t", np.cos(t))
    return xr.Dataset(data, coords={"t": ("t", t, {"units": "s"})}, attrs=attrs)


def _pixels(fig):
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())


def test_pendulum_figures_from_the_drawn_variables_are_those_from_the_whole_datasets(tmp_path):
    """The pendulum figure jobs read only DRAWN_VARIABLES (open_variables, no xarray): the same pixels as
    the figures drawn from the whole datasets (open_dataset), a diverged run (shorter, marked) included."""
    t = np.linspace(0.0, 2.0, 201)
    write_netcdf(_run(t, 1.0), tmp_path / "reference.nc")
    write_netcdf(_run(t, 1.01, method="baumgarte", decomposition="ff", k=1, status="stable"), tmp_path / "a.nc")
    diverged = _run(t[:120], 1.3, method="projection", decomposition="fd", k=1, status="diverged", t_diverged=t[119])
    write_netcdf(diverged, tmp_path / "b.nc")
    paths = [tmp_path / "a.nc", tmp_path / "b.nc"]
    drawn = [open_variables(p, DRAWN_VARIABLES) for p in paths]
    whole = [open_dataset(p) for p in paths]
    ref_drawn, ref_whole = (
        open_variables(tmp_path / "reference.nc", DRAWN_VARIABLES),
        open_dataset(tmp_path / "reference.nc"),
    )
    assert set(drawn[0]) == set(DRAWN_VARIABLES) and len(drawn[1]["t"]) == 120
    assert np.array_equal(
        _pixels(pendulum_figure(drawn, ref_drawn, k=1)), _pixels(pendulum_figure(whole, ref_whole, k=1))
    )
    assert np.array_equal(_pixels(error_figure({1: drawn}, ref_drawn)), _pixels(error_figure({1: whole}, ref_whole)))


def test_the_palette_png_has_the_pixels_of_its_quantization_at_any_compression():
    """compact_png's zlib level changes the bytes only: decoded, the palette PNG is the 256-colour quantization
    (maximum coverage, no dithering) of the figure, as written at the strongest compression."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3, 2))
    ax = fig.add_subplot()
    ax.pcolormesh(np.add.outer(np.arange(40.0), np.arange(60.0)), cmap="RdYlGn_r")
    ax.plot([0, 59], [0, 39], "k-")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    png = buf.getvalue()
    small = compact_png(png)
    assert small.startswith(b"\x89PNG") and len(small) < len(png)
    with Image.open(io.BytesIO(png)) as im:
        pal = im.convert("RGB").quantize(256, method=Image.Quantize.MAXCOVERAGE, dither=Image.Dither.NONE)
    strongest = io.BytesIO()
    pal.save(strongest, "PNG", optimize=True)
    with Image.open(io.BytesIO(small)) as a, Image.open(strongest) as b:
        assert a.mode == "P" and np.array_equal(np.asarray(a.convert("RGB")), np.asarray(b.convert("RGB")))


def test_the_work_precision_figure_from_its_drawn_variables_is_that_from_the_whole_dataset(tmp_path):
    """The convergence work-precision job reads only WORK_PRECISION_VARIABLES (open_variables): the same pixels
    as from the whole dataset (open_dataset), strings, a configuration without finite points and NaN included."""
    from icosim.figures.convergence import WORK_PRECISION_VARIABLES, work_precision_figure

    H = np.geomspace(1e-4, 1e-2, 5)
    configs = ["21 Baumgarte k=0", "21 Baumgarte k=1", "21 projection k=0", "22 Baumgarte k=2"]
    decs = ["ff", "ff", "fd", "fd"]
    nrmse = np.outer([1.0, 0.1, 2.0, 0.05], H) ** np.array([[1.0], [2.0], [1.0], [3.0]])
    nrmse[1, -1] = np.nan
    cost = 1.0 / np.outer([1.0, 1.5, 2.0, 3.0], H)
    cost[3] = np.nan  # drawn nowhere
    wp = xr.Dataset(
        {
            "nrmse": (("configuration", "H"), nrmse),
            "cpu_seconds_per_simulated_second": (("configuration", "H"), cost),
            "setup_seconds": ("configuration", np.ones(4)),
            "decomposition": ("configuration", np.array(decs, dtype=object)),
            "k": ("configuration", np.array([0, 1, 0, 2], dtype=np.int32)),
        },
        coords={"configuration": np.array(configs, dtype=object), "H": H},
    )
    write_netcdf(wp, tmp_path / "wp.nc")
    drawn, whole = open_variables(tmp_path / "wp.nc", WORK_PRECISION_VARIABLES), open_dataset(tmp_path / "wp.nc")
    assert set(drawn) == set(WORK_PRECISION_VARIABLES)
    assert np.array_equal(_pixels(work_precision_figure(drawn)), _pixels(work_precision_figure(whole)))
