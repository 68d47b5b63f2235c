"""The peers study in the workflow (workflow/rules/peers.smk): its jobs on the CI configuration, a refused series
naming what is allowed (dry runs on a copy of the workflow), and its configurations against the schema.  The
study's functions: tests/studies/peers/."""

import pytest
import yaml
from helpers import ROOT, copy_workflow, scheduled_jobs, snakemake, validate_config
from peers_data import CI, DEFAULT

PARTS = ("stability", "convergence", "pendulum", "fmi", "chains", "signals", "peers")
CONFIGS = [f"config/ci/{part}.yaml" for part in PARTS]


def test_ci_dry_run_lists_one_job_per_system_the_figure_the_claims_and_the_section(tmp_path):
    wf = copy_workflow(tmp_path)
    jobs = scheduled_jobs(snakemake(wf, "-n", "--configfile", *CONFIGS), "peers_")
    assert sorted(jobs["peers_system"]) == ["results/peers/dual_mass.nc", "results/peers/quarter_truck.nc"]
    assert jobs["peers_figure"] == ["results/peers/figures/peers.png", "results/peers/figures/peers.pdf"]
    assert jobs["peers_claims"][0] == "results/peers/claims.json"
    assert jobs["peers_report_section"] == ["results/report/peers.html"]


def test_a_series_of_an_unknown_master_stops_the_workflow_naming_the_allowed(tmp_path):
    wf = copy_workflow(tmp_path)
    ci = wf / "config" / "ci" / "peers.yaml"
    ci.write_text(ci.read_text().replace("{master: Ecos,", "{master: Ecos, substeps: 4,", 1))
    proc = snakemake(wf, "-n", "--configfile", *CONFIGS, check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0 and "unknown key 'substeps' for Ecos on quarter_truck" in out


def test_the_configurations_meet_the_schema_and_a_stray_key_does_not():
    validate_config(DEFAULT, "peers")
    validate_config(CI, "peers")
    bad = yaml.safe_load((ROOT / "config" / "peers.yaml").read_text())["peers"]
    bad["systems"]["dual_mass"]["gain"] = 2.0
    with pytest.raises(Exception, match="gain"):
        validate_config(bad, "peers")
