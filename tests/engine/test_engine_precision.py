"""The precision policy against 128-digit arithmetic: float64 where it is trusted, and the verdicts at the
extremes of the parameter space (near the origin, and decays and rotations up to 1e3 per step).

The references are the amplification matrices formed at 128 digits by the mpmath backend (no float64, no
ball arithmetic), their spectral radius from mpmath's eigenvalues or, for a verdict, a Schur-Cohn test on
their characteristic polynomial at those digits.
"""

import contextlib

import mpmath
import numpy as np
import pytest
from helpers import engine_schemes

from icosim import (
    TestModel,
    baumgarte,
    projection,
    spectral_radius,
    spectral_radius_float64,
    spectral_radius_mp,
    weighted_multiplier,
)
from icosim.engine.backends import Multiprecision
from icosim.engine.bounds import guard_digits
from icosim.problems.linear.spectral import amplification_matrix
from icosim.problems.linear.subsystems import decay_rate

SCHEMES = engine_schemes()


# -- float64 against 128 digits ---------------------------------------------------
@pytest.mark.parametrize("method,dec", SCHEMES)
def test_float64_agrees_with_128_digits_where_trusted(method, dec):
    rng = np.random.default_rng(5)
    lr, li = -2 * rng.random(6), 2 * rng.random(6)
    model, be = TestModel(lr, li, 2.0, 2.0, 2.0), Multiprecision(128)
    for k in (0, 2):
        rho, err = spectral_radius_float64(model, method, dec, k)
        trusted = np.isfinite(rho) & (np.abs(rho - 1) > err)
        assert trusted.any()
        at = np.flatnonzero(trusted)
        with _exponentials_computed_once():  # the schemes of a decomposition share them
            matrices = _matrices_128_digits(lr[at], li[at], (2.0, 2.0, 2.0), method, dec, k, be)
        for i, M in zip(at, matrices):
            # the eigenvalues of a Hessenberg form (mpmath's own reduction then has nothing to do)
            ref = float(np.max(np.abs(be.eigvals(_hessenberg(_less_structural_zeros(M))))))
            # the error estimate is honest and float64 is accurate here
            assert abs(rho[i] - ref) <= err[i]
            assert rho[i] == pytest.approx(ref, rel=1e-9)


def test_multiprecision_results_are_consistent_across_precisions():
    point = TestModel(-1e3, 1e3, 1e3, 2.0, 0.5)  # exp(-1000)-sized entries need guard digits
    method = weighted_multiplier(1, 1)
    r128 = spectral_radius_mp(point, method, "ff", 0, 128)
    r200 = spectral_radius_mp(point, method, "ff", 0, 200)
    assert abs(float(r128) - float(r200)) <= 1e-60 * max(1.0, float(r200))


# -- the precision policy at the origin and at the extremes -----------------------
EXTREME_SCHEMES = [
    (weighted_multiplier(1, 1), "ff", 0),
    (weighted_multiplier(1, 1), "ff", 2),
    (baumgarte(mu=1, index=1), "fd", 1),
    (baumgarte(mu=1, index=2), "ff", 2),
    (projection(), "fd", 2),
    (projection(), "dd", 1),
]


def _extreme_points():
    near_origin = [(-a, b) for a in (1e-4, 1e-3, 1e-2) for b in (0.0, 1e-4, 1e-3, 1e-2)]
    large = [(-a, b) for a in (1e-4, 1.0, 100.0, 1e3) for b in (1e-4, 1.0, 100.0, 1e3)]
    return np.array(near_origin + large)


#: The references' subsystem exponentials by what determines them (digits, the backend's arguments, the matrix).
_MP_EXPM = {}


@contextlib.contextmanager
def _exponentials_computed_once():
    """The 128-digit references of these cases and of the float64 comparison above share their subsystems'
    exponentials (subsystem 1's matrix depends on the point, its kind and k, subsystem 2's also on am21): each
    distinct matrix, alone or in a batch, is exponentiated once, by the backend itself, and its entries handed out
    again as the same numbers in the asking backend's context, where each reference used to exponentiate
    both again."""
    original = Multiprecision.expm

    def expm(self, M, *args, **kwargs):
        M = np.asarray(M, dtype=object)
        out = np.empty(M.shape, dtype=object)
        for at in np.ndindex(M.shape[:-2]):  # each matrix of a batch on its own
            entries = tuple(getattr(v, "_mpf_", None) or getattr(v, "_mpc_", v) for v in np.ravel(M[at]))
            key = (self.digits, args, tuple(sorted(kwargs.items())), M.shape[-2:], entries)
            if key not in _MP_EXPM:
                _MP_EXPM[key] = original(self, M[at], *args, **kwargs)
            for idx, v in np.ndenumerate(_MP_EXPM[key]):
                out[at + idx] = self.ctx.convert(v)  # exact: the value as it is, in this backend's context
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Multiprecision, "expm", expm)
        yield


def _matrices_128_digits(lr1, li1, rest, method, dec, k, be):
    """The amplification matrices :func:`spectral_radius_mp` forms at 128 digits at ``TestModel(lr1, li1, *rest)``:
    a batched macro step per set of points whose subsystems' exponentials get the same guard digits (a batch
    gets those of its largest decay), so that each matrix is the point's own."""
    c = TestModel(lr1, li1, *rest).coefficients()
    decays = [np.broadcast_to(decay_rate(s, d), np.shape(lr1)) for s, d in ((c.k1, c.delta1), (c.k2, c.delta2))]
    guards = [tuple(guard_digits(d[i]) for d in decays) for i in range(len(lr1))]
    matrices = [None] * len(lr1)
    for guard in set(guards):
        at = [i for i, g in enumerate(guards) if g == guard]
        model = TestModel(be.asarray(lr1[at]), be.asarray(li1[at]), *map(be.const, rest))
        for i, M in zip(at, amplification_matrix(model, method, dec, k, backend=be)):
            matrices[i] = M
    return matrices


