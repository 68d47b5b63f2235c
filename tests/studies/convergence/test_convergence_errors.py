"""Floor-free errors (icosim.studies.convergence.errors) against an independent 40-digit computation.

The reference here is plain time stepping of the co-simulation in mpmath at 40
significant digits (the engine's macro step with the Multiprecision backend,
consistent start and exact solution in mpmath too), and Eq. (72) formed from
the differences in mpmath: at 40 digits a difference of two O(1) numbers
keeps ~20 digits of an error of 1e-20.  It shares neither the error recurrence
nor the ball-arithmetic defect with the code under test.
"""

import mpmath
import numpy as np
import pytest

from icosim.engine.backends import Ball, Multiprecision
from icosim.engine.decompositions import get_decomposition
from icosim.engine.macrostep import macro_step
from icosim.problems.linear.problem import LinearCosimulation
from icosim.problems.linear.spectral import amplification_matrix
from icosim.studies.convergence.errors import DEFECT_REL_ACCURACY, exact_extension, local_defect, propagate_errors
from icosim.studies.convergence.experiment import Setup, dimensional_method
from icosim.studies.convergence.study import Study

#: Every method at every index of Figs. 21-23 (dimensional parameters), with the decompositions used.
SCHEMES = [
    ("baumgarte", {"index": 1, "mu": 1e-3}, "ff"),
    ("baumgarte", {"index": 2, "mu": 1e-3}, "ff"),
    ("baumgarte", {"index": 3}, "ff"),
    ("weighted", {"index": 1, "a": 1.0, "b": 1.0}, "ff"),
    ("weighted", {"index": 2, "a": 1.0}, "ff"),
    ("projection", {}, "ff"),
    ("baumgarte", {"index": 1, "mu": 5e-3}, "fd"),
    ("projection", {}, "dd"),
]


def _mp_nrmse(setup: Setup, H: float, N: int, method: str, params: dict, dec: str, k: int, digits: int = 40):
    """Eq. (72) of an N-step run, stepped and evaluated in mpmath at ``digits`` digits."""
    be = Multiprecision(digits)
    ctx = be.ctx
    m = dimensional_method(method, H, **params)
    c = setup.model(H).coefficients().map(be.const)
    problem = LinearCosimulation(c, dec, k, be)
    total = 1 + c.am21
    A = ctx.matrix([[0, 1], [-(c.k1 + c.am21 * c.k2) / total, -(c.delta1 + c.am21 * c.delta2) / total]])
    z0 = ctx.matrix([be.const(setup.x0), be.const(setup.v0) * be.const(H)])

    E = ctx.expm(A)  # one step of the exact solution; z(t) for integer t by steps from z0 (40 digits each)
    states = {0: z0}

    def state_at(t):
        if t not in states:
            states[t] = E * state_at(t - 1) if t > 0 else ctx.inverse(E) * state_at(t + 1)
        return states[t]

    def exact(t):
        z = state_at(t)
        x, v = z[0], z[1]
        a = A[1, 0] * x + A[1, 1] * v
        return {"x": x, "v": v, "a": a, "lambda_c": a + c.k1 * x + c.delta1 * v}

    names = {"lambda_c": "lambda_c", "a_tilde_1": "a", "a_tilde": "a"}
    variables = get_decomposition(dec).variables
    history = np.empty((k + 1, len(variables)), dtype=object)
    for j in range(k + 1):
        ex = exact(-j)
        for i, name in enumerate(variables):
            history[j, i] = ex[names[name]]
    state = np.empty((2, 2), dtype=object)
    state[:, 0], state[:, 1] = z0[0], z0[1]
    num, ref = [], []
    for n in range(1, N + 1):
        state, history, _ = macro_step(problem, m, state, history)
        ex = exact(n)
        num.append([state[0, 0], state[1, 0], state[0, 1] / H, state[1, 1] / H])
        ref.append([ex["x"], ex["x"], ex["v"] / H, ex["v"] / H])
    num, ref = np.array(num, dtype=object), np.array(ref, dtype=object)
    total = ctx.mpf(0)
    for j in range(4):
        r = ref[:, j]
        mean = sum(r) / N
        total += sum((r - num[:, j]) ** 2) / sum((r - mean) ** 2)
    return ctx.sqrt(total)


