"""What the claims and scheme-share jobs read of a panel: only the variables their checks name
(icosim.studies.stability.checks.PANEL_VARIABLES, read by icosim.io.netcdf.open_variables), with the verdicts and
shares that the whole datasets (icosim.io.netcdf.open_dataset) give."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import pytest  # noqa: E402
import yaml  # noqa: E402
from helpers import ROOT  # noqa: E402

from icosim.claims.registry import evaluate, load_claims  # noqa: E402
from icosim.io.netcdf import open_dataset, open_variables, write_netcdf  # noqa: E402
from icosim.studies.stability.checks import PANEL_VARIABLES  # noqa: E402
from icosim.studies.stability.comparison import scheme_shares  # noqa: E402
from icosim.studies.stability.datasets import stability_panel  # noqa: E402
from icosim.studies.stability.panels import figure_panels  # noqa: E402

CFG = yaml.safe_load((ROOT / "config" / "stability.yaml").read_text())["stability"]
COARSE = {"lr1": [-2.0, 0.0], "li1": [0.0, 2.0], "n": 9}
ZOOM = {"lr1": [-0.2, 0.0], "li1": [0.0, 0.2], "n": 11}  # every claim's region holds points


@pytest.fixture(scope="module")
def panel_files(tmp_path_factory):
    """Coarse panels of figures with several schemes, zooms and the index-3 method, written as the jobs write them."""
    where = tmp_path_factory.mktemp("panels")
    paths = []
    for fig in ("9", "13", "18"):
        specs = figure_panels(
            fig, CFG["figures"][fig], grid=COARSE, zoom_grid=ZOOM, precision={"policy": "auto", "digits": 30}
        )
        for n, spec in enumerate(specs):
            paths.append(where / f"fig{fig}_{n}.nc")
            write_netcdf(stability_panel(spec), paths[-1])
    return paths


def test_claims_from_the_checked_variables_alone_are_the_claims_from_the_datasets(panel_files):
    claims = load_claims(ROOT / "config" / "claims" / "stability.yaml")
    whole = evaluate(claims, [open_dataset(p) for p in panel_files])
    alone = evaluate(claims, [open_variables(p, PANEL_VARIABLES) for p in panel_files])
    assert [(v.claim.id, v.verdict, v.measured) for v in alone] == [(v.claim.id, v.verdict, v.measured) for v in whole]
    # the checks read the panels (no claim of these figures left without data)
    decided = {v.claim.id for v in whole if v.verdict in ("pass", "fail")}
    assert any(i.startswith("fig9") for i in decided) and any(i.startswith("fig18") for i in decided)


def test_scheme_shares_from_the_checked_variables_alone_are_the_shares_from_the_datasets(panel_files):
    whole = scheme_shares([open_dataset(p) for p in panel_files])
    alone = scheme_shares([open_variables(p, PANEL_VARIABLES) for p in panel_files])
    assert list(whole["figure"].values) == ["9", "13"] and whole.sizes["scheme"] == 3
    assert alone.identical(whole)
