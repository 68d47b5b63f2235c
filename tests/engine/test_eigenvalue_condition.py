"""The float64 estimate's spectral radius and the condition number of the eigenvalue attaining it, from one
LAPACK ``geev`` per matrix: against eigenvectors known by construction and against numpy's eigenvalues."""

import numpy as np

from icosim.engine.spectral.radius import _radius_and_condition


def _similar(B: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``S B S^-1`` for a random well-conditioned ``S``, and ``S``."""
    rng = np.random.default_rng(seed)
    S = np.eye(len(B)) + 0.3 * rng.standard_normal(B.shape)
    return S @ B @ np.linalg.inv(S), S


def _blocks(*blocks) -> np.ndarray:
    n = sum(len(b) for b in blocks)
    B, i = np.zeros((n, n)), 0
    for b in blocks:
        B[i : i + len(b), i : i + len(b)] = b
        i += len(b)
    return B


def test_kappa_of_a_dominant_complex_pair_is_that_of_its_eigenvectors():
    """B's pair a +- ib (the block [[a, -b], [b, a]]) has the right eigenvector (1, -i) and the left one (1, i)
    (``y^T B = lambda y^T``), y^T x = 2; in S B S^-1 they are S x and S^-T y: kappa = |S x| |S^-T y| / 2.
    A Jordan block at 0 (the history's zeros) and a real eigenvalue sit beside it."""
    a, b = 0.6, 0.7
    B = _blocks(np.array([[a, -b], [b, a]]), np.array([[0.5]]), np.array([[0.0, 1.0], [0.0, 0.0]]))
    M, S = _similar(B, 1)
    x = S @ np.array([1, -1j, 0, 0, 0])
    y = np.linalg.inv(S).T @ np.array([1, 1j, 0, 0, 0])
    rho, kappa = _radius_and_condition(M[None])
    np.testing.assert_allclose(rho, [np.hypot(a, b)], rtol=1e-13)
    np.testing.assert_allclose(kappa, [np.linalg.norm(x) * np.linalg.norm(y) / 2], rtol=1e-10)


def test_kappa_of_a_dominant_real_eigenvalue_is_that_of_its_eigenvectors():
    B = _blocks(np.array([[-0.9]]), np.array([[0.3, -0.4], [0.4, 0.3]]), np.array([[0.1]]))
    M, S = _similar(B, 2)
    x, y = S[:, 0], np.linalg.inv(S)[0]
    rho, kappa = _radius_and_condition(M[None])
    np.testing.assert_allclose(rho, [0.9], rtol=1e-13)
    np.testing.assert_allclose(kappa, [np.linalg.norm(x) * np.linalg.norm(y)], rtol=1e-10)


def test_rho_is_numpys_eig_bit_for_bit_in_a_batch_and_alone():
    """Matrices of a long chain's size (above LAPACK's blocking threshold: the workspace decides the
    reduction's rounding), a batch and each matrix alone."""
    M = np.random.default_rng(3).standard_normal((3, 160, 160))
    rho, kappa = _radius_and_condition(M)
    np.testing.assert_array_equal(rho, np.max(np.abs(np.linalg.eig(M)[0]), axis=-1))
    for i in range(len(M)):
        r, c = _radius_and_condition(M[i : i + 1])
        assert r[0] == rho[i] and c[0] == kappa[i]
