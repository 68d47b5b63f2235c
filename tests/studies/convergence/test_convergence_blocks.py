"""The error recurrence in blocks (icosim.studies.convergence.blocks) against every step formed one by one.

The block starts must be those of the plain block recurrence bit for bit (their rounding is compounded
over the run, ~1e-9 of the NRMSE at 10^6 steps); the sums of squares and the growth check formed from
the block starts and a few matrices per run must be those of the steps themselves.
"""

import numpy as np
import pytest

from icosim.studies.convergence.blocks import QR_MAX_CANCELLATION, BlockErrors, error_recurrence, error_recurrences
from icosim.studies.convergence.experiment import Setup, dimensional_method
from icosim.studies.convergence.study import Study


def _recurrence(seed: int, rho: float, n: int = 7, cond: float = 0.3):
    rng = np.random.default_rng(seed)
    Q = np.linalg.qr(rng.normal(size=(n, n)))[0]
    M = Q @ (np.diag(rho * np.linspace(0.3, 1, n)) + np.triu(rng.normal(size=(n, n)) * cond, 1)) @ Q.T
    D = rng.normal(size=(n, 2)) * 1e-12
    w = 0.05
    E = np.array([[np.cos(w), np.sin(w)], [-np.sin(w), np.cos(w)]])
    return M, D, E, lambda steps: np.stack([np.cos(w * steps), -np.sin(w * steps)], axis=-1)


def _plain_block_starts(M, D, E, z_at, n_steps, B):
    """eps at the block starts of ``eps_s+B = M^B eps_s + G_B z_s``, ``M^j``, ``G_j`` one product per step."""
    n = M.shape[0]
    P, G, Ej = np.eye(n), np.zeros((n, 2)), np.eye(2)
    for _ in range(1, B):
        P, G, Ej = M @ P, M @ G + D @ Ej, E @ Ej
    MB, GB = M @ P, M @ G + D @ Ej
    starts = np.arange(0, n_steps + 1, B)
    Z, e, out = z_at(starts), np.zeros(n), []
    for i in range(starts.size):
        out.append(e)
        e = MB @ e + GB @ Z[i]
    return np.array(out)


@pytest.mark.parametrize("n_steps, block", [(5, None), (100, None), (1000, 31), (4099, None), (4099, 64)])
@pytest.mark.parametrize("rho", [0.9, 1.0, 1.01])
def test_block_starts_are_those_of_the_plain_recurrence_bit_for_bit(n_steps, block, rho):
    M, D, E, z_at = _recurrence(n_steps, rho)
    errors = error_recurrence(M, D, E, z_at, n_steps, block=block)
    with np.errstate(over="ignore", invalid="ignore"):
        plain = _plain_block_starts(M, D, E, z_at, n_steps, errors.B)
    np.testing.assert_array_equal(errors.S[:, : M.shape[0]], plain)


def test_runs_stepped_together_are_the_runs_one_by_one():
    """Several step counts (and state sizes of one run) at once: every number as run alone, bit for bit."""
    runs = [
        (*_recurrence(s, rho)[:3], _recurrence(s, rho)[3], N)
        for s, (rho, N) in enumerate([(0.9, 10), (1.0, 5000), (1.01, 700), (0.95, 100000), (0.99, 16)])
    ]
    together = error_recurrences(runs)
    for run, got in zip(runs, together, strict=True):
        alone = error_recurrence(*run)
        np.testing.assert_array_equal(got.S, alone.S)
        np.testing.assert_array_equal(got.F, alone.F)


RANGES = [(1, None), (1, 50), ("half", None), (0, 3), (7, 9), ("B-1", "B+1"), ("B", "2B-1"), (2, 2)]