@pytest.mark.parametrize("method,params,dec", SCHEMES, ids=[f"{m}-{p.get('index', '')}-{d}" for m, p, d in SCHEMES])
@pytest.mark.parametrize("k", [0, 1, 2])
def test_floor_free_nrmse_agrees_with_40_digit_time_stepping(method, params, dec, k):
    """>= 6 significant digits at three step sizes, for every method and k (here: 1e-10 relative or better).

    The growth bound is lifted: index 2 and 3 with k >= 1 are unstable, and their (growing) errors must
    agree as well."""
    setup = Setup(end_time=0.01, growth_bound=1e30)
    n_steps = [10, 20, 40]
    study = Study(setup, n_steps, spectral_policy="float64")
    r = study.run(method, params, dec, k)
    for i, N in enumerate(n_steps):
        reference = _mp_nrmse(setup, setup.end_time / N, N, method, params, dec, k)
        got = r.nrmse_unfiltered[i]
        assert np.isfinite(got) and r.diverged_at[i] == -1
        assert abs(got - float(reference)) <= 1e-10 * float(reference), (N, got, mpmath.nstr(reference, 20))


@pytest.mark.parametrize(
    "method,params,dec,k",
    [("projection", {}, "ff", 2), ("weighted", {"index": 1, "a": 1.0, "b": 1.0}, "ff", 1)],
)
def test_no_round_off_floor_where_float64_state_stepping_has_one(method, params, dec, k):
    """At H = 5e-5 s the error of these schemes is ~1e-12 ... 1e-15 relative to the state: float64 state
    stepping (stepping "matrix") is off by 10 % or more there, the error recurrence agrees with 40 digits."""
    setup = Setup(end_time=0.02)
    N = 400
    study = Study(setup, [100, N], spectral_policy="float64")
    floor_free = study.run(method, params, dec, k).nrmse_unfiltered[1]
    float64_state = study.run(method, params, dec, k, stepping="matrix").nrmse_unfiltered[1]
    reference = float(_mp_nrmse(setup, setup.end_time / N, N, method, params, dec, k))
    assert floor_free == pytest.approx(reference, rel=1e-9)
    assert abs(float64_state - reference) > 0.1 * reference  # the floor this stepping removes


@pytest.mark.parametrize("method,params,dec", SCHEMES[::2], ids=[f"{m}-{d}" for m, _, d in SCHEMES[::2]])
def test_defect_is_proven_to_its_stated_accuracy(method, params, dec):
    """The rounded defect matches an independent 512-bit ball computation to the stated relative accuracy,
    at the smallest step size of the default study (where D is smallest, ~1e-26)."""
    setup, H, k = Setup(), 1e-6, 2
    c = setup.model(H).coefficients()
    m = dimensional_method(method, H, **params)
    d = local_defect(c, m, dec, k)
    assert d.rel_radius <= DEFECT_REL_ACCURACY
    be = Ball(512)
    with be.context():
        cb = c.map(be.const)
        M = amplification_matrix(cb, m, dec, k, backend=be)
        ext = exact_extension(cb, dec, k, be)
        D512 = be.mid(M @ ext.W - ext.W @ ext.E)
    size = np.max(np.abs(D512), axis=1, keepdims=True)
    relevant = size[:, 0] > DEFECT_REL_ACCURACY * size.max()  # rows below this are negligible by definition
    err = np.abs(d.D - D512)[relevant] / size[relevant]
    assert np.max(err) <= 2 * DEFECT_REL_ACCURACY
    assert 0 < np.max(np.abs(d.D)) < 1e-18  # what makes the float64 difference M w - w' useless here


