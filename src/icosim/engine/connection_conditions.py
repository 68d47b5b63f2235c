"""The conditions of signal connections coupled implicitly, closed by the one corrector (docs/signals.md).

``problem`` below is a :class:`~icosim.engine.problem.CosimulationProblem` (this module is imported by it).

A connection ``c`` (:class:`~icosim.engine.graph.Connection`) is the condition ``u_in = T(y_out)``, ``T(y) =
factor * y + offset``.  Coupled implicitly it holds at ``T_N+1``: the unknowns are the connections' variables
``e_c`` at ``T_N+1`` (their columns of ``e``); each unit is integrated over ``[T_N, T_N+1]`` with its inputs the
interpolation polynomial through ``e_c`` and the past samples (the corrector, Eq. 11), and the residual is

    r(e_c) = e_c - T(y(e_c)),

rows in the connections' order (level ``"signal"``).  Its Jacobian ``J = I - T dy/de_c`` comes from perturbed
corrector steps: each column's variable moved by ``delta`` and the unit it feeds stepped again from ``T_N``
(:meth:`SignalConditions.jacobians`), one step per column; a stateful problem restores the unit from the state it
saved at ``T_N`` before every step (:meth:`~icosim.engine.problem.CosimulationProblem.correct`).  The corrector
closes the conditions by Newton's rule (:mod:`icosim.engine.methods.newton`) from the predictor's ``e_p``, with
the Jacobian formed once per macro step, at ``e_p``; it converges when no variable changes by more than ``tol (1
+ |e_c|)`` (absolute below one, relative above), else the step fails naming the connections
(:class:`NotConverged`).

The last stage closes every connection and steps again every unit one feeds (:func:`icosim.engine.stages.plan`
with ``implicit``): a unit's step depends on ``e_c`` and its state at ``T_N`` only, so the conditions are one system
in ``e_c`` in any order of the units; Gauss-Seidel's earlier stages move Newton's start (Jacobi's one stage closes
them from ``e_p``).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from ..errors import StepFailure
from .graph import CouplingGraph

__all__ = ["SignalConditions", "ImplicitWork", "NotConverged", "LEVEL"]

#: The residuals' level name (the joints' are pos, vel, acc, force: :data:`icosim.engine.residuals.LEVELS`).
LEVEL = "signal"


class NotConverged(StepFailure):
    """Newton's iteration of implicitly coupled connections did not converge within its iterations."""


@dataclass
class ImplicitWork:
    """What the implicit connections cost: the Newton iterations of each macro step (corrector passes) and the
    perturbed steps of their Jacobians, since the last :meth:`reset`."""

    iterations: list = field(default_factory=list)
    perturbed_steps: int = 0

    def reset(self) -> None:
        self.iterations, self.perturbed_steps = [], 0


@dataclass(frozen=True, eq=False)
class SignalConditions:
    """The conditions of ``connections`` (indices into ``graph.connections``) at ``T_N+1``."""

    graph: CouplingGraph
    connections: tuple[int, ...]

    @cached_property
    def columns(self) -> tuple[int, ...]:
        """The entries of ``e`` the conditions solve for: the connections' variables, in their order."""
        return tuple(self.graph.connection_column(c) for c in self.connections)

    @cached_property
    def targets(self) -> tuple[int, ...]:
        """The units the connections feed: those the corrector steps again (and the Jacobian's columns perturb); a
        unit only read is final after its predictor step."""
        cons = self.graph.connections
        return tuple(sorted({cons[c].target for c in self.connections}))

    def _transformed(self, problem: Any, ys: Sequence[Any]) -> Any:
        cons = self.graph.connections
        values = [cons[c].factor * problem.signal_output(cons[c].source, ys[cons[c].source], cons[c].output)
                  + cons[c].offset for c in self.connections]  # fmt: skip
        return np.stack(np.broadcast_arrays(*values), axis=-1)

    def residuals(self, problem: Any, ys: Sequence[Any], e_s: Any) -> dict[str, Any]:
        """``e_c - T(y)``: ``e_s`` the connections' variables (``(..., n_c)``, the stage's columns), ``ys[i]`` unit
        ``i``'s outputs from its step with them."""
        return {LEVEL: np.asarray(e_s) - self._transformed(problem, ys)}

    def jacobians(self, problem: Any, state: Any, history: Any, e: Any, ys: Sequence[Any],
                  work: ImplicitWork | None = None) -> dict[str, Any]:  # fmt: skip
        """``d r / d e_c = I - T dy/de_c`` at ``e`` (all of ``e``; ``ys`` the outputs there), ``(..., n_c, n_c)``:
        per column the unit it feeds stepped once more with the variable moved by ``p max(1, |e_c|)`` (forward
        differences, ``p`` the problem's :attr:`~icosim.engine.problem.CosimulationProblem.connection_perturbation`;
        the unit restores its state at ``T_N`` itself)."""
        n = len(self.connections)
        base = self._transformed(problem, ys)
        dT = np.zeros(base.shape[:-1] + (n, n))
        for j, perturbed, delta, rows in self.perturbed_outputs(problem, state, history, e, ys, work):
            if rows:
                dT[..., rows, j] = (self._transformed(problem, perturbed)[..., rows] - base[..., rows]) / delta
        return {LEVEL: np.eye(n) - dT}

    def perturbed_outputs(self, problem: Any, state: Any, history: Any, e: Any, ys: Sequence[Any],
                          work: ImplicitWork | None = None) -> Iterator[tuple[int, list[Any], float, list[int]]]:  # fmt: skip
        """Per connection ``j``: the outputs ``ys`` with the unit it feeds stepped once more, its variable moved by
        ``delta = p max(1, |e_c|)``, and the rows (connections) that unit's outputs feed -- the forward differences
        of every Jacobian by the connections' variables."""
        cons, graph = self.graph.connections, self.graph
        e = np.asarray(e, dtype=float)
        for j, c in enumerate(self.connections):
            col, unit = graph.connection_column(c), cons[c].target
            delta = problem.connection_perturbation * max(1.0, float(np.max(np.abs(e[..., col]), initial=0.0)))
            moved = np.array(e, copy=True)
            moved[..., col] += delta
            _, y_unit = problem.correct(unit, state, history, moved)
            if work is not None:
                work.perturbed_steps += 1
            perturbed = list(ys)
            perturbed[unit] = y_unit
            yield j, perturbed, delta, [d for d, c_d in enumerate(self.connections) if cons[c_d].source == unit]

    def describe(self, problem: Any, bad: Sequence[int], change: Any) -> str:
        """The connections ``bad`` and their variables' change (``(..., n_c)``), for a message."""
        return ", ".join(f"{problem.describe_connection(c)} (change {np.max(change[..., self.connections.index(c)]):.3g})"
                         for c in bad)  # fmt: skip

    def unconverged(self, e_new: Any, e_s: Any, tol: float) -> list[int]:
        """The connections whose variable changed by more than ``tol (1 + |e_c|)`` (any point of a batch)."""
        change = np.abs(np.asarray(e_new, dtype=float) - np.asarray(e_s, dtype=float))
        bound = tol * (1.0 + np.abs(np.asarray(e_new, dtype=float)))
        over = np.any((change > bound) | ~np.isfinite(change), axis=tuple(range(change.ndim - 1)))
        return [self.connections[j] for j in np.flatnonzero(np.atleast_1d(over))]
