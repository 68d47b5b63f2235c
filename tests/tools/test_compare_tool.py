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


def test_a_directory_without_datasets_is_refused_not_equal(tmp_path):
    """Comparing nothing proves nothing: a run directory given one level too deep (its results/ itself)
    or an empty one is a difference that names the side, not "equal"."""
    run = _tree(tmp_path / "run")
    for old, new, side in ((run / "results", run, "OLD"), (run, tmp_path / "empty", "NEW")):
        problems, _ = compare_results.compare(old, new)
        assert len(problems) == 1 and problems[0].startswith(f"{side} ") and "no datasets" in problems[0]
        assert compare_results.main([str(old), str(new), "--tolerances"]) == 1


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


# -- --tolerances ------------------------------------------------------------------------------------------------


def _run_tree(root, *, rho=1.0, verdict=1, claim="pass", nrmse=1e-3, phi=0.5, status="bounded", extra=False):
    """A small run: a Jacobi and a Gauss-Seidel stability panel, a convergence panel, a pendulum run, the claims."""
    res = root / "results"
    for scheme in ("jacobi", "gauss-seidel-12"):
        grid = {"lr1": [-1.0, 0.0], "li1": [0.0, 1.0]}
        ds = xr.Dataset(
            {
                "rho": (("lr1", "li1"), np.array([[0.5, rho], [np.nan, 2.0]])),
                "rho_upper": (("lr1", "li1"), np.array([[0.5, rho], [np.nan, 2.0]]) * (1 + 1e-9 * (rho != 1.0))),
                "verdict": (("lr1", "li1"), np.array([[1, verdict], [3, 2]], dtype=np.int8)),
            },
            coords=grid,
        )
        ds.attrs.update(figure="9", scheme=scheme, n_stable=2, seconds_total=1.0)
        write_netcdf(ds, res / f"stability/fig9/{scheme}/r1_k0_full.nc")
    conv = xr.Dataset(
        {"nrmse": (("k", "H"), np.array([[nrmse, np.nan]])), "order": ("k", [2.0])}, coords={"k": [0], "H": [0.1, 0.2]}
    )
    write_netcdf(conv, res / "convergence/fig21/jacobi/ff_c1.nc")
    run = xr.Dataset({"phi1": ("t", [0.1, phi]), "phi2": ("t", [0.2, 0.3])}, coords={"t": [0.0, 0.01]})
    run.attrs.update(status=status, run="projection_ff_k0_gauss-seidel-12")
    write_netcdf(run, res / "pendulum/runs/gauss-seidel-12/projection_ff_k0.nc")
    claims = [{"id": "fig9_stable", "verdict": claim, "measured": "0.5 (1.2 s)"},
              {"id": "gs_fig9_same", "verdict": "pass", "measured": "x"}]  # fmt: skip
    if rho != 1.0:
        claims[0]["measured"] = "0.5 (0.3 s)"  # timing numbers in the measured text: a note
    (res / "stability/claims.json").write_text(json.dumps({"claims": claims}))
    if extra:  # a figure NEW adds
        write_netcdf(ds, res / "stability/figdf-baumgarte/jacobi/r1_k0_full.nc")
    return root


def _tolerances(old, new, **kw):
    stats = compare_results.tol.new_stats()
    problems, notes = compare_results.compare(old, new, tolerances=True, stats=stats, **kw)
    return problems, notes, stats


def test_tolerances_pass_within_them(tmp_path):
    old = _run_tree(tmp_path / "old")
    new = _run_tree(tmp_path / "new", rho=1.0 + 1e-13, nrmse=1e-3 * (1 + 1e-10), phi=0.5 + 1e-10, extra=True)
    problems, notes, stats = _tolerances(old, new, allow_new_files=True)
    assert problems == []
    text = "\n".join(notes)
    assert "stability/figdf-baumgarte/jacobi/r1_k0_full.nc: only in NEW (added)" in text
    assert "rho_upper" in text  # another variable: a note
    assert "field 'measured' differs in 1 claim(s): fig9_stable" in text
    assert 0 < stats["stability"]["rho"] < 1e-12 and stats["stability"]["datasets"] == 2
    assert 0 < stats["convergence"]["nrmse"] < 1e-9 and 0 < stats["pendulum"]["angle"] < 1e-9
    assert stats["claims"]["ids"] == {("stability", "fig9_stable"), ("stability", "gs_fig9_same")}
    assert not stats["claims"]["changed"]
    # without the flag, the added figure is a difference
    assert _tolerances(old, new)[0] == ["stability/figdf-baumgarte/jacobi/r1_k0_full.nc: only in NEW"]


