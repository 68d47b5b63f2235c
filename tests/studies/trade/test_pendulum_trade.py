"""The pendulum's speed-accuracy studies (the speed-accuracy trade): variable-step Lagrange weights, the step-size
controller, the predictor-corrector error estimate, adaptive runs, counters, fits, limits, datasets.

Every number asserted comes from theory (Lagrange remainders, the controller's formulas, the
leading term of the extrapolation error), from an independent computation (counting wrappers
around the right-hand sides, the monolithic reference, a fixed-H run), or from the paper.
"""

import math
from fractions import Fraction as F

import numpy as np
import pytest
import yaml
from helpers import ROOT, validate_config

from icosim import ParameterError, make_method
from icosim.engine.control.controller import StepController, pc_estimate
from icosim.engine.lagrange import (
    corrector_nodes,
    lagrange_coefficients,
    lagrange_weights,
    monomial_coefficients,
    predictor_nodes,
    variable_corrector_nodes,
    variable_predictor_nodes,
    weights_at,
)
from icosim.engine.macrostep import macro_step
from icosim.engine.schema import with_registries
from icosim.engine.schemes import SCHEMES, standard_schemes
from icosim.problems.pendulum import runs as runs_module
from icosim.problems.pendulum.config import trade_plan
from icosim.problems.pendulum.model import PendulumParameters
from icosim.problems.pendulum.problem import PendulumCosimulation
from icosim.problems.pendulum.reference import consistent_history, reference_solution
from icosim.problems.pendulum.runs import run_adaptive, run_cosimulation
from icosim.studies.trade.adaptive import fixed_at_error
from icosim.studies.trade.measures import angle_errors, config_label
from icosim.studies.trade.orders import decade_order, error_floor, pendulum_order
from icosim.studies.trade.stability_limit import stability_limit

P = PendulumParameters()
CFG = yaml.safe_load((ROOT / "config" / "pendulum.yaml").read_text())["pendulum"]
PROJECTION = make_method("projection")
BAUMGARTE = make_method("baumgarte", index=1, mu=1e-3)


# -- variable-step Lagrange weights against exact polynomials ------------------------------------
NODE_STEPS = [
    [F(1)] * 3,  # equidistant
    [F(1, 2), F(3, 2), F(2)],
    [F(2), F(1, 3), F(5, 7)],
    [F(7, 10), F(7, 10), F(9, 4)],
]


def _poly(coeffs, x):
    return sum(c * x**m for m, c in enumerate(coeffs))


@pytest.mark.parametrize("k", [0, 1, 2, 3])
@pytest.mark.parametrize("steps", NODE_STEPS, ids=["equal", "var1", "var2", "var3"])
def test_variable_step_weights_reproduce_polynomials_exactly(k, steps):
    """Degree <= k: extrapolation (tau = 1) and interpolation (tau in [0, 1]) are exact; for tau^(k+1)
    the error is the node polynomial prod (tau - tau_j) (the Lagrange remainder), exactly."""
    H, past = F(1), steps[:k]
    for nodes, taus in (
        (variable_predictor_nodes(H, past), [F(1)]),
        (variable_corrector_nodes(H, past), [F(0), F(1, 3), F(1, 2), F(9, 10), F(1)]),
    ):
        assert len(nodes) == k + 1
        rng = np.random.default_rng(k)
        coeffs = [F(int(c), 7) for c in rng.integers(-20, 20, k + 1)]
        for tau in taus:
            w = lagrange_weights(nodes, tau)
            assert sum(w) == 1
            assert sum(wj * _poly(coeffs, tj) for wj, tj in zip(w, nodes)) == _poly(coeffs, tau)
            remainder = tau ** (k + 1) - sum(wj * tj ** (k + 1) for wj, tj in zip(w, nodes))
            assert remainder == math.prod(tau - tj for tj in nodes)
        C = lagrange_coefficients(nodes)  # monomial form: l_j(tau_i) = delta_ij
        for i, ti in enumerate(nodes):
            assert [sum(C[m][j] * ti**m for m in range(k + 1)) for j in range(k + 1)] == [
                int(i == j) for j in range(k + 1)
            ]


@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_variable_step_nodes_with_equal_steps_are_the_equidistant_ones(k):
    """Equal steps give the paper's nodes 0, -1, ..., -k and 1, 0, ..., -k+1 and the same exact weights."""
    pred = variable_predictor_nodes(F(3, 10), [F(3, 10)] * k)
    corr = variable_corrector_nodes(F(3, 10), [F(3, 10)] * k)
    assert pred == tuple(F(n) for n in predictor_nodes(k))
    assert corr == tuple(F(n) for n in corrector_nodes(k))
    assert lagrange_weights(pred, 1) == weights_at(predictor_nodes(k), 1)
    assert lagrange_coefficients(corr) == monomial_coefficients(corrector_nodes(k))


