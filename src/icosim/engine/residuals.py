"""The coupling conditions of a joint, formed in one place with one sign convention.

Every problem's outputs at ``T_N+1`` are, per subsystem, the joint point's position, velocity and acceleration
and the coupling force the subsystem sees (``lambda_c`` for a force-driven one, its drive's force for a
kinematically driven one).  The conditions are the differences **first subsystem minus second**: the joint
constraint ``g`` on the position, velocity and acceleration levels where the decomposition has it (a
force-driven subsystem, :attr:`~icosim.engine.decompositions.Decomposition.has_constraint_condition`) and the
balance of the coupling forces where a subsystem is kinematically driven.  A problem whose levels are not in
the engine's dimensionless time scales them (``scale``: ``g``, ``H g'``, ``H^2 g''``).

>>> import numpy as np
>>> from icosim.engine.decompositions import get_decomposition
>>> y = np.array([[1.0, 2.0, 3.0, 4.0], [0.5, 2.5, 3.0, 1.0]])[..., None]  # two subsystems, one component
>>> r = coupling_conditions(y, get_decomposition("fd"))
>>> [r[key].tolist() for key in ("pos", "vel", "acc", "force")]
[[0.5], [-0.5], [0.0], [3.0]]
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

    from .decompositions import Decomposition

__all__ = ["coupling_conditions", "differences"]

#: The rows of a subsystem's outputs.
POSITION, VELOCITY, ACCELERATION, FORCE = range(4)


def differences(y: np.ndarray) -> np.ndarray:
    """The outputs of the first subsystem minus the second's: ``y[..., 0, :, :] - y[..., 1, :, :]``."""
    return y[..., 0, :, :] - y[..., 1, :, :]


def coupling_conditions(
    y: np.ndarray, decomposition: Decomposition, *, scale: Sequence[Any] | None = None
) -> dict[str, np.ndarray]:
    """``{pos, vel, acc, force}`` from the outputs ``y[..., i, q, c]`` (subsystem ``i`` = 0, 1; output ``q`` as
    :data:`POSITION` ...; component ``c`` of the joint), first minus second.  Levels a decomposition lacks are
    empty (no rows); ``scale`` multiplies the position, velocity and acceleration levels."""
    d = differences(y)
    empty = d[..., 0, :0]
    out = {"pos": empty, "vel": empty, "acc": empty}
    if decomposition.has_constraint_condition:
        levels = [d[..., q, :] for q in (POSITION, VELOCITY, ACCELERATION)]
        if scale is not None:
            levels = [s * level for s, level in zip(scale, levels)]
        out["pos"], out["vel"], out["acc"] = levels
    out["force"] = d[..., FORCE, :] if decomposition.has_force_balance else empty
    return out
