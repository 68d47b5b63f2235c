"""The coupling conditions' Jacobian at one float64 point (an FMU's macro step) as a sparse map in floats.

The conditions are linear in the outputs and the coupling variables together (:mod:`icosim.engine.residuals`),
so their Jacobian by the coupling variables is linear in the responders' sensitivities, plus a constant (a
multiplier's own entry in a balance of forces).  :class:`PointJacobian` finds that map by applying the general
assembly (:meth:`icosim.engine.problem.CosimulationProblem.jacobians`) to unit vectors -- by linearity, as the
stability matrix is found from the macro step -- so it restates no condition.  It is used only where every
entry is at most two terms, each a sensitivity or a constant times +1 or -1 (a difference of two sides; a
multiplier and a drive's force): a sum of two terms does not depend on their order, so evaluating the entries
in Python floats and multiplying by the levels' factors afterwards, as the general assembly does, gives its
numbers exactly, without numpy's overhead on arrays of a few values.  Larger stages take the general assembly.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .residuals import LEVELS

__all__ = ["PointJacobian", "MAX_ENTRIES"]

#: Above this many entries a loop in Python floats costs more than numpy's assembly.
MAX_ENTRIES = 32


class PointJacobian:
    """``{level: J}`` of one point from its sensitivities as floats, each entry ``(+-s_i +- s_j) * f + c``."""

    def __init__(self, entries: list[tuple[int, float, int, float, float, int]], blocks: list[tuple]):
        self.entries, self.blocks = entries, blocks

    @classmethod
    def make(cls, general: Callable[[np.ndarray], dict[str, np.ndarray]], n: int) -> PointJacobian | None:
        """The map of ``general`` -- the assembly on a stack of ``n`` flattened sensitivities (first axis),
        unscaled, returning each level ``(stack, rows, cols)`` -- or None where it is not of that form."""
        levels = general(np.concatenate([np.eye(n), np.zeros((1, n))]))  # unit vectors, then the constant
        entries, blocks, at = [], [], 0
        for q, key in enumerate(LEVELS):
            values = levels[key].reshape(n + 1, -1)
            blocks.append((key, at, at + values.shape[1], levels[key].shape[1:]))
            at += values.shape[1]
            for column in values.T:
                constant = float(column[n])
                coefficients = column[:n] - constant  # small integers: exact
                terms = [(int(i), float(coefficients[i])) for i in np.flatnonzero(coefficients)]
                if len(terms) + (constant != 0.0) > 2 or constant not in (-1.0, 0.0, 1.0):
                    return None
                if any(c not in (-1.0, 1.0) for _, c in terms):
                    return None
                (i, si), (j, sj) = (terms + [(-1, 0.0), (-1, 0.0)])[:2]
                entries.append((i, si, j, sj, constant, q))
        if len(entries) > MAX_ENTRIES:
            return None
        return cls(entries, blocks)

    def __call__(self, s: list[float], factors: tuple[float, float, float, float]) -> dict[str, np.ndarray]:
        values = []
        for i, si, j, sj, constant, q in self.entries:
            v = 0.0 if i < 0 else s[i] if si > 0 else -s[i]
            if j >= 0:
                v = v + s[j] if sj > 0 else v - s[j]
            f = factors[q]
            if f != 1.0:
                v = v * f
            if constant:
                v = constant + v
            values.append(v)
        out = np.array(values)
        return {key: out[a:b].reshape(shape) for key, a, b, shape in self.blocks}
