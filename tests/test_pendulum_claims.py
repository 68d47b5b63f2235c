"""The claim of Sect. 4 (config/claims/pendulum.yaml) on a shorter horizon.

Every configuration of config/pendulum.yaml at every k is co-simulated for
``T_CLAIM`` seconds with the configured method parameters, integrator and
divergence bounds; the observed outcome (diverged or not) must be the one the
claim states.  0.4 s decides the claim: the weighted multiplier at k = 2
diverges after about 0.2 s, while the stable runs stay orders of magnitude
inside the bounds (checked here too, so that "stable" is not a near miss).
"""

from pathlib import Path

import numpy as np
import pytest
import yaml

from icosim import make_method
from icosim.pendulum import (
    PendulumParameters,
    configured_runs,
    expected_outcome,
    load_claims,
    reference_dataset,
    run_cosimulation,
    run_dataset,
    summarize,
)

ROOT = Path(__file__).resolve().parents[1]
CFG = yaml.safe_load((ROOT / "config" / "pendulum.yaml").read_text())["pendulum"]
CLAIMS = load_claims(ROOT / CFG["claims"])
RUNS = configured_runs(CFG)
T_CLAIM = 0.4


def _run(method_name, decomposition, k, t_end=T_CLAIM):
    return run_cosimulation(
        PendulumParameters(**CFG["model"]),
        make_method(method_name, **CFG["methods"][method_name]),
        decomposition,
        k,
        H=CFG["H"],
        t_end=t_end,
        **CFG["integrator"],
        **CFG["sensitivities"],
        **CFG["corrector"],
        **CFG["divergence"],
    )


def test_the_claim_covers_exactly_the_configured_exceptions():
    """Every exception of the claim names a configured run (no typo silently ignored)."""
    for claim in CLAIMS:
        for ex in claim["check"].get("exceptions", []):
            assert (ex["method"], ex["decomposition"], int(ex["k"])) in RUNS


@pytest.mark.parametrize("run", RUNS, ids=["_".join(map(str, r)) for r in RUNS])
def test_sect4_stability_claim(run):
    method_name, decomposition, k = run
    result = _run(method_name, decomposition, k)
    observed = "unstable" if result.diverged else "stable"
    for claim in CLAIMS:
        assert observed == expected_outcome(claim, method_name, decomposition, k), (claim["id"], run, result.reason)
    # the stored series never hold NaN, and a diverged run ends before its divergence time
    for values in result.series.values():
        assert np.all(np.isfinite(values))
    if result.diverged:
        assert result.t[-1] < result.t_diverged <= T_CLAIM
    else:
        # well inside the bounds: no near miss
        g = np.hypot(result.series["g_cax_corrector"], result.series["g_cay_corrector"])
        assert np.max(g) < 1e-3 * CFG["divergence"]["max_constraint"]
        assert result.t[-1] == pytest.approx(T_CLAIM)


def test_summary_and_dataset_contract():
    """Datasets keep the names other tools read; the summary turns a diverged run into a claim verdict."""
    cfg_model = PendulumParameters(**CFG["model"])
    t_end = 0.25
    ref = reference_dataset(cfg_model, CFG["H"], t_end, {"title": "test"})
    runs = []
    for method_name, dec, k in [("weighted", "ff", 2), ("projection", "dd", 0)]:
        res = _run(method_name, dec, k, t_end=t_end)
        ds = run_dataset(
            res,
            make_method(method_name, **CFG["methods"][method_name]),
            dec,
            k,
            {"H": CFG["H"], "tol": None},
            {"title": "test"},
        )
        for name in ("phi1", "phi2", "g_cax", "g_cay", "lambda_cax", "lambda_cay"):
            assert ds[name].dims == ("t",)
        for attr in ("method", "decomposition", "k", "diverged", "t_diverged"):
            assert attr in ds.attrs
        assert ds.attrs["tol"] == "none"
        runs.append(ds)
    assert ref.attrs["method"] == "monolithic"
    assert np.max(np.abs(ref["g_cax"].values)) < 1e-14
    summary = summarize(runs, ref, CLAIMS)
    cid = CLAIMS[0]["id"]
    assert list(summary["observed"].values) == ["unstable", "stable"]
    assert list(summary[f"verdict_{cid}"].values) == ["pass", "pass"]
    assert summary["err_phi1"].values[1] < 1e-4


@pytest.mark.parametrize(
    "patch, needle",
    [
        ({"t_ned": 3.0}, "t_ned"),
        ({"integrator": {"rtol": 1e-6, "atol": 1e-6, "newton_tol": 1e-8, "method": "BDF"}}, "method"),
        ({"configurations": [{"method": "weighted", "decomposition": "df"}]}, "df"),
        ({"H": -1e-3}, "-0.001"),
    ],
)
def test_schema_rejects_bad_config_naming_it(patch, needle):
    from snakemake.utils import validate

    bad = {**CFG, **patch}
    validate(dict(CFG), str(ROOT / "workflow" / "schemas" / "pendulum.schema.yaml"))  # the real config passes
    with pytest.raises(Exception, match=needle):
        validate(bad, str(ROOT / "workflow" / "schemas" / "pendulum.schema.yaml"))
