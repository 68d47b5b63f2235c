"""The Snakemake side of the convergence part: bad configuration and claims fail when the
workflow is parsed (dry runs on a copy of the workflow), and the claims job raises before it
writes anything."""

import runpy
from types import SimpleNamespace

import pytest
import yaml
from helpers import ROOT, copy_workflow, snakemake

from icosim.io.netcdf import write_netcdf
from icosim.studies.convergence.datasets import run_panel
from icosim.studies.convergence.experiment import Setup, step_counts
from icosim.studies.convergence.panels import PanelSpec
from icosim.studies.convergence.study import Study


@pytest.fixture(scope="module")
def workflow_copy(tmp_path_factory):
    return copy_workflow(tmp_path_factory.mktemp("wf"))


def _bad_claims(tmp_path):
    doc = yaml.safe_load((ROOT / "config" / "claims" / "convergence.yaml").read_text())
    doc["claims"][3]["check"]["expect"][1]["unstable"] = "yes"
    path = tmp_path / "claims.yaml"
    path.write_text(yaml.safe_dump(doc))
    return str(path)


@pytest.mark.parametrize(
    "override, names",
    [
        ({"step_sizes": {"H_min": 1.0e-2, "H_max": 1.0e-3}}, ["convergence.step_sizes", "H_min < H_max"]),
        ({"step_sizes": {"H_max": 5.0}}, ["convergence.step_sizes.H_max = 5.0", "convergence.end_time"]),
        ({"initial_conditions": {"x0": 0.0, "v0": 0.0}}, ["convergence.initial_conditions", "both zero"]),
        ({"claims": {"file": "BAD"}}, ["baumgarte_index2", "expect[1].unstable must be true"]),
    ],
)
def test_bad_configuration_fails_before_any_job_naming_the_key(workflow_copy, tmp_path, override, names):
    if override.get("claims", {}).get("file") == "BAD":
        override = {"claims": {"file": _bad_claims(tmp_path)}}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({"convergence": override}))
    proc = snakemake(workflow_copy, "-n", "results/report/convergence.html", "--configfile", str(bad), check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0
    for name in names:
        assert name in out, out[-2000:]
    assert "rule convergence_panel" not in out  # nothing was scheduled


def test_claims_job_raises_before_writing_on_a_reference_mismatch(tmp_path):
    """With enforce_reference, a `ci: true` claim that does not reproduce its reference stops the
    job before the JSON is written; without a mismatch the JSON is written."""
    spec = PanelSpec("23", "ff", "all", "projection", {}, ({},), (0,))
    study = Study(Setup(end_time=0.2), step_counts(0.2, 2e-4, 2e-2, 5))
    panel = tmp_path / "panel.nc"
    write_netcdf(run_panel(spec, study, {"min_points": 3}), panel)
    claim = {
        "id": "proj",
        "source": "s",
        "statement": "s",
        "figures": ["23"],
        "ci": True,
        "check": {
            "kind": "convergence_order",
            "tolerance": 0.25,
            "select": {"figure": "23", "decomposition": "ff"},
            "expect": [{"k": 0, "order": 2}],
        },
    }
    out = tmp_path / "claims.json"

    def run(reference, enforce):
        (tmp_path / "c.yaml").write_text(yaml.safe_dump({"claims": [{**claim, "reference": reference}]}))
        job = SimpleNamespace(
            input=SimpleNamespace(claims=str(tmp_path / "c.yaml"), datasets=[str(panel)]),
            output=SimpleNamespace(json=str(out), tsv=str(tmp_path / "claims.tsv")),
            log=[str(tmp_path / "log")],
            params=SimpleNamespace(enforce_reference=enforce),
        )
        runpy.run_path(str(ROOT / "workflow" / "scripts" / "claims.py"), init_globals={"snakemake": job})

    run("undecided", enforce=False)  # no enforcement: the verdict is written whatever it is
    assert out.exists()
    verdict = yaml.safe_load(out.read_text())["claims"][0]["verdict"]
    assert verdict in ("pass", "fail")
    out.unlink()
    (tmp_path / "claims.tsv").unlink()
    with pytest.raises(SystemExit, match="proj"):
        run("undecided", enforce=True)
    assert not out.exists() and not (tmp_path / "claims.tsv").exists()
    run(verdict, enforce=True)
    assert out.exists()
    assert "proj\t" in (tmp_path / "claims.tsv").read_text()
