"""Spectral radius of the amplification matrix: float64 with an error estimate, and mpmath.

float64 runs vectorised over the whole parameter grid.  Each float64 value
comes with an error estimate of two parts.

* A rounding floor: what rounding errors of size ``u nu ||M||_F`` move the
  eigenvalue of largest modulus, to first order, at most: ``kappa`` times that,
  ``kappa`` the eigenvalue's condition number.  Such errors are the
  eigensolver's backward error (a small multiple of ``n u ||M||``) and the
  rounding of ``M`` where it is normwise, inherited from the exponential blocks
  ``E = exp(A)`` of the subsystems, which scaling and squaring computes to
  about ``u ||A|| ||E||`` (its squarings grow with ``||A||``), hence
  ``nu = max(1, ||A||_1)`` over the subsystems.
* The spread of re-runs with the inputs disturbed at the size of their rounding
  errors: the exponential blocks (absolute noise ``~ u ||E||``) and the
  amplification matrix itself (``~ u ||M||``), times a safety factor.  It needs
  no model of *why* float64 fails: cancellation in the corrections
  (sensitivities that both decay like ``exp(lr)``), underflow, or eigenvalues
  clustered at 1 near the origin all show up as a large spread.  A run's effect
  on ``rho`` is a random draw, which can come out arbitrarily small; the floor
  does not rest on it.

A second disturbed run is made only where the first one's estimate, ``DOUBT``
times over, reaches ``|rho - 1|`` (a fraction of a percent of a grid: the
points near 1, which are certified anyway, and the ill-conditioned ones);
elsewhere the verdict does not hang on it.  The multiprecision path recomputes
one point with every derived quantity formed at ``digits`` significant digits.

>>> from icosim import TestModel, make_method
>>> from icosim.problems.linear.family import TwoMass
>>> m, point = make_method("weighted", a=1, b=1), TwoMass(TestModel(-0.05, 0.5), "ff", k=2)
>>> rho, err = spectral_radius_float64(point, m)
>>> rho_mp = spectral_radius_mp(point, m, digits=40)
>>> bool(abs(float(rho) - float(rho_mp)) <= err), bool(rho > 1)
(True, True)
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Literal, overload

import numpy as np

from ..backends import Float64, Multiprecision
from ..schemes import JACOBI, Scheme, get_scheme
from .matrix import matrix_of

if TYPE_CHECKING:
    from ..methods.base import CouplingMethod
    from .family import LinearFamily

__all__ = [
    "spectral_radius_float64",
    "Float64Radius",
    "spectral_radius_mp",
    "SAFETY",
    "DISTURBANCE",
    "DOUBT",
    "FLOOR",
    "SIDE_BY_SIDE",
]


#: Safety factor on the measured spread of disturbed float64 results.
SAFETY = 10.0


#: Disturbance size, in units of the float64 unit roundoff.
DISTURBANCE = 4.0


#: A second disturbed run is made where ``DOUBT`` times the first one's estimate reaches ``|rho - 1|``.
DOUBT = 1000.0


#: The rounding floor, in units of ``eps * max(kappa * nu * ||M||_F, 1)`` (module docstring): the backward
#: error of the eigensolver and the rounding of ``M``, each a small multiple of ``u nu ||M||_F`` for the
#: matrices of a few to a dozen rows here.
FLOOR = 32.0


def _spectral_radius_of(M: np.ndarray, backend: Float64 | Multiprecision) -> Any:
    ev = backend.eigvals(M)
    return np.max(np.abs(ev), axis=-1)


def _radius_and_condition(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Spectral radius of each float64 matrix and the condition number of the eigenvalue that attains it.

    ``kappa = |x| |u| / |u^H x|`` (``M x = lambda x``, ``u^H M = lambda u^H``): a perturbation ``E`` moves that
    eigenvalue by at most ``kappa ||E||_2`` to first order.  One LAPACK ``geev`` per matrix gives the
    eigenvalues and both eigenvectors from the same Schur form: the eigenvalues are ``numpy.linalg.eig``'s
    bit for bit (the same call with the same workspace; ``eigvals`` runs the same Hessenberg QR, equal but
    for the last bits of large matrices, seen from about 150 rows), and the left eigenvector is that of the
    very eigenvalue, not the inverse of the right ones (a defective eigenvalue elsewhere, the history's zeros,
    leaves those without an inverse) nor one of ``M^T``'s matched by value (in a cluster of close eigenvalues
    that can be another one's).  ``kappa`` is capped at ``1/sqrt(eps)``: an eigenvalue that ill-conditioned
    is, at float64's rounding, as good as defective, and a perturbation ``delta`` moves it by about
    ``sqrt(delta)`` (a 2 x 2 Jordan block), which the cap gives; a larger Jordan block moves it further, which
    the disturbed runs see.
    """
    from scipy.linalg.lapack import dgeev, dgeev_lwork  # here: a job that forms no radius starts faster

    batch, n = M.shape[:-2], M.shape[-1]
    wr, wi = np.empty(batch + (n,)), np.empty(batch + (n,))
    vl, vr = np.empty(batch + (n, n)), np.empty(batch + (n, n))
    # the optimal workspace, as numpy.linalg.eig asks for it: its blocked reductions, so its rounding
    lwork = int(dgeev_lwork(n, compute_vl=1, compute_vr=1)[0]) if n else 1
    for idx in np.ndindex(*batch):
        wr[idx], wi[idx], vl[idx], vr[idx], info = dgeev(M[idx], compute_vl=1, compute_vr=1, lwork=lwork)
        if info > 0:
            raise np.linalg.LinAlgError("Eigenvalues did not converge")  # as numpy.linalg.eig reports it
    w = wr + 1j * wi
    i = np.argmax(np.abs(w), axis=-1)[..., None]
    lam = np.take_along_axis(w, i, axis=-1)[..., 0]
    # a complex pair is stored as two real columns (LAPACK's layout): re + i im for the eigenvalue with
    # positive imaginary part, re - i im for its conjugate
    sign = np.sign(lam.imag)[..., None]
    re = np.where(sign < 0, i - 1, i)[..., None, :]
    im = np.where(sign > 0, i + 1, i)[..., None, :]

    def vector(V: np.ndarray) -> np.ndarray:
        part = lambda j: np.take_along_axis(V, j, axis=-1)[..., 0]  # noqa: E731
        return part(re) + 1j * sign * part(im)

    x, u = vector(vr), vector(vl)
    kappa = np.linalg.norm(x, axis=-1) * np.linalg.norm(u, axis=-1) / np.abs(np.sum(u.conj() * x, axis=-1))
    return np.abs(lam), np.fmin(kappa, 1 / np.sqrt(np.finfo(float).eps))