@pytest.mark.parametrize("n_steps, block", [(7, 3), (100, None), (1000, 16), (4099, None), (20000, None)])
@pytest.mark.parametrize("rho, cond", [(0.9, 0.3), (1.0, 0.1), (1.003, 0.3)])
def test_sums_of_squares_are_those_of_every_step(n_steps, block, rho, cond):
    """Eq. (72)'s sums over whole runs, halves, the start-up and ranges that end inside blocks, against the sums
    of the steps formed one by one (long double squares of the same float64 steps)."""
    M, D, E, z_at = _recurrence(n_steps + 7, rho, cond=cond)
    errors = error_recurrence(M, D, E, z_at, n_steps, block=block)
    steps = errors.materialize().array().astype(np.longdouble)
    B = errors.B
    named = {"half": n_steps // 2 + 1, "B-1": B - 1, "B+1": B + 1, "B": B, "2B-1": 2 * B - 1}
    for first, last in RANGES:
        first, last = named.get(first, first), named.get(last, last)
        stop = n_steps if last is None else min(last, n_steps)
        expect = (steps[first : stop + 1, :5] ** 2).sum(axis=0).astype(float)
        got = errors.sum_squares(slice(0, 5), first, last)
        np.testing.assert_allclose(got, expect, rtol=1e-11, atol=0, err_msg=f"{first}..{last}")


def test_blocks_whose_terms_cancel_are_summed_step_by_step():
    """A column whose block values are 1e-9 of their terms (the coupling variables at index 3): the QR factor
    would carry its rounding into every block alike, so those blocks are the steps' own sums."""
    rng = np.random.default_rng(5)
    B, n, nb = 200, 5, 30
    F = rng.normal(size=(B, n, n + 2))
    s0 = rng.normal(size=n + 2)
    F[:, 0, :] -= np.outer(F[:, 0, :] @ s0, s0) / (s0 @ s0)  # column 0 annihilates s0
    S = s0 + 1e-9 * rng.normal(size=(nb, n + 2))
    errors = BlockErrors(F, S, nb * B - 1)
    sums = errors._block_sums([0, 1])
    terms = np.abs(S) @ np.linalg.norm(F[:, 0, :], axis=0)
    assert np.all(terms > QR_MAX_CANCELLATION * np.sqrt(sums[:, 0]))  # the case this test is about
    np.testing.assert_array_equal(sums[:, 0], np.square(F[:, 0, :] @ S.T).sum(axis=0))
    exact = (np.einsum("jk,bk->bj", F[:, 1, :].astype(np.longdouble), S.astype(np.longdouble)) ** 2).sum(axis=1)
    np.testing.assert_allclose(sums[:, 1], exact.astype(float), rtol=1e-13)


def _plain_first_step_beyond(array, exact, bound):
    with np.errstate(invalid="ignore", over="ignore"):
        mag = np.max(np.abs(exact + array[1:, :4]), axis=-1)
    bad = ~np.isfinite(mag) | (mag > bound)
    return int(np.argmax(bad)) + 1 if bad.any() else None


@pytest.mark.parametrize("n_steps, block", [(1, None), (9, 1), (1000, 16), (4099, 64)])
@pytest.mark.parametrize("rho", [0.9, 1.01, 1.6])
def test_growth_check_finds_the_first_step_of_every_step(n_steps, block, rho):
    """The bound of each block's errors screens blocks; the first step beyond a bound (or not finite: rho 1.6
    overflows) is that of the steps one by one, the exact values given as an array or as a function."""
    M, D, E, z_at = _recurrence(n_steps, rho, cond=0.0)
    D = D * 1e9
    with np.errstate(over="ignore", invalid="ignore"):
        errors = error_recurrence(M, D, E, z_at, n_steps, block=block)
        array = errors.materialize().array()
    exact = z_at(np.arange(1, n_steps + 1))[:, [0, 1, 0, 1]]
    finite = np.abs(array[np.isfinite(array).all(axis=1), :4])
    assert errors.max_abs_bound(slice(0, 4)) >= (finite.max() if finite.size else 0.0)
    sums = np.max(np.abs(exact) + np.nan_to_num(np.abs(array[1:, :4]), posinf=0.0), axis=-1)
    with np.errstate(over="ignore"):
        bounds = [*np.quantile(sums, [0.0, 0.5, 1.0]), 2 * sums.max(), np.inf]
    for bound in bounds:
        plain = _plain_first_step_beyond(array, exact, bound)
        assert errors.first_step_beyond(exact, bound, slice(0, 4)) == plain
        got = errors.first_step_beyond(
            lambda steps: exact[steps - 1], bound, slice(0, 4), exact_max=float(np.max(np.abs(exact)))
        )
        assert got == plain


@pytest.mark.parametrize(
    "method, params, dec, k",
    [("baumgarte", {"index": 3}, "fd", 0), ("weighted", {"index": 1, "a": 1.0, "b": 1.0}, "ff", 1)],
)
def test_curve_is_eq72_of_every_step(method, params, dec, k):
    """A curve's NRMSE and its parts (study.run) against Eq. (72) of the run's errors formed step by step, on
    schemes whose parts cancel strongly (index 3: errors of 1e-20 in positions and multipliers)."""
    setup = Setup(end_time=0.05)
    study = Study(setup, [50, 500, 5000], spectral_policy="float64")
    r = study.run(method, params, dec, k)
    for i, (H, N) in enumerate(zip(study.H, study.n_steps)):
        errors, diverged, _, _ = study._errors(dimensional_method(method, H, **params), dec, k, i, "error")
        assert diverged is None
        e = errors.array()[:, :5]
        var, var_half, var_lam = study._variances(i)
        total = np.sum(e[1:] ** 2, axis=0)
        half = np.sum(e[N // 2 + 1 :] ** 2, axis=0)
        scale = np.array([1.0, 1.0, 1 / H**2, 1 / H**2])
        nrmse = np.sqrt(np.sum(total[[0, 2, 1, 3]] * scale / var))
        nrmse_half = np.sqrt(np.sum(half[[0, 2, 1, 3]] * scale / var_half))
        assert r.nrmse_unfiltered[i] == pytest.approx(nrmse, rel=1e-12)
        assert r.nrmse_second_half[i] == pytest.approx(nrmse_half, rel=1e-12)
        assert r.nrmse_lambda[i] == pytest.approx(np.sqrt(total[4] / var_lam), rel=1e-10)