def _less_structural_zeros(M):
    """M without eigenvalues 0 its structure shows exactly: a zero row or column (a coupling value no step
    reads), or two equal rows i, j (projected states; e_i - e_j is a left null vector, so adding column i to
    column j, then dropping row and column i, is a similarity that drops the 0)."""
    while True:
        n = len(M)
        zero = [i for i in range(n) if not any(M[i]) or not any(M[:, i])]
        equal = [(i, j) for i in range(n) for j in range(i + 1, n) if all(M[i] == M[j])]
        if zero:
            i = zero[0]
        elif equal:
            (i, j), M = equal[0], M.copy()
            M[:, j] += M[:, i]
        else:
            return M
        M = np.delete(np.delete(M, i, axis=0), i, axis=1)


def _hessenberg(M):
    """An upper Hessenberg matrix similar to M: Gaussian elimination with row pivoting, each row operation
    undone on the columns (real arithmetic, no transformation kept)."""
    A = np.array(M, dtype=object)
    for j in range(len(A) - 2):
        p = j + 1 + int(np.argmax([abs(v) for v in A[j + 1 :, j]]))
        A[[j + 1, p]] = A[[p, j + 1]]
        A[:, [j + 1, p]] = A[:, [p, j + 1]]
        if A[j + 1, j] != 0:
            m = A[j + 2 :, j] / A[j + 1, j]
            A[j + 2 :] -= np.outer(m, A[j + 1])
            A[:, j + 1] += A[:, j + 2 :] @ m
    return A


def _schur_stable(M, one):
    """rho(M) < 1 in M's own arithmetic, without eigenvalues: the Schur-Cohn test (all reflection
    coefficients of det(zI - M) below 1 in modulus), the polynomial formed from a Hessenberg form of M."""
    H = _hessenberg(_less_structural_zeros(M))  # the zeros dropped are inside the unit circle
    p = [[one]]  # p[i]: characteristic polynomial of the leading i x i block, highest power first
    for i in range(len(H)):
        q, below = [a - H[i, i] * b for a, b in zip(p[i] + [0], [0] + p[i])], one
        for j in range(i - 1, -1, -1):
            below *= H[j + 1, j]
            q[i + 1 - j :] = [a - H[j, i] * below * b for a, b in zip(q[i + 1 - j :], p[j])]
        p.append(q)
    a = p[-1]
    while len(a) > 1:
        reflection = a[-1] / a[0]
        if abs(reflection) >= 1:
            return False
        a = [x - reflection * y for x, y in zip(a[:-1], a[:0:-1])]
    return True


@pytest.mark.slow
@pytest.mark.parametrize("method,dec,k", EXTREME_SCHEMES)
@pytest.mark.parametrize("am21", [1e-3, 1.0, 1e3])
def test_precision_policy_classifies_like_128_digits_at_the_extremes(method, dec, k, am21):
    pts = _extreme_points()
    model = TestModel(pts[:, 0], pts[:, 1], am21, 2.0, 0.5)
    res = spectral_radius(model, method, dec, k)
    assert np.all(np.isfinite(res.rho))
    be = Multiprecision(128)
    with _exponentials_computed_once():
        ref = _matrices_128_digits(pts[:, 0], pts[:, 1], (am21, 2.0, 0.5), method, dec, k, be)
    assert all(mpmath.isfinite(v) for M in ref for v in M.ravel())
    # every verdict agrees with 128 digits; "marginal" only where rho = 1 to those digits (no float64 guess there)
    for verdict, M in zip(res.verdict, ref):
        if verdict == "marginal":
            assert abs(np.max(np.abs(be.eigvals(M))) - 1) < 1e-60
        else:
            assert verdict == ("stable" if _schur_stable(M, be.const(1)) else "unstable")


def test_float64_fails_outright_at_the_extremes_and_the_policy_catches_it():
    """Velocity-level corrections at k = 0 divide quantities that both decay like
    exp(lr1): at lr1 = -1000 float64 underflows to 0/0."""
    pts = _extreme_points()
    model = TestModel(pts[:, 0], pts[:, 1], 1.0, 2.0, 0.5)
    method = weighted_multiplier(1, 1)
    raw, err = spectral_radius_float64(model, method, "ff", 0)
    failed = ~np.isfinite(raw)
    assert failed.any()
    res = spectral_radius(model, method, "ff", 0)
    assert np.all(res.arithmetic[failed] == "ball") and np.all(res.certified[failed])
    assert np.all(np.isin(res.verdict[failed], ("stable", "unstable")))
    assert np.all(np.isfinite(res.rho))


def test_origin_is_marginal_and_decided_at_high_precision():
    # a free mass: a Jordan block at eigenvalue 1, float64 only gets rho to ~1e-8; the proof cannot separate rho
    # from 1 at any precision (it is 1), so the point is marginal, with an enclosure containing 1
    res = spectral_radius(TestModel(0.0, 0.0, 2.0, 2.0, 2.0), baumgarte(mu=1, index=1), "ff", 2)
    assert res.verdict == "marginal" and res.arithmetic == "ball" and res.bits == 1024
    assert res.rho_lower <= 1 <= res.rho_upper and res.rho_upper - res.rho_lower < 1e-9
    assert not res.stable


def test_mp_backend_does_not_touch_global_mpmath_precision():
    import mpmath

    before = mpmath.mp.dps
    Multiprecision(200).asarray([1.0])
    spectral_radius_mp(TestModel(-0.5, 0.5), projection(), "ff", 1, 64)
    assert mpmath.mp.dps == before
