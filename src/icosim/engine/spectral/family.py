"""What the spectral analysis asks of a model: a family of linear co-simulation problems over parameter points.

The engine knows no model.  A model whose macro step is linear in the state and the coupling history (the
linear two-mass model, a linear chain: :mod:`icosim.problems.linear`) offers its points as a
:class:`LinearFamily`: a grid of points, each point one configuration of one coupling graph (its subsystems, joints and
their decompositions) and order ``k``.
The engine forms the amplification matrix from the macro step by linearity
(:func:`icosim.engine.spectral.matrix.amplification_matrix`), its spectral radius in float64 with an error
estimate, at any precision, and certified in ball arithmetic, and applies the precision policy -- asking the
family only what follows.

A family's problem (:meth:`LinearFamily.problem`) is a :class:`~icosim.engine.problem.CosimulationProblem`
whose state and coupling history pack into one vector (``n_state``, ``pack(state, history)``,
``unpack(w)``: the coordinates the matrix acts on) and, in float64, can be disturbed at the size of its
rounding (``disturbed(rng, rel)``, a copy; ``generator_norm()``, per point, the norm that bounds how its
inputs' rounding grows: the float64 error estimate of :mod:`icosim.engine.spectral.radius`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Sequence

    import numpy as np

    from ..backends import Backend
    from ..graph import CouplingGraph
    from ..methods.base import CouplingMethod
    from ..schemes import Scheme

__all__ = ["LinearFamily"]


class LinearFamily(ABC):
    """Parameter points of one linear co-simulation problem (one coupling graph, one ``k``), as the spectral
    analysis asks for them.  Points are addressed by index tuples of :attr:`shape`."""

    #: the coupling graph (:class:`~icosim.engine.graph.CouplingGraph`) and the order k
    graph: CouplingGraph = None  # type: ignore[assignment]  # a placeholder: every family sets its own
    k: int = 0
    #: why a point whose derived quantities overflow float64 is undecided
    overflow_reason = "overflow: a derived quantity of the model is not finite in float64"

    @property
    @abstractmethod
    def shape(self) -> tuple:
        """The shape of the grid of points."""

    @abstractmethod
    def problem(self, backend: Backend, *, exact: bool = False) -> Any:
        """The problem over every point in ``backend``'s arithmetic, with a trailing axis of length one for the
        basis vectors the macro step is applied to.  ``exact``: the point's parameters taken as the exact
        numbers they are (a float as its binary value, a decimal string as the decimal) and every derived
        quantity formed in the backend (multiprecision, balls); else float64 arrays."""

    @abstractmethod
    def point(self, index: tuple[int, ...]) -> LinearFamily:
        """The family of the one point at ``index`` (its parameters as given, for an exact recomputation)."""

    @abstractmethod
    def subset(self, mask: np.ndarray) -> LinearFamily:
        """The points where the boolean array ``mask`` (of :attr:`shape`) holds, as a flat grid."""

    @abstractmethod
    def overflowing(self) -> np.ndarray:
        """A boolean array of :attr:`shape`: points whose derived quantities are not finite in float64."""

    @abstractmethod
    def safe(self, mask: np.ndarray) -> LinearFamily:
        """The grid with the points where ``mask`` holds replaced by harmless ones (computed, then discarded)."""

    @abstractmethod
    def guard_bits(self) -> int:
        """Bits a ball computation of this one point needs on top of the target precision (entries as small as
        ``exp(-decay)`` of a heavily damped subsystem)."""

    @classmethod
    @abstractmethod
    def stack(cls, points: Sequence[LinearFamily], backend: Backend) -> LinearFamily:
        """Single points (their exact parameters in ``backend``) as one grid: a leading axis of object arrays,
        on which the backend does for every point what it does for that point alone."""

    def check(self, method: CouplingMethod | None, scheme: Scheme) -> None:
        """Refuse (:class:`~icosim.errors.ParameterError`) a method or scheme the graph cannot take."""
        from ..stages import plan

        plan(scheme, self.graph, method)
