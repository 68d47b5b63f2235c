"""A link's part of a macro step in one compiled call: input samples, polynomial, integration, outputs.

:class:`icosim.problems.pendulum.problem.PendulumCosimulation` calls :func:`_link_step` once per link
integration: the samples of the link's input (with the forward-difference members), the monomial
coefficients of its polynomial, the shared first-step Jacobian, :func:`~.compiled._radau` and the
link's outputs (:func:`~.compiled_links.member_outputs`, the expressions of
:mod:`icosim.problems.pendulum.links`), where the numpy calls around a call of the integrator cost several
times the integration itself.

The kernels inline those of :mod:`.compiled`: their disk cache is dropped when it, or a source it
inlines, changes (:func:`~.kernel_cache.drop_stale_cache`).
"""

from __future__ import annotations

import numba
import numpy as np

from . import compiled
from .compiled import _jacobian, _radau
from .compiled_algebra import nan_maximum
from .compiled_links import FORCE, member_outputs, member_rhs
from .kernel_cache import KERNEL_SOURCES, compile_record, drop_stale_cache, gc_paused

__all__ = ["STATS", "warm_up", "compile_kernels"]

drop_stale_cache("compiled_step", ("compiled.py",) + KERNEL_SOURCES)  # before the kernels are defined

#: Counters of :func:`_link_step` (``stats[...]``): integrations, accepted steps, rejected steps,
#: right-hand side evaluations of the integrations, integrations that split the macro step, Jacobians
#: (the integrations' and the shared first-step ones), right-hand side evaluations of the shared ones.
STATS = ("integrations", "steps", "rejected", "fev", "split", "jev", "jac_fev")


@numba.njit(cache=True)
def _link_samples(K, e, history, col, perturb, fd_step):
    """The samples (B, K, 2) of one link's input at the corrector nodes ``1, 0, ..., -K+2``:
    ``e[col:col+2]``, then ``history[0..K-2, col:col+2]`` (``corrector_samples`` of the engine's problem);
    with ``perturb`` two more members whose first sample has component ``m`` moved by
    ``fd_step * max(1, |e|)`` (the problem's forward differences)."""
    B = 3 if perturb else 1
    S = np.empty((B, K, 2))
    for b in range(B):
        S[b, 0, 0], S[b, 0, 1] = e[col], e[col + 1]
        for j in range(1, K):
            S[b, j, 0], S[b, j, 1] = history[j - 1, col], history[j - 1, col + 1]
    if perturb:
        for m in range(2):
            v = e[col + m]
            S[1 + m, 0, m] = v + fd_step * nan_maximum(1.0, abs(v))
    return S


@numba.njit(cache=True)
def _link_step(
    link, kind, par, H, C, e, history, col, perturb, fd_step, y_start, jac0, fresh_jac, tol, max_steps, stats
):
    """One link over one macro step from ``y_start`` for the samples of :func:`_link_samples`.

    The monomial coefficients ``coef[b, m] = sum_j C[m, j] S[b, j]`` (``C`` (k+1, k+1): the problem's
    ``C_corr``), the Newton matrix of the first step from member 0 at ``t = 0`` when ``fresh_jac``
    (written to ``jac0`` (n, n), else read from it), :func:`_radau` over ``[0, H]`` and the outputs
    (4, 2) of every member at ``H`` with the input ``sum_m coef[b, m]``.  ``tol`` =
    ``(rtol, atol, newton_tol)``.  Adds to ``stats`` (:data:`STATS`): the shared Jacobian when computed,
    the integration's counts when it succeeds.  Returns ``(y, out, status, t, h_abs)`` (status as
    :func:`_radau`'s).
    """
    S = _link_samples(C.shape[0], e, history, col, perturb, fd_step)
    B, K, _ = S.shape
    n = jac0.shape[0]
    coef = np.empty((B, K, 2))
    for b in range(B):  # einsum("mj,bju->bmu", C, S): the sum over j in index order
        for m in range(K):
            for u in range(2):
                acc = C[m, 0] * S[b, 0, u]
                for j in range(1, K):
                    acc += C[m, j] * S[b, j, u]
                coef[b, m, u] = acc
    y0 = np.empty((B, n))
    for b in range(B):
        for i in range(n):
            y0[b, i] = y_start[i]
    if fresh_jac:
        J = _jacobian(link, kind, par, H, coef[0:1].copy(), 0.0, y0[0:1].copy())
        for i in range(n):
            for j in range(n):
                jac0[i, j] = J[0, i, j]
        stats[5] += 1
        stats[6] += 2
    y, f, counts, h_next, status, t, h_abs = _radau(
        link, kind, par, H, coef, 0.0, H, y0, jac0, tol[0], tol[1], tol[2], max_steps, np.empty(0), np.empty((0, 0, 0))
    )
    out = np.empty((B, 4, 2))
    if status:
        return y, out, status, t, h_abs
    for b in range(B):
        ux, uy = coef[b, 0, 0], coef[b, 0, 1]  # np.add.reduce(coef, axis=1): the input at tau = 1
        for m in range(1, K):
            ux += coef[b, m, 0]
            uy += coef[b, m, 1]
        member_outputs(link, kind, par, y[b], f[b], ux, uy, out[b])
    n_steps, n_rejected = counts[0], counts[1]
    stats[0] += 1
    stats[1] += n_steps
    stats[2] += n_rejected
    stats[3] += counts[2]
    stats[4] += 1 if n_steps > 1 or n_rejected > 0 else 0
    stats[5] += counts[3]
    return y, out, status, t, h_abs


@numba.njit(cache=True)
def _link_outputs(link, kind, par, H, end, e, col, perturb, fd_step):
    """The outputs (B, 4, 2) of a link at its end state ``end`` for the input ``e[col:col+2]`` held at
    ``T_N+1`` (the right-hand side at ``t = H`` with a constant input polynomial), with ``perturb`` also
    for the two perturbed inputs of :func:`_link_samples`."""
    S = _link_samples(1, e, e.reshape((1, e.shape[0])), col, perturb, fd_step)
    B = S.shape[0]
    n = end.shape[0]
    f = np.empty(n)
    out = np.empty((B, 4, 2))
    for b in range(B):
        member_rhs(link, kind, par, H, H, end, S[b, 0:1], f)
        member_outputs(link, kind, par, end, f, S[b, 0, 0], S[b, 0, 1], out[b])
    return out


def warm_up() -> None:
    """Compile the kernels the co-simulation calls, or load them from numba's disk cache, now
    (:func:`.compiled.warm_up` and the entry points here, with the argument types of the problem's calls).

    A timed run calls this first, so that its CPU seconds are those of its macro steps alone.
    """
    compiled.warm_up()
    y, par = np.zeros(2), np.ones(4)
    e, history, C = np.zeros(2), np.zeros((1, 2)), np.ones((1, 1))
    tol, stats = np.array([1e-6, 1e-6, 1e-8]), np.zeros(len(STATS), np.int64)
    with gc_paused():  # numba's compiler: no time in Python's collections
        _link_step(1, FORCE, par, 1.0, C, e, history, 0, False, 1e-3, y, np.zeros((2, 2)), True, tol, 1, stats)
        _link_outputs(1, FORCE, par, 1.0, y, e, 0, False, 1e-3)


def compile_kernels() -> dict:
    """:func:`warm_up` and its record (:func:`~icosim.problems.pendulum.integrator.kernel_cache.compile_record`): what
    the workflow's compile job runs before the co-simulations."""
    kernels = {"_jacobian": _jacobian, "_radau": _radau, "_link_step": _link_step, "_link_outputs": _link_outputs}
    return compile_record(warm_up, kernels)