def test_float_nodes_agree_with_exact_ones():
    exact = lagrange_weights(variable_predictor_nodes(F(1, 1000), [F(2, 1000), F(1, 2000), F(3, 1000)]), 1)
    floats = lagrange_weights(variable_predictor_nodes(1e-3, [2e-3, 5e-4, 3e-3]), 1.0)
    np.testing.assert_allclose(floats, [float(w) for w in exact], rtol=1e-12)
    with pytest.raises(ValueError, match="distinct"):
        lagrange_weights((0.0, 0.0), 1.0)
    with pytest.raises(ValueError, match="> 0"):
        variable_predictor_nodes(1e-3, [0.0])


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-21"])
@pytest.mark.parametrize("k", [0, 1, 2])
def test_set_macro_step_with_equal_steps_is_bitwise_the_fixed_step(k, scheme):
    """The problem's variable-step weights at equal steps are the fixed-H weights: one macro step is identical
    (with either scheme)."""
    fixed = PendulumCosimulation(P, "ff", k, 2e-3)
    variable = PendulumCosimulation(P, "ff", k, 7e-4)
    variable.set_macro_step(2e-3, [2e-3] * k)
    assert np.array_equal(fixed.w_pred, variable.w_pred) and np.array_equal(fixed.C_corr, variable.C_corr)
    hist = consistent_history(P, "ff", k, 2e-3)
    a = macro_step(fixed, PROJECTION, P.initial_state(), hist, scheme=scheme)
    b = macro_step(variable, PROJECTION, P.initial_state(), hist, scheme=scheme)
    for x, y in zip(a, b):
        assert np.array_equal(x, y)
    with pytest.raises(ParameterError):
        variable.set_macro_step(-1.0)
    if k:
        with pytest.raises(ParameterError):
            variable.set_macro_step(1e-3, [])


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-12"])
def test_a_retried_step_is_the_step_of_a_fresh_problem(scheme):
    """A rejected step retried from the same state and history with another H (the adaptive loop) computes
    exactly what a problem set up for that H computes, at the same cost: the first attempt's predictor
    responses are dropped, not found stale by the Jacobians and integrated again."""
    hist = consistent_history(P, "ff", 2, 2e-3)
    state = P.initial_state()
    retried = PendulumCosimulation(P, "ff", 2, 2e-3)
    retried.set_macro_step(8e-3, [2e-3, 2e-3])
    macro_step(retried, PROJECTION, state, hist, scheme=scheme)  # the rejected attempt
    retried.set_macro_step(1e-3, [2e-3, 2e-3])
    fresh = PendulumCosimulation(P, "ff", 2, 2e-3)
    fresh.set_macro_step(1e-3, [2e-3, 2e-3])
    a = macro_step(retried, PROJECTION, state, hist, scheme=scheme)
    b = macro_step(fresh, PROJECTION, state, hist, scheme=scheme)
    for x, y in zip(a, b):
        assert np.array_equal(x, y)
    assert retried.stats["integrations"] - fresh.stats["integrations"] == fresh.stats["integrations"]


def _drive(dec, k, pattern, T, *, variable=True, scheme="jacobi"):
    """Macro steps of sizes cycling through ``pattern`` up to ``T``; max angle error against the reference."""
    H0 = pattern[-1]
    prob = PendulumCosimulation(P, dec, k, H0, rtol=1e-10, atol=1e-10)
    hist = consistent_history(P, dec, k, H0, rtol=1e-14, atol=1e-14)
    state, past, t, ts, phis = P.initial_state(), [H0] * k, 0.0, [0.0], [P.initial_state()[[0, 4]]]
    i = 0
    while t < T - 1e-12:
        h = pattern[i % len(pattern)]
        prob.set_macro_step(h, past if variable else None)
        state, hist, _ = macro_step(prob, PROJECTION, state, hist, scheme=scheme)
        past, t, i = ([h] + past)[:k], t + h, i + 1
        ts.append(t)
        phis.append(state[[0, 4]])
    ref = reference_solution(P, np.array(ts), rtol=1e-14, atol=1e-14)
    phis = np.array(phis)
    return max(np.max(np.abs(phis[:, 0] - ref["phi1"])), np.max(np.abs(phis[:, 1] - ref["phi2"])))


