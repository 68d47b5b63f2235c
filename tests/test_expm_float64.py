"""The float64 matrix exponential of a stack (icosim.engine.expm) against 50-digit mpmath and scipy."""

import mpmath
import numpy as np
import pytest
import scipy.linalg

from icosim.engine.backends import Float64
from icosim.engine.expm import expm_stack

U = np.finfo(float).eps / 2


def _subsystem_matrix(stiffness, damping, gain, k):
    """A force-driven subsystem's propagator generator with its input polynomial of order k (as
    icosim.engine.subsystems builds it): the oscillator block and a nilpotent chain."""
    n = 3 + k
    M = np.zeros((n, n))
    M[0, 1], M[1, 0], M[1, 1], M[1, 2] = 1.0, -stiffness, -damping, gain
    for j in range(k):
        M[2 + j, 3 + j] = 1.0
    return M


def _stack():
    """Subsystem matrices over the project's range of coefficients (every degree and scaling of the
    algorithm is reached) and random matrices of 1-norms from 1e-3 to 40."""
    rng = np.random.default_rng(3)
    mats = [
        _subsystem_matrix(kk, dd, g, 2)
        for kk in (0.0, 1e-3, 0.3, 1.0, 4.0, 30.0)
        for dd in (0.0, 0.1, 1.0, 8.0)
        for g in (1.0, 10.0)
    ]
    for scale in (1e-3, 0.05, 0.5, 2.0, 10.0):
        mats += list(scale * rng.standard_normal((6, 5, 5)) / 5)
    return np.array(mats)


def _exact(M):
    with mpmath.workdps(50):
        return np.array(mpmath.expm(mpmath.matrix(M.tolist())).tolist(), dtype=float)


def _normwise(E, T):
    return np.abs(E - T).sum(axis=0).max() / np.abs(T).sum(axis=0).max()


def test_stack_is_as_accurate_as_scipy_against_50_digits():
    A = _stack()
    E = expm_stack(A)
    worst = {"stack": 0.0, "scipy": 0.0}
    for M, F in zip(A, E, strict=True):
        T = _exact(M)
        worst["stack"] = max(worst["stack"], _normwise(F, T))
        worst["scipy"] = max(worst["scipy"], _normwise(scipy.linalg.expm(M), T))
    # scaling and squaring is normwise accurate to a modest multiple of u (times e^||A|| for decaying ones)
    assert worst["stack"] <= 100 * U
    assert worst["stack"] <= max(worst["scipy"], 20 * U)


def test_a_matrix_alone_and_in_a_stack_is_the_same_bit_for_bit():
    A = _stack()
    E = expm_stack(A)
    for i in (0, 7, 20, len(A) - 1):
        assert expm_stack(A[i]).tobytes() == E[i].tobytes()
        assert expm_stack(A[i : i + 1])[0].tobytes() == E[i].tobytes()
    grid = A.reshape((2, -1) + A.shape[1:])  # leading axes of a grid
    assert expm_stack(grid).reshape(A.shape).tobytes() == E.tobytes()


def test_the_float64_backend_forms_a_grid_once_and_each_point_the_same():
    A = np.broadcast_to(_stack()[:8], (40, 8, 5, 5)).copy()  # a stack large enough to be kept
    be = Float64()
    E1, E2 = be.expm(A), be.expm(A.copy())
    assert E1 is E2 and not E1.flags.writeable
    assert be.expm(A[3, 2]).tobytes() == E1[3, 2].tobytes()


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_matrix_gives_nan_and_spoils_no_other(bad):
    A = _stack()[:5].copy()
    A[2, 0, 0] = bad
    E = expm_stack(A)
    assert np.all(np.isnan(E[2]))
    assert np.all(np.isfinite(np.delete(E, 2, axis=0)))
    np.testing.assert_array_equal(np.delete(E, 2, axis=0), expm_stack(np.delete(A, 2, axis=0)))
