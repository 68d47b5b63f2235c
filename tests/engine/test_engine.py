"""The co-simulation engine checked against independent routes.

Every number asserted here comes from an independent computation: closed forms
worked out by hand, the growth rate of plain time stepping, 128-digit
arithmetic, or the exact monolithic solution.  The linear model's own pieces
(its subsystems, its parameters) are checked in tests/problems/linear/.
"""

from fractions import Fraction

import numpy as np
import pytest
from helpers import correct_all, engine_schemes, growth_rate, predict_all

from icosim import (
    LinearCosimulation,
    ParameterError,
    PhysicalModel,
    TestModel,
    baumgarte,
    make_method,
    projection,
    spectral_radius,
    spectral_radius_float64,
    spectral_radius_mp,
    weighted_multiplier,
)
from icosim.engine.backends import Multiprecision
from icosim.engine.lagrange import corrector_nodes, predictor_nodes, weights_at
from icosim.engine.methods import engine_method
from icosim.engine.run import simulate
from icosim.problems.linear.exact import MonolithicSolution, consistent_start
from icosim.problems.linear.spectral import amplification_matrix

SCHEMES = engine_schemes()


# -- Lagrange polynomials ------------------------------------------------------
@pytest.mark.parametrize("k", [0, 1, 2, 3, 5])
def test_lagrange_weights_reproduce_polynomials_of_degree_k(k):
    for nodes in (predictor_nodes(k), corrector_nodes(k)):
        for degree in range(k + 1):
            p = (lambda d: lambda t: Fraction(t) ** d)(degree)
            for tau in (Fraction(1), Fraction(1, 3), Fraction(-7, 2)):
                value = sum(w * p(t) for w, t in zip(weights_at(nodes, tau), nodes))
                assert value == p(tau)


def test_extrapolation_weights_known_values():
    # linear extrapolation 2 e_N - e_N-1, quadratic 3 e_N - 3 e_N-1 + e_N-2
    assert weights_at(predictor_nodes(1), 1) == (2, -1)
    assert weights_at(predictor_nodes(2), 1) == (3, -3, 1)


def test_corrector_with_predicted_value_reproduces_predictor():
    """Eq. (15) linearises about e_p: the interpolation polynomial through the
    predicted value is the extrapolation polynomial, so y*(e_p) = y_p exactly."""
    c = TestModel(-0.3, 0.8, 2.0, 1.5, 0.7).coefficients()
    rng = np.random.default_rng(3)
    for dec in ("ff", "fd", "dd"):
        for k in (0, 1, 2, 3):
            prob = LinearCosimulation(c, dec, k)
            state = rng.standard_normal((2, 2))
            hist = rng.standard_normal((k + 1, prob.n_coupling))
            y_pred = predict_all(prob, state, hist)
            _, y_corr = correct_all(prob, state, hist, prob.extrapolate(hist))
            np.testing.assert_allclose(y_corr, y_pred, rtol=1e-12, atol=1e-12)


# -- spectral radius against the growth rate of time stepping -----------------
@pytest.mark.parametrize("method,dec", SCHEMES)
@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_spectral_radius_equals_growth_rate_of_time_stepping(method, dec, k):
    # a point where the coupling, not the physics, decides: undamped subsystem 2
    # rate ratios 2 and strong damping in subsystem 1
    model = TestModel(-0.05, 0.9, 2.0, 2.0, 2.0)
    rho, _ = spectral_radius_float64(model, method, dec, k)
    prob = LinearCosimulation(model.coefficients(), dec, k)
    assert growth_rate(prob, method) == pytest.approx(float(rho), rel=3e-3)


# -- a closed form worked out by hand ------------------------------------------
def _dd_projection_k0_closed_form(model):
    """Displacement/displacement projection, k = 0, by hand.

    Both masses follow the same constant acceleration a over the step:
    x+ = x + v + a/2, v+ = v + a.  The force balance mu_2 = mu_1 at T_N+1 with
    mu_1 = a + k1 x+ + d1 v+ and mu_2 = -am21 (a + k2 x+ + d2 v+) gives
    a = -(K x + (K + D) v) / S with K = k1 + am21 k2, D = d1 + am21 d2,
    S = 1 + am21 + K/2 + D (the predictor drops out: the model is linear).
    """
    c = model.coefficients()
    K = c.k1 + c.am21 * c.k2
    D = c.delta1 + c.am21 * c.delta2
    S = 1 + c.am21 + K / 2 + D
    M = np.array([[1 - K / (2 * S), 1 - (K + D) / (2 * S)], [-K / S, 1 - (K + D) / S]])
    return np.max(np.abs(np.linalg.eigvals(M)))


