"""The coupling schemes (Jacobi, Gauss-Seidel in both orders) checked against independent routes.

Every number asserted here comes from an independent computation: the growth
rate of plain time stepping, closed forms worked out by hand (docs/gauss_seidel.md),
the scipy matrix exponential, the exact monolithic solution, or the symmetry of
the model.
"""

import math

import numpy as np
import pytest
import scipy.linalg
from helpers import growth_rate, pair_jacobians, predict_all

from icosim import (
    LinearCosimulation,
    ParameterError,
    TestModel,
    baumgarte,
    make_method,
    projection,
    spectral_radius_float64,
    spectral_radius_mp,
    weighted_multiplier,
)
from icosim.engine.graph import CouplingGraph
from icosim.engine.macrostep import macro_step
from icosim.engine.schemes import GS12, GS21, JACOBI, SCHEMES, GaussSeidel, Jacobi, get_scheme, standard_schemes
from icosim.engine.stages import couples, plan
from icosim.order_fit import asymptotic_order
from icosim.problems.linear.model import Coefficients
from icosim.problems.linear.spectral import amplification_matrix
from icosim.studies.convergence.experiment import Setup, step_counts
from icosim.studies.convergence.study import Study

CASES = [
    (baumgarte(mu=1, index=1), "ff"),
    (baumgarte(mu=1, index=2), "fd"),
    (baumgarte(index=3), "ff"),
    (weighted_multiplier(1, 1), "ff"),
    (weighted_multiplier(0.5, 0.25), "fd"),
    (projection(), "ff"),
    (projection(), "fd"),
    (projection(), "dd"),
]


def _random_models(seed, n):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield TestModel(
            -2 * rng.random(), 2 * rng.random(), 10 ** rng.uniform(-1, 1), 3 * rng.random(), 3 * rng.random()
        )


def _expm_blocks(k_, d_, g_):
    """``Phi`` and the response ``r`` to a unit constant input of ``x' = v, v' = -k x - d v + g u``
    over one macro step, from scipy's matrix exponential of the 3x3 augmented system."""
    A = np.array([[0, 1, 0], [-k_, -d_, g_], [0, 0, 0]], dtype=float)
    E = scipy.linalg.expm(A)
    return E[:2, :2], E[:2, 2]


# -- the scheme objects ---------------------------------------------------------
def test_scheme_names_and_roles():
    assert (JACOBI.name, GS12.name, GS21.name) == ("jacobi", "gauss-seidel-12", "gauss-seidel-21")
    assert get_scheme(None) is JACOBI and get_scheme("jacobi") == Jacobi()
    assert get_scheme("gauss-seidel-12") == GS12 == GaussSeidel(first=1) == GaussSeidel((1, 2))
    assert get_scheme("gauss-seidel-21") == GS21 == GaussSeidel(first=2) == GaussSeidel((2, 1))
    assert get_scheme(GS21) is GS21  # a scheme is returned as it is
    assert (JACOBI.stages(2), GS12.stages(2), GS21.stages(2)) == (((0, 1),), ((0,), (1,)), ((1,), (0,)))
    pair = CouplingGraph.pair("ff")
    assert (plan(JACOBI, pair).integrations, plan(GS12, pair).integrations) == (4, 3)
    # any order of any number of subsystems is spelled by its numbers (dots from ten subsystems on)
    assert get_scheme("gauss-seidel-312") == GaussSeidel((3, 1, 2))
    assert GaussSeidel(tuple(range(10, 0, -1))).name == "gauss-seidel-10.9.8.7.6.5.4.3.2.1"
    assert get_scheme("gauss-seidel-10.9.8.7.6.5.4.3.2.1") == GaussSeidel(tuple(range(10, 0, -1)))
    # the name is the one spelling (files, attributes): the variants' names, and only the variants are variants
    as_integrated = (GaussSeidel(first=1, leading_outputs="as-integrated"),
                     GaussSeidel(first=2, leading_outputs="as-integrated"))  # fmt: skip
    assert [s.name for s in as_integrated] == ["gauss-seidel-12-as-integrated", "gauss-seidel-21-as-integrated"]
    assert [get_scheme(s.name) for s in as_integrated] == list(as_integrated)
    assert [s.variant for s in (JACOBI, GS12, GS21, *as_integrated)] == [False, False, False, True, True]
    assert list(SCHEMES) == ["jacobi", "gauss-seidel-12", "gauss-seidel-21", *(s.name for s in as_integrated)]
    assert standard_schemes() == ("jacobi", "gauss-seidel-12", "gauss-seidel-21")


