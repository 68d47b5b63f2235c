"""The signal study's check kinds and its claims file on datasets whose numbers theory gives: errors C H^p of a
known order p (or turning, pre-asymptotic), growth runs against their predicted rho, two couplings' errors in a
known ratio.  Each claim is decided only by data that can decide it: "undecided" where there is none."""

import numpy as np
import pytest
from helpers import ROOT

from icosim.claims.registry import evaluate, load_claims
from icosim.io.netcdf import open_dataset, write_netcdf
from icosim.studies.signals.checks import check_growth, check_order, check_ratio
from icosim.studies.signals.study import case_dataset

FIT = {"decades": 1.0, "tolerance": 0.1, "min_points": 3}
H = [5e-3, 2.5e-3, 1.25e-3, 6.25e-4]


def case(by, k, errors, *, scheme="jacobi", H=H, growth=None, implicit=False, **extra):
    """A case dataset as the study writes it, with the given errors over H and growth runs ``[(H, rho, measured),
    ...]`` (the predicted verdict from rho, as the study decides it with a zero error estimate)."""
    spec = {"by": by, "k": k, "H": sorted(H), "growth_H": [g[0] for g in growth or []]} | extra
    if by == "connections":
        spec["scheme"] = "gauss-seidel" if scheme != "jacobi" else "jacobi"
        spec |= {"order": ["system1", "system2"]} if scheme != "jacobi" else {}
        spec |= {"implicit": True} if implicit else {}
    order = np.argsort(H)
    e = np.asarray(errors, dtype=float)[order]
    n = len(H)
    runs = {"error": e, "error_end": e, "predicted_rho": np.full(n, 0.999), "rho_error": np.full(n, 1e-14),
            "predicted_verdict": ["stable"] * n}  # fmt: skip
    verdict = lambda r: "stable" if r < 1 else "unstable"  # noqa: E731
    g = {"growth_rho": [r for _, r, _ in growth or []], "growth_rho_error": [1e-14] * len(growth or []),
         "growth_verdict": [verdict(r) for _, r, _ in growth or []],
         "measured_growth": [m for _, _, m in growth or []]}  # fmt: skip
    info = {"scheme": scheme, "amplitude": 0.5, "prediction_reason": "", "predicted_H_max": 0.04}
    return case_dataset(spec, runs, g, info, fit=FIT, t_end=0.25, growth_steps=300).to_xarray()


def power(p, c=1.0, H=H):
    return [c * h**p for h in H]


def test_orders_of_errors_c_h_to_the_p_pass_and_fail_by_the_tolerance():
    data = [case("connections", k, power(k + 1)) for k in (0, 1, 2)]
    expect = [{"k": k, "order": k + 1} for k in (0, 1, 2)]
    assert check_order(data, select={"by": "connections"}, expect=expect, tolerance=0.1).holds is True
    wrong = [{"k": 1, "order": 2.2}]
    assert check_order(data, select={"by": "connections"}, expect=wrong, tolerance=0.1).holds is False


def test_an_order_that_has_not_settled_is_undecided():
    """``H + c H^2`` with both terms equal inside the smallest decade: the local slopes still turn."""
    turning = [h + 800.0 * h**2 for h in H]
    out = check_order([case("connections", 0, turning)], select={}, expect=[{"k": 0, "order": 1}], tolerance=0.1)
    assert out.holds is None and "pre-asymptotic" in out.measured


def test_an_unstable_run_is_undecided_not_failed():
    errors = power(1)
    errors[0] = np.nan  # diverged at the smallest H
    out = check_order([case("connections", 0, errors)], select={}, expect=[{"k": 0, "order": 1}], tolerance=0.1)
    assert out.holds is None


