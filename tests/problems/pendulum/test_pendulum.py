"""The double pendulum of Sect. 4: integrator, subsystems, dd formulation, projection, sensitivities.

Independent routes: scipy's ``solve_ivp`` (Radau and DOP853) for the batched
Radau IIA; the monolithic model in minimal coordinates (Lagrange's equations,
derived separately from the link subsystems) for the subsystem equations and
the coupling conditions; central differences through full corrector
integrations for the forward-difference sensitivities; the KKT conditions
for the projection.
"""

import math

import numpy as np
import pytest
from helpers import correct_all, predict_all
from reference_links import NumpyLink1, NumpyLink2
from reference_radau import radau_batch
from scipy.integrate import solve_ivp

from icosim import ParameterError, make_method
from icosim.engine.macrostep import macro_step
from icosim.errors import StepFailure
from icosim.problems.pendulum.config import configured_runs
from icosim.problems.pendulum.integrator.systems import IntegrationError
from icosim.problems.pendulum.integrator.tableau import MU_REAL
from icosim.problems.pendulum.manifold import ProjectionError, _constraint_jacobian, project_state
from icosim.problems.pendulum.model import PendulumParameters, joint_constraint
from icosim.problems.pendulum.problem import PendulumCosimulation
from icosim.problems.pendulum.reference import Monolithic, consistent_history, reference_solution
from icosim.problems.pendulum.runs import run_cosimulation

P = PendulumParameters()
H = 1e-3


# -- the integrator ---------------------------------------------------------------------
def _pendulum_rhs(t, Y):
    return Monolithic(P).rhs(t, Y)


#: The two starts and the end time of the comparison with scipy's Radau.
RADAU_STARTS, RADAU_T1 = np.array([Monolithic(P).initial_state(), [0.3, -1.0, 0.5, 0.0]]), 2.0