def test_non_equidistant_macro_nodes_keep_the_order():
    """dd, k = 2 with steps alternating H, H/2: halving H divides the error by ~2^3 (order k + 1, as with
    fixed H); with the equidistant weights on those nodes the error is O(H), not O(H^3)."""
    errs = [_drive("dd", 2, [H, H / 2], 0.06) for H in (2e-3, 1e-3)]
    assert abs(math.log2(errs[0] / errs[1]) - 3) < 0.2, errs
    wrong = [_drive("dd", 2, [H, H / 2], 0.06, variable=False) for H in (2e-3, 1e-3)]
    assert math.log2(wrong[0] / wrong[1]) < 1.2 and wrong[1] > 100 * errs[1], wrong
    # Gauss-Seidel (link 2 first) on the same nodes: the same order
    gs = [_drive("dd", 2, [H, H / 2], 0.06, scheme="gauss-seidel-21") for H in (2e-3, 1e-3)]
    assert abs(math.log2(gs[0] / gs[1]) - 3) < 0.2, gs


# -- the step-size controller -------------------------------------------------------------------
def test_controller_rejects_then_accepts_on_a_model_error():
    """err(H) = (H/H*)^p: a step at 4 H* is rejected; the retry at safety * H* (the controller's formula
    H err^(-1/p) safety) has err = safety^p < 1 and is accepted."""
    p, H_star = 3, 1e-3
    c = StepController(order=p)
    err = lambda H: (H / H_star) ** p  # noqa: E731
    H = 4 * H_star
    assert not c.accepts(err(H))
    H = c.after_reject(H, err(H))
    assert H == pytest.approx(0.9 * H_star, rel=1e-12)
    assert c.accepts(err(H)) and err(H) == pytest.approx(0.9**p)


def test_controller_limits():
    c = StepController(order=2, fac_min=0.2, fac_max=2.0, H_min=1e-5, H_max=1e-2)
    assert c.after_accept(1e-3, 1e-30, None) == pytest.approx(2e-3)  # growth limited to fac_max
    assert c.after_accept(1e-3, 0.0, None) == pytest.approx(2e-3)
    assert c.after_reject(1e-3, 1e30) == pytest.approx(2e-4)  # shrink limited to fac_min
    assert c.after_reject(1e-3, math.inf) == pytest.approx(2e-4)
    assert c.after_reject(1e-3, 1.0001) <= 0.9 * 1e-3  # a rejected step always shrinks, by at least the safety
    assert c.after_accept(1e-3, 1e-6, None, after_reject=True) == pytest.approx(1e-3)  # no growth after a rejection
    assert c.after_accept(8e-3, 1e-30, None) == pytest.approx(1e-2)  # H_max
    assert c.after_reject(2e-5, 1e6) == pytest.approx(1e-5)  # H_min
    # PI formula: H safety err^(-beta1/p) err_prev^(beta2/p)
    assert c.after_accept(1e-3, 0.5, 0.25) == pytest.approx(1e-3 * 0.9 * 0.5 ** (-0.35) * 0.25**0.2, rel=1e-12)
    with pytest.raises(ParameterError):
        StepController(order=0)
    with pytest.raises(ParameterError):
        StepController(order=1, fac_min=1.5)


def test_adaptive_run_rejects_a_too_large_first_step_and_retries_with_the_controllers_size():
    """Projection ff k = 1 from H0 = 2e-2 at tol = 1e-4: the estimate of that step, computed here
    independently with one macro step, is > 1; the run rejects it and retries with after_reject(H0, err)."""
    H0, tol = 2e-2, 1e-4
    settings = dict(H_min=1e-5, H_max=5e-2)
    prob = PendulumCosimulation(P, "ff", 1, H0)
    hist = consistent_history(P, "ff", 1, H0)
    _, h1, _ = macro_step(prob, PROJECTION, P.initial_state(), hist)
    err0 = pc_estimate(h1[0], prob.extrapolate(hist), tol)
    assert err0 > 1
    res = run_adaptive(P, PROJECTION, "ff", 1, t_end=0.045, tol=tol, drift_tol=1.0, H0=H0, controller=settings)
    assert res.rejected_H[0] == H0
    expected = StepController(order=2, **settings).after_reject(H0, err0)
    assert res.rejected_H[1:2] == [expected] or res.H[0] == pytest.approx(expected, rel=1e-12)
    assert res.status == "stable" and res.t[-1] == pytest.approx(0.045, abs=1e-15)
    assert np.all(res.estimate <= 1)


# -- the error estimate's order ------------------------------------------------------------------
def _derivative_at_zero(names, order):
    """``d^order/dt^order`` of reference quantities at t = 0 (least squares degree-10 fit over [-0.02, 0.02])."""
    t = np.linspace(-0.02, 0.02, 41)
    ref = reference_solution(P, t, rtol=1e-14, atol=1e-14)
    return np.array([np.polynomial.polynomial.polyfit(t, ref[n], 10)[order] * math.factorial(order) for n in names])