def test_dd_projection_k0_matches_closed_form():
    rng = np.random.default_rng(7)
    for _ in range(40):
        model = TestModel(
            -2 * rng.random(), 2 * rng.random(), 10 ** rng.uniform(-2, 2), 3 * rng.random(), 3 * rng.random()
        )
        rho, _ = spectral_radius_float64(model, projection(), "dd", 0)
        assert float(rho) == pytest.approx(_dd_projection_k0_closed_form(model), rel=1e-12, abs=1e-14)


def _ff_index3_k0_closed_form(model):
    """Force/force, index 3 (Baumgarte beta = gamma = 0), k = 0, by hand.

    With a constant force lambda over the step, subsystem i ends at
    s_i+ = Phi_i s_i + g_i r_i lambda, where r_i is the response to a unit
    constant force.  Position-level condition x_2+ = x_1+ fixes lambda; the
    recurrence is linear in (x1, v1, x2, v2) (lambda_N drops out).  Phi_i and
    r_i are evaluated here with the scipy matrix exponential of the
    subsystem's own 3x3 augmented system, independently of the engine.
    """
    import scipy.linalg

    c = model.coefficients()
    blocks = []
    for k_, d_, g_ in ((c.k1, c.delta1, 1.0), (c.k2, c.delta2, -1.0 / c.am21)):
        A = np.array([[0, 1, 0], [-k_, -d_, g_], [0, 0, 0]], dtype=float)
        E = scipy.linalg.expm(A)
        blocks.append((E[:2, :2], E[:2, 2]))
    (P1, r1), (P2, r2) = blocks
    # lambda = -(x2p - x1p)/(r2x - r1x) with the homogeneous parts x_ip = (P_i s_i)_x
    denom = r2[0] - r1[0]
    M = np.zeros((4, 4))
    M[0:2, 0:2], M[2:4, 2:4] = P1, P2
    lam_row = np.concatenate([P1[0], -P2[0]]) / denom  # lambda = (x1p - x2p)/denom
    M[0:2] += np.outer(r1, lam_row)
    M[2:4] += np.outer(r2, lam_row)
    return np.max(np.abs(np.linalg.eigvals(M)))


def test_ff_index3_k0_matches_closed_form():
    rng = np.random.default_rng(11)
    for _ in range(40):
        model = TestModel(
            -2 * rng.random(), 2 * rng.random(), 10 ** rng.uniform(-1, 1), 3 * rng.random(), 3 * rng.random()
        )
        rho, _ = spectral_radius_float64(model, baumgarte(index=3), "ff", 0)
        assert float(rho) == pytest.approx(_ff_index3_k0_closed_form(model), rel=1e-10, abs=1e-12)


# -- method identities and refusals -------------------------------------------
@pytest.mark.parametrize("dec", ["ff", "fd"])
@pytest.mark.parametrize("k", [0, 1, 2])
def test_index3_baumgarte_and_weighted_multiplier_are_identical(dec, k):
    lr, li = np.meshgrid(np.linspace(-2, 0, 9), np.linspace(0, 2, 9), indexing="ij")
    model = TestModel(lr, li, 2.0, 2.0, 2.0)
    Mb = amplification_matrix(model, baumgarte(index=3), dec, k)
    Mw = amplification_matrix(model, weighted_multiplier(index=3), dec, k)
    np.testing.assert_array_equal(Mb, Mw)
    Mb2 = amplification_matrix(model, baumgarte(beta=0, gamma=0), dec, k)
    np.testing.assert_array_equal(Mb, Mb2)


def test_weighted_multiplier_is_the_weighted_sum_of_level_corrections():
    """Eq. (24): lambda = (lambda_pos + a lambda_vel + b lambda_acc)/(1 + a + b)."""
    model = TestModel(-0.4, 1.1, 2.0, 0.5, 1.5)
    a, b = 0.7, 2.5
    Mw = amplification_matrix(model, weighted_multiplier(a, b), "ff", 1)
    # the corrected lambda is linear in the levels' corrections, and so is the step
    Mp = amplification_matrix(model, baumgarte(beta=0, gamma=0), "ff", 1)
    Mv = amplification_matrix(model, weighted_multiplier(0, 1e300), "ff", 1)  # b dominates: acc level
    Mvel = amplification_matrix(model, weighted_multiplier(1e300, 0), "ff", 1)  # a dominates: vel level
    np.testing.assert_allclose(Mw, (Mp + a * Mvel + b * Mv) / (1 + a + b), rtol=1e-9, atol=1e-12)


