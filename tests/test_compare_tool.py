"""tools/compare_results.py finds what differs between two runs and forgives only timings."""

import importlib.util
import json

import numpy as np
import xarray as xr
from helpers import ROOT
from matplotlib.figure import Figure

from icosim.io.netcdf import write_netcdf

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


def test_certification_timings_are_volatile(tmp_path):
    # the certified recheck's seconds (panel attributes) and its share in the stability section
    assert {"seconds_certify", "cpu_seconds_certify"} <= compare_results.VOLATILE_ATTRS
    phrase = "<p>The certification took {}% of the sweeps' compute time ({} of {} CPU-seconds in 144 panel jobs).</p>"
    assert compare_results._mask_html(phrase.format(27, 6, 21)) == compare_results._mask_html(phrase.format(26, 6, 23))
    cell = "<table><thead><tr><th>certification CPU s</th><th>its share of CPU</th></tr></thead><tbody><tr><td>{}</td><td>{}%</td></tr></tbody></table>"
    assert compare_results._mask_html(cell.format(0.9, 39)) == compare_results._mask_html(cell.format(1.0, 37))
    assert compare_results._mask_html("<p>6 of 21 points</p>") != compare_results._mask_html("<p>6 of 23 points</p>")


def test_allow_added_forgives_only_what_new_adds(tmp_path):
    from icosim.io.netcdf import provenance_attrs

    def tree(root, job, extra_attr=None, coord=False, rho=1.0):
        ds = xr.Dataset({"rho": ("x", np.array([0.5, rho]))})
        if coord:
            ds = ds.assign_coords(scheme=("x", np.array(["jacobi", "jacobi"], dtype=object)))
        ds.attrs.update(provenance_attrs(job, title="t"))
        if extra_attr:
            ds.attrs.update(extra_attr)
        write_netcdf(ds, root / "results/p.nc")
        return root

    old = tree(tmp_path / "old", {"k": 1})
    new = tree(tmp_path / "new", {"k": 1, "scheme": "jacobi"}, {"scheme": "jacobi"}, coord=True)
    assert compare_results.compare(old, new)[0]  # without the option: differs
    assert compare_results.compare(old, new, ["scheme"])[0] == []
    # a changed value, or a changed key besides the added one, is still caught
    changed = tree(tmp_path / "changed", {"k": 2, "scheme": "jacobi"}, {"scheme": "jacobi"}, coord=True)
    assert any("config_json" in p for p in compare_results.compare(old, changed, ["scheme"])[0])
    value = tree(tmp_path / "value", {"k": 1, "scheme": "jacobi"}, {"scheme": "jacobi"}, coord=True, rho=2.0)
    assert any("rho: values differ" in p for p in compare_results.compare(old, value, ["scheme"])[0])
    # an attribute OLD already had is compared as usual
    old2 = tree(tmp_path / "old2", {"k": 1}, {"scheme": "jacobi"})
    new2 = tree(tmp_path / "new2", {"k": 1}, {"scheme": "gauss-seidel-12"})
    assert any("scheme" in p for p in compare_results.compare(old2, new2, ["scheme"])[0])