@pytest.fixture(scope="module")
def radau_exact_ends():
    """The end states from RADAU_STARTS, DOP853 at 1e-13: one solution for every tolerance compared."""
    return [
        solve_ivp(_pendulum_rhs, (0, RADAU_T1), y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
        for y0 in RADAU_STARTS
    ]


@pytest.mark.parametrize("tol", [1e-6, 1e-9])
def test_radau_batch_agrees_with_scipy_radau_on_the_monolithic_pendulum(tol, radau_exact_ends):
    """Same method, same tolerance: both land within a few tolerances of a 1e-13 DOP853 solution."""
    y0, t1 = RADAU_STARTS, RADAU_T1
    ours = radau_batch(_pendulum_rhs, 0.0, t1, y0, rtol=tol, atol=tol, first_step=1e-3)
    for b in range(2):
        scipy_radau = solve_ivp(_pendulum_rhs, (0, t1), y0[b], method="Radau", rtol=tol, atol=tol, first_step=1e-3)
        exact = radau_exact_ends[b]
        err_ours = np.max(np.abs(ours.y[b] - exact))
        err_scipy = np.max(np.abs(scipy_radau.y[:, -1] - exact))
        assert err_ours < 100 * tol
        assert np.max(np.abs(ours.y[b] - scipy_radau.y[:, -1])) < 100 * tol
        # the same algorithm: a comparable accuracy and step count (shared steps: at least scipy's)
        assert err_ours < 10 * err_scipy + tol
        assert 0.5 * (scipy_radau.t.size - 1) <= ours.n_steps <= 3 * (scipy_radau.t.size - 1)


def test_radau_batch_members_match_single_integrations():
    """Batching only shares the step sequence: each member matches its own integration to ~tol."""
    y0 = np.array([[0.7, -0.7, 0.0, 0.0], [0.2, 0.4, 1.0, -2.0], [-1.0, 0.5, 0.0, 3.0]])
    batch = radau_batch(_pendulum_rhs, 0.0, 1.0, y0, rtol=1e-8, atol=1e-8)
    for b in range(3):
        single = radau_batch(_pendulum_rhs, 0.0, 1.0, y0[b], rtol=1e-8, atol=1e-8)
        assert np.max(np.abs(batch.y[b] - single.y[0])) < 1e-6
    # identical members give bit-identical results (no cross-talk between members)
    twin = radau_batch(_pendulum_rhs, 0.0, 1.0, np.array([y0[1], y0[1]]), rtol=1e-8, atol=1e-8)
    assert np.array_equal(twin.y[0], twin.y[1])


def test_link_subsystem_over_a_macro_step_matches_solve_ivp():
    """A force-driven link 2 with a quadratic input polynomial: radau_batch vs solve_ivp Radau and DOP853."""
    coef = np.array([[[1.0, 5.0], [200.0, -300.0], [-4e4, 2e4]]])  # (B=1, K=3, 2) in tau = t/H
    link = NumpyLink2(P, "force")
    fun = link.rhs(coef, H)
    y0 = P.initial_state()[2:] + np.array([0, 0, 0, 0.3, -0.2, 1.5])
    ours = radau_batch(fun, 0.0, H, y0, rtol=1e-6, atol=1e-6).y[0]
    f1 = lambda t, y: fun(t, y[None, :])[0]  # noqa: E731
    radau = solve_ivp(f1, (0, H), y0, method="Radau", rtol=1e-6, atol=1e-6).y[:, -1]
    exact = solve_ivp(f1, (0, H), y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    bound = 1e-6 * (1 + np.abs(exact))  # the requested accuracy, atol + rtol |y|
    assert np.all(np.abs(ours - exact) < bound)
    assert np.all(np.abs(radau - exact) < bound)
    assert np.all(np.abs(ours - radau) < bound)


# -- subsystems against the monolithic model --------------------------------------------
def _outputs_at_start(link, state, u):
    """Outputs (P, P', P'', f) of a link at its initial instant for a constant input ``u``."""
    fun = link.rhs(np.asarray(u, dtype=float)[None, None, :], H)
    y = state[None, :]
    return link.outputs(y, fun(0.0, y), np.asarray(u, dtype=float)[None, :])[0]


@pytest.mark.parametrize("omegas", [(0.0, 0.0), (1.3, -2.1)])
def test_links_reproduce_the_monolithic_joint_force_and_acceleration(omegas):
    """Fed with the exact joint force / acceleration, every subsystem variant reproduces the monolithic
    joint acceleration / force: the coupling conditions of ff, fd and dd hold at the exact solution."""
    mono = Monolithic(P)
    Y = np.array([0.4, -1.1, *omegas])
    lam, acc = (v for v in mono.joint_quantities(Y))
    state = mono.cosim_state(Y)
    s1, s2 = state[:2], state[2:]
    out = {
        ("1", "force"): _outputs_at_start(NumpyLink1(P, "force"), s1, lam),
        ("2", "force"): _outputs_at_start(NumpyLink2(P, "force"), s2, lam),
        ("1", "kinematic"): _outputs_at_start(NumpyLink1(P, "kinematic"), s1, acc),
        ("2", "kinematic"): _outputs_at_start(NumpyLink2(P, "kinematic"), s2, acc),
    }
    for key, y in out.items():
        np.testing.assert_allclose(y[0], out[("1", "force")][0], atol=1e-14, err_msg=f"position {key}")
        np.testing.assert_allclose(y[1], out[("1", "force")][1], atol=1e-13, err_msg=f"velocity {key}")
        np.testing.assert_allclose(y[2], acc, atol=1e-12, err_msg=f"joint acceleration {key}")
    np.testing.assert_allclose(out[("2", "kinematic")][3], lam, atol=1e-12)  # mu_2 = lambda_c
    e1 = np.array([math.cos(Y[0]), math.sin(Y[0])])
    n1 = np.array([-e1[1], e1[0]])
    # link 1 driven kinematically carries the tangential joint force only
    np.testing.assert_allclose(out[("1", "kinematic")][3], np.dot(n1, lam) * n1, atol=1e-12)


def test_initial_state_is_consistent():
    assert np.max(np.abs(joint_constraint(P, P.initial_state()))) < 1e-15
    assert np.max(np.abs(joint_constraint(P, Monolithic(P).cosim_state(np.array([0.3, 2.0, -1.0, 0.5]))))) < 1e-15


# -- the dd formulation ---------------------------------------------------------------
@pytest.mark.parametrize("decomposition, n_unknowns", [("ff", 2), ("fd", 4), ("dd", 2)])
def test_unknowns_and_conditions_match(decomposition, n_unknowns):
    """The projection method's linear system is square and regular for every decomposition."""
    prob = PendulumCosimulation(P, decomposition, 1, H)
    state, hist = P.initial_state(), consistent_history(P, decomposition, 1, H)
    e = prob.extrapolate(hist)
    y, jac = prob._linearise(state, hist, e)
    res = prob.residuals(y)
    assert prob.n_coupling == n_unknowns
    rows = res["acc"].shape[-1] + res["force"].shape[-1]
    assert rows == n_unknowns
    J = np.concatenate([jac["acc"], jac["force"]], axis=0)
    assert J.shape == (n_unknowns, n_unknowns)
    assert np.linalg.cond(J) < 1e8


def test_dd_conditions_vanish_at_the_exact_solution():
    """dd: with the exact joint acceleration over the step, both conditions are zero to integration accuracy."""
    k = 2
    prob = PendulumCosimulation(P, "dd", k, H, rtol=1e-12, atol=1e-12)
    ref = reference_solution(P, np.array([H, 0.0, -H]))
    e_exact = np.stack([ref["a_x"], ref["a_y"]], axis=-1)  # at T_1, T_0, T_-1
    state = P.initial_state()
    _, y = correct_all(prob, state, e_exact[1:], e_exact[0])
    r = prob.residuals(y)
    scale = np.abs(e_exact).max()
    assert abs(r["acc"][0]) < 1e-8 * scale  # interpolation error of a quadratic over 1 ms
    assert abs(r["force"][0]) < 1e-8 * scale


def test_dd_converges_to_the_reference_with_order_k_plus_1():
    """A consistent dd formulation converges: halving H divides the error by ~2^(k+1)."""
    t_end = 0.05
    for k in (0, 1):
        errs = []
        for h in (2e-3, 1e-3):
            r = run_cosimulation(P, make_method("projection"), "dd", k, H=h, t_end=t_end, rtol=1e-11, atol=1e-11)
            ref = reference_solution(P, r.t)
            errs.append(max(np.max(np.abs(r.series[v] - ref[v])) for v in ("phi1", "phi2")))
        order = math.log2(errs[0] / errs[1])
        assert abs(order - (k + 1)) < 0.3, (k, errs, order)


# -- sensitivities --------------------------------------------------------------------
@pytest.mark.parametrize("decomposition", ["ff", "fd", "dd"])
def test_forward_difference_sensitivities_match_central_differences(decomposition):
    """The batched forward differences against central differences through separate corrector runs."""
    k = 1
    prob = PendulumCosimulation(P, decomposition, k, H)
    mono = Monolithic(P)
    state = mono.cosim_state(np.array([0.5, -1.2, 1.1, -0.4]))
    hist = consistent_history(P, decomposition, k, H)
    e = prob.extrapolate(hist)
    _, jac = prob._linearise(state, hist, e)
    for j in range(prob.n_coupling):
        h = 1e-2 * max(1.0, abs(e[j]))
        ep, em = e.copy(), e.copy()
        ep[j] += h
        em[j] -= h
        rp = prob.residuals(correct_all(prob, state, hist, ep)[1])
        rm = prob.residuals(correct_all(prob, state, hist, em)[1])
        for key in ("pos", "vel", "acc", "force"):
            central = (rp[key] - rm[key]) / (2 * h)
            scale = np.max(np.abs(jac[key])) if jac[key].size else 1.0
            np.testing.assert_allclose(
                jac[key][..., j], central, rtol=0, atol=1e-5 * scale, err_msg=f"{key}, column {j}"
            )


def test_predictor_is_the_extrapolation_polynomial():
    """The unperturbed member of the first batch (interpolation through e_p) equals the extrapolation."""
    from icosim.engine.lagrange import monomial_coefficients, predictor_nodes

    k = 2
    prob = PendulumCosimulation(P, "ff", k, H)
    state, hist = P.initial_state(), consistent_history(P, "ff", k, H) * np.array([1.0, 1.3])
    y = predict_all(prob, state, hist)
    C = np.array(monomial_coefficients(predictor_nodes(k)), dtype=float)
    coef = np.einsum("mj,ju->mu", C, hist)[None]  # extrapolation through e_N, e_N-1, e_N-2
    link = NumpyLink1(P, "force")
    direct = radau_batch(link.rhs(coef, H), 0.0, H, state[:2], rtol=1e-6, atol=1e-6)
    y_direct = link.outputs(direct.y, direct.f, coef.sum(axis=1))[0]
    np.testing.assert_allclose(y[0], y_direct, rtol=1e-10, atol=1e-13)


# -- projection -----------------------------------------------------------------------
def test_projection_satisfies_constraints_and_is_the_mass_weighted_projection():
    state = Monolithic(P).cosim_state(np.array([0.6, -0.9, 1.7, -2.3]))
    rng = np.random.default_rng(5)
    disturbed = state + 1e-3 * rng.standard_normal(8)
    out = project_state(P, disturbed)
    pos, vel = [0, 2, 3, 4], [1, 5, 6, 7]
    G = _constraint_jacobian(P, out[pos])
    assert np.max(np.abs(joint_constraint(P, out))) < 1e-14
    assert np.max(np.abs(G @ out[vel])) < 1e-13
    # KKT: M (q - q*) lies in the range of G^T (likewise the velocities)
    M = np.array([P.JO1, P.m2, P.m2, P.J2])
    for idx in (pos, vel):
        d = M * (out[idx] - disturbed[idx])
        coeff, *_ = np.linalg.lstsq(G.T, d, rcond=None)
        assert np.max(np.abs(G.T @ coeff - d)) < 1e-12 * max(1.0, np.max(np.abs(d)))
    # a consistent state stays put; projecting twice changes nothing
    np.testing.assert_allclose(project_state(P, state), state, atol=1e-14)
    np.testing.assert_allclose(project_state(P, out), out, atol=1e-14)


def test_projection_that_does_not_converge_raises_a_step_failure():
    """No unprojected state is ever returned: too few Gauss-Newton iterations or a non-finite state raise."""
    state = Monolithic(P).cosim_state(np.array([0.6, -0.9, 1.7, -2.3]))
    disturbed = state + np.array([0.2, 0.0, 0.1, -0.1, 0.3, 0.0, 0.0, 0.0])
    with pytest.raises(ProjectionError, match="Gauss-Newton"):
        project_state(P, disturbed, max_iter=1)
    assert np.max(np.abs(joint_constraint(P, project_state(P, disturbed)))) < 1e-14  # enough iterations: fine
    with pytest.raises(ProjectionError):
        project_state(P, np.where(np.arange(8) == 2, np.nan, state))
    assert issubclass(ProjectionError, StepFailure)


def test_singular_newton_matrix_is_an_integration_error():
    """Radau's Newton matrix MU/h I - J singular (J = MU/h I): an IntegrationError (a StepFailure), not LinAlgError."""
    A = MU_REAL / 0.5 * np.eye(2)
    with pytest.raises(IntegrationError, match="singular"):
        radau_batch(lambda t, y: y @ A.T, 0.0, 0.5, np.ones(2), jac=lambda t, y: np.broadcast_to(A, (1, 2, 2)))
    assert issubclass(IntegrationError, StepFailure)


# -- options and bad input ------------------------------------------------------------------
def test_fully_implicit_corrector_reduces_the_residual():
    """Corrector iterations (fully implicit) drive the Baumgarte condition far below one step's residual."""
    method = make_method("baumgarte", index=1, mu=1e-3)
    state = Monolithic(P).cosim_state(np.array([0.5, -1.2, 3.0, -4.0]))
    hist = consistent_history(P, "ff", 1, H)
    beta, gamma = method.params["beta"], method.params["gamma"]

    def baumgarte_residual(y, prob):
        r = prob.residuals(y)
        return np.max(np.abs(r["pos"] + beta * r["vel"] + gamma * r["acc"]))

    prob = PendulumCosimulation(P, "ff", 1, H)
    semi = baumgarte_residual(macro_step(prob, method, state, hist)[2], prob)
    full = baumgarte_residual(macro_step(prob, method, state, hist, iterations=4, tol=1e-15)[2], prob)
    assert full < 1e-3 * semi


@pytest.mark.parametrize(
    "method_name, kw, decomposition",
    [("baumgarte", {"index": 1, "mu": 1e-3}, "fd"), ("projection", {}, "ff"), ("projection", {}, "dd")],
)
def test_fully_implicit_option_stops_early_with_the_conditions_met(method_name, kw, decomposition):
    """iterations = 6, tol = 1e-8: the corrector passes stop once the method's conditions are below tol
    (here after the second pass: one pass leaves a residual above tol, one re-linearisation meets it)."""
    method = make_method(method_name, **kw)
    state = Monolithic(P).cosim_state(np.array([0.5, -1.2, 3.0, -4.0]))
    hist = consistent_history(P, decomposition, 1, H)
    prob = PendulumCosimulation(P, decomposition, 1, H)
    residual_of_pass, outputs = [], [None, None]
    correct = prob.correct

    def counting_correct(i, *args):
        end, y_i = correct(i, *args)
        outputs[i] = y_i
        if i == 1:  # a corrector pass (Jacobi) ends with link 2
            residual_of_pass.append(np.max(np.abs(method.condition_residuals(prob.residuals(prob.stack(outputs))))))
        return end, y_i

    prob.correct = counting_correct
    tol = 1e-8
    _, _, y = macro_step(prob, method, state, hist, iterations=6, tol=tol)
    assert 2 <= len(residual_of_pass) < 6
    assert residual_of_pass[0] > tol  # the semi-implicit step alone does not meet tol here
    assert np.max(np.abs(method.condition_residuals(prob.residuals(y)))) <= tol
    assert residual_of_pass[-1] <= tol


def test_bad_input_is_refused_with_the_name():
    with pytest.raises(ParameterError, match="dd"):
        run_cosimulation(P, make_method("weighted", a=1, b=1), "dd", 0, H=H, t_end=0.01)
    with pytest.raises(ParameterError, match="t_end"):
        run_cosimulation(P, make_method("projection"), "ff", 0, H=H, t_end=0.0105)
    with pytest.raises(ParameterError, match="decomposition"):
        PendulumCosimulation(P, "xx", 0, H)
    with pytest.raises(ParameterError, match="m1"):
        PendulumParameters(m1=-1.0)
    cfg = {
        "H": H,
        "t_end": 0.01,
        "k": [0],
        "methods": {"weighted": {"a": 1, "b": 1}},
        "configurations": [{"method": "weighted", "decomposition": "dd"}],
    }
    with pytest.raises(ParameterError, match=r"configurations\[0\]"):
        configured_runs(cfg)
    cfg["configurations"] = [{"method": "baumgarte", "decomposition": "ff"}]
    with pytest.raises(ParameterError, match="baumgarte"):
        configured_runs(cfg)


def test_reference_dataset_keeps_the_naming_contract_after_a_netcdf_round_trip(tmp_path):
    """Other tools read phi1, phi2, g_cax, g_cay, lambda_cax, lambda_cay as data variables over t."""
    from icosim.io.netcdf import open_dataset, write_netcdf
    from icosim.problems.pendulum.model import PendulumParameters
    from icosim.studies.pendulum.datasets import reference_dataset

    ds = reference_dataset(PendulumParameters(), 1e-3, 0.01, {"title": "test"})
    write_netcdf(ds, tmp_path / "reference.nc")
    back = open_dataset(tmp_path / "reference.nc")
    for name in ("phi1", "phi2", "g_cax", "g_cay", "lambda_cax", "lambda_cay"):
        assert name in back.data_vars and back[name].dims == ("t",)
    assert list(back.coords) == ["t"] and back.attrs["method"] == "monolithic"
