"""The coupling scheme as a dimension of the workflow: configuration and scheduling.  The comparison of stable
shares and the report's comparison of schemes: tests/report/test_report_schemes.py; the pendulum's Gauss-Seidel
step: tests/problems/pendulum/test_pendulum_schemes.py.

Dry runs work on a copy of the workflow; nothing here writes to the checkout's results/.
"""

import pytest
import yaml
from helpers import ROOT, copy_workflow, scheduled, snakemake, validate_config

from icosim import ParameterError
from icosim.engine.schemes import GS12
from icosim.problems.pendulum.config import configured_schemes
from icosim.problems.pendulum.names import run_name
from icosim.studies.convergence.config import configured_curves
from icosim.studies.convergence.panels import figure_panels as conv_figure_panels
from icosim.studies.stability.panels import figure_panels

BOTH = ("jacobi", "gauss-seidel-12", "gauss-seidel-21")


def part(name):
    return yaml.safe_load((ROOT / "config" / f"{name}.yaml").read_text())[name]


@pytest.fixture(scope="module")
def workflow_copy(tmp_path_factory):
    return copy_workflow(tmp_path_factory.mktemp("wf"))


# -- configuration ------------------------------------------------------------------------------
def test_jacobi_only_config_switches_off_every_other_scheme():
    only = yaml.safe_load((ROOT / "config" / "jacobi_only.yaml").read_text())
    for name in ("stability", "convergence"):
        for fig, cfg in part(name)["figures"].items():
            if [s if isinstance(s, str) else s["name"] for s in cfg.get("schemes", ["jacobi"])] != ["jacobi"]:
                assert only[name]["figures"][str(fig)]["schemes"] == ["jacobi"], (name, fig)
    assert only["pendulum"]["schemes"] == ["jacobi"]


def test_default_config_computes_figs_9_to_15_and_21_to_23_with_both_orders():
    for name, figs in (("stability", range(9, 16)), ("convergence", range(21, 24))):
        for fig in figs:
            names = {s if isinstance(s, str) else s["name"] for s in part(name)["figures"][str(fig)]["schemes"]}
            assert set(BOTH) <= names
    assert set(configured_schemes(part("pendulum"))) == set(BOTH)


@pytest.mark.parametrize(
    "name, override, message",
    [
        ("stability", {"figures": {"9": {"schemes": ["seidel"]}}}, "seidel"),
        ("stability", {"figures": {"9": {"schemes": [{"name": "gauss-seidel-12"}]}}}, "rows"),
        ("convergence", {"figures": {"21": {"schemes": []}}}, "schemes"),
        ("pendulum", {"schemes": ["gauss-seidel-12"]}, "jacobi"),
    ],
)
def test_bad_schemes_are_refused_by_the_schemas(name, override, message):
    cfg = part(name)
    for key, value in override.items():
        if key == "figures":
            for fig, sub in value.items():
                cfg["figures"][fig].update(sub)
        else:
            cfg[key] = value
    with pytest.raises(Exception, match=message):
        validate_config(cfg, name)


def test_pendulum_schemes_must_include_jacobi():
    with pytest.raises(ParameterError, match="pendulum.schemes must include jacobi"):
        configured_schemes({"schemes": ["gauss-seidel-21"]})
    with pytest.raises(ParameterError, match="pendulum.schemes: scheme must be one of"):
        configured_schemes({"schemes": ["jacobi", "sequential"]})


def test_every_scheme_of_a_figure_has_the_jacobi_layout():
    cfg = part("stability")
    kw = dict(grid=cfg["grid"], zoom_grid=cfg["zoom_grid"], precision=cfg["precision"])
    for fig in ("9", "13"):
        specs = figure_panels(fig, cfg["figures"][fig], **kw)
        strip = lambda s: {**s.as_dict(), "scheme": None}  # noqa: E731
        by_scheme = {scheme: [strip(s) for s in specs if s.scheme == scheme] for scheme in BOTH}
        assert by_scheme["gauss-seidel-21"] == by_scheme["jacobi"] == by_scheme["gauss-seidel-12"]
        assert {s.figure for s in specs} == {fig}
    conv = part("convergence")
    specs = conv_figure_panels("21", conv["figures"]["21"], conv["k"])
    assert {s.figure for s in specs} == {"21"} and {s.scheme for s in specs} == set(BOTH)
    curves = configured_curves(conv)
    assert {c["scheme"] for c in curves if c["figure"] == "22"} == set(BOTH)


