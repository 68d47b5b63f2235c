"""The linear two-mass model's parameter points as a family of the engine's spectral analysis.

:class:`TwoMass` holds a :class:`~icosim.problems.linear.model.TestModel` (Eq. 71), a
:class:`~icosim.problems.linear.model.PhysicalModel` or :class:`~icosim.problems.linear.model.Coefficients`
whose attributes broadcast to a grid, with the decomposition and the order ``k``, and answers what
:class:`icosim.engine.spectral.family.LinearFamily` asks: the problem over the grid
(:class:`~icosim.problems.linear.problem.LinearCosimulation`), single points taken exactly, the points whose
coefficients overflow float64, the guard bits of a heavily damped subsystem.

>>> from icosim import TestModel
>>> f = TwoMass(TestModel([-0.1, -0.2], 0.5), "ff", k=1)
>>> f.shape, f.point((1,)).model.lr1
((2,), -0.2)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ...engine import layout
from ...engine.bounds import check_finite
from ...engine.decompositions import get_decomposition
from ...engine.graph import CouplingGraph
from ...engine.spectral.family import LinearFamily
from .model import Coefficients, PhysicalModel, TestModel, eq71_coefficients
from .problem import LinearCosimulation
from .subsystems import decay_rate

__all__ = ["TwoMass", "OVERFLOW"]

#: Why a point of the two-mass model is undecided when its coefficients overflow float64.
OVERFLOW = "overflow: a derived coefficient (k1, delta1, k2, delta2) is not finite in float64"


@dataclass(frozen=True)
class TwoMass(LinearFamily):
    """Points of the two-mass model for one decomposition and ``k``.

    ``converted``: the attributes are already numbers of the backend they will be used in (a stack of exact
    points, :meth:`stack`), not to be converted again.
    """

    model: object
    decomposition: object
    k: int
    converted: bool = False

    def __post_init__(self):
        model = self.model
        if isinstance(model, PhysicalModel):
            model = model.coefficients()
        if not isinstance(model, (TestModel, Coefficients)):
            model = model.coefficients()
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "decomposition", get_decomposition(self.decomposition))

    @property
    def graph(self) -> CouplingGraph:
        """The paper's two subsystems joined by the decomposition's joint."""
        return CouplingGraph.pair(self.decomposition)

    @property
    def _names(self):
        return tuple(f.name for f in fields(self.model))

    def _arrays(self):
        return [np.asarray(getattr(self.model, n)) for n in self._names]

    @property
    def shape(self) -> tuple:
        return np.broadcast_shapes(*(a.shape for a in self._arrays()))

    def coefficients(self, backend=None) -> Coefficients:
        """The subsystem coefficients: float64 arrays, or (``backend``) every derived quantity formed in its
        arithmetic from the parameters taken exactly."""
        m = self.model
        if backend is None or self.converted:
            return m.coefficients() if isinstance(m, TestModel) else m
        values = (backend.const(getattr(m, n)) for n in self._names)
        if isinstance(m, TestModel):  # checked when it was made: its values as exact numbers need no second check
            return eq71_coefficients(*values)
        return Coefficients(*values)

    def problem(self, backend, *, exact: bool = False):
        c = self.coefficients(backend if exact else None)
        c = c.map(lambda a: layout.batched(backend.asarray(a)[..., None]))  # room for the basis vectors
        return LinearCosimulation(c, self.decomposition, self.k, backend)

    def point(self, index) -> TwoMass:
        arrays = np.broadcast_arrays(*(np.asarray(getattr(self.model, n), dtype=float) for n in self._names))
        return TwoMass(type(self.model)(*(float(a[index]) for a in arrays)), self.decomposition, self.k)

    def subset(self, mask) -> TwoMass:
        c = self.coefficients()
        shape = self.shape
        return TwoMass(c.map(lambda a: np.broadcast_to(np.asarray(a, dtype=float), shape)[mask]), self.decomposition,
                       self.k)  # fmt: skip

    def overflowing(self):
        shape = self.shape
        with np.errstate(all="ignore"):
            c = self.coefficients()
            bad = np.zeros(shape, dtype=bool)
            for name in ("k1", "delta1", "k2", "delta2"):
                bad |= ~np.isfinite(np.broadcast_to(np.asarray(getattr(c, name), dtype=float), shape))
        return bad

    overflow_reason = OVERFLOW

    def safe(self, mask) -> TwoMass:
        arrays = np.broadcast_arrays(*(np.asarray(getattr(self.model, n), dtype=float) for n in self._names))
        safe = [np.where(mask, 0.0, a) if a.dtype.kind == "f" else a for a in arrays]
        return TwoMass(type(self.model)(*safe), self.decomposition, self.k)

    def guard_bits(self) -> int:
        """Extra bits for entries as small as ``exp(-decay)`` (a heavily damped subsystem over one macro step).

        The propagators hold entries of size ``exp(-decay)`` next to O(1) ones; their differences need
        ``decay / ln 2`` more bits for the same relative accuracy (the ball radii would otherwise swallow
        them, honestly but uselessly).  ``decay`` is the largest ``-Re`` of a subsystem eigenvalue, in macro
        steps.
        """
        c = self.coefficients()
        decay = 0.0
        for name, k, d in (("1", c.k1, c.delta1), ("2", c.k2, c.delta2)):
            check_finite(f"k{name}", k)
            check_finite(f"delta{name}", d)
            decay = max(decay, float(decay_rate(float(k), float(d))))
        bits = decay / math.log(2)
        return int(math.ceil(bits)) if bits < 2**62 else 2**62  # beyond any cap (inf for a decay past a double)

    @classmethod
    def stack(cls, points, backend) -> TwoMass:
        coeffs = [p.coefficients(backend) for p in points]
        columns = []
        for f in fields(Coefficients):
            column = np.empty(len(coeffs), dtype=object)
            column[:] = [getattr(c, f.name) for c in coeffs]
            columns.append(column)
        first = points[0]
        return cls(Coefficients(*columns), first.decomposition, first.k, converted=True)