class _PointNoise:
    """Draws of ``rng`` broadcast over the batch's leading axes ``batch``: every point gets the draws it would
    get alone, so its estimate does not depend on the batch it is computed in.  A bare matrix (two axes: a
    block the same at every point, such as a kinematically driven mass's) is drawn whole, in any batch."""

    def __init__(self, rng: np.random.Generator, batch: tuple):
        self.rng, self.batch = rng, tuple(batch)

    def standard_normal(self, shape: tuple[int, ...]) -> np.ndarray:
        shape, n = tuple(shape), len(self.batch)
        if len(shape) <= 2:
            return self.rng.standard_normal(shape)
        if shape[:n] != self.batch and shape[:n] != (1,) * n:
            raise ValueError(f"pointwise draws of shape {shape} do not lead with the batch's axes {self.batch}")
        return np.broadcast_to(self.rng.standard_normal(shape[n:]), shape)


def _each_alone(f: Callable[[np.ndarray], Sequence[Any]], M: np.ndarray, batch: tuple) -> tuple[np.ndarray, ...]:
    """``f`` (returning arrays over a batch) of every matrix of ``M`` as a batch of one, laid out as a matrix
    alone (column after column): the reductions after LAPACK follow a batch's memory layout, which orders
    their sums, so the same matrix in another batch could get other last bits."""
    outs: list[np.ndarray] | None = None
    for idx in np.ndindex(*batch):
        parts = f(np.asfortranarray(M[idx])[None])
        if outs is None:
            outs = [np.empty(batch, dtype=np.asarray(q).dtype) for q in parts]
        for out, q in zip(outs, parts):
            out[idx] = q[0]
    assert outs is not None  # a batch has at least one point
    return tuple(outs)


#: Points times rows up to which a problem and its disturbed copy are formed side by side: a macro step that
#: small costs its calls, not its arithmetic; a larger one costs the arithmetic, which a batch twice as large
#: does not make cheaper.
SIDE_BY_SIDE = 4096


