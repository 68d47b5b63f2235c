"""The coupling conditions of joints, formed in one place with one sign convention.

Per port, every problem reports the position, velocity and acceleration of the port and the force it sees
(:mod:`icosim.engine.graph`).  The conditions of a joint are differences **first side minus second**:

* the joint constraint ``g`` on the position, velocity and acceleration levels, where the joint's
  decomposition has it (a force-driven side, :attr:`~icosim.engine.decompositions.Decomposition.has_constraint_condition`);
* the balance of the coupling forces, where a side is kinematically driven: ``f_first - f_second`` with each
  side's force in the convention of the joint's multiplier (``+lambda_j`` acts on the first side,
  ``-lambda_j`` on the second): a force-driven side's is ``lambda_j`` itself, a kinematically driven side's
  is the force its drive exerts, ``+R`` on the first side and ``-R`` on the second.  (``fd``:
  ``lambda_j + R_2 = 0``, the drive of the second side exerts what the joint would: ``-lambda_j``.)

A problem whose levels are not in the engine's dimensionless time scales them (``scale``: ``g``, ``H g'``,
``H^2 g''``).  The conditions are linear in the outputs and the coupling variables together, so the same
function maps output sensitivities to the conditions' Jacobian
(:meth:`icosim.engine.problem.CosimulationProblem.jacobians`).

Rows: the constraint rows of the joints that have one, in the joints' order, ``n_c`` each; then the balance
rows of those that have one, in the joints' order, ``n_c`` each.

>>> import numpy as np
>>> from icosim.engine.graph import CouplingGraph
>>> g = CouplingGraph.pair("fd")
>>> y = np.array([[1.0, 2.0, 3.0, 4.0], [0.5, 2.5, 3.0, -1.0]])[..., None]  # two ports, one component
>>> r = Conditions(g, (0,), (0, 1))(y, np.array([4.0, 3.0]))  # e = (lambda_c, a_tilde_1)
>>> [r[key].tolist() for key in ("pos", "vel", "acc", "force")]
[[0.5], [-0.5], [0.0], [3.0]]
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property
from typing import Any

import numpy as np

from .graph import FORCE, CouplingGraph

__all__ = ["Conditions", "LEVELS", "plain_factors", "level_factors"]

#: The levels of the conditions: the constraint on three levels, the balance of forces.
LEVELS = ("pos", "vel", "acc", "force")


def _index(positions: Sequence[int]) -> Any:
    """An index of the port axis: an int for one port (the axis dropped, no copy), else an array."""
    return positions[0] if len(positions) == 1 else np.array(positions)


def plain_factors(scale: Sequence[Any] | None) -> tuple[float, float, float, float] | None:
    """The levels' factors as floats (the balance of forces: 1), or None where the constraint levels' are not
    plain numbers (then each level is multiplied in their own arithmetic)."""
    if scale is None:
        return (1.0, 1.0, 1.0, 1.0)
    if all(type(f) is float or type(f) is int for f in scale[:3]):
        return (float(scale[0]), float(scale[1]), float(scale[2]), 1.0)
    return None


def level_factors(scale: Sequence[Any], dtype: Any) -> np.ndarray | None:
    """The constraint levels' factors as a float64 column ``(3, 1)`` where they and the outputs (``dtype``) are
    float64 -- one product scales the three levels, as level by level -- else None (each level is multiplied
    in the numbers' own arithmetic)."""
    if dtype != np.float64 or plain_factors(scale) is None:
        return None
    return np.array([float(f) for f in scale[:3]])[:, None]


class Conditions:
    """The coupling conditions of ``joints`` of ``graph``, read from the outputs of ``units``.

    Called with ``y`` -- the outputs of ``units`` stacked port after port, ``(..., n_ports, 4, n_c)`` -- and
    ``e`` -- the joints' coupling variables, :attr:`columns` of the graph's ``e``, on the last axis -- it
    returns ``{pos, vel, acc, force}`` (rows on the last axis; a level no joint has is empty).  A
    force-driven side of a subsystem in ``held`` saw the multiplier as it was when it integrated, not as it
    is corrected (a finished subsystem whose outputs stay as integrated): its ``lambda_j`` is read from
    ``e_held``.  ``scale`` multiplies the constraint's levels; ``factors``, its :func:`level_factors` where
    the caller keeps them (a problem's, formed once per scale).  The conditions hold no state.
    """

    def __init__(self, graph: CouplingGraph, joints: Sequence[int], units: Sequence[int], held: Sequence[int] = ()):
        self.graph, self.joints, self.units = graph, tuple(joints), tuple(units)
        held_units = set(held)
        offsets, at = {}, 0
        for i in self.units:
            offsets[i] = at
            at += graph.ports[i]
        n_c = graph.n_components
        #: the entries of the graph's ``e`` that are these joints' coupling variables
        self.columns = tuple(c for j in self.joints for c in graph.columns(j))
        local = {c: n for n, c in enumerate(self.columns)}

        def position(i: int, p: int) -> int:
            return offsets[i] + p

        joints_ = [graph.joints[j] for j in self.joints]
        constrained = [jt for jt in joints_ if jt.decomposition.has_constraint_condition]
        self._first = _index([position(*jt.sides[0]) for jt in constrained])
        self._second = _index([position(*jt.sides[1]) for jt in constrained])
        self._n_constraint = len(constrained) * n_c
        # balance rows: f_first - f_second with lambda_j (force-driven side) or +-R (kinematically driven)
        self._balance: list[list[tuple[str, Any, float]]] = []
        for j, jt in zip(self.joints, joints_):
            if not jt.decomposition.has_force_balance:
                continue
            parts: list[tuple[str, Any, float]] = []
            for side, sign in ((0, 1.0), (1, -1.0)):
                if jt.decomposition.kinds[side] == "force":
                    v = graph._variable(j, "force")
                    first = local[graph.columns(j)[v * n_c]]
                    what = "held" if jt.sides[side][0] in held_units else "lambda"
                    parts.append((what, slice(first, first + n_c), sign))
                else:  # the drive's force in the multiplier's convention: +R first side, -R second
                    parts.append(("reaction", position(*jt.sides[side]), sign * (1.0 if side == 0 else -1.0)))
            self._balance.append(parts)
        self._n_balance = len(self._balance) * n_c

    @cached_property
    def n_rows(self) -> dict[str, int]:
        return {"pos": self._n_constraint, "vel": self._n_constraint, "acc": self._n_constraint,
                "force": self._n_balance}  # fmt: skip

    def __call__(
        self, y: Any, e: Any, *, scale: Sequence[Any] | None = None, e_held: Any = None, factors: Any = None
    ) -> dict[str, Any]:
        out = {}
        if self._n_constraint:
            first, second = self._first, self._second
            # the three levels at once: (..., [joint,] level, component)
            diff = y[..., first, :3, :] - y[..., second, :3, :]
            several = not isinstance(first, int)
            if factors is None and scale is not None:
                factors = level_factors(scale, diff.dtype)
            if factors is not None:
                diff = diff * factors  # each level times its own factor, as level by level
            for q, key in enumerate(("pos", "vel", "acc")):
                level = diff[..., q, :]
                if several:  # several joints: (..., joint, component) -> rows
                    level = level.reshape(level.shape[:-2] + (-1,))
                out[key] = level if scale is None or factors is not None else scale[q] * level
        else:
            empty = self._empty(y, e)
            out.update(pos=empty, vel=empty, acc=empty)
        if self._balance:
            held = e if e_held is None else e_held
            rows = [self._balance_row(parts, y, e, held) for parts in self._balance]
            out["force"] = rows[0] if len(rows) == 1 else np.concatenate(np.broadcast_arrays(*rows), axis=-1)
        else:
            out["force"] = self._empty(y, e)
        return out

    @staticmethod
    def _empty(y: Any, e: Any) -> Any:
        """No rows (a level no joint has)."""
        lead, other = y.shape[:-3], e.shape[:-1]
        return np.zeros((lead if lead == other else np.broadcast_shapes(lead, other)) + (0,), dtype=y.dtype)

    @staticmethod
    def _balance_row(parts: list, y: Any, e: Any, held: Any) -> Any:
        """``f_first - f_second`` of one joint (``parts``: how each side's force is read, with its sign in
        the difference and, for a drive, the side's sign)."""
        total = None
        for what, where, sign in parts:
            source = {"lambda": e, "held": held}.get(what)
            value = source[..., where] if source is not None else y[..., where, FORCE, :]
            if total is None:
                total = value if sign > 0 else -value
            else:
                total = total + value if sign > 0 else total - value
        return total