@pytest.mark.parametrize("dec", ["ff", "fd"])
@pytest.mark.parametrize("k", [0, 1, 2])
def test_predictor_corrector_difference_is_the_extrapolation_error(dec, k):
    """From exact history, e_c - e_p = H^(k+1) e^(k+1)(0) (1 + O(H)) (Lagrange remainder at tau = 1 of the
    nodes 0, -1, ..., -k; the projection's corrected e is exact to higher order): slope k + 1 and the constant."""
    names = ["lambda_cax", "lambda_cay"] + (["a_x", "a_y"] if dec == "fd" else [])
    deriv = _derivative_at_zero(names, k + 1)
    est = []
    for H in (1e-3, 5e-4):
        prob = PendulumCosimulation(P, dec, k, H)
        hist = consistent_history(P, dec, k, H, rtol=1e-14, atol=1e-14)
        _, h1, _ = macro_step(prob, PROJECTION, P.initial_state(), hist)
        diff = h1[0] - prob.extrapolate(hist)
        est.append(np.max(np.abs(diff)))
        ratio = diff / (H ** (k + 1) * deriv)
    assert abs(math.log2(est[0] / est[1]) - (k + 1)) < 0.05
    np.testing.assert_allclose(ratio, 1.0, atol=0.05)


def test_predictor_corrector_difference_on_non_equidistant_nodes():
    """k = 2, past steps 2H: nodes 0, -2, -4; the remainder constant is prod(1 - tau_j)/3! = 1*3*5/6 = 2.5."""
    k, H = 2, 5e-4
    times = np.array([0.0, -2 * H, -4 * H])
    ref = reference_solution(P, times, rtol=1e-14, atol=1e-14)
    hist = np.stack([ref["lambda_cax"], ref["lambda_cay"]], axis=-1)
    prob = PendulumCosimulation(P, "ff", k, H)
    prob.set_macro_step(H, [2 * H, 2 * H])
    _, h1, _ = macro_step(prob, PROJECTION, P.initial_state(), hist)
    diff = h1[0] - prob.extrapolate(hist)
    deriv = _derivative_at_zero(["lambda_cax", "lambda_cay"], 3)
    np.testing.assert_allclose(diff / (2.5 * H**3 * deriv), 1.0, atol=0.05)


# -- adaptive runs: drift ------------------------------------------------------------------------
def test_adaptive_run_keeps_the_drift_within_tolerance():
    """Baumgarte ff k = 0 at a loose tol: the drift criterion is what limits H (a run without it drifts
    more than drift_tol); with it every accepted state has |g_c| <= drift_tol."""
    kw = dict(t_end=0.05, tol=1e-1, H0=1e-3, controller=dict(H_min=1e-5, H_max=2e-2))
    free = run_adaptive(P, BAUMGARTE, "ff", 0, drift_tol=1.0, **kw)
    drift_free = np.max(np.hypot(free.series["g_cax"], free.series["g_cay"]))
    drift_tol = drift_free / 4
    held = run_adaptive(P, BAUMGARTE, "ff", 0, drift_tol=drift_tol, **kw)
    g = np.hypot(held.series["g_cax"], held.series["g_cay"])
    assert held.status == "stable"
    assert np.max(g) <= drift_tol
    assert held.H.size > free.H.size  # the criterion was active
    # the stored drift is the joint constraint of the stored states, recomputed independently
    np.testing.assert_allclose(
        np.max(np.abs(held.drift)), np.max(np.abs(np.concatenate([held.series["g_cax"][1:], held.series["g_cay"][1:]])))
    )


# -- counters and CPU seconds ----------------------------------------------------------------------
def test_counts_are_what_they_say(monkeypatch):
    """Right-hand side evaluations, Jacobians and Radau steps counted by wrappers around the links'
    right-hand sides (independent of the integrator's own counts); macro steps = T/H.

    On the numpy reference path (tests/reference_radau.py: the closures are what it calls); the compiled
    kernel's counters equal its counters (tests/problems/pendulum/test_pendulum_compiled.py)."""
    import reference_links
    from reference_radau import NumpyPendulum

    monkeypatch.setattr(runs_module, "PendulumCosimulation", NumpyPendulum)

    calls = {"rhs": 0, "jac": 0, "step_end": 0}

    def counting(cls):
        original = cls.rhs

        def rhs(self, coef, H):
            fun = original(self, coef, H)

            def counted(t, Y):
                calls["rhs"] += 1
                if np.ndim(t) == 0 and np.ndim(Y) == 3:
                    calls["jac"] += 1  # finite-difference Jacobian: all perturbations in one call
                elif np.ndim(t) == 0 and float(t) > 0:
                    calls["step_end"] += 1  # f at the end of an accepted step
                return fun(t, Y)

            return counted

        monkeypatch.setattr(cls, "rhs", rhs)

    counting(reference_links.NumpyLink1)
    counting(reference_links.NumpyLink2)
    H, T = 2e-3, 0.02
    res = run_cosimulation(P, BAUMGARTE, "fd", 1, H=H, t_end=T)
    assert res.stats["rejected"] == 0  # so every f at t > 0 ends an accepted step
    assert res.stats["macro_steps"] == round(T / H) == res.t.size - 1
    assert res.stats["fev"] + res.jacobian_stats["fev"] == calls["rhs"]
    assert res.jacobian_stats["jev"] == calls["jac"]
    assert res.stats["steps"] == calls["step_end"]


