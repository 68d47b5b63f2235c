"""The claims of config/claims/pendulum.yaml (Sect. 4 and the project's about the other schemes) on a shorter horizon.

Every configuration of config/pendulum.yaml at every k is co-simulated for
``T_CLAIM`` seconds with the configured method parameters, integrator and
divergence bounds, with every scheme a claim is about (``check.scheme``, default
the paper's Jacobi); the observed outcome (diverged or not) must be the one each
claim about that scheme states.  0.4 s decides the claims: the weighted multiplier at k = 2
diverges after about 0.2 s with Jacobi (the Gauss-Seidel runs within 0.05 s), while the
stable runs stay orders of magnitude inside the bounds (checked here too, so that "stable"
is not a near miss).
"""

import numpy as np
import pytest
import yaml
from helpers import ROOT, validate_config

import icosim.problems.pendulum.problem
from icosim import ParameterError, make_method
from icosim.claims.registry import evaluate_claim, load_claims, parse_claims
from icosim.engine.schemes import get_scheme
from icosim.problems.pendulum.config import configured_runs, configured_schemes
from icosim.problems.pendulum.integrator.systems import IntegrationError
from icosim.problems.pendulum.linearised import linear_test_model_rho, pendulum_test_model
from icosim.problems.pendulum.model import PendulumParameters
from icosim.problems.pendulum.runs import run_cosimulation
from icosim.studies.pendulum.checks import expected_outcome
from icosim.studies.pendulum.datasets import reference_dataset, run_dataset
from icosim.studies.pendulum.summary import summarize

CFG = yaml.safe_load((ROOT / "config" / "pendulum.yaml").read_text())["pendulum"]
CLAIMS = load_claims(ROOT / CFG["claims"]["file"])
RUNS = configured_runs(CFG)
T_CLAIM = 0.4


def _scheme(claim) -> str:
    """The scheme whose runs a claim is about (a check that names none: the paper's, Jacobi)."""
    return get_scheme(claim.check.get("scheme", "jacobi")).name


#: The schemes the claims are about, in the order of pendulum.schemes (each with its claims).
CLAIM_SCHEMES = [s for s in configured_schemes(CFG) if any(_scheme(c) == s for c in CLAIMS)]
SCHEME_RUNS = [(scheme, *run) for scheme in CLAIM_SCHEMES for run in RUNS]


def _claim_with(**check):
    """The shipped claim with some check parameters replaced."""
    return parse_claims([{**CLAIMS[0].as_dict(), "check": {**CLAIMS[0].check, **check}}])[0]


def _run(method_name, decomposition, k, t_end=T_CLAIM, scheme="jacobi"):
    return run_cosimulation(
        PendulumParameters(**CFG["model"]),
        make_method(method_name, **CFG["methods"][method_name]),
        decomposition,
        k,
        H=CFG["H"],
        t_end=t_end,
        scheme=scheme,
        **CFG["integrator"],
        **CFG["sensitivities"],
        **CFG["corrector"],
        **CFG["divergence"],
    )


def test_the_claim_covers_exactly_the_configured_exceptions():
    """Every exception of a claim names a configured run and every claim a configured scheme (no typo silently
    ignored); the paper's claim of Sect. 4 is about Jacobi."""
    for claim in CLAIMS:
        assert claim.check["kind"] == "pendulum_stability"
        assert _scheme(claim) in configured_schemes(CFG), claim.id
        for ex in claim.check.get("exceptions", []):
            assert (ex["method"], ex["decomposition"], int(ex["k"])) in RUNS
    assert CLAIMS[0].id == "sect4_stability" and _scheme(CLAIMS[0]) == "jacobi"
    assert {_scheme(c) for c in CLAIMS} == set(CLAIM_SCHEMES)


