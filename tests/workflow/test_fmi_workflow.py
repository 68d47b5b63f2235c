"""The FMU part of the workflow (workflow/rules/fmi.smk): its jobs and rerun triggers (dry runs on a copy of the
workflow, which need neither fmpy nor a compiler) and its configuration.  The study's functions:
tests/studies/fmi/.
"""

import json
import os
import shutil
import time

import pytest
import yaml
from helpers import ROOT, copy_workflow, scheduled_jobs, snakemake

from icosim.problems.fmu.errors import SceneError
from icosim.studies.fmi.config import order_cases, scene_files

CI = [
    "config/ci/stability.yaml",
    "config/ci/convergence.yaml",
    "config/ci/pendulum.yaml",
    "config/ci/fmi.yaml",
    "config/ci/chains.yaml",
]


def ci_fmi_config():
    base = yaml.safe_load((ROOT / "config" / "fmi.yaml").read_text())["fmi"]
    ci = yaml.safe_load((ROOT / "config" / "ci" / "fmi.yaml").read_text())["fmi"]
    base["orders"] |= ci["orders"]
    return base


@pytest.fixture(scope="module")
def workflow_copy(tmp_path_factory):
    wf = copy_workflow(tmp_path_factory.mktemp("wf"))
    shutil.copytree(ROOT / "fmus", wf / "fmus", ignore=shutil.ignore_patterns("__pycache__"))
    return wf


# -- the DAG -------------------------------------------------------------------------------------------------


def test_ci_dry_run_lists_the_fmu_jobs(workflow_copy):
    proc = snakemake(workflow_copy, "-n", "--configfile", *CI)
    jobs = scheduled_jobs(proc, "fmi_")
    cfg = ci_fmi_config()
    assert jobs["fmi_units"] == ["results/fmi/units/units.json"]
    scenes = sorted(cfg["scenes"])
    assert sorted(jobs["fmi_scene"]) == sorted(
        [f"results/fmi/{s}.nc" for s in scenes] + [f"results/fmi/validation/{s}.nc" for s in scenes]
    )
    assert sorted(jobs["fmi_orders"]) == sorted(f"results/fmi/orders/{c}.nc" for c in order_cases(cfg))
    assert len(jobs["fmi_orders"]) == 6  # projection and Baumgarte index 1, ff, k = 0, 1, 2
    assert jobs["fmi_claims"][0] == "results/fmi/claims.json"
    assert jobs["fmi_report_section"] == ["results/report/fmi.html"]


def _make_outputs(wf):
    """Every FMU output as an empty file, each newer than what it is built from (the order of the DAG), all in
    the past."""
    cfg = ci_fmi_config()
    stages = [
        ["results/fmi/units/units.json"],
        [f"results/fmi/{s}.nc" for s in cfg["scenes"]]
        + [f"results/fmi/validation/{s}.nc" for s in cfg["scenes"]]
        + [f"results/fmi/orders/{c}.nc" for c in order_cases(cfg)],
        ["results/fmi/claims.json", "results/fmi/claims.tsv"],
        ["results/report/fmi.html"],
    ]
    t = time.time() - 1000
    for path in wf.rglob("*"):  # the sources older than every output
        if path.is_file():
            os.utime(path, (t, t))
    for stage in stages:
        t += 10
        for name in stage:
            path = wf / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text("")
            os.utime(path, (t, t))


def test_editing_a_scene_reruns_only_that_scenes_jobs(tmp_path):
    wf = copy_workflow(tmp_path)
    shutil.copytree(ROOT / "fmus", wf / "fmus", ignore=shutil.ignore_patterns("__pycache__"))
    _make_outputs(wf)
    target = "results/report/fmi.html"
    proc = snakemake(wf, "-n", target, "--configfile", *CI)
    assert not scheduled_jobs(proc, "fmi_"), proc.stdout[-2000:]
    scene = wf / "config" / "scenes" / "two_mass_fd.yaml"
    scene.write_text(scene.read_text() + "\n# edited\n")
    jobs = scheduled_jobs(snakemake(wf, "-n", target, "--configfile", *CI), "fmi_")
    assert sorted(jobs) == ["fmi_claims", "fmi_report_section", "fmi_scene"]
    assert sorted(jobs["fmi_scene"]) == ["results/fmi/two_mass_fd.nc", "results/fmi/validation/two_mass_fd.nc"]


def test_a_scene_that_fails_its_schema_stops_the_workflow(tmp_path):
    wf = copy_workflow(tmp_path)
    scene = wf / "config" / "scenes" / "two_mass_ff.yaml"
    scene.write_text(scene.read_text().replace("scheme: jacobi", "scheme: sideways"))
    proc = snakemake(wf, "-n", "--configfile", *CI, check=False)
    assert proc.returncode != 0
    assert "two_mass_ff.yaml" in proc.stdout + proc.stderr and "sideways" in proc.stdout + proc.stderr


def test_the_configuration_names_existing_scenes_and_whole_step_counts():
    cfg = ci_fmi_config()
    assert set(scene_files(cfg, ROOT)) == set(cfg["scenes"])
    bad = {**cfg, "scenes": {"nowhere": {"builtin": "none"}}}
    with pytest.raises(SceneError, match="nowhere"):
        scene_files(bad, ROOT)
    odd = json.loads(json.dumps(cfg))
    odd["orders"]["cases"][0]["H"] = [3.0e-3, 1.0e-3]
    with pytest.raises(SceneError, match="does not divide"):
        order_cases(odd)