def test_growth_within_the_share_of_rho_minus_one():
    """rho 1.09: a measured 1.0905 is 0.5/90 of rho - 1 off (pass at 5 %), 1.10 is 1/9 off (fail)."""
    near = case("connections", 0, power(1), growth=[(0.2, 1.09, 1.0905)])
    far = case("connections", 0, power(1), growth=[(0.2, 1.09, 1.10)])
    assert check_growth([near], select={}, verdict="unstable", tolerance=0.05).holds is True
    assert check_growth([far], select={}, verdict="unstable", tolerance=0.05).holds is False
    decays, grows = (case("connections", 1, power(2), growth=[(0.2, 0.98, m)]) for m in (0.985, 1.001))
    assert check_growth([decays], select={}, verdict="stable").holds is True
    assert check_growth([grows], select={}, verdict="stable").holds is False
    assert check_growth([decays], select={}, verdict="unstable", tolerance=0.05).holds is None
    # any verdict: a decay by 0.985 against rho 0.98 is 1/4 of |rho - 1| off, 0.9805 is 1/40 off
    close = case("connections", 1, power(2), growth=[(0.2, 0.98, 0.9805)])
    assert check_growth([near, close], select={}, verdict="any", tolerance=0.05).holds is True
    assert check_growth([near, decays], select={}, verdict="any", tolerance=0.05).holds is False


def test_the_ratio_of_two_couplings_at_their_common_steps():
    joint_H = [1.25e-3, 6.25e-4, 3.125e-4]
    signals = case("connections", 1, power(2))
    half = case("joint", 1, power(2, 0.5, joint_H), H=joint_H, method="baumgarte")
    double = case("joint", 1, power(2, 2.0, joint_H), H=joint_H, method="baumgarte")
    out = check_ratio([signals, half], select={"by": "joint"}, against={"by": "connections"}, value=1.0)
    assert out.holds is True and len(out.numbers["rows"]) == 2  # 1.25e-3 and 6.25e-4 are common
    assert all(r["ratio"] == pytest.approx(0.5) for r in out.numbers["rows"])
    assert (
        check_ratio([signals, double], select={"by": "joint"}, against={"by": "connections"}, value=1.0).holds is False
    )
    apart = case("joint", 1, power(2, 0.5, [1e-4, 2e-4, 4e-4]), H=[1e-4, 2e-4, 4e-4], method="baumgarte")
    assert check_ratio([signals, apart], select={"by": "joint"}, against={"by": "connections"}, value=1.0).holds is None


def theory_datasets():
    """What theory says of the configured cases: order k + 1 for the connections (Jacobi k = 0, 1, 2,
    Gauss-Seidel k = 0, 1, implicit Jacobi k = 0, 1) and the joint (k = 0, 1, 2), growth or decay by the predicted
    rho, the joint's error below the connections'."""
    joint_H = [1.25e-3, 6.25e-4, 3.125e-4]
    out = [case("connections", k, power(k + 1), growth=[(0.2, 1.09, 1.091)]) for k in (0, 1, 2)]
    out += [case("connections", 0, power(1), scheme="gauss-seidel-12", growth=[(0.2, 1.04, 1.0401)])]
    out += [case("connections", 1, power(2), scheme="gauss-seidel-12", growth=[(0.2, 0.98, 0.981)])]
    out += [case("connections", k, power(k + 1), implicit=True, growth=[(0.2, 0.97, 0.9701)]) for k in (0, 1)]
    out += [case("joint", k, power(k + 1, 0.1, joint_H), H=joint_H, method="baumgarte") for k in (0, 1, 2)]
    return out


def test_the_claims_file_decides_theory_as_its_references(tmp_path):
    """Through NetCDF files, as the claims job reads them."""
    paths = []
    for i, ds in enumerate(theory_datasets()):
        paths.append(tmp_path / f"{i}.nc")
        write_netcdf(ds, paths[-1])
    verdicts = evaluate(load_claims(ROOT / "config" / "claims" / "signals.yaml"), [open_dataset(p) for p in paths])
    got = {v.claim.id: v.verdict for v in verdicts}
    assert got == {v.claim.id: v.claim.reference for v in verdicts}, got
    assert {"pass", "undecided"} == set(got.values())


def test_an_implicit_case_decides_the_implicit_claim():
    """Runs that decay by the predicted rho (0.9501 against 0.95) pass it; faster (0.90) fail it."""
    claims = load_claims(ROOT / "config" / "claims" / "signals.yaml")
    for measured, verdict in ((0.9501, "pass"), (0.90, "fail")):
        implicit = case("connections", 0, power(1), implicit=True, growth=[(0.2, 0.95, measured)])
        got = {v.claim.id: v.verdict for v in evaluate(claims, theory_datasets() + [implicit])}
        assert got["signals_implicit_growth_is_the_predicted_rho"] == verdict
        assert got["signals_growth_is_the_predicted_rho"] == "pass"  # the explicit claim reads explicit cases only
