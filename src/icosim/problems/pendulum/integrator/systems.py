"""The compiled integrator (:mod:`.compiled`) from Python: its systems, its result and its error.

* :class:`CompiledLink` -- a link of the pendulum for the kernels (its ids and constants), with the
  forward-difference Jacobian and an integration over an interval;
* :func:`monolithic_radau` -- the whole pendulum in minimal coordinates integrated by the same
  kernel (the monolithic baseline of the speed-accuracy study);
* :class:`RadauResult` -- the end of an integration, :class:`IntegrationError` -- its failure
  (:func:`link_failure` turns a kernel's status code into it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ....errors import StepFailure
from ..links import Link1
from .compiled import (
    _DERIVATIVE_NOT_FINITE,
    _ERROR_NOT_FINITE,
    _SINGULAR,
    _STEP_TOO_SMALL,
    _TOO_MANY_STEPS,
    _jacobian,
    _radau,
)
from .compiled_links import FORCE, KINEMATIC, MONOLITHIC, link_parameters, monolithic_parameters

__all__ = ["CompiledLink", "monolithic_radau", "RadauResult", "IntegrationError", "link_failure"]


class IntegrationError(StepFailure):
    """The step size fell below round-off level, the solution stopped being finite or a
    Newton matrix was singular.

    A :class:`~icosim.errors.StepFailure`: a co-simulation run records it as
    *failed*, not as diverged (a solver failure says nothing about stability).
    """


@dataclass
class RadauResult:
    """End of a batched integration.

    ``y`` and ``f = fun(t1, y)`` have shape ``(B, n)``; ``n_steps`` accepted
    and ``n_rejected`` rejected step attempts, ``n_fev`` batched right-hand
    side evaluations, ``n_jev`` Jacobians.  With ``record_steps``, ``t_steps``
    ``(n_steps + 1,)`` and ``y_steps`` ``(n_steps + 1, B, n)`` hold the start
    and every accepted step.
    """

    y: np.ndarray
    f: np.ndarray
    n_steps: int
    n_rejected: int
    n_fev: int
    n_jev: int
    h_next: float
    t_steps: np.ndarray | None = None
    y_steps: np.ndarray | None = None


def _float_array(x, ndim):
    """A writable C-contiguous float64 copy: one numba specialisation for every caller."""
    a = np.array(x, dtype=np.float64, order="C")
    if a.ndim != ndim:
        raise ValueError(f"expected {ndim} dimensions, got shape {a.shape}")
    return a


class CompiledLink:
    """A link (:class:`~icosim.problems.pendulum.links.Link1` or ``Link2``) for the compiled kernels.

    Its ids and parameter array stand for the closure ``link.rhs(coef, H)``:
    ``coef`` (B, K, 2) are the monomial coefficients of the input in ``tau = t / H``.
    """

    def __init__(self, link):
        self.link_id = 1 if isinstance(link, Link1) else 2
        self.kind_id = FORCE if link.kind == "force" else KINEMATIC
        self.n = link.n
        self.par = link_parameters(link)

    def fd_jacobian(self, coef, H: float, t: float, y) -> np.ndarray:
        """The forward-difference Jacobian (B, n, n) of ``link.rhs(coef, H)`` at ``(t, y[b])``."""
        return _jacobian(
            self.link_id, self.kind_id, self.par, float(H), _float_array(coef, 3), float(t), _float_array(y, 2)
        )

    def radau(self, coef, H: float, t0: float, t1: float, y0, **options) -> RadauResult:
        """Integrate ``link.rhs(coef, H)`` from ``t0`` to ``t1`` for the initial values ``y0`` (B, n)
        (``jac0`` an (n, n) matrix; the options of :func:`_integrate`)."""
        return _integrate(self.link_id, self.kind_id, self.par, coef, H, t0, t1, y0, **options)


def monolithic_radau(params, t0: float, t1: float, y0, **options) -> RadauResult:
    """The whole pendulum in minimal coordinates (:class:`~icosim.problems.pendulum.reference.Monolithic`, state
    ``(phi1, phi2, w1, w2)``, ``y0`` (n,) or (B, n)) from ``t0`` to ``t1`` by the links' Radau IIA (the
    options of :func:`_integrate`)."""
    y0 = np.atleast_2d(np.asarray(y0, dtype=np.float64))
    coef = np.zeros((y0.shape[0], 1, 2))  # no input
    return _integrate(MONOLITHIC, FORCE, monolithic_parameters(params), coef, 1.0, t0, t1, y0, **options)


def _integrate(
    link_id,
    kind_id,
    par,
    coef,
    H,
    t0,
    t1,
    y0,
    *,
    rtol: float = 1e-6,
    atol: float = 1e-6,
    jac0=None,
    newton_tol: float = 1e-8,
    max_steps: int = 100000,
    record_steps: bool = False,
) -> RadauResult:
    """:func:`~.compiled._radau` on a system, with ``rtol``, ``atol`` and ``newton_tol`` (relative to the
    error scale ``atol + rtol |y|``) as in scipy, ``jac0`` the Newton matrix's Jacobian for the first
    step (forward differences otherwise), and with ``record_steps`` the start and every accepted step
    (:attr:`RadauResult.t_steps`, :attr:`RadauResult.y_steps`).

    Raises :class:`IntegrationError` if the step size falls below round-off level, values stop being
    finite or a Newton matrix is singular.
    """
    if not (np.isfinite(rtol) and np.isfinite(atol) and rtol > 0 and atol > 0):
        raise ValueError(f"rtol and atol must be finite and > 0, got rtol={rtol!r}, atol={atol!r}")
    y0 = _float_array(y0, 2)
    n = y0.shape[1]
    jac0 = np.empty((0, 0)) if jac0 is None else _float_array(np.broadcast_to(jac0, (n, n)), 2)
    m = int(max_steps) + 1 if record_steps else 0
    t_rec, y_rec = np.empty(m), np.empty((m,) + y0.shape)
    y, f, counts, h_next, status, t, h_abs = _radau(
        link_id,
        kind_id,
        par,
        float(H),
        _float_array(coef, 3),
        float(t0),
        float(t1),
        y0,
        jac0,
        float(rtol),
        float(atol),
        float(newton_tol),
        int(max_steps),
        t_rec,
        y_rec,
    )
    if status:
        raise link_failure(status, t, h_abs, max_steps)
    n_steps, n_rejected, n_fev, n_jev = counts.tolist()
    result = RadauResult(y, f, n_steps, n_rejected, n_fev, n_jev, float(h_next))
    if record_steps:
        result.t_steps, result.y_steps = t_rec[: n_steps + 1].copy(), y_rec[: n_steps + 1].copy()
    return result


def link_failure(status, t, h_abs, max_steps) -> IntegrationError:
    """The :class:`IntegrationError` for a status code of :func:`~.compiled._radau` (its time, step size and
    ``max_steps``)."""
    if status == _STEP_TOO_SMALL:
        return IntegrationError(f"step size {h_abs:.3g} below round-off level at t = {t:.17g}")
    if status == _ERROR_NOT_FINITE:
        return IntegrationError(f"non-finite error estimate at t = {t:.17g}")
    if status == _SINGULAR:  # with the message of numpy's LinAlgError for a singular matrix
        return IntegrationError(f"singular Newton matrix at t = {t:.17g}: Singular matrix")
    if status == _TOO_MANY_STEPS:
        return IntegrationError(f"more than {max_steps} steps")
    assert status == _DERIVATIVE_NOT_FINITE, f"unknown status {status}"
    return IntegrationError(f"non-finite derivative at t = {t:.17g}")
