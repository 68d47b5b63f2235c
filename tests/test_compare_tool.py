"""tools/compare_results.py finds what differs between two runs and forgives only timings."""

import importlib.util
import json

import numpy as np
import xarray as xr
from helpers import ROOT
from matplotlib.figure import Figure

from icosim.datasets import write_netcdf

spec = importlib.util.spec_from_file_location("compare_results", ROOT / "tools" / "compare_results.py")
compare_results = importlib.util.module_from_spec(spec)
spec.loader.exec_module(compare_results)


def _tree(root, *, rho=1.0, seconds=1.0, verdict="pass", line=1.0, history="now"):
    res = root / "results"
    ds = xr.Dataset(
        {"rho": ("x", np.array([0.5, rho, np.nan])), "name": ("x", np.array(["a", "b", "c"], dtype=object))}
    )
    ds.attrs.update(figure="9", seconds_total=seconds, history=history)
    write_netcdf(ds, res / "stability/fig9/r1.nc")
    (res / "stability/claims.json").write_text(json.dumps({"claims": [{"id": "c", "verdict": verdict}]}))
    fig = Figure(figsize=(1, 1))
    fig.subplots().plot([0, 1], [0, line])
    fig.savefig(res / "stability/fig9.png", format="png", dpi=20)
    return root


def test_equal_runs_and_timings_are_equal(tmp_path):
    old = _tree(tmp_path / "old")
    new = _tree(tmp_path / "new", seconds=2.0, history="later")
    problems, notes = compare_results.compare(old, new)
    assert problems == [] and "1 .nc" in notes[0]


def test_values_attributes_verdicts_and_pixels_are_caught(tmp_path):
    old = _tree(tmp_path / "old")
    new = _tree(tmp_path / "new", rho=np.nextafter(1.0, 2.0), verdict="fail", line=0.5)
    problems, _ = compare_results.compare(old, new)
    text = "\n".join(problems)
    assert "r1.nc:rho: values differ" in text  # one ulp
    assert "claims.json: JSON differs" in text and "fig9.png: pixels differ" in text
    (new / "results/stability/extra.tsv").write_text("x")
    assert any("only in NEW" in p for p in compare_results.compare(old, new)[0])


def test_report_masks_only_timings():
    cell = "<table><thead><tr><th>figure</th><th>mp CPU s</th></tr></thead><tbody><tr><td>Fig. 9</td><td>{}</td></tr></tbody></table>"
    assert compare_results._mask_html(cell.format("1.5")) == compare_results._mask_html(cell.format("7.0"))
    other = cell.replace("mp CPU s", "points")
    assert compare_results._mask_html(other.format("1.5")) != compare_results._mask_html(other.format("7.0"))