def test_cpu_seconds_are_process_time_of_the_stepping(monkeypatch):
    """A fake process clock advancing by 1 per call: the run reads it exactly twice, around the stepping,
    after the compiled integrator is loaded (numba's compilation or cache load is not timed)."""
    ticks, calls = iter(range(100)), []

    def clock():
        calls.append("clock")
        return float(next(ticks))

    monkeypatch.setattr(runs_module.time, "process_time", clock)
    monkeypatch.setattr(runs_module, "warm_up", lambda: calls.append("warm_up"))
    res = run_cosimulation(P, PROJECTION, "ff", 0, H=5e-3, t_end=0.01)
    assert res.cpu_seconds == 1.0
    assert calls == ["warm_up", "clock", "clock"]


def test_angle_errors_max_and_time_weighted_rms():
    t = np.array([0.0, 1.0, 3.0])
    ref = {"phi1": np.zeros(3), "phi2": np.zeros(3)}
    err_max, err_rms = angle_errors(t, np.array([0.0, 2.0, 2.0]), np.zeros(3), ref)
    # sq = (d1^2 + d2^2)/2 = 0, 2, 2; trapezoid: 0.5*(0+2)*1 + 0.5*(2+2)*2 = 5 over T = 3
    assert err_max == 2.0 and err_rms == pytest.approx(math.sqrt(5 / 3))


# -- fits, limits, equal error ---------------------------------------------------------------------
def test_order_rule_statuses():
    H = np.geomspace(1e-4, 2e-2, 10)
    assert decade_order(H, 2 * H**3).status == "asymptotic"
    f = decade_order(H, H**2 + 1e7 * H**4)  # both terms equal at 3e-4: still turning in the decade
    assert f.status == "pre-asymptotic" and f.spread > 0.1
    unstable = H < 3e-4
    assert decade_order(H, np.where(unstable, np.nan, H**2), unstable).status == "unstable as H -> 0"
    assert decade_order(H[:2], H[:2]).status == "too few points"
    floor = error_floor(0.2 / H, reference_accuracy=1e-14)
    e = np.maximum(H**4, 1e-15)  # a floor reached below H ~ 6e-4
    fit = pendulum_order(H, e, floor=floor)
    assert fit.status == "asymptotic" and abs(fit.order - 4) < 1e-9 and fit.H_min > 1e-4
    assert pendulum_order(H, np.full(H.shape, 1e-16), floor=floor).status == "at the error floor"
    unstable = H > 1e-3
    f = pendulum_order(H, np.where(unstable, np.nan, np.maximum(H**3, 1e-16)), unstable, floor=1e-11)
    assert f.status == "no stable decade above the floor"


def test_stability_limit_search():
    lim = stability_limit(lambda H: H <= 3.3e-3, [1e-3, 2e-3, 5e-3, 1e-2], resolution=0.02)
    assert lim.status == "bisected" and lim.H_max <= 3.3e-3 < lim.H_unstable <= 1.02 * lim.H_max
    assert [h for h, *_ in lim.evaluations[:3]] == [1e-3, 2e-3, 5e-3]  # the scan stops at the first unstable H
    band = stability_limit(lambda H: 1.5e-3 <= H <= 7e-3, [1e-3, 2e-3, 5e-3, 1e-2], resolution=0.02)
    assert band.H_band_low == 2e-3 and band.H_max <= 7e-3 < band.H_unstable
    assert stability_limit(lambda H: True, [1e-3, 1e-2]).status == "stable up to the cap"
    assert stability_limit(lambda H: False, [1e-3, 1e-2]).status == "no stable step size"