@pytest.mark.parametrize(
    "scheme, method_name, decomposition, k",
    SCHEME_RUNS,
    ids=[f"{m}_{d}_{k}" + ("" if s == "jacobi" else f"_{s}") for s, m, d, k in SCHEME_RUNS],
)
def test_sect4_stability_claim(scheme, method_name, decomposition, k):
    """Each run against every claim about its scheme (Jacobi: the paper's claim of Sect. 4)."""
    run = (method_name, decomposition, k)
    claims = [claim for claim in CLAIMS if _scheme(claim) == scheme]
    assert claims  # CLAIM_SCHEMES holds only schemes some claim is about
    result = _run(method_name, decomposition, k, scheme=scheme)
    assert result.status in ("stable", "diverged"), result.reason  # a failed run would decide nothing
    observed = "unstable" if result.diverged else "stable"
    for claim in claims:
        expected = expected_outcome(claim.check, method_name, decomposition, k)
        assert observed == expected, (claim.id, scheme, run, result.reason)
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
        for attr in ("method", "decomposition", "k", "status", "reason", "diverged", "t_diverged", "failed"):
            assert attr in ds.attrs
        assert ds.attrs["tol"] == "none"
        assert ds.attrs["status"] == ("diverged" if res.diverged else "stable")
        assert ds.attrs["failed"] == 0 and np.isnan(ds.attrs["t_failed"])
        assert f"n_split = {ds.attrs['n_split']} " in ds.attrs["sensitivities"]
        runs.append(ds)
    assert runs[0].attrs["method_a"] == 1.0 and runs[0].attrs["method_a_units"] == "1"
    assert ref.attrs["method"] == "monolithic"
    assert np.max(np.abs(ref["g_cax"].values)) < 1e-14
    summary = summarize(runs, ref, CLAIMS)
    cid = CLAIMS[0].id
    assert list(summary["observed"].values) == ["unstable", "stable"]
    assert list(summary[f"verdict_{cid}"].values) == ["pass", "pass"]
    # the summary's error is the largest deviation from the independent monolithic reference
    stable_run = runs[1]
    ref_phi1 = ref["phi1"].sel(t=stable_run["t"], method="nearest").values
    assert summary["err_phi1"].values[1] == pytest.approx(np.max(np.abs(stable_run["phi1"].values - ref_phi1)))
    # an exception the claim names (weighted/fd/k=2) was not run: the claim stays undecided
    v = evaluate_claim(CLAIMS[0], [summary])
    assert v.verdict == "undecided" and "not run: weighted_fd_k2" in v.measured
    assert v.numbers["runs"]["weighted_ff_k2"] == {"expected": "unstable", "observed": "unstable", "verdict": "pass"}
    # the same claim restricted to the runs made passes ...
    only_ff = _claim_with(exceptions=[{"method": "weighted", "decomposition": "ff", "k": 2, "expected": "unstable"}])
    assert evaluate_claim(only_ff, [summary]).verdict == "pass"
    # ... and fails when the data contradict it
    all_stable = _claim_with(exceptions=[])
    assert evaluate_claim(all_stable, [summary]).verdict == "fail"


def test_failed_integration_is_not_counted_as_unstable(monkeypatch):
    """A subsystem integration that fails is a failed run (not diverged): the claim gets no pass from it.

    weighted/ff/k = 2 is expected unstable, so counting a solver failure as a divergence would make it pass."""
    # a link's compiled macro step (icosim.problems.pendulum.integrator.compiled), as the problem calls it
    real_step, calls = icosim.problems.pendulum.problem._link_step, []
    fail_at_step = 11  # four integrations per macro step (predictor+sensitivities and corrector, two links)

    def failing_step(*args, **kwargs):
        calls.append(1)
        if len(calls) == 4 * (fail_at_step - 1) + 1:
            raise IntegrationError("injected failure")
        return real_step(*args, **kwargs)

    monkeypatch.setattr(icosim.problems.pendulum.problem, "_link_step", failing_step)
    t_end = 0.05
    res = _run("weighted", "ff", 2, t_end=t_end)
    assert res.status == "failed" and res.failed and not res.diverged
    assert res.t_failed == pytest.approx(fail_at_step * CFG["H"]) and np.isnan(res.t_diverged)
    assert res.t[-1] == pytest.approx((fail_at_step - 1) * CFG["H"]) and "injected failure" in res.reason
    method = make_method("weighted", **CFG["methods"]["weighted"])
    ds = run_dataset(res, method, "ff", 2, {"H": CFG["H"]}, {"title": "test"})
    assert (ds.attrs["status"], ds.attrs["failed"], ds.attrs["diverged"]) == ("failed", 1, 0)
    assert "injected failure" in ds.attrs["reason"]
    ref = reference_dataset(PendulumParameters(**CFG["model"]), CFG["H"], t_end, {"title": "test"})
    summary = summarize([ds], ref, CLAIMS)
    cid = CLAIMS[0].id
    assert str(summary["observed"].values[0]) == "failed"
    assert str(summary[f"verdict_{cid}"].values[0]) == "undecided"
    only_ff = _claim_with(exceptions=[{"method": "weighted", "decomposition": "ff", "k": 2, "expected": "unstable"}])
    assert evaluate_claim(only_ff, [summary]).verdict == "undecided"


