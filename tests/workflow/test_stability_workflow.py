"""The Snakemake side of the stability part: scheduling, validation, rerun triggers, CI merge.

Each test works on a copy of the workflow in a temporary directory, so it
never touches results/ of the checkout.  Dry runs are cheap; one test runs a
tiny real workflow (two figures: 6 panels of Fig. 18 and 2 of Fig. 19, on 4 x 4
points) to check the rerun triggers.  One job per figure computes its panels
(rule stability_panels_fig<figure>), one draws it for every scheme
(stability_figure_fig<figure>): changing one panel's parameter reruns at most the
jobs of its figure.
"""

import copy
import json
import os
import re
from pathlib import Path

import pytest
import yaml
from helpers import ROOT, copy_workflow, scheduled, scheduled_jobs, snakemake

from icosim.studies.stability.panels import figure_panels, figure_schemes, panel_id


@pytest.fixture(scope="module")
def workflow_copy(tmp_path_factory):
    return copy_workflow(tmp_path_factory.mktemp("wf"))


def stability_config(root=ROOT):
    return yaml.safe_load((root / "config" / "stability.yaml").read_text())["stability"]


def panel_files(cfg, fig):
    """The datasets of a figure's panels as configured: results/stability/fig<figure>/<scheme>/<panel>.nc."""
    specs = figure_panels(
        fig, cfg["figures"][fig], grid=cfg["grid"], zoom_grid=cfg["zoom_grid"], precision=cfg["precision"]
    )
    return [f"results/stability/fig{fig}/{s.scheme}/{panel_id(s.row, s.k, s.view)}.nc" for s in specs]


def test_one_figure_target_schedules_only_that_figures_panels(workflow_copy):
    proc = snakemake(workflow_copy, "-n", "results/stability/figures/fig9_jacobi.png")
    jobs = scheduled_jobs(proc, "stability_")
    # one job computes the figure's panels, one draws it: no other figure's job, no claims
    assert set(jobs) == {"stability_panels_fig9", "stability_figure_fig9"}
    cfg = stability_config()
    expected = panel_files(cfg, "9")
    assert sorted(jobs["stability_panels_fig9"]) == sorted(expected) and len(set(expected)) == len(expected)
    schemes = [name for name, _ in figure_schemes("9", cfg["figures"]["9"])]
    assert "jacobi" in schemes
    for scheme in schemes:  # 4 rows x k = 0, 1, 2, plus the zoom of row 4, k = 2, for every scheme
        assert len([f for f in expected if f"/fig9/{scheme}/" in f]) == 4 * 3 + 1
    assert jobs["stability_figure_fig9"] == [
        f"results/stability/figures/fig9_{scheme}.{ext}" for scheme in schemes for ext in ("png", "pdf")
    ]
    assert not scheduled(proc, "stability_claims")