def test_baumgarte_index_parameters():
    assert baumgarte(mu=0.5, index=1).params["beta"] == 1.0
    assert baumgarte(mu=0.5, index=1).params["gamma"] == 0.25
    assert baumgarte(mu=0.5, index=2).params["gamma"] == 0.0
    assert baumgarte(index=3).params == {"beta": 0.0, "gamma": 0.0, "index": 3}


@pytest.mark.parametrize("method", [baumgarte(mu=1, index=1), weighted_multiplier(1, 1)])
def test_displacement_displacement_refused_for_baumgarte_and_weighted(method):
    with pytest.raises(ParameterError, match="position level"):
        amplification_matrix(TestModel(-1, 1), method, "dd", 0)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(name="nope"), "method must be one of"),
        (dict(name="baumgarte", index=1), "needs mu$"),
        (dict(name="baumgarte", index=4, mu=1), "index must be 1, 2 or 3"),
        (dict(name="baumgarte", beta=-1, gamma=0), ">= 0"),
        (dict(name="weighted", a=1), r"needs a and b \(or index\)"),
        (dict(name="weighted", a=float("nan"), b=1), "finite"),
        (dict(name="projection", a=1), "not used by method"),
        (dict(name="weighted", a=1, b=0, index=1), "index 1 needs b > 0"),
        (dict(name="weighted", a=1, b=1, index=3), "index 3 means a = b = 0"),
    ],
)
def test_method_parameter_errors_name_the_parameter(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        make_method(kwargs.pop("name"), **kwargs)


# -- convergence of the trajectory as H -> 0 --------------------------------------
@pytest.mark.parametrize(
    "method,dec,k,order",
    [
        (projection(), "ff", 0, 2),
        (projection(), "ff", 2, 4),
        (baumgarte(index=3), "ff", 0, 2),
        (projection(), "dd", 1, 2),
        (weighted_multiplier(1, 1), "fd", 1, 2),
        (weighted_multiplier(1, 1), "ff", 0, 2),
        (baumgarte(beta=2 * 5e-3, gamma=25e-6), "ff", 1, 2),  # dimensional mu = 5e-3 s: see below
        (baumgarte(beta=0.0, gamma=0.0), "ff", 0, 2),
    ],
)
def test_trajectory_converges_to_exact_monolithic_solution(method, dec, k, order):
    T, Hs = 0.5, np.array([2e-3, 1e-3, 5e-4])
    n = np.round(T / Hs).astype(int)

    def model(H):
        return PhysicalModel(1.0, 2.0, 1000.0, 1000.0, 10.0, 10.0, H)

    solutions = [MonolithicSolution(model(H).coefficients(), 0.1, 0.0) for H in Hs]
    if method.name == "baumgarte" and method.params["beta"]:
        # beta, gamma given in s and s^2: the engine takes beta/H and gamma/H^2, a method per H
        p = method.params
        runs = [([i], baumgarte(beta=p["beta"] / H, gamma=p["gamma"] / H**2)) for i, H in enumerate(Hs)]
    else:  # every H in one batch (a macro step costs about the same), each run as far as the finest H's
        runs = [(list(range(len(Hs))), method)]
    errors = [None] * len(Hs)
    for at, run_method in runs:
        prob = LinearCosimulation(model(Hs[at]).coefficients(), dec, k)
        state, hist = (np.stack(s) for s in zip(*(consistent_start(prob, solutions[i]) for i in at)))
        traj = simulate(prob, run_method, state, hist, max(n[at]))
        assert traj.diverged_at is None
        states = np.array(traj.states)
        for b, i in enumerate(at):
            exact = solutions[i].state(np.arange(n[i] + 1))
            errors[i] = max(np.max(np.abs(states[: n[i] + 1, b, j, 0] - exact[:, 0])) for j in range(2))
    errors = np.array(errors)
    assert np.all(np.diff(errors) < 0)
    observed = np.log2(errors[:-1] / errors[1:])
    assert np.all(observed > order - 0.3)


def test_small_solver_keeps_multiprecision():
    from icosim.engine.methods import solve_small

    be = Multiprecision(60)
    rng = np.random.default_rng(2)
    J = rng.standard_normal((3, 3)) + 3 * np.eye(3)
    x_true = rng.standard_normal(3)
    Jm, bm = be.asarray(J), be.asarray(J) @ be.asarray(x_true)
    x = solve_small(Jm, bm)
    assert all(abs(xi - be.const(float(xt))) < be.const(1e-50) for xi, xt in zip(x, x_true))
    np.testing.assert_allclose(solve_small(J, J @ x_true), x_true, rtol=1e-12)


def _fd_k0_closed_form(model, level_weights, project):
    """Force/displacement, k = 0, by hand (Eqs. 33-53 with constant inputs).

    Subsystem 1 is force driven: ``s1+ = Phi1 s1 + r1 lambda`` (scipy's expm of
    its own 3x3 augmented system).  Subsystem 2 follows a constant acceleration
    ``a``: ``x2+ = x2 + v2 + a/2``, ``v2+ = v2 + a``, with multiplier
    ``mu2 = -am21 (a + k2 x2+ + d2 v2+)``.  Each level's correction solves the
    2x2 system (level condition, ``mu2 - lambda = 0``) linearised about the
    predicted (lambda_N, a_N); the weighted sum of corrections gives the new
    coupling variables; projection (Eq. 55) if asked.
    """
    import scipy.linalg

    c = model.coefficients()
    E = scipy.linalg.expm(np.array([[0, 1, 0], [-c.k1, -c.delta1, 1.0], [0, 0, 0]]))
    Phi1, r1 = E[:2, :2], E[:2, 2]
    am, k1, d1, k2, d2 = c.am21, c.k1, c.delta1, c.k2, c.delta2

    def subsystems(w, lam, acc):
        s1 = Phi1 @ w[0:2] + r1 * lam
        s2 = np.array([w[2] + w[3] + acc / 2, w[3] + acc])
        return s1, s2, -k1 * s1[0] - d1 * s1[1] + lam, acc, -am * (acc + k2 * s2[0] + d2 * s2[1])

    def step(w):
        lam_p, acc_p = w[4], w[5]
        s1, s2, a1, a2, mu2 = subsystems(w, lam_p, acc_p)
        res = {"pos": s2[0] - s1[0], "vel": s2[1] - s1[1], "acc": a2 - a1}
        d_lam = {"pos": -r1[0], "vel": -r1[1], "acc": -(-k1 * r1[0] - d1 * r1[1] + 1)}
        d_acc = {"pos": 0.5, "vel": 1.0, "acc": 1.0}
        d_mu2 = -am * (1 + k2 / 2 + d2)
        e = np.array([lam_p, acc_p])
        for level, weight in level_weights.items():
            J = np.array([[d_lam[level], d_acc[level]], [-1.0, d_mu2]])
            e = e + weight * np.linalg.solve(J, -np.array([res[level], mu2 - lam_p]))
        s1, s2, *_ = subsystems(w, e[0], e[1])
        if project:
            s1 = s2 = (s1 + am * s2) / (1 + am)
        return np.concatenate([s1, s2, e])

    M = np.column_stack([step(col) for col in np.eye(6)])
    return np.max(np.abs(np.linalg.eigvals(M)))


@pytest.mark.parametrize(
    "method,weights,project",
    [
        (weighted_multiplier(1, 1), {"pos": 1 / 3, "vel": 1 / 3, "acc": 1 / 3}, False),
        (weighted_multiplier(0.5, 2), {"pos": 1 / 3.5, "vel": 0.5 / 3.5, "acc": 2 / 3.5}, False),
        (projection(), {"acc": 1.0}, True),
        (baumgarte(index=3), {"pos": 1.0}, False),
    ],
)
def test_fd_k0_matches_closed_form(method, weights, project):
    rng = np.random.default_rng(0)
    for _ in range(25):
        model = TestModel(
            -2 * rng.random(), 2 * rng.random(), 10 ** rng.uniform(-1, 1), 3 * rng.random(), 3 * rng.random()
        )
        rho, _ = spectral_radius_float64(model, method, "fd", 0)
        assert float(rho) == pytest.approx(_fd_k0_closed_form(model, weights, project), rel=1e-10, abs=1e-12)


def test_corrector_iterations_stop_when_the_coupling_variables_settle():
    """For the linear model one corrector step is exact (constant sensitivities,
    Sect. 2.1.1), so with a tolerance the second pass changes nothing and stops."""
    from icosim.engine.macrostep import macro_step

    c = TestModel(-0.3, 0.9, 2.0, 2.0, 2.0).coefficients()
    for method, dec in ((baumgarte(mu=1, index=1), "ff"), (weighted_multiplier(1, 1), "fd"), (projection(), "dd")):
        prob = LinearCosimulation(c, dec, 2)
        calls = []
        original = prob.correct
        prob.correct = lambda *a, _o=original, _c=calls: _c.append(1) or _o(*a)
        rng = np.random.default_rng(1)
        state, hist = rng.standard_normal((2, 2)), rng.standard_normal((3, prob.n_coupling))
        one = macro_step(prob, method, state, hist)
        calls.clear()
        more = macro_step(prob, method, state, hist, iterations=5, tol=1e-9)
        assert len(calls) == 2  # one corrector pass: both subsystems (Jacobi)
        np.testing.assert_allclose(more[0], one[0], rtol=1e-12, atol=1e-12)
        if method.name != "weighted":  # Baumgarte and projection satisfy their conditions
            y = correct_all(prob, state, hist, more[1][0])[1]
            assert np.max(np.abs(method.condition_residuals(prob.residuals(y, more[1][0])))) < 1e-12
        calls.clear()
        macro_step(prob, method, state, hist, iterations=3)  # no tol: every pass runs
        assert len(calls) == 3 * 2


def test_policy_accepts_physical_models_including_overdamped():
    H = np.array([1e-3, 1e-2, 1e-1])
    pm = PhysicalModel(1.0, 2.0, 1000.0, 1000.0, 200.0, 10.0, H)  # subsystem 1 overdamped
    res = spectral_radius(pm, projection(), "ff", 1)
    for i, h in enumerate(H):
        ref = spectral_radius_mp(PhysicalModel(1.0, 2.0, 1000.0, 1000.0, 200.0, 10.0, h), projection(), "ff", 1, 40)
        assert res.rho[i] == pytest.approx(float(ref), rel=1e-9)


def test_policy_survives_a_point_no_precision_can_decide(monkeypatch):
    import icosim.engine.spectral.policy as st
    from icosim.problems.linear.family import TwoMass

    original = TwoMass.coefficients

    def fails_at_origin(family, backend=None):
        m = family.model
        if backend is not None and not family.converted and float(m.lr1) == 0 and float(m.li1) == 0:
            raise ZeroDivisionError("no result here")
        return original(family, backend)

    # the batch of certified points fails as a whole, then each point is certified alone: only the origin fails
    monkeypatch.setattr(TwoMass, "coefficients", fails_at_origin)
    # identical undamped subsystems: rho = 1 exactly at (0, 0.3) (tests/engine/test_certified.py checks it to 80 digits)
    model = TestModel(np.array([0.0, 0.0, -0.5]), np.array([0.0, 0.3, 0.5]), 1.0, 1.0, 1.0)
    res = st.spectral_radius(TwoMass(model, "ff", 2), baumgarte(mu=1, index=1))
    assert res.n_failed == 1 and res.verdict[0] == "undecided" and not res.stable[0]
    assert res.reason[0] == "ZeroDivisionError: no result here" and res.digits[0] == -1
    assert res.verdict[1] == "marginal" and res.verdict[2] in ("stable", "unstable")


def test_one_problem_serves_methods_in_turn_as_fresh_problems_do():
    """A problem with constant sensitivities hands the same Jacobians every step, and their combinations are
    factored once: a second method on the same problem combines other levels and must not get the first's
    factors.  Each run equals a run on a problem of its own, whichever ran before."""
    from icosim.problems.linear.chain import Chain, ChainSegment

    H = 1e-3
    chain = Chain(tuple(ChainSegment((m,), (c,), (d,)) for m, c, d in ((1, 1e3, 2), (2, 500, 1), (0.5, 2e3, 0.5))),
                  ("ff", "ff"), H)  # fmt: skip
    methods = [("weighted", dict(index=1, a=1.0, b=1.0)), ("baumgarte", dict(index=1, mu=1e-2)), ("projection", {})]

    def run(problem, name, params):
        method = engine_method(make_method(name, **params), H)
        start, history = np.array([[0.1, 0.0]] * 3), np.zeros((2, problem.n_coupling))
        return np.array(simulate(problem, method, start, history, 50).states[-1])

    alone = [run(chain.problem(1), *m) for m in methods]
    shared = chain.problem(1)
    for order in (methods, methods[::-1]):
        for m in order:
            assert np.array_equal(run(shared, *m), alone[methods.index(m)]), m[0]