def _matrices(problems: Sequence[Any], method: CouplingMethod | None, scheme: Scheme, points: int) -> list[np.ndarray]:
    """The matrices of a problem over ``points`` points and its disturbed copies: in one batched macro step where
    the problem lays them side by side (``side_by_side``: a new leading axis, the same values per point as each
    alone) and the batch is small (:data:`SIDE_BY_SIDE`), else one by one."""
    beside = getattr(problems[0], "side_by_side", None)
    if beside is None or len(problems) == 1 or points * problems[0].n_state > SIDE_BY_SIDE:
        return [matrix_of(p, method, scheme) for p in problems]
    return list(matrix_of(beside(problems[1:]), method, scheme))


def _spread(Md: np.ndarray, z: np.ndarray, rho: np.ndarray, rel: float) -> np.ndarray:
    """``|rho_d - rho|`` of one disturbed run: the matrix ``Md`` of the disturbed exponential blocks, itself
    disturbed by the standard normal draws ``z`` at ``rel`` of its largest entry (inf where it is not finite)."""
    ok = np.all(np.isfinite(Md), axis=(-1, -2))
    Md = np.where(ok[..., None, None], Md, 0.0)
    norm = np.max(np.abs(Md), axis=(-1, -2), keepdims=True)
    Md = Md + rel * norm * z
    ok &= np.all(np.isfinite(Md), axis=(-1, -2))  # entries near the float64 limit overflow with the noise
    Md = np.where(ok[..., None, None], Md, 0.0)
    rho_d = np.where(ok, _spectral_radius_of(Md, Float64()), np.nan)
    return np.where(ok, np.abs(rho_d - rho), np.inf)