ALLOWED = (
    "jacobi, gauss-seidel-12, gauss-seidel-21, gauss-seidel-12-as-integrated, gauss-seidel-21-as-integrated "
    r"or gauss-seidel-<order> \(e.g. gauss-seidel-312\)"
)


@pytest.mark.parametrize(
    "make,match",
    [
        (lambda: get_scheme("gauss"), f"scheme must be one of {ALLOWED}, got 'gauss'"),
        (lambda: GaussSeidel(first=3), "first must be 1 or 2"),
        (lambda: GaussSeidel(first=True), "first must be 1 or 2"),
        (lambda: GaussSeidel((1, 3)), "order must name each of the subsystems 1 ... N once"),
        (lambda: get_scheme("gauss-seidel-1223"), "scheme 'gauss-seidel-1223': order must name each of the subsystems"),
        (lambda: get_scheme("gauss-seidel-1.2"), f"scheme must be one of {ALLOWED}, got 'gauss-seidel-1.2'"),
        # the old spelling (a generic name with first=...) is gone: the generic name is refused ...
        (lambda: get_scheme("gauss-seidel"), f"scheme must be one of {ALLOWED}, got 'gauss-seidel'"),
        # ... and a name that is not a string is refused naming the argument
        (lambda: get_scheme(2), f"scheme must be one of {ALLOWED}, got 2"),
        (
            lambda: GaussSeidel(first=1, leading_outputs="as-computed"),
            "leading_outputs must be one of reevaluated, as-integrated",
        ),
    ],
    ids=[
        "unknown-name",
        "first-3",
        "first-bool",
        "order-repeats",
        "order-repeats-by-name",
        "order-spelled-twice",
        "generic-name",
        "not-a-name",
        "leading-outputs",
    ],
)
def test_bad_scheme_is_refused_naming_the_argument(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_get_scheme_takes_the_name_only():
    """``first`` is part of the name (gauss-seidel-21), not an argument of its own."""
    with pytest.raises(TypeError):
        get_scheme("gauss-seidel", first=2)
    with pytest.raises(TypeError):
        get_scheme("jacobi", 1)


def test_step_counts_three_integrations_for_gauss_seidel():
    prob = LinearCosimulation(TestModel(-0.3, 0.7).coefficients(), "fd", 1)
    state, hist = np.ones((2, 2)), np.ones((2, 2))
    for scheme, n in ((JACOBI, 4), (GS12, 3), (GS21, 3)):
        prob.work.reset()
        macro_step(prob, baumgarte(mu=1, index=1), state, hist, scheme=scheme)
        assert prob.work.subsystem_integrations == n == plan(scheme, prob.graph).integrations


# -- spectral radius against the growth rate of time stepping -------------------
@pytest.mark.parametrize("scheme", [GS12, GS21], ids=lambda s: s.name)
@pytest.mark.parametrize("method,dec", CASES, ids=lambda x: getattr(x, "name", x))
@pytest.mark.parametrize("k", [0, 1, 2])
def test_spectral_radius_equals_growth_rate_of_time_stepping(scheme, method, dec, k):
    """The amplification matrix is built from the macro step by linearity; time stepping grows by rho."""
    model = TestModel(-0.05, 0.9, 2.0, 2.0, 2.0)
    rho, _ = spectral_radius_float64(model, method, dec, k, scheme=scheme)
    prob = LinearCosimulation(model.coefficients(), dec, k)
    assert growth_rate(prob, method, scheme=scheme) == pytest.approx(float(rho), rel=3e-3)


# -- hand derivations (docs/gauss_seidel.md) -----------------------------------------
def _ff_index3_k0_gs(model, first):
    """Force/force, index 3, k = 0, Gauss-Seidel, by hand; the 5x5 matrix on (x1, v1, x2, v2, lambda_N).

    The first subsystem A advances with the constant force lambda_N:
    s_A+ = Phi_A s_A + r_A lambda_N (final; r_A the response to a unit force,
    gain included).  The second, B, with the constant lambda*:
    s_B+ = Phi_B s_B + r_B lambda*.  The position condition x_B+ = x_A+ gives
    lambda* = (x_A+ - (Phi_B s_B)_x) / (r_B)_x.
    """
    c = model.coefficients()
    sub = [_expm_blocks(c.k1, c.delta1, 1.0), _expm_blocks(c.k2, c.delta2, -1.0 / c.am21)]
    A, B = (0, 1) if first == 1 else (1, 0)
    M = np.zeros((5, 5))
    sl = [slice(0, 2), slice(2, 4)]
    (PA, rA), (PB, rB) = sub[A], sub[B]
    M[sl[A], sl[A]] = PA
    M[sl[A], 4] = rA
    # lambda* as a row over the state: (x_A+ - (Phi_B s_B)_x) / (r_B)_x
    lam = np.zeros(5)
    lam[sl[A]] = PA[0]
    lam[4] = rA[0]
    lam[sl[B]] -= PB[0]
    lam /= rB[0]
    M[sl[B], sl[B]] = PB
    M[sl[B]] += np.outer(rB, lam)
    M[4] = lam
    return M


@pytest.mark.parametrize("first", [1, 2])
def test_ff_index3_k0_gauss_seidel_matches_hand_derivation(first):
    for model in _random_models(21 + first, 25):
        M = amplification_matrix(model, baumgarte(index=3), "ff", 0, scheme=GaussSeidel(first=first))
        np.testing.assert_allclose(M, _ff_index3_k0_gs(model, first), rtol=1e-10, atol=1e-12)


def _fd_baumgarte_k0_gs(model, beta, gamma, first):
    """Force/displacement, Baumgarte (beta, gamma), k = 0, Gauss-Seidel, by hand; 6x6 on
    (x1, v1, x2, v2, lambda_N, a_N).

    S1 is force-driven (gain 1), S2 a double integrator driven by a_tilde, its
    multiplier mu2 = (a + k2 x2 + d2 v2)/g2 with g2 = -1/am21.  The finished
    subsystem's end state is fixed; its acceleration and force follow the new
    values algebraically (a1 = -k1 x1 - d1 v1 + lambda*, f1 = lambda*;
    a2 = a*, mu2 as above).  Conditions at T_N+1 (subsystem 2 minus 1):
    (x2 - x1) + beta (v2 - v1) + gamma (a2 - a1) = 0 and mu2 - lambda* = 0,
    linear in (lambda*, a*).
    """
    c = model.coefficients()
    P1, r1 = _expm_blocks(c.k1, c.delta1, 1.0)
    k1, d1, k2, d2, g2 = c.k1, c.delta1, c.k2, c.delta2, -1.0 / c.am21
    M = np.zeros((6, 6))
    for col in range(6):
        w = np.eye(6)[col]
        s1, s2, lamN, aN = w[0:2], w[2:4], w[4], w[5]
        if first == 1:  # S1 with lambda_N (final), S2 with a*
            x1, v1 = P1 @ s1 + r1 * lamN
            # unknowns u = (lambda*, a*): rows J u = b
            x2c, v2c = s2[0] + s2[1], s2[1]  # S2's end state without a*: x2 + v2 + a*/2, v2 + a*
            J = np.array(
                [[-gamma, 0.5 + beta + gamma], [-1.0, (1 + k2 / 2 + d2) / g2]],
            )
            b = -np.array(
                [x2c - x1 + beta * (v2c - v1) + gamma * (k1 * x1 + d1 * v1), (k2 * x2c + d2 * v2c) / g2],
            )
            lam, a = np.linalg.solve(J, b)
            x2, v2 = x2c + a / 2, v2c + a
        else:  # S2 with a_N (final), S1 with lambda*
            x2, v2 = s2[0] + s2[1] + aN / 2, s2[1] + aN
            x1c, v1c = P1 @ s1  # S1's end state without lambda*: + r1 lambda*
            # a1 = -k1 x1 - d1 v1 + lambda* with x1 = x1c + r1x lambda*, v1 = v1c + r1v lambda*
            da1 = -k1 * r1[0] - d1 * r1[1] + 1.0
            J = np.array(
                [
                    [-r1[0] - beta * r1[1] - gamma * da1, gamma],
                    [-1.0, 1.0 / g2],
                ]
            )
            b = -np.array(
                [x2 - x1c + beta * (v2 - v1c) - gamma * (-k1 * x1c - d1 * v1c), (k2 * x2 + d2 * v2) / g2],
            )
            lam, a = np.linalg.solve(J, b)
            x1, v1 = np.array([x1c, v1c]) + r1 * lam
        M[:, col] = [x1, v1, x2, v2, lam, a]
    return M


@pytest.mark.parametrize("first", [1, 2])
@pytest.mark.parametrize("beta,gamma", [(2.0, 1.0), (0.5, 0.0), (0.0, 0.0)])
def test_fd_baumgarte_k0_gauss_seidel_matches_hand_derivation(first, beta, gamma):
    for model in _random_models(31 + first, 20):
        M = amplification_matrix(model, baumgarte(beta=beta, gamma=gamma), "fd", 0, scheme=GaussSeidel(first=first))
        np.testing.assert_allclose(M, _fd_baumgarte_k0_gs(model, beta, gamma, first), rtol=1e-9, atol=1e-11)


@pytest.mark.parametrize("am21", [0.25, 0.5, 1.0, 2.0, 4.0])
def test_free_masses_index3_k0_added_mass_rule(am21):
    """Free masses (the origin of the parameter plane), ff, index 3, k = 0, by hand
    (docs/gauss_seidel.md): in gap d, relative velocity w and lambda the recurrence is
    lower triangular with eigenvalues 0, -1 and -m_B/m_A (B the corrected subsystem),
    besides the rigid motion's double eigenvalue 1: rho = max(1, m_B/m_A)."""
    origin = TestModel(0.0, 0.0, am21, 1.0, 1.0)
    for scheme, ratio in ((GS12, am21), (GS21, 1 / am21)):
        rho = float(spectral_radius_mp(origin, baumgarte(index=3), "ff", 0, digits=40, scheme=scheme))
        assert rho == pytest.approx(max(1.0, ratio), rel=1e-15)


# -- symmetry -------------------------------------------------------------------------------
def _swapped(c: Coefficients) -> Coefficients:
    """The same physical model with subsystems 1 and 2 exchanged (the mass ratio inverts)."""
    return Coefficients(c.k2, c.delta2, c.k1, c.delta1, 1 / c.am21)


@pytest.mark.parametrize(
    "method,dec",
    [(baumgarte(mu=1, index=1), "ff"), (weighted_multiplier(1, 1), "ff"), (projection(), "ff"), (projection(), "dd")],
    ids=lambda x: getattr(x, "name", x),
)
@pytest.mark.parametrize("k", [0, 1, 2])
def test_swapping_subsystems_and_order_mirrors_the_result(method, dec, k):
    """ff and dd are symmetric in the subsystems: exchanging them and the order changes only the variables."""
    models = list(_random_models(41 + k, 10))
    # the 10 points as one batch (the float64 radius is vectorised over points), each checked on its own
    fields = ("lr1", "li1", "am21", "alr21", "ali21")
    c = TestModel(*(np.array([getattr(m, f) for m in models]) for f in fields)).coefficients()
    for scheme, mirror in ((GS12, GS21), (GS21, GS12), (JACOBI, JACOBI)):
        rho, err = spectral_radius_float64(c, method, dec, k, scheme=scheme)
        rho_m, err_m = spectral_radius_float64(_swapped(c), method, dec, k, scheme=mirror)
        assert rho.shape == (len(models),)
        assert np.all(np.abs(rho_m - rho) <= err + err_m)  # equal within float64's error estimates
    rho_same, _ = spectral_radius_float64(_swapped(c), method, dec, k, scheme=GS12)
    rho_12, _ = spectral_radius_float64(c, method, dec, k, scheme=GS12)
    assert np.any(np.abs(rho_same - rho_12) > 1e-6)  # swapping the subsystems without the order does change the result


@pytest.mark.parametrize(
    "method,dec", [(baumgarte(mu=1, index=1), "ff"), (projection(), "dd")], ids=lambda x: getattr(x, "name", x)
)
def test_identical_subsystems_give_the_same_result_in_both_orders(method, dec):
    lr, li = np.meshgrid(np.linspace(-2, 0, 7), np.linspace(0, 2, 7), indexing="ij")
    model = TestModel(lr, li, 1.0, 1.0, 1.0)
    for k in (0, 1, 2):
        r12, err12 = spectral_radius_float64(model, method, dec, k, scheme=GS12)
        r21, err21 = spectral_radius_float64(model, method, dec, k, scheme=GS21)
        # equal within float64's own error estimates (defective eigenvalues on li1 = 0 reach ~1e-8)
        assert np.all(np.abs(r12 - r21) <= err12 + err21)
        assert np.median(np.abs(r12 - r21)) < 1e-13


# -- why "correct both sequentially" is not a scheme of its own --------------------------
def _correct_both_sequentially(prob, method, state, hist, first):
    """Jacobi's predictor and corrected values, the first subsystem A corrected with them, then the
    coupling conditions solved again with A's finished outputs (algebraic gradients) and B's full
    gradients, linearised about the prediction.  Returns (e of Jacobi, e re-solved)."""
    A = first - 1
    e_p = prob.extrapolate(hist)
    y_p = predict_all(prob, state, hist)
    e = method.corrected_coupling(e_p, prob.residuals(y_p, e_p), pair_jacobians(prob, state, hist, e_p, y_p),
                                  prob.backend)  # fmt: skip
    end_A, y_A = prob.correct(A, state, hist, e)
    ys = [prob.predict(i, state, hist)[1] for i in range(2)]
    ys[A] = prob.reevaluate(A, end_A, y_A, e, e_p)  # A's finished outputs, at the linearisation point e_p
    fixed = [None, None]
    fixed[A] = end_A
    y = prob.stack(ys)
    e2 = method.corrected_coupling(
        e_p, prob.residuals(y, e_p), pair_jacobians(prob, state, hist, e_p, y, tuple(fixed)), prob.backend
    )
    return e, e2


@pytest.mark.parametrize("dec", ["ff", "fd"])
@pytest.mark.parametrize("first", [1, 2])
def test_correcting_both_sequentially_reproduces_jacobi_except_for_the_weighted_multiplier(dec, first):
    """Baumgarte and projection: Jacobi's corrected values meet the conditions exactly with both corrected
    outputs (the model is linear), so re-solving them with A's finished outputs returns the same values.
    The weighted multiplier's values meet none of its conditions, and re-solving moves them."""
    rng = np.random.default_rng(5)
    c = TestModel(-0.3, 0.9, 2.0, 1.5, 0.5).coefficients()
    for k in (0, 1, 2):
        prob = LinearCosimulation(c, dec, k)
        state, hist = rng.standard_normal((2, 2)), rng.standard_normal((k + 1, prob.n_coupling))
        for method in (baumgarte(mu=1, index=1), baumgarte(mu=0.5, index=2), projection()):
            e, e2 = _correct_both_sequentially(prob, method, state, hist, first)
            np.testing.assert_allclose(e2, e, rtol=1e-10, atol=1e-12)
        e, e2 = _correct_both_sequentially(prob, weighted_multiplier(1, 1), state, hist, first)
        assert np.max(np.abs(e2 - e)) > 1e-3 * np.max(np.abs(e))


# -- Jacobi is the paper's loop, unchanged --------------------------------------------------
@pytest.mark.parametrize("method,dec", CASES, ids=lambda x: getattr(x, "name", x))
def test_jacobi_macro_step_is_the_papers_loop_to_the_last_bit(method, dec):
    """The scheme machinery adds nothing to Jacobi's arithmetic: the paper's loop written out
    (predict both, solve, correct both, project) gives bitwise the same step."""
    lr, li = np.meshgrid(np.linspace(-2, 0, 5), np.linspace(0, 2, 5), indexing="ij")
    c = TestModel(lr, li, 2.0, 1.5, 0.7).coefficients().map(lambda a: np.asarray(a)[..., None, None])
    rng = np.random.default_rng(3)
    for k in (0, 2):
        prob = LinearCosimulation(c, dec, k)
        state, hist = rng.standard_normal((2, 2)), rng.standard_normal((k + 1, prob.n_coupling))
        e_p = prob.extrapolate(hist)
        y = predict_all(prob, state, hist)
        e = method.corrected_coupling(e_p, prob.residuals(y, e_p), pair_jacobians(prob, state, hist, e_p, y),
                                      prob.backend)  # fmt: skip
        ends = [prob.correct(i, state, hist, e)[0] for i in range(2)]
        expected = prob.join(ends)
        if method.projection:
            expected = prob.project(expected)
        got, h1, _ = macro_step(prob, method, state, hist, scheme="jacobi")
        np.testing.assert_array_equal(got, expected)
        np.testing.assert_array_equal(h1[..., 0, :], e)


# -- convergence to the monolithic solution -------------------------------------------------
@pytest.mark.parametrize("scheme", [GS12, GS21], ids=lambda s: s.name)
@pytest.mark.parametrize(
    "method,params,dec",
    [
        ("projection", {}, "ff"),
        ("projection", {}, "fd"),
        ("projection", {}, "dd"),
        ("baumgarte", {"index": 1, "mu": 5e-3}, "ff"),
    ],
)
def test_gauss_seidel_converges_with_order_k_plus_1(scheme, method, params, dec):
    """docs/gauss_seidel.md: the leading subsystem's coupling force over the step (extrapolation) and
    the corrected one's (interpolation) differ by O(H^(k+1)); the impulse defect O(H^(k+2)) per step
    sums to a global error O(H^(k+1)) -- one order below Jacobi projection's k + 2."""
    study = Study(Setup(), step_counts(1.0, 1e-4, 1e-2, 7))
    for k in (0, 1, 2):
        r = study.run(method, params, dec, k, scheme=scheme)
        fit = asymptotic_order(r.H, r.nrmse, r.unstable)  # floor-free errors: the smallest-H decade decides
        assert fit.decided and fit.order == pytest.approx(k + 1, abs=0.1), (k, fit)


def test_gauss_seidel_loses_jacobi_projections_extra_order():
    """Jacobi projection (ff) converges with k + 2 (the paper); Gauss-Seidel with k + 1 (derivation)."""
    study = Study(Setup(), step_counts(1.0, 1e-4, 1e-2, 7))
    for k in (0, 1):
        orders = {}
        for scheme in (JACOBI, GS12):
            r = study.run("projection", {}, "ff", k, scheme=scheme)
            orders[scheme.name] = asymptotic_order(r.H, r.nrmse, r.unstable).order
        assert orders["jacobi"] == pytest.approx(k + 2, abs=0.15)
        assert orders["gauss-seidel-12"] == pytest.approx(k + 1, abs=0.1)


def test_gauss_seidel_on_the_simulate_path_equals_the_matrix_path():
    study = Study(Setup(), step_counts(1.0, 1e-3, 1e-2, 3))
    for scheme in (GS12, GS21):
        a = study.run("baumgarte", {"index": 1, "mu": 5e-3}, "fd", 1, scheme=scheme, stepping="matrix")
        b = study.run("baumgarte", {"index": 1, "mu": 5e-3}, "fd", 1, scheme=scheme, stepping="simulate")
        np.testing.assert_allclose(a.nrmse, b.nrmse, rtol=1e-7)


def test_make_method_and_scheme_by_name():
    m = make_method("projection")
    M1 = amplification_matrix(TestModel(-0.5, 0.5), m, "ff", 1, scheme="gauss-seidel-21")
    M2 = amplification_matrix(TestModel(-0.5, 0.5), m, "ff", 1, scheme=GaussSeidel(first=2))
    np.testing.assert_array_equal(M1, M2)


def test_an_eigenvalue_one_is_shared_by_every_scheme():
    """docs/gauss_seidel.md: for a mode with eigenvalue 1 the coupling history is constant, so extrapolation and
    interpolation give the same input and every scheme maps the mode alike.  At a point where Jacobi's projection
    (ff, k = 1) has an eigenvalue 1 (found by bisection along lr1), both Gauss-Seidel orders have it too."""
    method, li1 = projection(), 1.0

    def gap(lr1, scheme):  # the largest real eigenvalue minus 1
        ev = np.linalg.eigvals(amplification_matrix(TestModel(lr1, li1, 1.0, 1.0, 1.0), method, "ff", 1, scheme=scheme))
        return float(np.max(ev.real[np.abs(ev.imag) < 1e-12])) - 1

    lo, hi = -2.0, -0.05
    assert gap(lo, JACOBI) * gap(hi, JACOBI) < 0  # a real eigenvalue crosses 1 in between
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gap(lo, JACOBI) * gap(mid, JACOBI) > 0 else (lo, mid)
    for scheme in (GS12, GS21):
        ev = np.linalg.eigvals(amplification_matrix(TestModel(lo, li1, 1.0, 1.0, 1.0), method, "ff", 1, scheme=scheme))
        assert np.min(np.abs(ev - 1)) < 1e-8
    # away from that point the schemes' eigenvalues differ (the check is not vacuous)
    ev_j = np.sort_complex(np.linalg.eigvals(amplification_matrix(TestModel(-1.0, li1, 1, 1, 1), method, "ff", 1)))
    ev_g = np.sort_complex(
        np.linalg.eigvals(amplification_matrix(TestModel(-1.0, li1, 1, 1, 1), method, "ff", 1, scheme=GS12))
    )
    assert np.max(np.abs(ev_j - ev_g)) > 1e-3


@pytest.mark.parametrize("k, node_integral", [(0, 1), (1, 0.5), (2, 5 / 6)])
def test_impulse_defect_of_the_two_polynomials(k, node_integral):
    """docs/gauss_seidel.md, Sect. 4 (ff): over one step the leading subsystem's extrapolated force and the
    corrected one's interpolated force differ by an impulse -H^(k+2) lambda^(k+1)/k! int_0^1 prod (tau + j) dtau
    + O(H^(k+3)).  Checked for lambda = exp (every derivative 1 at t = 0) at 40 digits: the ratio of the
    impulse to the leading term tends to 1 like H."""
    import mpmath

    from icosim.engine.lagrange import corrector_nodes, monomial_coefficients, predictor_nodes

    def integral(nodes, samples):  # int_0^1 of the Lagrange polynomial through (nodes, samples)
        C = monomial_coefficients(nodes)
        return sum(C[m][j] * samples[j] / (m + 1) for m in range(len(nodes)) for j in range(len(nodes)))

    with mpmath.workdps(40):
        ratios = []
        for H in (mpmath.mpf("1e-2"), mpmath.mpf("1e-3")):
            pred = integral(predictor_nodes(k), [mpmath.exp(n * H) for n in predictor_nodes(k)])
            corr = integral(corrector_nodes(k), [mpmath.exp(n * H) for n in corrector_nodes(k)])
            impulse = H * (pred - corr)
            leading = -(H ** (k + 2)) / math.factorial(k) * node_integral
            ratios.append(float(impulse / leading))
    assert abs(ratios[1] - 1) < 2e-3 and abs(ratios[1] - 1) < abs(ratios[0] - 1) / 5


@pytest.mark.parametrize("name", list(SCHEMES))
@pytest.mark.parametrize("dec", ["ff", "fd", "df", "dd"])
def test_a_scheme_refuses_exactly_the_decompositions_whose_corrector_system_is_singular(name, dec):
    """``couples`` is decided from the registries alone; here the corrector's linear system itself
    (projection: the acceleration constraint and the force balance, Jacobians from the problem) is
    singular at random points exactly where the scheme refuses the decomposition."""
    from icosim.engine.methods.base import _conditions

    scheme = get_scheme(name)
    rng = np.random.default_rng(7)
    c = TestModel(*rng.uniform([-1, 0.2, 0.5, 0.5, 0.5], [-0.1, 2, 3, 2, 2], size=(4, 5)).T).coefficients()
    problem = LinearCosimulation(c, dec, 1)
    state, history = np.zeros((4, 2, 2)), np.zeros((4, 2, problem.n_coupling))
    ends = [problem.predict(i, state, history)[0] for i in range(2)]
    e = problem.extrapolate(history)
    y = problem.stack([problem.predict(i, state, history)[1] for i in range(2)])
    fixed = [ends[i] if (i,) == scheme.stages(2)[0] and name != "jacobi" else None for i in range(2)]
    J = pair_jacobians(problem, state, history, e, y, fixed, algebraic=scheme.reevaluates_leading)
    method = make_method("projection")
    levels = [lv for w, lv in method.solves if w != 0][0]
    A = _conditions(levels, J, axis=-2, const=float)
    singular = np.linalg.matrix_rank(A) < problem.n_coupling
    assert np.all(singular == (not couples(scheme, dec)))
    if not couples(scheme, dec):
        with pytest.raises(ParameterError, match=rf"scheme {name} cannot couple decomposition {dec}.*Allowed"):
            amplification_matrix(c, method, dec, 1, scheme=scheme)
