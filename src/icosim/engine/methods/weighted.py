"""Weighted multiplier approach (Eqs. 24-27, 47-53): three solves, one per constraint level.

The corrected coupling variables are the mean of the position-, velocity- and
acceleration-level solutions with weights ``(1, a, b)/(1 + a + b)``.  Index 2:
``b = 0``; index 3: ``a = b = 0``, which is the index-3 Baumgarte method term
for term.  ``a`` and ``b`` are dimensionless in every setting.

>>> m = weighted_multiplier(a=1, b=1)
>>> [str(w) for w, _ in m.solves], m.params["index"]
(['1/3', '1/3', '1/3'], 1)
"""

from __future__ import annotations

from fractions import Fraction

from ...errors import ParameterError
from ..decompositions import NEEDS_CONSTRAINT_CONDITION
from .base import CouplingMethod, MethodSpec, Parameter, exact

__all__ = ["weighted_multiplier", "SPEC"]


def weighted_multiplier(
    a: float | Fraction | None = None, b: float | Fraction | None = None, *, index: int | None = None
) -> CouplingMethod:
    """Weighted multiplier approach (Eq. 24/53) with weights ``a``, ``b`` >= 0.

    ``index=2`` sets ``b = 0`` (``a`` required), ``index=3`` sets ``a = b = 0``.
    """
    if index is not None:
        if index not in (1, 2, 3):
            raise ParameterError(f"index must be 1, 2 or 3, got {index!r}")
        if index == 3:
            if a not in (None, 0) or b not in (None, 0):
                raise ParameterError("index 3 means a = b = 0; drop a and b")
            a, b = 0.0, 0.0
        elif index == 2:
            if b not in (None, 0):
                raise ParameterError("index 2 means b = 0; drop b")
            if a is None:
                raise ParameterError("weighted multiplier index 2 needs a")
            b = 0.0
        elif a is None or b is None:
            raise ParameterError("weighted multiplier index 1 needs a and b")
    if a is None or b is None:
        raise ParameterError("weighted multiplier needs a and b (or index)")
    # exact rationals (decimal input stays exact), so multiprecision runs are not limited by 1/3 in binary
    fa, fb = exact("a", a), exact("b", b)
    a, b = float(fa), float(fb)
    if a < 0 or b < 0:
        raise ParameterError(f"a and b must be >= 0, got a={a!r}, b={b!r}")
    if index is None:  # the index follows from the weights
        index = 3 if a == b == 0 else 2 if b == 0 else 1
    elif index == 1 and b == 0:
        raise ParameterError("index 1 needs b > 0 (b = 0 is the index-2 method)")
    s = 1 + fa + fb
    solves = ((1 / s, (1, 0, 0)), (fa / s, (0, 1, 0)), (fb / s, (0, 0, 1)))
    return CouplingMethod(
        "weighted",
        solves,
        params={"a": a, "b": b, "index": index},
        requires_constraint=True,
        refusal=NEEDS_CONSTRAINT_CONDITION,
    )


SPEC = MethodSpec(
    name="weighted",
    label="weighted multiplier",
    short_label="weighted",
    build=weighted_multiplier,
    parameters=(
        Parameter(
            "a", "weighted multiplier: weight of the velocity level", symbol="a", tex="$a$", tex_dimensional="$a$"
        ),
        Parameter(
            "b", "weighted multiplier: weight of the acceleration level", symbol="b", tex="$b$", tex_dimensional="$b$"
        ),
    ),
    indices=(1, 2, 3),
    unused_at_index={2: ("b",), 3: ("a", "b")},
    requires_constraint=True,
    label_parameters=("a", "b"),
)
