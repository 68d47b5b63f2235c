"""The co-simulation problem: what :func:`icosim.macrostep.macro_step` needs of it.

A problem couples two subsystems through the coupling variables ``e`` of its
decomposition.  :class:`CosimulationProblem` holds what every problem shares --
the decomposition, the approximation order ``k``, the arithmetic, the
extrapolation (Eq. 9/35/59) and shift of the coupling history, the samples the
corrector's interpolation polynomial runs through (Eq. 11), and a count of the
work done -- and states the contract a subclass meets.  The linear test model
(:class:`icosim.linear_problem.LinearCosimulation`) and the double pendulum
(:class:`icosim.pendulum.problem.PendulumCosimulation`) are the two subclasses.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .backend import Float64
from .decompositions import get_decomposition
from .lagrange import corrector_nodes, predictor_nodes, weights_at
from .limits import check_k

__all__ = ["CosimulationProblem", "Work"]


@dataclass
class Work:
    """Work done by a problem since the last :meth:`reset`.

    ``subsystem_integrations`` counts calls of a subsystem integrator (a
    batched call counts once), ``coupling_solves`` linear solves of coupling
    conditions, ``projections`` projection steps.  The problems count their
    integrations, :func:`icosim.macrostep.macro_step` the solves and
    projections.
    """

    subsystem_integrations: int = 0
    coupling_solves: int = 0
    projections: int = 0

    def reset(self):
        self.subsystem_integrations = self.coupling_solves = self.projections = 0

    def as_dict(self) -> dict:
        return asdict(self)


class CosimulationProblem:
    """Base class of co-simulation problems (two subsystems, Jacobi scheme).

    Arrays: the state ``s`` is the subsystems' states at ``T_N`` (layout set by
    the subclass); the coupling history ``h[..., j, :] = e_N-j``, ``j = 0..k``;
    the outputs ``y`` at ``T_N+1`` are what the coupling conditions are formed
    from.  Leading batch axes are allowed wherever the subclass allows them.

    A subclass calls ``super().__init__(decomposition, k, backend)`` and
    implements

    ``predict(state, history) -> y_p``
        outputs at ``T_N+1`` after integrating every subsystem with the
        extrapolation polynomials through the history (step 1).
    ``residuals(y) -> dict``
        the coupling conditions at ``T_N+1``: ``pos``, ``vel``, ``acc`` (the
        constraint on each level, shape ``(..., n_c)``) and ``force`` (balance
        of the multipliers of kinematically driven subsystems, ``(..., n_f)``).
    ``jacobians(state, history, e, y) -> dict``
        ``d residuals / d e_N+1`` for the same levels, shape ``(..., n, n_e)``.
    ``correct(state, history, e_new) -> (state_new, y_new)``
        integration with the interpolation polynomials through
        :meth:`corrector_samples` (step 3).
    ``project(state) -> state``
        the projection step (step 4; needed by methods that project).

    and counts each subsystem integration in :attr:`work`.  The base class
    provides :meth:`extrapolate`, :meth:`shift` and :meth:`corrector_samples`;
    :func:`icosim.macrostep.macro_step` only calls these eight members plus
    :attr:`backend`.  The subsystems are advanced in parallel (Jacobi): both
    see only the coupling variables, never each other's new state.
    """

    def __init__(self, decomposition, k: int, backend=None):
        k = check_k(k)  # 0 .. icosim.limits.MAX_K
        self.backend = be = backend or Float64()
        self.decomposition = get_decomposition(decomposition)
        self.k = k
        self.pred_nodes = predictor_nodes(k)
        self.corr_nodes = corrector_nodes(k)
        #: Lagrange weights of the extrapolation (Eq. 9) at ``T_N+1``, in the backend's arithmetic
        self.w_pred = np.array([be.const(w) for w in weights_at(self.pred_nodes, 1)], dtype=be.dtype)
        self.work = Work()

    @property
    def n_coupling(self) -> int:
        """Number of coupling variables ``e`` (per time point)."""
        return self.decomposition.n_coupling

    def extrapolate(self, history):
        """Predicted coupling variables ``e_p`` at ``T_N+1`` (Eq. 9/35/59)."""
        return sum(self.w_pred[j] * history[..., j, :] for j in range(self.k + 1))

    def corrector_samples(self, history, e_new):
        """Samples of the interpolation polynomial (Eq. 11): ``e_new`` at ``T_N+1``, then ``e_N ... e_N-k+1``."""
        return _prepend(e_new, history[..., : self.k, :])

    def shift(self, history, e_new):
        """The history one macro step later: ``e_new`` prepended, the oldest sample dropped."""
        return _prepend(e_new, history[..., :-1, :])

    # -- to be implemented by a subclass ------------------------------------------
    def predict(self, state, history):  # pragma: no cover - contract
        raise NotImplementedError

    def residuals(self, y):  # pragma: no cover - contract
        raise NotImplementedError

    def jacobians(self, state, history, e, y):  # pragma: no cover - contract
        raise NotImplementedError

    def correct(self, state, history, e_new):  # pragma: no cover - contract
        raise NotImplementedError

    def project(self, state):  # pragma: no cover - contract
        raise NotImplementedError(f"{type(self).__name__} has no projection step")


def _prepend(e_new, older):
    """Stack ``e_new`` in front of older samples (leading axes broadcast)."""
    lead = np.broadcast_shapes(e_new.shape[:-1], older.shape[:-2])
    older = np.broadcast_to(older, lead + older.shape[-2:])
    return np.concatenate([np.broadcast_to(e_new, lead + e_new.shape[-1:])[..., None, :], older], axis=-2)