class Float64Radius:
    """The float64 spectral radius and its error estimate (module docstring) at the points of ``family``, as
    :func:`spectral_radius_float64` gives them.  The plain and the first disturbed matrices of every point are
    formed when it is made (side by side in one batched macro step where that is cheaper: :func:`_matrices`), the
    eigenvalues when it is called, of the points asked for -- with ``pointwise`` draws a point's numbers are those
    it gets alone, so the points left out change nothing.
    """

    def __init__(
        self,
        family: LinearFamily,
        method: CouplingMethod | None,
        *,
        seed: int = 0,
        scheme: str | Scheme = JACOBI,
        doubt: float = DOUBT,
        pointwise: bool = False,
    ):
        self.family, self.method, self.scheme = family, method, get_scheme(scheme)
        self.doubt, self.pointwise = doubt, pointwise
        family.check(method, self.scheme)
        self.rel = DISTURBANCE * Float64.eps
        with np.errstate(all="ignore"):
            problem = family.problem(Float64())
            rng = np.random.default_rng(seed)
            noise = _PointNoise(rng, family.shape) if pointwise else rng
            disturbed = problem.disturbed(noise, self.rel)  # the run's draws: its blocks, then its matrix
            self.M, self.Md = _matrices([problem, disturbed], method, self.scheme, math.prod(family.shape))
            self.z = noise.standard_normal(self.Md.shape)
            self._after_first = copy.deepcopy(rng)  # where the second run starts drawing
            self.nu = problem.generator_norm()

    def __call__(self, mask: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(rho, err)`` at every point (of the family's shape), or (``pointwise``) at the points where the
        boolean array ``mask`` holds (flat, in C order)."""
        shape = self.family.shape
        if mask is not None and not self.pointwise:
            raise ValueError("points apart need pointwise draws")

        def pick(a: Any) -> Any:  # the asked-for points of an array over the family (a number: the same at every point)
            if mask is None or not np.ndim(a):
                return a
            return np.broadcast_to(a, shape + np.shape(a)[len(shape) :])[mask]

        with np.errstate(all="ignore"):
            return self._estimate(mask, pick)

    def _estimate(self, mask: np.ndarray | None, pick: Callable[[Any], Any]) -> tuple[np.ndarray, np.ndarray]:
        M = pick(self.M)
        finite = np.all(np.isfinite(M), axis=(-1, -2))
        M_safe = np.where(finite[..., None, None], M, 0.0)
        points = finite.shape
        rho, kappa = (
            _each_alone(_radius_and_condition, M_safe, points) if self.pointwise else _radius_and_condition(M_safe)
        )
        rho = np.where(finite, rho, np.nan)
        spread = _spread(pick(self.Md), pick(self.z), rho, self.rel)
        # the second disturbed run only where the first one's estimate, ``doubt`` times over, reaches |rho - 1|:
        # elsewhere no second spread seen on the project's grids came near deciding (docs/engine.md)
        frobenius = lambda M: (np.linalg.norm(M, axis=(-2, -1)),)  # noqa: E731
        (norm,) = _each_alone(frobenius, M_safe, points) if self.pointwise else frobenius(M_safe)
        amplified = kappa * pick(self.nu) * norm  # kappa nu ||M||_F
        floor = FLOOR * Float64.eps * np.maximum(amplified, 1.0)
        twice = np.isfinite(rho) & np.isfinite(spread) & ~(self.doubt * (SAFETY * spread + floor) < np.abs(rho - 1))
        if twice.any():
            where = twice
            if mask is not None:
                where = np.zeros(self.family.shape, dtype=bool)
                where[mask] = twice
            subset = self.family.subset(where)
            rng = copy.deepcopy(self._after_first)
            noise = _PointNoise(rng, subset.shape) if self.pointwise else rng
            Md = matrix_of(subset.problem(Float64()).disturbed(noise, self.rel), self.method, self.scheme)
            z = noise.standard_normal(Md.shape)
            again = _spread(Md, z, rho[twice], self.rel)
            spread[twice] = np.fmax(spread[twice], again)
            spread[twice] = np.where(np.isfinite(again), spread[twice], np.inf)
        err = SAFETY * spread + floor
        return rho, np.where(np.isfinite(rho), err, np.inf)


@overload
def spectral_radius_float64(
    family: LinearFamily,
    method: CouplingMethod | None,
    *,
    error_estimate: Literal[True] = ...,
    seed: int = ...,
    scheme: str | Scheme = ...,
    doubt: float = ...,
    pointwise: bool = ...,
) -> tuple[np.ndarray, np.ndarray]: ...


@overload
def spectral_radius_float64(
    family: LinearFamily,
    method: CouplingMethod | None,
    *,
    error_estimate: bool,
    seed: int = ...,
    scheme: str | Scheme = ...,
    doubt: float = ...,
    pointwise: bool = ...,
) -> tuple[np.ndarray, np.ndarray | None]: ...


def spectral_radius_float64(
    family: LinearFamily,
    method: CouplingMethod | None,
    *,
    error_estimate: bool = True,
    seed: int = 0,
    scheme: str | Scheme = JACOBI,
    doubt: float = DOUBT,
    pointwise: bool = False,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Spectral radius in float64 at every point of ``family`` (:mod:`icosim.engine.spectral.family`).

    Returns ``(rho, err)``; ``err`` is the error estimate described in the
    module docstring (``None`` if not requested; ``doubt=np.inf`` makes the
    second disturbed run on every point; ``pointwise``: every point's disturbances are those it gets alone,
    the same draws for every point of the grid, so its ``(rho, err)`` is the same bit for bit in any batch
    -- else the draws are independent over the grid and follow its shape).  Non-finite values are
    returned as they are (never raised), so one bad point cannot spoil a grid.
    """
    if error_estimate:
        return Float64Radius(family, method, seed=seed, scheme=scheme, doubt=doubt, pointwise=pointwise)()
    be = Float64()
    scheme = get_scheme(scheme)
    family.check(method, scheme)
    with np.errstate(all="ignore"):
        M = matrix_of(family.problem(be), method, scheme)
        finite = np.all(np.isfinite(M), axis=(-1, -2))
        M_safe = np.where(finite[..., None, None], M, 0.0)
        return np.where(finite, _spectral_radius_of(M_safe, be), np.nan), None


def spectral_radius_mp(
    family: LinearFamily, method: CouplingMethod, digits: int = 128, *, scheme: str | Scheme = JACOBI
) -> Any:
    """Spectral radius of the one point of ``family`` at ``digits`` significant digits.

    The parameters are taken exactly as given -- a float as the binary number
    it is, a :class:`~fractions.Fraction` or decimal string as the decimal
    number (``"-0.3"`` is -3/10, not -0.29999999999999998890) -- and every
    derived quantity is formed in multiprecision, as are the method's exact
    parameters.  Returns an ``mpf`` with ``digits`` significant digits.
    """
    be = Multiprecision(digits)
    scheme = get_scheme(scheme)
    family.check(method, scheme)
    M = matrix_of(family.problem(be, exact=True), method, scheme)
    return _spectral_radius_of(M, be)
