"""Newton's rule: the corrector's step on implicitly coupled signal connections (docs/signals.md).

The conditions of connections coupled implicitly (:mod:`icosim.engine.connection_conditions`, level
``"signal"``) are closed by ``e <- e - J^-1 r``: one solve per corrector pass, no projection.  It couples
connections, not joints, so it is not among the joints' methods (:data:`~icosim.engine.methods.METHODS`); the
macro step uses it at a stage that closes connections.

>>> import numpy as np
>>> NEWTON.corrected_coupling(np.array([1.0, 2.0]), {"signal": np.array([1.0, 1.0])},
...                           {"signal": np.eye(2) * 2}, None).tolist()
[0.5, 1.5]
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..connection_conditions import LEVEL
from .solve import solve_small

__all__ = ["NewtonRule", "NEWTON"]


@dataclass(frozen=True)
class NewtonRule:
    """``e - J^-1 r`` on the level ``"signal"``."""

    name: str = "newton"
    projection: bool = False
    n_solves: int = 1

    def corrected_coupling(self, e_pred: np.ndarray, residuals: Mapping[str, np.ndarray],
                           jacobians: Mapping[str, np.ndarray], backend: Any, factors: Any = None) -> np.ndarray:  # fmt: skip
        return e_pred - solve_small(jacobians[LEVEL], residuals[LEVEL])


#: The rule the macro step closes implicit connections with.
NEWTON = NewtonRule()