def test_linear_test_model_at_the_pendulum_point_predicts_the_claim():
    """Sect. 3 <-> Sect. 4: at lr1 = -d H/(2 m) the test model's rho exceeds 1 exactly for the configurations
    the claim calls unstable (the paper's explanation of Fig. 8)."""
    params = PendulumParameters(**CFG["model"])
    model = pendulum_test_model(params, CFG["H"])
    np.testing.assert_allclose(model.lr1, -params.d * CFG["H"] / (2 * params.m1))
    # modal frequencies of two hinged uniform rods, undamped (M, K of the linearisation), bracket the damped ones
    m, length, g, J = params.m1, params.l1, params.g, params.J1
    M = np.array(
        [[J + m * length**2 / 4 + m * length**2, m * length**2 / 2], [m * length**2 / 2, J + m * length**2 / 4]]
    )
    K = np.diag([1.5 * m * g * length, 0.5 * m * g * length])
    omega0 = np.sort(np.sqrt(np.linalg.eigvals(np.linalg.solve(M, K)).real))
    assert np.all(model.li1 / CFG["H"] < omega0) and np.all(model.li1 / CFG["H"] > 0.9 * omega0)
    for method_name, dec, k in RUNS:
        rho, _ = linear_test_model_rho(
            params, CFG["H"], make_method(method_name, **CFG["methods"][method_name]), dec, k
        )
        expected = expected_outcome(CLAIMS[0].check, method_name, dec, k)
        assert (rho > 1) == (expected == "unstable"), (method_name, dec, k, rho)


@pytest.mark.parametrize(
    "patch, needle",
    [
        ({"t_ned": 3.0}, "t_ned"),
        ({"integrator": {"rtol": 1e-6, "atol": 1e-6, "newton_tol": 1e-8, "method": "BDF"}}, "method"),
        ({"configurations": [{"method": "weighted", "decomposition": "fx"}]}, "fx"),
        ({"H": -1e-3}, "-0.001"),
    ],
)
def test_schema_rejects_bad_config_naming_it(patch, needle):
    bad = {**CFG, **patch}
    validate_config(dict(CFG), "pendulum")  # the real config passes
    with pytest.raises(Exception, match=needle):
        validate_config(bad, "pendulum")


@pytest.mark.parametrize("method_name", ["baumgarte", "weighted", "projection"])
def test_configuration_with_df_is_refused_naming_it_and_the_reason(method_name):
    """df is a registered decomposition (the schema takes it), but the pendulum has no coupling conditions for it:
    the check the workflow makes right after the schema's (configured_runs) refuses it, naming the
    configuration, df and why."""
    bad = {**CFG, "configurations": [*CFG["configurations"], {"method": method_name, "decomposition": "df"}]}
    validate_config(bad, "pendulum")
    where = rf"pendulum\.configurations\[{len(CFG['configurations'])}\] \({method_name}, df\)"
    with pytest.raises(
        ParameterError, match=rf"{where}: .*not for 'df' \(link 1 kinematically driven, link 2 force-driven"
    ):
        configured_runs(bad)