def test_linear_prediction_is_the_policys_verdict(monkeypatch):
    """The predicted limit counts only a ``stable`` verdict as stable: a marginal or undecided step size
    (rho NaN, nothing known) is not, and the dataset records the verdict at the bracket's upper end."""
    from icosim.problems.pendulum.linearised import combined_verdict
    from icosim.studies.trade import linear_study
    from icosim.studies.trade import stability_limit as limits

    settings = {key: CFG[key] for key in ("model", "methods")}
    rho, verdict = linear_study.linear_stability(
        P, make_method("baumgarte", **CFG["methods"]["baumgarte"]), "ff", 1, 1e-3
    )
    assert verdict == "stable" and 0 < rho < 1
    assert combined_verdict(["stable", "undecided"]) == "undecided"
    assert combined_verdict(["marginal", "unstable"]) == "unstable"

    def fake(params, method, decomposition, k, H, *, scheme="jacobi"):
        return (0.5, "stable") if H < 3e-3 else (math.nan, "undecided") if H < 6e-3 else (2.0, "unstable")

    monkeypatch.setattr(limits, "linear_stability", fake)
    pred = limits.linear_predicate(settings, "baumgarte", "ff", 1)
    lim = limits.stability_limit(pred, [1e-3, 2e-3, 5e-3, 1e-2], resolution=0.02)
    assert lim.H_max < 3e-3 <= lim.H_unstable
    assert [info["verdict"] for H, ok, info in lim.evaluations if H == lim.H_unstable] == ["undecided"]


def test_measured_predicate_runs_without_a_reference(monkeypatch):
    """The limit search's runs solve no reference: their records are those of a run with one, the errors NaN."""
    from icosim.problems.pendulum.config import run_settings
    from icosim.studies.trade import measures
    from icosim.studies.trade.stability_limit import measured_predicate

    settings = run_settings(CFG, ["projection"])
    with_errors = measures.measured_run(
        settings, "jacobi", "projection", "ff", 1, 5e-3, 0.01, reference=dict(CFG["trade"]["reference"])
    )

    def no_reference(*args, **kwargs):
        raise AssertionError("the limit search solved a reference")

    monkeypatch.setattr(measures, "reference_solution", no_reference)
    ok, rec = measured_predicate(settings, "jacobi", "projection", "ff", 1, 0.01)(5e-3)
    assert ok and math.isnan(rec["error_max"]) and math.isnan(rec["error_rms"])
    assert math.isfinite(with_errors["error_max"])
    untimed = set(rec) - {"error_max", "error_rms", "cpu_seconds"}
    assert {key: rec[key] for key in untimed} == {key: with_errors[key] for key in untimed}


def test_fixed_at_error_is_exact_for_a_power_law():
    """error = C H^p, N = T/H: log-log interpolation between grid points is exact."""
    T, C, p = 1.0, 3.0, 2.0
    H = np.array([1e-3, 2e-3, 5e-3, 1e-2])
    n, cpu, how = fixed_at_error(H, C * H**p, T / H, 1e-3 * T / H, C * 3e-3**p)
    assert how == "interpolated" and n == pytest.approx(T / 3e-3, rel=1e-12) and cpu == pytest.approx(1e-3 * T / 3e-3)
    assert fixed_at_error(H, C * H**p, T / H, T / H, C * 1e-4**p)[2] == "not bracketed"


# -- configuration ---------------------------------------------------------------------------------
def test_shipped_configuration_validates_and_schemes_match():
    validate_config(CFG, "pendulum")
    schema = yaml.safe_load((ROOT / "workflow" / "schemas" / "pendulum.schema.yaml").read_text())
    # the schema's schemes are the registry's, filled in when the workflow validates (no list of its own)
    assert schema["$defs"]["scheme"] == {}
    assert with_registries(schema)["$defs"]["scheme"]["enum"] == list(SCHEMES)
    plan = trade_plan(CFG)
    # the 21 configurations with every scheme of pendulum.schemes (Jacobi, Gauss-Seidel 1->2 and 2->1:
    # every registered scheme but the variants)
    assert len(plan["configs"]) == 21 * len(CFG["schemes"]) and len(CFG["trade"]["error_over_H"]["H"]) >= 8
    assert {c[1] for c in plan["configs"]} == set(CFG["schemes"]) == set(standard_schemes())
    assert min(CFG["trade"]["error_over_H"]["H"]) == 1e-4 and max(CFG["trade"]["error_over_H"]["H"]) == 2e-2
    assert config_label("jacobi", "baumgarte", "ff", 1) == "baumgarte_ff_k1"
    assert config_label("gauss-seidel-12", "baumgarte", "ff", 1) == "baumgarte_ff_k1_gauss-seidel-12"
    # the Gauss-Seidel adaptive configuration runs only while its scheme is configured (config/jacobi_only.yaml)
    assert any(c.get("scheme") == "gauss-seidel-12" for c in plan["adaptive"]["configurations"])
    only = trade_plan(dict(CFG, schemes=["jacobi"]))
    assert {c.get("scheme", "jacobi") for c in only["adaptive"]["configurations"]} == {"jacobi"}
    assert {g[0] for g in only["groups"]} == {"jacobi"} and len(only["configs"]) == 21


