"""The signal-coupling study in the workflow (workflow/rules/signals.smk): its jobs, a rerun trigger and a refused
case (dry runs on a copy of the workflow, which has no units beside it: the case scenes are checked on stand-ins),
and its configuration against the schema.  The study's functions: tests/studies/signals/."""

import os
import time

import pytest
import yaml
from helpers import ROOT, copy_workflow, scheduled_jobs, snakemake, validate_config

from icosim.studies.signals.config import study_cases

CI = [
    f"config/ci/{part}.yaml" for part in ("stability", "convergence", "pendulum", "fmi", "chains", "signals", "peers")
]


def ci_signals_config():
    base = yaml.safe_load((ROOT / "config" / "signals.yaml").read_text())["signals"]
    ci = yaml.safe_load((ROOT / "config" / "ci" / "signals.yaml").read_text())["signals"]
    return base | {"cases": ci["cases"]}


@pytest.fixture(scope="module")
def workflow_copy(tmp_path_factory):
    return copy_workflow(tmp_path_factory.mktemp("wf"))


def test_ci_dry_run_lists_the_signal_jobs(workflow_copy):
    jobs = scheduled_jobs(snakemake(workflow_copy, "-n", "--configfile", *CI), "signals_")
    cases = study_cases(ci_signals_config())
    assert (
        len(cases) == 10
    )  # Jacobi k = 0, 1, 2; Gauss-Seidel k = 0, 1; implicit Jacobi k = 0, 1; the joint k = 0, 1, 2
    assert sorted(jobs["signals_case"]) == sorted(f"results/signals/{c}.nc" for c in cases)
    assert jobs["signals_figure"] == ["results/signals/figures/signals.png", "results/signals/figures/signals.pdf"]
    assert jobs["signals_claims"][0] == "results/signals/claims.json"
    assert jobs["signals_report_section"] == ["results/report/signals.html"]


def test_editing_the_claims_reruns_only_the_claims_and_the_section(tmp_path):
    wf = copy_workflow(tmp_path)
    cases = study_cases(ci_signals_config())
    stages = [
        [f"results/signals/{c}.nc" for c in cases],
        ["results/signals/figures/signals.png", "results/signals/figures/signals.pdf", "results/signals/claims.json",
         "results/signals/claims.tsv"],
        ["results/report/signals.html"],
    ]  # fmt: skip
    t = time.time() - 1000
    for path in wf.rglob("*"):
        if path.is_file():
            os.utime(path, (t, t))
    for stage in stages:
        t += 10
        for name in stage:
            (wf / name).parent.mkdir(parents=True, exist_ok=True)
            (wf / name).write_text("")
            os.utime(wf / name, (t, t))
    target = "results/report/signals.html"
    assert not scheduled_jobs(snakemake(wf, "-n", target, "--configfile", *CI), "signals_")
    claims = wf / "config" / "claims" / "signals.yaml"
    claims.write_text(claims.read_text() + "\n# edited\n")
    jobs = scheduled_jobs(snakemake(wf, "-n", target, "--configfile", *CI), "signals_")
    assert sorted(jobs) == ["signals_claims", "signals_report_section"]


def test_a_case_the_scene_checks_refuse_stops_the_workflow_naming_it(tmp_path):
    wf = copy_workflow(tmp_path)
    ci = wf / "config" / "ci" / "signals.yaml"
    ci.write_text(ci.read_text().replace("scheme: jacobi", "scheme: sideways", 1))
    proc = snakemake(wf, "-n", "--configfile", *CI, check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0 and "connections_sideways_k0" in out and "'sideways' is not allowed" in out


def test_the_configurations_meet_the_schema_and_a_stray_key_does_not():
    validate_config(yaml.safe_load((ROOT / "config" / "signals.yaml").read_text())["signals"], "signals")
    validate_config(ci_signals_config(), "signals")
    bad = ci_signals_config()
    bad["cases"][0] = bad["cases"][0] | {"gain": 2.0}
    with pytest.raises(Exception, match="gain"):
        validate_config(bad, "signals")
