"""The co-simulation problem: what :func:`icosim.engine.macrostep.macro_step` needs of it.

A problem couples two subsystems through the coupling variables ``e`` of its
decomposition.  :class:`CosimulationProblem` holds what every problem shares --
the decomposition, the approximation order ``k``, the arithmetic, the
extrapolation (Eq. 9/35/59) and shift of the coupling history, the samples the
corrector's interpolation polynomial runs through (Eq. 11), and a count of the
work done -- and states the contract a subclass meets.  The linear test model
(:class:`icosim.problems.linear.problem.LinearCosimulation`) and the double pendulum
(:class:`icosim.problems.pendulum.problem.PendulumCosimulation`) are the two subclasses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from . import layout
from .backends import Backend, Float64
from .bounds import check_k
from .decompositions import Decomposition, get_decomposition
from .lagrange import corrector_nodes, predictor_nodes, weights_at

__all__ = ["CosimulationProblem", "Work"]


@dataclass
class Work:
    """Work done by a problem since the last :meth:`reset`.

    ``subsystem_integrations`` counts calls of a subsystem integrator (a
    batched call counts once), ``coupling_solves`` linear solves of coupling
    conditions, ``projections`` projection steps.  The problems count their
    integrations, :func:`icosim.engine.macrostep.macro_step` the solves and
    projections.
    """

    subsystem_integrations: int = 0
    coupling_solves: int = 0
    projections: int = 0

    def reset(self) -> None:
        self.subsystem_integrations = self.coupling_solves = self.projections = 0

    def as_dict(self) -> dict:
        return asdict(self)


class CosimulationProblem:
    """Base class of co-simulation problems (two subsystems, any coupling scheme).

    Arrays: the state ``s`` is the subsystems' states at ``T_N`` (layout set by
    the subclass); the coupling history ``h[..., j, :] = e_N-j``, ``j = 0..k``;
    the outputs ``y`` at ``T_N+1`` are what the coupling conditions are formed
    from.  Leading batch axes are allowed wherever the subclass allows them.

    The problem knows nothing of the order in which its subsystems advance:
    :func:`icosim.engine.macrostep.macro_step` drives each subsystem ``i`` (0 or 1)
    separately, as the scheme (:mod:`icosim.engine.schemes`: Jacobi, Gauss-Seidel)
    says.  A subclass calls ``super().__init__(decomposition, k, backend)`` and
    implements, per subsystem ``i``:

    ``predict(i, state, history, *, final=False) -> (end_i, y_i)``
        subsystem ``i`` integrated over the macro step with the extrapolation
        polynomials through the history (Eq. 9/35/59): its state ``end_i`` at
        ``T_N+1`` and its outputs ``y_i``.  ``final=True`` says the subsystem
        leads a sequential scheme: ``end_i`` is final and no gradient through
        its integration will be asked for (a problem that computes gradients
        in the same pass may skip them).
    ``correct(i, state, history, e_new) -> (end_i, y_i)``
        subsystem ``i`` integrated with the interpolation polynomials through
        :meth:`corrector_samples` (Eq. 11).
    ``reevaluate(i, end_i, y_i, e_old, e_new) -> y_i``
        the outputs of subsystem ``i`` at its fixed end state ``end_i``,
        re-evaluated with the coupling variables ``e_new`` at ``T_N+1``
        instead of ``e_old`` (only the outputs its equations of motion tie
        algebraically to the input at ``T_N+1`` change: acceleration, coupling
        force, multiplier).

    and, for the coupled pair,

    ``join(ends) -> state`` and ``stack(ys) -> y``
        the subsystems' end states and outputs as one state and one output array.
    ``residuals(y) -> dict``
        the coupling conditions at ``T_N+1``: ``pos``, ``vel``, ``acc`` (the
        constraint on each level, shape ``(..., n_c)``) and ``force`` (balance
        of the multipliers of kinematically driven subsystems, ``(..., n_f)``).
    ``jacobians(state, history, e, y, fixed=(None, None), algebraic=True) -> dict``
        ``d residuals / d e_N+1`` at ``e`` for the same levels, shape
        ``(..., n, n_e)``.  ``fixed[i] is None``: subsystem ``i`` responds
        through its corrector integration (full gradients, Eq. 13/39/63);
        otherwise ``fixed[i]`` is its final end state and it responds only
        algebraically (as :meth:`reevaluate`), or, with ``algebraic=False``,
        not at all (its outputs stay as integrated).
    ``project(state) -> state``
        the projection step (needed by methods that project).

    and counts each subsystem integration in :attr:`work`.  The base class
    provides :meth:`extrapolate`, :meth:`shift` and :meth:`corrector_samples`;
    :func:`icosim.engine.macrostep.macro_step` only calls these members plus
    :attr:`backend`.
    """

    def __init__(self, decomposition: str | Decomposition, k: int, backend: Backend | None = None) -> None:
        k = check_k(k)  # 0 .. icosim.engine.bounds.MAX_K
        self.backend = be = backend or Float64()
        self.decomposition = get_decomposition(decomposition)
        self.k = k
        self.pred_nodes = predictor_nodes(k)
        self.corr_nodes = corrector_nodes(k)
        #: Lagrange weights of the extrapolation (Eq. 9) at ``T_N+1``, in the backend's arithmetic
        self.w_pred = np.array([be.const(w) for w in weights_at(self.pred_nodes, 1)], dtype=be.dtype)
        self.work = Work()
        self._extrapolated: tuple = (None, None, None)  # (history, weights, e_p) of the last extrapolation

    @classmethod
    def check_decomposition(cls, decomposition: str | Decomposition) -> None:
        """Refuse (:class:`~icosim.errors.ParameterError`) a decomposition whose coupling conditions this
        problem cannot form; the linear test model forms them for every registered one."""

    @property
    def n_coupling(self) -> int:
        """Number of coupling variables ``e`` (per time point)."""
        return self.decomposition.n_coupling

    def extrapolate(self, history: np.ndarray) -> np.ndarray:
        """Predicted coupling variables ``e_p`` at ``T_N+1`` (Eq. 9/35/59).  A macro step asks for it once and
        every predictor again: the last one is kept (for the same history and weights)."""
        last_history, last_weights, e_p = self._extrapolated
        if last_history is history and last_weights is self.w_pred:
            return e_p
        e_p = sum(self.w_pred[j] * history[..., j, :] for j in range(self.k + 1))
        self._extrapolated = (history, self.w_pred, e_p)
        return e_p

    def corrector_samples(self, history: np.ndarray, e_new: np.ndarray) -> np.ndarray:
        """Samples of the interpolation polynomial (Eq. 11): ``e_new`` at ``T_N+1``, then ``e_N ... e_N-k+1``."""
        return _prepend(e_new, history[..., : self.k, :])

    def shift(self, history: np.ndarray, e_new: np.ndarray) -> np.ndarray:
        """The history one macro step later: ``e_new`` prepended, the oldest sample dropped."""
        return _prepend(e_new, history[..., :-1, :])

    # -- to be implemented by a subclass ------------------------------------------
    def predict(  # pragma: no cover - contract
        self, i: int, state: np.ndarray, history: np.ndarray, *, final: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def correct(  # pragma: no cover - contract
        self, i: int, state: np.ndarray, history: np.ndarray, e_new: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def reevaluate(  # pragma: no cover - contract
        self, i: int, end: np.ndarray, y: np.ndarray, e_old: np.ndarray, e_new: np.ndarray
    ) -> np.ndarray:
        raise NotImplementedError

    def join(self, ends: Sequence[np.ndarray]) -> np.ndarray:  # pragma: no cover - contract
        raise NotImplementedError

    def stack(self, ys: Sequence[np.ndarray]) -> np.ndarray:  # pragma: no cover - contract
        raise NotImplementedError

    def residuals(self, y: np.ndarray) -> dict[str, np.ndarray]:  # pragma: no cover - contract
        raise NotImplementedError

    def jacobians(  # pragma: no cover - contract
        self,
        state: np.ndarray,
        history: np.ndarray,
        e: np.ndarray,
        y: np.ndarray,
        fixed: Sequence[np.ndarray | None] = (None, None),
        algebraic: bool = True,
    ) -> dict[str, np.ndarray]:
        raise NotImplementedError

    def project(self, state: np.ndarray) -> np.ndarray:  # pragma: no cover - contract
        raise NotImplementedError(f"{type(self).__name__} has no projection step")


def _prepend(e_new: np.ndarray, older: np.ndarray) -> np.ndarray:
    """Stack ``e_new`` in front of older samples (leading axes broadcast)."""
    if e_new.ndim == 1 and older.ndim == 2:  # one point (the pendulum's every macro step): no broadcasting
        return np.concatenate([e_new[None, :], older])
    lead = np.broadcast_shapes(e_new.shape[:-1], older.shape[:-2])
    older = np.broadcast_to(older, lead + older.shape[-2:])
    return layout.concatenate([np.broadcast_to(e_new, lead + e_new.shape[-1:])[..., None, :], older], axis=-2)