def test_bad_trade_configuration_names_the_key():
    import copy

    bad = copy.deepcopy(CFG)
    bad["trade"]["error_over_H"]["t_end"] = 0.2003
    with pytest.raises(ParameterError, match=r"error_over_H.t_end"):
        trade_plan(bad)
    bad = copy.deepcopy(CFG)
    bad["schemes"] = ["gauss_seidel"]
    with pytest.raises(ParameterError, match="pendulum.schemes"):
        trade_plan(bad)
    bad = copy.deepcopy(CFG)
    bad["trade"]["adaptive"]["configurations"][0] = {"method": "weighted", "decomposition": "dd", "k": 1, "tol": [1e-3]}
    with pytest.raises(ParameterError, match=r"adaptive.configurations\[0\]"):
        trade_plan(bad)
    bad = copy.deepcopy(CFG)
    bad["trade"]["adaptive"]["H0"] = 1.0
    with pytest.raises(ParameterError, match="H0"):
        trade_plan(bad)


# -- datasets: the contract other tools read -------------------------------------------------------
@pytest.fixture(scope="module")
def small_studies(tmp_path_factory):
    """Every study on a tiny grid, written and read back as NetCDF (as the workflow does)."""
    from icosim.io.netcdf import open_dataset, write_netcdf
    from icosim.studies.trade.adaptive import adaptive_study
    from icosim.studies.trade.baselines import linear_orders_dataset, monolithic_baselines
    from icosim.studies.trade.stability_limit import limits_study, merge_limits
    from icosim.studies.trade.sweep import sweep_group
    from icosim.studies.trade.tolerance import tolerance_study
    from icosim.studies.trade.work_precision import work_precision_dataset

    trade = CFG["trade"]
    settings = {key: CFG[key] for key in ("model", "methods", "integrator", "sensitivities", "corrector", "divergence")}
    ref = trade["reference"]
    H, T = [5e-3, 1e-2, 2e-2], 0.04
    sweeps = [
        sweep_group(settings, "jacobi", "baumgarte", "ff", [0, 1], H, T, reference=ref, repeats=1),
        sweep_group(settings, "jacobi", "projection", "ff", [1], H, T, reference=ref, repeats=1),
        sweep_group(settings, "gauss-seidel-12", "projection", "ff", [1], H, T, reference=ref, repeats=1),
    ]  # labels of different lengths: none may be cut to the first file's string width
    root = tmp_path_factory.mktemp("trade")

    def round_trip(ds, name):  # as the workflow passes datasets from job to job
        write_netcdf(ds, root / f"{name}.nc")
        return open_dataset(root / f"{name}.nc")

    sweeps = [round_trip(ds, f"sweep{i}") for i, ds in enumerate(sweeps)]
    mono = monolithic_baselines(P, [1e-4, 1e-8], T, reference=ref, repeats=1)
    lin = linear_orders_dataset(
        settings,
        [
            ("baumgarte_ff_k0", "jacobi", "baumgarte", "ff", 0),
            ("baumgarte_ff_k1", "jacobi", "baumgarte", "ff", 1),
            ("projection_ff_k1", "jacobi", "projection", "ff", 1),
            ("projection_ff_k1_gauss-seidel-12", "gauss-seidel-12", "projection", "ff", 1),
        ],
        H,
        model=trade["linear_orders"]["model"],
        x0=0.1,
        t_end=0.1,
    )
    wp = work_precision_dataset(sweeps, mono, lin, fit=trade["fit"], accuracy_levels=[1e-4, 1e-12])
    # a run the linear study does not hold is an error, not a row of NaN
    with pytest.raises(ValueError, match="no configuration projection_ff_k1_gauss-seidel-12"):
        partial = lin.drop_sel(config=["projection_ff_k1_gauss-seidel-12"])
        work_precision_dataset(sweeps, mono, partial, fit=trade["fit"], accuracy_levels=[1e-4])
    limit_groups = []
    for scheme, method, k in (
        ("jacobi", "baumgarte", 1),
        ("jacobi", "projection", 0),
        ("gauss-seidel-21", "projection", 0),
    ):
        limits = {"scan": [5e-3, 2e-2], "t_end": 0.05, "resolution": 0.5}
        ds = limits_study(settings, scheme, method, "ff", [k], limits=limits)
        limit_groups.append(round_trip(ds, f"limits_{scheme}_{method}"))
    lim = merge_limits(limit_groups)
    tol = tolerance_study(
        settings, [{"method": "projection", "decomposition": "ff", "k": 1}], [1e-2], [1e-3, 1e-8], T, reference=ref
    )
    study = dict(
        trade["adaptive"],
        t_end=0.04,
        H_fixed=[2e-3, 1e-2],
        configurations=[
            {"method": "projection", "decomposition": "ff", "k": 1, "tol": [1e-2, 1e-4]},
            {"scheme": "gauss-seidel-21", "method": "projection", "decomposition": "ff", "k": 1, "tol": [1e-2]},
        ],
    )
    ad = adaptive_study(settings, study, reference=ref)
    out = {}
    for name, ds in (("work_precision", wp), ("stability_limit", lim), ("tolerance", tol), ("adaptive", ad)):
        write_netcdf(ds, root / f"{name}.nc")
        out[name] = open_dataset(root / f"{name}.nc")
    return out