@pytest.mark.parametrize(
    "override, names",
    [
        ({"grid": {"npoints": 5}}, ["npoints"]),
        ({"precision": {"policy": "fastest"}}, ["fastest", "policy"]),
        ({"figures": {"9": {"rows": [{"am21": -1.0}]}}}, ["am21"]),
        ({"figures": {"9": {"zoom": {"rows": [7], "k": [2]}}}}, ["stability.figures.9.zoom.rows"]),
        (
            {"figures": {"18": {"rows": [{"a": 1.0}]}}},
            ["stability.figures.18", "row 1", "not used by method"],
        ),
        # grids are checked when the workflow is parsed, not in the sweep jobs
        ({"grid": {"lr1": [0.0, -2.0]}}, ["stability.grid.lr1 must be increasing"]),
        ({"zoom_grid": {"li1": [0.2, 0.2]}}, ["stability.zoom_grid.li1 must be increasing"]),
        ({"zoom_grid": {"lr1": [-0.2, 0.1]}}, ["stability.zoom_grid.lr1 must lie in lr1 <= 0"]),
        ({"grid": {"li1": [-1.0, 2.0]}}, ["stability.grid.li1 must lie in li1 >= 0"]),
        # the claims file is read (and checked) when the workflow is parsed
        ({"claims": {"file": "BADCLAIMS"}}, ["fig9_wide_stable_range", "check (stable_fraction) lacks ['op']"]),
    ],
)
def test_bad_configuration_fails_before_any_job_naming_the_key(workflow_copy, tmp_path, override, names):
    bad = tmp_path / "bad.yaml"
    if override.get("claims", {}).get("file") == "BADCLAIMS":
        # the shipped claims with one check parameter left out
        doc = yaml.safe_load((ROOT / "config" / "claims" / "stability.yaml").read_text())
        del doc["claims"][0]["check"]["op"]
        (tmp_path / "claims.yaml").write_text(yaml.safe_dump(doc))
        override = {"claims": {"file": str(tmp_path / "claims.yaml")}}
    bad.write_text(yaml.safe_dump({"stability": override}))
    proc = snakemake(workflow_copy, "-n", "--configfile", str(bad), check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0
    for name in names:
        assert name in out, out[-2000:]
    assert "rule stability_panels" not in out and "rule stability_figure" not in out  # nothing was scheduled


def ci_config():
    """config/stability.yaml with config/ci/stability.yaml merged in, as --configfile does."""
    from snakemake.utils import update_config

    merged = copy.deepcopy(stability_config())
    update_config(merged, yaml.safe_load((ROOT / "config" / "ci" / "stability.yaml").read_text())["stability"])
    return merged


def layout_count(cfg):
    """Panels the configuration asks for, counted from its layout: per figure and scheme, rows x k
    plus the zooms (independent of figure_panels)."""
    n = 0
    for fig, fc in cfg["figures"].items():
        zoom = fc.get("zoom") or {"rows": [], "k": []}
        for _, rows in figure_schemes(str(fig), fc):
            rows = rows or range(1, len(fc["rows"]) + 1)
            n += len(rows) * len(fc["k"]) + len([r for r in rows if r in zoom["rows"]]) * len(zoom["k"])
    return n


def test_ci_override_keeps_every_panel_on_coarse_grids():
    """--configfile is merged recursively (lists replaced): the CI file only coarsens grids."""
    full = stability_config()
    merged = ci_config()
    assert merged["figures"] == full["figures"]
    assert merged["grid"]["n"] < full["grid"]["n"] and merged["zoom_grid"]["n"] < full["zoom_grid"]["n"]
    assert merged["grid"]["lr1"] == full["grid"]["lr1"]

    def specs(cfg):
        return [
            s
            for f, fc in cfg["figures"].items()
            for s in figure_panels(f, fc, grid=cfg["grid"], zoom_grid=cfg["zoom_grid"], precision=cfg["precision"])
        ]

    assert len(specs(merged)) == len(specs(full)) == layout_count(full)
    assert {s.n for s in specs(merged)} == {merged["grid"]["n"], merged["zoom_grid"]["n"]}
    assert merged["claims"]["enforce_reference"] is True


def test_ci_override_is_what_snakemake_schedules(workflow_copy):
    proc = snakemake(workflow_copy, "results/stability/claims.json", "-n", "--configfile", "config/ci/stability.yaml")
    jobs = scheduled_jobs(proc, "stability_panels_fig")
    merged = ci_config()
    assert set(jobs) == {f"stability_panels_fig{fig}" for fig in merged["figures"]}  # one job per figure
    assert sum(len(outs) for outs in jobs.values()) == layout_count(merged)
    for fig in merged["figures"]:
        assert sorted(jobs[f"stability_panels_fig{fig}"]) == sorted(panel_files(merged, str(fig)))


#: the figures of the tiny run (Jacobi only, as Figs. 18 and 19 are configured)
TINY_FIGURES = ("results/stability/figures/fig18_jacobi.png", "results/stability/figures/fig19_jacobi.png")


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    """A real run of a two-figure configuration on a 4 x 4 grid: Fig. 18 with two rows (6 panels) and,
    to tell one figure's jobs from another's, Fig. 19 with one row and k = 0, 1 (2 panels)."""
    wf = copy_workflow(tmp_path_factory.mktemp("tiny"))
    cfg = yaml.safe_load((wf / "config" / "stability.yaml").read_text())
    st = cfg["stability"]
    st["grid"]["n"] = 4
    st["zoom_grid"]["n"] = 3
    st["figures"] = {
        "18": {**st["figures"]["18"], "rows": [{}, {"am21": 3.0}]},
        "19": {**st["figures"]["19"], "rows": [{"mu": 1.0}], "k": [0, 1]},
    }
    (wf / "config" / "stability.yaml").write_text(yaml.safe_dump(cfg))
    snakemake(wf, "-c2", *TINY_FIGURES)
    return wf


def edit_config(wf, fn):
    path = wf / "config" / "stability.yaml"
    cfg = yaml.safe_load(path.read_text())
    fn(cfg["stability"])
    path.write_text(yaml.safe_dump(cfg))


def test_tiny_run_writes_the_panels_and_the_figure(tiny_run):
    for row in (1, 2):
        for k in (0, 1, 2):
            assert (tiny_run / f"results/stability/fig18/jacobi/r{row}_k{k}_full.nc").is_file()
    assert sorted(panel_files(stability_config(tiny_run), "18")) == sorted(
        str(p.relative_to(tiny_run)) for p in (tiny_run / "results/stability/fig18").rglob("*.nc")
    )
    assert (tiny_run / "results/stability/figures/fig18_jacobi.png").read_bytes()[:4] == b"\x89PNG"
    assert (tiny_run / "results/stability/figures/fig18_jacobi.pdf").read_bytes()[:4] == b"%PDF"
    assert (tiny_run / "logs/stability/panels/fig18.log").is_file()


def test_changing_one_row_reruns_that_figures_jobs_only(tiny_run):
    proc = snakemake(tiny_run, "-n", *TINY_FIGURES)
    assert not scheduled_jobs(proc, "stability_")  # up to date
    edit_config(tiny_run, lambda st: st["figures"]["18"]["rows"][1].update(am21=4.0))
    proc = snakemake(tiny_run, "-n", *TINY_FIGURES)
    jobs = scheduled_jobs(proc, "stability_")
    # at most the jobs of the figure whose panel changed: Fig. 19's panels and figure are not rerun
    assert set(jobs) == {"stability_panels_fig18", "stability_figure_fig18"}
    assert sorted(jobs["stability_panels_fig18"]) == sorted(panel_files(stability_config(tiny_run), "18"))
    edit_config(tiny_run, lambda st: st["figures"]["18"]["rows"][1].update(am21=3.0))  # back
    assert not scheduled_jobs(snakemake(tiny_run, "-n", *TINY_FIGURES), "stability_")


def test_restyling_reruns_no_sweep_and_library_edits_rerun_their_users(tiny_run):
    target = TINY_FIGURES[0]
    edit_config(tiny_run, lambda st: st["plot"].update(style="dots"))
    proc = snakemake(tiny_run, "-n", target)
    assert not scheduled_jobs(proc, "stability_panels")
    assert scheduled(proc, "stability_figure_fig18")
    edit_config(tiny_run, lambda st: st["plot"].update(style="field"))

    # Snakemake reruns on an input newer than the output *with different content*: edit the modules
    figures, panels = tiny_run / "src/icosim/figures/stability.py", tiny_run / "src/icosim/studies/stability/panels.py"
    texts = {path: path.read_text() for path in (figures, panels)}
    with open(figures, "a") as fh:
        fh.write("\n# edited by test_stability_workflow\n")
    proc = snakemake(tiny_run, "-n", target)
    assert not scheduled_jobs(proc, "stability_panels") and scheduled(proc, "stability_figure_fig18")
    with open(panels, "a") as fh:
        fh.write("\n# edited by test_stability_workflow\n")
    proc = snakemake(tiny_run, "-n", target)
    assert sorted(scheduled(proc, "stability_panels_fig18")) == sorted(panel_files(stability_config(tiny_run), "18"))
    for path, text in texts.items():  # back: the datasets and figures built before are up to date again
        path.write_text(text)


def report_inputs(proc):
    text = proc.stdout + proc.stderr
    block = re.search(r"rule report:\n(.*?)\n\n", text, re.S).group(1)
    inputs = re.search(r"input: ([^\n]+)", block).group(1).split(", ")
    return [Path(f).stem for f in inputs if f.startswith("results/report/")]


def test_report_assembles_sections_in_configured_order(workflow_copy, tmp_path):
    proc = snakemake(workflow_copy, "reports/icosim_report.html", "-n")
    parts = report_inputs(proc)
    assert "stability" in parts
    default_order = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["report"]["sections"]
    assert parts == [p for p in default_order if p in parts]
    # another order, and a part left out, are followed
    order = tmp_path / "order.yaml"
    order.write_text(yaml.safe_dump({"report": {"title": "t", "sections": ["pendulum", "stability"]}}))
    proc = snakemake(workflow_copy, "reports/icosim_report.html", "-n", "--configfile", str(order))
    parts = report_inputs(proc)
    assert parts[-1] == "stability" and "convergence" not in parts


def test_enforced_references_fail_the_claims_job_when_not_reproduced(tiny_run):
    """The CI mechanism: with enforce_reference, a `ci: true` claim whose verdict differs from
    its recorded reference fails the run; a reproduced one lets it pass."""
    edit_config(tiny_run, lambda st: st["claims"].update(enforce_reference=True))
    claims_path = tiny_run / "config/claims/stability.yaml"
    claim = {
        "id": "fig18_k0_good",
        "source": "Sect. 3.5",
        "statement": "Index 3 with k = 0 achieves a good stability behaviour.",
        "figures": ["18"],
        "check": {
            "kind": "stable_fraction",
            "select": {"figure": "18", "k": 0, "view": "full"},
            "op": ">=",
            # the tiny grid's undamped axis (a quarter of its points) is marginal: >= 0.9 would be undecided
            "value": 0.7,
        },
        "ci": True,
    }
    claims_path.write_text(yaml.safe_dump({"claims": [{**claim, "reference": "fail"}]}))
    proc = snakemake(tiny_run, "results/stability/claims.json", "-c1", check=False)
    assert proc.returncode != 0
    log = (tiny_run / "logs/stability/claims.log").read_text() + proc.stdout + proc.stderr
    assert "fig18_k0_good" in log and "reference fail" in log
    assert not (tiny_run / "results/stability/claims.json").exists()
    claims_path.write_text(yaml.safe_dump({"claims": [{**claim, "reference": "pass"}]}))
    snakemake(tiny_run, "results/stability/claims.json", "-c1")
    verdicts = json.loads((tiny_run / "results/stability/claims.json").read_text())["claims"]
    assert [(v["id"], v["verdict"], v["matches_reference"]) for v in verdicts] == [("fig18_k0_good", "pass", True)]
    edit_config(tiny_run, lambda st: st["claims"].update(enforce_reference=False))


def test_library_digests_follow_the_real_imports(tiny_run):
    """A rule reruns when a module its script imports (directly or not) changes, and only then:
    touching a module without changing it reruns nothing, editing the pendulum's problem reruns no
    stability job, editing a stability check reruns the claims."""
    snakemake(tiny_run, "results/stability/claims.json", *TINY_FIGURES, "-c1")  # up to date with the current config
    os.utime(tiny_run / "src/icosim/studies/stability/panels.py")  # newer than every dataset, the same text
    proc = snakemake(tiny_run, "-n", "results/stability/claims.json", *TINY_FIGURES)
    assert not scheduled_jobs(proc, "stability_")
    with open(tiny_run / "src/icosim/problems/pendulum/problem.py", "a") as fh:
        fh.write("\n# edited by test_stability_workflow\n")
    proc = snakemake(tiny_run, "-n", "results/stability/claims.json", *TINY_FIGURES)
    assert not scheduled_jobs(proc, "stability_")
    with open(tiny_run / "src/icosim/studies/stability/checks.py", "a") as fh:
        fh.write("\n# edited by test_stability_workflow\n")
    proc = snakemake(tiny_run, "-n", "results/stability/claims.json", *TINY_FIGURES)
    assert set(scheduled_jobs(proc, "stability_")) == {"stability_claims"}
