"""The conditions of joints and implicitly coupled connections closed together by one corrector (docs/signals.md,
"Joints beside connections").

``problem`` below is a :class:`~icosim.engine.problem.CosimulationProblem` (this module is imported by it).

The unknowns are every joint's coupling variables ``e_j`` and every connection's ``e_c`` at ``T_N+1`` (the joints'
columns of ``e`` first, as the graph orders them).  The conditions are the joints' levels (``pos``, ``vel``,
``acc``, ``force``: :class:`~icosim.engine.residuals.Conditions`, read from the joint units' port outputs) and the
connections' (``signal``: ``e_c - T(y)``, :class:`~icosim.engine.connection_conditions.SignalConditions`), every
unit stepped with its inputs the interpolation polynomials through ``e``.  Their Jacobian in both kinds of variable

.. math::

    J = \\begin{pmatrix} \\partial r_j/\\partial e_j & \\partial r_j/\\partial e_c \\\\
                         -T\\,\\partial y/\\partial e_j & I - T\\,\\partial y/\\partial e_c \\end{pmatrix}

comes from perturbed corrector steps: each joint unit's coupling inputs moved one at a time (its sensitivity, which
gives its port outputs and its connected outputs from the same steps: the first column's blocks, the joint units'
signal outputs by the multipliers) and each connection's variable moved and the unit it feeds stepped again (the
second column's: a joint unit's port outputs by the connections' inputs, and the connections' own block).

The joints' method solves the conditions (:class:`WithSignals`): the connections' rows join every solve of the method after
the force balance, unweighted, so a solve of the method's constraint levels and the balance holds the connections'
conditions too.  Its iteration is Newton's, with the Jacobian formed once per macro step at the predictor, to
``tol (1 + |e|)`` on every variable's change (:meth:`unconverged`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from .connection_conditions import LEVEL, ImplicitWork, SignalConditions
from .graph import CouplingGraph
from .residuals import Conditions

__all__ = ["JointSignalConditions", "WithSignals"]


@dataclass(frozen=True, eq=False)
class JointSignalConditions:
    """Every joint's conditions (read from the joint units ``responders``) and every connection's, at ``T_N+1``."""

    graph: CouplingGraph
    responders: tuple[int, ...]

    @cached_property
    def joints(self) -> Conditions:
        return Conditions(self.graph, range(self.graph.n_joints), self.responders)

    @cached_property
    def signals(self) -> SignalConditions:
        return SignalConditions(self.graph, tuple(range(len(self.graph.connections))))

    @cached_property
    def columns(self) -> tuple[int, ...]:
        """The entries of ``e`` solved for: the joints', then the connections'."""
        return self.joints.columns + self.signals.columns

    @cached_property
    def connections(self) -> tuple[int, ...]:
        return self.signals.connections

    @cached_property
    def targets(self) -> tuple[int, ...]:
        """The units stepped again: every joint unit and every unit a connection feeds."""
        return tuple(sorted(set(self.responders) | set(self.signals.targets)))

    def residuals(self, problem: Any, ys: Sequence[Any], e_s: Any) -> dict[str, Any]:
        """The joints' levels (scaled as the problem's, :meth:`~icosim.engine.problem.CosimulationProblem.residuals`)
        and the connections' ``signal``; ``e_s`` the stage's columns (:attr:`columns`)."""
        n = len(self.joints.columns)
        y = problem.stack([ys[i] for i in self.responders])
        return problem.residuals(y, e_s[..., :n], self.joints) | self.signals.residuals(problem, ys, e_s[..., n:])

    def jacobians(self, problem: Any, state: Any, history: Any, e: Any, ys: Sequence[Any],
                  work: ImplicitWork | None = None) -> dict[str, Any]:  # fmt: skip
        """``d r / d (e_j, e_c)`` at ``e`` (all of ``e``; ``ys`` the outputs there), every level ``(..., rows,
        columns)`` (module docstring)."""
        graph, cons = self.graph, self.graph.connections
        n_j, n_c = len(self.joints.columns), len(self.connections)
        e = np.asarray(e, dtype=float)
        base = self.signals._transformed(problem, ys)
        # joint variables: the joint units' sensitivities, their port and their connected outputs
        ports, signal_rows = [], np.zeros(base.shape[:-1] + (n_c, n_j))
        for i in self.responders:
            S, S_signals = problem.output_sensitivities(i, state, history, e, ys[i])
            B = graph.input_matrix(i, self.joints.columns)  # (inputs, joint columns)
            ports.append(np.moveaxis(np.tensordot(S, B, axes=([-4], [0])), -1, -4))
            for row, c in enumerate(self.connections):
                if cons[c].source == i and S_signals is not None:  # -T dy/de_j
                    signal_rows[..., row, :] = -cons[c].factor * (np.moveaxis(S_signals, -1, 0)[cons[c].output] @ B)
        dE = np.eye(n_j)
        joint_by_joint = problem.residuals(problem.stack(ports), dE, self.joints)
        # connections' variables: the unit each feeds stepped again
        joint_by_signal = {key: np.zeros(v.shape[:-2] + (v.shape[-2], n_c)) for key, v in
                           ((k, np.swapaxes(a, -1, -2)) for k, a in joint_by_joint.items())}  # fmt: skip
        signal_by_signal = np.zeros(base.shape[:-1] + (n_c, n_c))
        y0 = problem.stack([ys[i] for i in self.responders])
        r0 = problem.residuals(y0, np.zeros(n_j), self.joints)
        for j, perturbed, delta, rows in self.signals.perturbed_outputs(problem, state, history, e, ys, work):
            unit = cons[self.connections[j]].target
            if rows:
                moved_T = self.signals._transformed(problem, perturbed)
                signal_by_signal[..., rows, j] = -(moved_T[..., rows] - base[..., rows]) / delta
            if unit in self.responders:  # its port outputs: the joints' conditions by the connection's input
                r1 = problem.residuals(problem.stack([perturbed[i] for i in self.responders]), np.zeros(n_j),
                                       self.joints)  # fmt: skip
                for key in r1:
                    joint_by_signal[key][..., j] = (r1[key] - r0[key]) / delta
        signal_by_signal = signal_by_signal + np.eye(n_c)
        out = {key: np.concatenate([np.swapaxes(joint_by_joint[key], -1, -2), joint_by_signal[key]], axis=-1)
               for key in joint_by_joint}  # fmt: skip
        out[LEVEL] = np.concatenate([signal_rows, signal_by_signal], axis=-1)
        return out

    def unconverged(self, e_new: Any, e_s: Any, tol: float) -> list[int]:
        """The entries of :attr:`columns` (their positions) whose variable changed by more than ``tol (1 + |e|)``."""
        change = np.abs(np.asarray(e_new, dtype=float) - np.asarray(e_s, dtype=float))
        bound = tol * (1.0 + np.abs(np.asarray(e_new, dtype=float)))
        over = np.any((change > bound) | ~np.isfinite(change), axis=tuple(range(change.ndim - 1)))
        return [int(j) for j in np.flatnonzero(np.atleast_1d(over))]

    def describe(self, problem: Any, bad: Sequence[int], change: Any) -> str:
        """The variables of ``bad`` (positions in :attr:`columns`) and their change, for a message."""
        names = self.graph.variable_names()
        n_j = len(self.joints.columns)
        return ", ".join(
            (f"{names[self.columns[j]]} of the joints" if j < n_j else problem.describe_connection(self.connections[j - n_j]))
            + f" (change {np.max(change[..., j]):.3g})" for j in bad)  # fmt: skip


@dataclass(frozen=True)
class WithSignals:
    """A joints' method whose every solve also holds the connections' conditions (level ``signal``, stacked after
    the force balance, unweighted: :func:`icosim.engine.methods.base._conditions`)."""

    method: Any

    @property
    def name(self) -> str:
        return self.method.name

    @property
    def projection(self) -> bool:
        return self.method.projection

    @property
    def n_solves(self) -> int:
        return self.method.n_solves

    def corrected_coupling(self, e_pred: np.ndarray, residuals: Mapping[str, np.ndarray],
                           jacobians: Mapping[str, np.ndarray], backend: Any, factors: Any = None) -> np.ndarray:  # fmt: skip
        return self.method.corrected_coupling(e_pred, _joined(residuals, -1), _joined(jacobians, -2), backend)


def _joined(parts: Mapping[str, np.ndarray], axis: int) -> dict[str, np.ndarray]:
    """The joints' levels with the connections' rows after the force balance's (on ``axis``)."""
    out = {key: value for key, value in parts.items() if key != LEVEL}
    out["force"] = np.concatenate([parts["force"], parts[LEVEL]], axis=axis)
    return out
