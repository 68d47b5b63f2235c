"""The double pendulum under the Gauss-Seidel schemes (icosim.problems.pendulum): the sensitivities of a corrector
with one link finished against central differences, the rank the finished link leaves the position level, and
runs that count their integrations and detect divergence."""

import numpy as np
import pytest
from helpers import pair_jacobians

from icosim import make_method
from icosim.engine.schemes import GS12, GS21
from icosim.problems.pendulum.model import PendulumParameters
from icosim.problems.pendulum.problem import PendulumCosimulation
from icosim.problems.pendulum.reference import Monolithic, consistent_history
from icosim.problems.pendulum.runs import run_cosimulation

P, H = PendulumParameters(), 1e-3


@pytest.mark.parametrize("decomposition", ["ff", "fd", "dd"])
@pytest.mark.parametrize("lead", [0, 1])
def test_pendulum_gauss_seidel_jacobians_match_central_differences(decomposition, lead):
    """The finished link responds algebraically, the other through its corrector: d residuals / d e
    of that map by central differences (separate corrector runs and re-evaluations)."""
    k = 1
    prob = PendulumCosimulation(P, decomposition, k, H)
    state = Monolithic(P).cosim_state(np.array([0.5, -1.2, 1.1, -0.4]))
    hist = consistent_history(P, decomposition, k, H)
    e = prob.extrapolate(hist)
    end, y_lead = prob.predict(lead, state, hist, final=True)
    fixed = [None, None]
    fixed[lead] = end
    ys = [None, None]
    ys[lead] = y_lead
    ys[1 - lead] = prob.predict(1 - lead, state, hist)[1]
    jac = pair_jacobians(prob, state, hist, e, prob.stack(ys), tuple(fixed))

    def residuals(ee):
        ys = [None, None]
        ys[lead] = prob.reevaluate(lead, end, y_lead, e, ee)
        ys[1 - lead] = prob.correct(1 - lead, state, hist, ee)[1]
        return prob.residuals(prob.stack(ys))

    for j in range(prob.n_coupling):
        h = 1e-2 * max(1.0, abs(e[j]))
        ep, em = e.copy(), e.copy()
        ep[j] += h
        em[j] -= h
        rp, rm = residuals(ep), residuals(em)
        for key in ("acc", "force"):  # the levels every decomposition's projection solves
            central = (rp[key] - rm[key]) / (2 * h)
            scale = np.max(np.abs(jac[key])) if jac[key].size else 1.0
            np.testing.assert_allclose(jac[key][..., j], central, rtol=0, atol=1e-5 * scale, err_msg=key)


@pytest.mark.parametrize("decomposition", ["ff", "fd"])
def test_pendulum_link2_first_leaves_position_level_singular(decomposition):
    """docs/gauss_seidel.md, Sect. 5: with link 2 finished, only link 1 (one degree of freedom) can move
    the joint: the position-level rows are of rank one; with link 1 finished link 2 meets them."""
    prob = PendulumCosimulation(P, decomposition, 1, H)
    state = Monolithic(P).cosim_state(np.array([0.5, -1.2, 1.1, -0.4]))
    hist = consistent_history(P, decomposition, 1, H)
    e = prob.extrapolate(hist)

    def scaled_condition(lead, level):
        fixed = [None, None]
        fixed[lead] = prob.predict(lead, state, hist, final=True)[0]
        ys = [prob.predict(i, state, hist, final=fixed[i] is not None)[1] for i in range(2)]
        jac = pair_jacobians(prob, state, hist, e, prob.stack(ys), tuple(fixed))
        A = np.concatenate([jac[level], jac["force"]])
        return np.linalg.cond(A / np.max(np.abs(A), axis=1, keepdims=True))

    assert scaled_condition(1, "pos") > 1e5 and scaled_condition(1, "vel") > 1e5  # link 2 first
    assert scaled_condition(0, "pos") < 1e2 and scaled_condition(1, "acc") < 1e2


def test_pendulum_gauss_seidel_runs_count_three_integrations_and_detect_divergence():
    stable = run_cosimulation(P, make_method("projection"), "ff", 1, H=H, t_end=0.02, scheme=GS12)
    assert stable.status == "stable" and stable.stats["integrations"] == 3 * stable.stats["macro_steps"]
    assert np.max(np.abs(np.hypot(stable.series["g_cax"], stable.series["g_cay"]))) < 1e-9  # projected
    singular = run_cosimulation(P, make_method("weighted", a=1, b=1), "ff", 0, H=H, t_end=0.02, scheme=GS21)
    assert singular.status == "diverged" and singular.t_diverged <= 2 * H and "lambda_c" in singular.reason