def test_datasets_have_the_contract_names_and_dims(small_studies):
    wp, lim, ad = small_studies["work_precision"], small_studies["stability_limit"], small_studies["adaptive"]
    for name in ("error_max", "error_rms", "cpu_seconds", "n_macro_steps"):
        assert wp[name].dims == ("config", "H")
    assert list(wp["config"].values) == [
        "baumgarte_ff_k0",
        "baumgarte_ff_k1",
        "projection_ff_k1",
        "projection_ff_k1_gauss-seidel-12",
    ]
    assert list(wp["scheme"].values) == ["jacobi"] * 3 + ["gauss-seidel-12"]
    # every configuration found its linear model's row (the labels are the same spelling as the sweeps')
    assert np.all(np.isfinite(wp["rho_linear"].values))
    for name in ("H_max", "H_max_linear"):
        assert lim[name].dims == ("config",)
    assert list(lim["config"].values) == ["baumgarte_ff_k1", "projection_ff_k0", "projection_ff_k0_gauss-seidel-21"]
    # the linear bracket's upper end: a verdict of the policy, "" where the search found no unstable H
    assert set(map(str, lim["verdict_linear_unstable"].values)) <= {"", "unstable", "marginal", "undecided"}
    for name in ("error_max", "n_macro_steps", "cpu_seconds"):
        assert ad[name].dims == ("config", "tol")
    assert list(ad["config"].values) == ["projection_ff_k1", "projection_ff_k1_gauss-seidel-21"]
    assert list(ad["scheme"].values) == ["jacobi", "gauss-seidel-21"]
    # counts over (config, H) are the end time over H for the runs that reached it
    ok = wp["status"].values == "stable"
    np.testing.assert_array_equal(
        wp["n_macro_steps"].values[ok], np.broadcast_to(np.round(0.04 / wp["H"].values), ok.shape)[ok]
    )
    assert np.all(wp["cpu_seconds"].values[ok] > 0)


def test_report_conclusions_are_the_datasets(small_studies):
    """The trade section's sentences are built from the same rows the tables show."""
    from icosim.report.pendulum_trade import trade_section
    from icosim.studies.trade.conclusions import adaptive_summary, order_rows, order_summary

    s = small_studies
    html = trade_section(
        work_precision=s["work_precision"],
        stability_limit=s["stability_limit"],
        tolerance=s["tolerance"],
        adaptive=s["adaptive"],
        figure_pngs={},
    )
    rows = order_rows(s["work_precision"])
    summary = order_summary(rows)
    assert f"{summary['asymptotic']} of {summary['n']} configurations have an asymptotic order" in html
    ad = adaptive_summary(s["adaptive"])["projection_ff_k1"]
    assert f"in {ad['fewer']} of {ad['compared']} comparisons" in html or "no adaptive error is bracketed" in html
    assert ad["drift_ok"]


def test_figures_draw_every_scheme(small_studies):
    """Every trade figure is drawn from the datasets, Gauss-Seidel configurations in their own rows/panels."""
    from icosim.figures import pendulum_trade as figs
    from icosim.problems.pendulum.names import TRADE_FIGURE_DATASETS

    s = small_studies
    # the workflow's table: one job per figure, each given the datasets the table names
    assert list(figs.TRADE_FIGURES) == list(TRADE_FIGURE_DATASETS)
    drawn = {
        name: make(*(s[stem] for stem in TRADE_FIGURE_DATASETS[name])) for name, make in figs.TRADE_FIGURES.items()
    }
    wp = drawn["work_precision"]
    assert len([ax for ax in wp.axes if ax.get_title().startswith("Gauss–Seidel 1→2, k = 1")]) == 1
    err = drawn["error_over_H"]
    assert [ax.get_title() for ax in err.axes] == [
        "Jacobi, k = 0",
        "Jacobi, k = 1",
        "Gauss–Seidel 1→2, k = 0",
        "Gauss–Seidel 1→2, k = 1",
    ]
    lim = drawn["stability_limit"]
    assert [ax.get_title() for ax in lim.axes] == ["Jacobi", "Gauss–Seidel 2→1"]
    ad = drawn["adaptive"]
    assert ad.axes[1].get_title() == "projection ff k=1, Gauss–Seidel 2→1"