def test_a_scheme_for_some_rows_only():
    cfg = part("stability")
    fig = dict(cfg["figures"]["11"], schemes=["jacobi", {"name": "gauss-seidel-12-as-integrated", "rows": [1]}])
    specs = figure_panels("11", fig, grid=cfg["grid"], zoom_grid=cfg["zoom_grid"], precision=cfg["precision"])
    variant = [s for s in specs if s.scheme == "gauss-seidel-12-as-integrated"]
    assert {s.row for s in variant} == {1} and len(variant) == len(fig["k"])
    with pytest.raises(ParameterError, match="rows: \\[5\\]"):
        figure_panels(
            "11",
            dict(fig, schemes=[{"name": "jacobi", "rows": [5]}]),
            grid=cfg["grid"],
            zoom_grid=cfg["zoom_grid"],
            precision=cfg["precision"],
        )


def test_run_names():
    assert run_name("projection", "dd", 1) == "projection_dd_k1"
    assert run_name("projection", "dd", 1, GS12) == "projection_dd_k1_gauss-seidel-12"


# -- scheduling -------------------------------------------------------------------------------------
def test_one_figure_target_schedules_that_figures_job_only(workflow_copy):
    proc = snakemake(workflow_copy, "-n", "results/stability/figures/fig9_gauss-seidel-21.png")
    text = proc.stdout + proc.stderr
    assert "rule stability_panels_fig9:" in text and "rule stability_figure_fig9:" in text
    assert "stability_panels_fig10" not in text and "rule pendulum" not in text and "rule convergence" not in text
    panels = scheduled(proc, "stability_panels_fig9")
    assert len([p for p in panels if "/gauss-seidel-21/" in p]) == 4 * 3 + 1
    assert len([p for p in panels if "/jacobi/" in p]) == 4 * 3 + 1


@pytest.fixture(scope="module")
def full_dry_run(workflow_copy):
    """The default command's dry run on the fresh copy, where nothing is built yet: every job of the workflow
    is listed (as ``--forceall`` would list them); one run for the tests that read the whole listing."""
    return snakemake(workflow_copy, "-n")


def test_default_run_has_every_scheme_and_jacobi_only_none_but_jacobi(workflow_copy, full_dry_run):
    proc = full_dry_run
    text = proc.stdout + proc.stderr
    assert "rule stability_scheme_figure:" in text
    runs = scheduled(proc, "pendulum_run")
    assert len(runs) == len(BOTH) * 21 and {r.split("/")[3] for r in runs} == set(BOTH)
    only = snakemake(workflow_copy, "-n", "--configfile", "config/jacobi_only.yaml")
    text = only.stdout + only.stderr
    assert "gauss-seidel" not in text and "stability_scheme" not in text


def test_one_trade_job_per_method_and_decomposition_writes_both_studies_for_every_scheme(full_dry_run):
    """Error over H and the stability limit of one (method, decomposition) share one job (one start-up),
    which writes each study's dataset of every scheme at its own path."""
    import re

    proc = full_dry_run
    text = proc.stdout + proc.stderr
    jobs = [
        re.search(r"output: ([^\n]+)", block).group(1).split(", ")
        for block in re.split(r"\n(?=\S*rule [\w-]+:)", text)
        if re.match(r"\S*rule pendulum_trade_group:", block)
    ]
    pairs = {(c["method"], c["decomposition"]) for c in part("pendulum")["configurations"]}
    assert len(jobs) == len(pairs)
    expected = {
        f"results/pendulum/trade/{study}/{scheme}/{m}_{d}.nc": (m, d)
        for m, d in pairs
        for study in ("sweep", "limits")
        for scheme in BOTH
    }
    assert sorted(o for outputs in jobs for o in outputs) == sorted(expected)
    assert all(len({expected[o] for o in outputs}) == 1 for outputs in jobs)
    assert "rule pendulum_sweep:" not in text and "rule pendulum_limits:" not in text