def test_exact_extension_is_the_exact_solution_in_packed_variables():
    """w*_N = W z_N, stepped by E: the state rows are the exact state and the history rows the exact
    coupling variables at T_N, T_N-1, ... (from the closed-form monolithic solution, independently)."""
    from icosim.problems.linear.exact import MonolithicSolution

    setup, H, k = Setup(), 2e-3, 2
    c = setup.model(H).coefficients()
    sol = MonolithicSolution(c, setup.x0, setup.v0 * H)
    be = Ball(128)
    with be.context():
        ext = exact_extension(c.map(be.const), "fd", k, be)
    W, E = be.mid(ext.W), be.mid(ext.E)
    N = 7
    zN = sol.state(float(N))[:2]
    np.testing.assert_allclose(E @ zN, sol.state(float(N + 1))[:2], rtol=1e-12)
    w = W @ zN
    expect = [zN[0], zN[1], zN[0], zN[1]]
    for j in range(k + 1):  # fd: (lambda_c, a_tilde_1) at T_N-j
        st = sol.state(float(N - j))
        expect += [st[3], st[2]]
    np.testing.assert_allclose(w, expect, rtol=1e-10, atol=1e-16)


def _plain_first_step_beyond(errors, exact, bound):
    """The per-step check the block screen replaces: every step, no screening."""
    with np.errstate(invalid="ignore"):
        mag = np.max(np.abs(exact + errors.array()[1:, :4]), axis=-1)
    bad = ~np.isfinite(mag) | (mag > bound)
    return int(np.argmax(bad)) + 1 if bad.any() else None


@pytest.mark.parametrize(
    "n_steps, block", [(1, None), (7, 3), (9, 1), (100, None), (1000, 16), (1000, 2048), (4099, 64)]
)
@pytest.mark.parametrize("case", ["growing", "nan", "inf", "exact_nan", "exact_inf", "bounded", "tail"])
def test_block_screen_finds_the_same_first_step_as_every_step(n_steps, block, case):
    """``first_step_beyond``/``max_abs`` against the plain per-step computation, on runs of an unstable
    (rho 1.01), a stable and a poisoned error recurrence (NaN or inf in the errors or the exact values);
    the last block's steps past N (planted huge and NaN in "tail") never count."""
    rng = np.random.default_rng(n_steps)
    n = 6
    rho = 1.01 if case in ("growing", "tail") else 0.9
    Q = np.linalg.qr(rng.normal(size=(n, n)))[0]
    M = Q @ np.diag(rho * np.linspace(0.5, 1, n)) @ Q.T
    D, E = rng.normal(size=(n, 2)) * 1e-3, np.array([[np.cos(0.1), np.sin(0.1)], [-np.sin(0.1), np.cos(0.1)]])
    z_at = lambda steps: np.stack([np.cos(0.1 * steps), -np.sin(0.1 * steps)], axis=-1)  # noqa: E731
    errors = propagate_errors(M, D, E, z_at, n_steps, block=block)
    exact = z_at(np.arange(1, n_steps + 1))[:, [0, 1, 0, 1]]
    step = n_steps // 2 + 1
    b, j = divmod(step, errors.B)
    if case in ("nan", "inf"):
        errors.blocks[j, 2, b] = np.nan if case == "nan" else -np.inf
    if case in ("exact_nan", "exact_inf"):
        exact[step - 1, 1] = np.nan if case == "exact_nan" else np.inf
    last = n_steps - (errors.blocks.shape[2] - 1) * errors.B  # the last block's last step
    if case == "tail":
        errors.blocks[last + 1 :, :, -1] = np.where(np.arange(n) % 2, np.nan, 1e300)
    plain = errors.array()[:, :4]
    np.testing.assert_equal(errors.max_abs(slice(0, 4)), np.max(np.abs(plain)))
    # bounds below, at and above the run's largest sums: each crossing found at the same step
    with np.errstate(invalid="ignore"):
        sums = np.max(np.abs(exact + plain[1:]), axis=-1)
    finite = sums[np.isfinite(sums)] if np.isfinite(sums).any() else np.ones(1)
    for bound in [*np.quantile(finite, [0.0, 0.5, 0.99, 1.0]), 2 * finite.max(), np.inf]:
        assert errors.first_step_beyond(exact, bound, slice(0, 4)) == _plain_first_step_beyond(errors, exact, bound)
