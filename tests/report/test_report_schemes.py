"""The comparison of the coupling schemes: the stable shares of the panels side by side
(icosim.studies.stability.comparison) and the report's tables of them, of the orders and of the pendulum's runs
(icosim.report.schemes)."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from helpers import scheme_panel_spec

from icosim.report.schemes import order_rows, pendulum_rows, share_cells, stability_schemes
from icosim.studies.stability.comparison import scheme_shares
from icosim.studies.stability.datasets import stability_panel

BOTH = ("jacobi", "gauss-seidel-12", "gauss-seidel-21")


def _panel(figure, scheme, row, k, n=5):
    return stability_panel(scheme_panel_spec(figure, scheme, row, k, n))


def test_scheme_shares_tabulates_the_panels():
    panels = [_panel("9", s, row, k) for s in BOTH for row in (1, 2) for k in (1, 2)]
    panels += [_panel("16", "jacobi", 1, 1)]  # one scheme only: not compared
    ds = scheme_shares(panels)
    assert list(ds["figure"].values) == ["9"] and list(ds["scheme"].values) == list(BOTH)
    for p in panels[:-1]:
        share = float(ds["stable_share"].sel(figure="9", row=p.attrs["row"], k=p.attrs["k"], scheme=p.attrs["scheme"]))
        assert share == pytest.approx(float(p["stable"].values.mean()))
    cells = share_cells(ds)
    assert len(cells) == 2 and cells[0]["resolution"] == pytest.approx(0.25)
    html = stability_schemes(shares=ds, claims=[], comparison_png=_png(), figure_pngs=[], figures_cfg={})
    assert "Gauss–Seidel 1→2" in html and "Fig. 9 (baumgarte, ff) k = 1" in html


def _png(tmp=[]):  # noqa: B006 - one small PNG per session
    if not tmp:
        import tempfile

        from matplotlib.figure import Figure

        path = Path(tempfile.mkdtemp()) / "x.png"
        Figure(figsize=(1, 1)).savefig(path, dpi=10)
        tmp.append(path)
    return tmp[0]


def test_order_rows_and_pendulum_rows_read_the_data():
    recs = [
        {
            "figure": "23",
            "scheme": scheme,
            "decomposition": "ff",
            "method": "projection",
            "panel": "all",
            "index": 1,
            "k": 0,
            "order": order,
            "unstable": np.array([unstable] * 3),
        }
        for scheme, order, unstable in zip(BOTH, (2.0, 1.0, np.nan), (False, False, True))
    ]
    schemes, rows = order_rows(recs)
    assert schemes == list(BOTH)
    [(label, values)] = rows
    assert label.startswith("Fig. 23: ff, projection") and values == {
        "jacobi": 2.0,
        "gauss-seidel-12": 1.0,
        "gauss-seidel-21": "unstable",
    }
    summary = xr.Dataset(
        {
            "status": ("run", ["stable", "diverged"]),
            "t_diverged": ("run", [np.nan, 0.02]),
            "t_failed": ("run", [np.nan, np.nan]),
            "t_last": ("run", [0.5, 0.019]),
            "err_phi1": ("run", [1e-6, 1.0]),
            "err_phi2": ("run", [2e-6, 1.0]),
            "rho_test_model": ("run", [0.999, 1.85]),
            "reason": ("run", ["none", "|lambda_c| > 1000 N"]),
        },
        coords={
            "method": ("run", ["baumgarte"] * 2),
            "decomposition": ("run", ["ff"] * 2),
            "k": ("run", [1, 1]),
            "scheme": ("run", ["jacobi", "gauss-seidel-12"]),
        },
    )
    schemes, rows = pendulum_rows(summary)
    assert schemes == ["jacobi", "gauss-seidel-12"]
    [(key, by)] = rows
    assert key == ("baumgarte", "ff", 1) and by["gauss-seidel-12"]["t"] == 0.02
    assert by["jacobi"]["err_phi"] == 2e-6