def test_tolerances_catch_what_exceeds_them(tmp_path):
    old = _run_tree(tmp_path / "old")
    new = _run_tree(tmp_path / "new", rho=1.0 + 1e-11, nrmse=1e-3 * (1 + 1e-8), phi=0.5 + 1e-8)
    problems, _, stats = _tolerances(old, new)
    text = "\n".join(problems)
    assert (
        "stability/fig9/jacobi/r1_k0_full.nc:rho: relative difference 1e-11 > 1e-12 at 1 points (lr1=-1.0, li1=1.0)"
        in text
    )
    assert "convergence/fig21/jacobi/ff_c1.nc:nrmse: relative difference 1e-08 > 1e-09" in text
    assert (
        "pendulum/runs/gauss-seidel-12/projection_ff_k0.nc:phi1: absolute difference 1e-08 > 1e-09 at 1 points (t=0.01)"
        in text
    )
    assert len(problems) == 4  # rho in both schemes' panels, nrmse, phi1
    assert stats["stability"]["rho"] > 1e-12 and stats["pendulum"]["angle"] > 1e-9


def test_tolerances_catch_changed_verdicts(tmp_path):
    old = _run_tree(tmp_path / "old")
    new = _run_tree(tmp_path / "new", verdict=2, claim="fail")
    problems, _, stats = _tolerances(old, new)
    text = "\n".join(problems)
    assert "stability/fig9/gauss-seidel-12/r1_k0_full.nc:verdict: 1 value(s) changed (lr1=-1.0, li1=1.0): 1->2" in text
    assert "stability/claims.json: claim fig9_stable: verdict pass -> fail (the same claim)" in text
    assert stats["stability"]["verdicts"] == 2 and stats["claims"]["changed"] == {("stability", "fig9_stable")}
    # a changed status attribute, or a NaN where OLD had a number, fails too
    new2 = _run_tree(tmp_path / "new2", rho=np.nan, status="diverged")
    text = "\n".join(_tolerances(old, new2)[0])
    assert "rho: NaN in one run only at 1 points" in text
    assert "projection_ff_k0.nc: global attribute 'status': 'bounded' != 'diverged'" in text


def test_tolerances_command_line_prints_the_table(tmp_path, capsys):
    old = _run_tree(tmp_path / "old")
    new = _run_tree(tmp_path / "new", rho=1.0 + 1e-13)
    assert compare_results.main([str(old), str(new), "--tolerances"]) == 0
    out = capsys.readouterr().out
    assert "max rel rho" in out and "equal within the tolerances" in out
    assert compare_results.main([str(old), str(new)]) == 1  # bitwise: rho differs


def test_a_summary_with_more_runs_is_compared_at_old_runs(tmp_path):
    """NEW's pendulum summary holds more runs than OLD's: compared at OLD's runs, a changed status found."""

    def summary(path, runs, status):
        ds = xr.Dataset({"status": ("run", np.array(status, dtype=object)), "err_phi1": ("run", np.ones(len(runs)))})
        write_netcdf(ds.assign_coords(run=("run", np.array(runs, dtype=object))), path)

    old, new = tmp_path / "old/results/pendulum", tmp_path / "new/results/pendulum"
    summary(old / "summary.nc", ["projection_ff_k0", "projection_ff_k0_gauss-seidel-12"], ["bounded", "diverged"])
    runs = ["projection_ff_k0", "projection_ff_k0_gauss-seidel-12", "projection_ff_k0_gauss-seidel-21"]
    summary(new / "summary.nc", runs, ["bounded", "diverged", "bounded"])
    problems, notes, stats = _tolerances(tmp_path / "old", tmp_path / "new")
    assert problems == [] and stats["pendulum"]["datasets"] == 1
    assert "pendulum/summary.nc: NEW has 1 more run labels than OLD: compared at OLD's 2" in "\n".join(notes)
    summary(new / "summary.nc", runs, ["bounded", "bounded", "bounded"])
    problems = _tolerances(tmp_path / "old", tmp_path / "new")[0]
    assert problems == [
        "pendulum/summary.nc:status: 1 value(s) changed (run='projection_ff_k0_gauss-seidel-12'): 'diverged'->'bounded'"
    ]
