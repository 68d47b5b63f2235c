"""The double pendulum's coupling conditions, by the kinds of its two links (docs/pendulum.md).

The outputs of the two links at ``T_N+1`` are the joint point's position, velocity and acceleration and the
joint force each link sees.  The pendulum's coupling variable ``lambda_c`` is the joint force *on link 2*
(link 1 feels ``-lambda_c``), and a kinematically driven link's force output is that of its drive in the
same sense; so its conditions are its own, not the engine's (:mod:`icosim.engine.residuals`, whose
multiplier acts with ``+lambda`` on the first side).  Every residual here is *link 1 minus link 2*: the
joint constraint ``g_c = P_1 - P_2`` on each level and the force balance ``f_1 - f_2`` (the paper writes
Eq. 57c the other way round, ``mu_2 - mu_1 = 0``: the same condition; the sign of a residual and of its
Jacobian rows together does not change the corrected coupling variables).  Which rows close the system
depends on how each link is driven (a decomposition's ``kinds``, :mod:`icosim.engine.decompositions`).
Link 1 is pinned to the ground, so it can move its joint point only along its normal ``n1``: where it is
kinematically driven, the conditions are taken along ``e1`` and ``n1``.  A kinematically driven link 1
with a force-driven link 2 (df) has no conditions here: the pinned link cannot follow a prescribed joint
acceleration in two directions, and none is derived.

>>> sorted(kinds for kinds in CONDITIONS)
[('force', 'force'), ('force', 'kinematic'), ('kinematic', 'kinematic')]
"""

from __future__ import annotations

import numpy as np

from ...engine.decompositions import DECOMPOSITIONS, get_decomposition
from ...errors import ParameterError

__all__ = ["CONDITIONS", "check_decomposition"]


def differences(y):
    """Link 1's outputs minus link 2's, ``(..., 4, 2)``."""
    return y[..., 0, :, :] - y[..., 1, :, :]


def _constraint(y, balance):
    """ff and fd: the joint constraint on each level; fd also link 2's drive balancing ``lambda_c``."""
    d = differences(y)
    empty = d[..., 0, :0]
    return {"pos": d[..., 0, :], "vel": d[..., 1, :], "acc": d[..., 2, :], "force": d[..., 3, :] if balance else empty}


def _both_kinematic(y):  # dd: link 1 moves its joint only along n1; the normal component balances
    d = differences(y)
    P1x, P1y = y[..., 0, 0, 0], y[..., 0, 0, 1]
    length = np.sqrt(P1x * P1x + P1y * P1y)  # np.linalg.norm's sum of squares, in its order
    e1x, e1y = P1x / length, P1y / length

    def along_e1(v):
        return (e1x * v[..., 0] + e1y * v[..., 1])[..., None]

    return {
        "pos": along_e1(d[..., 0, :]),
        "vel": along_e1(d[..., 1, :]),
        "acc": along_e1(d[..., 2, :]),
        # n1 . (f_1 - mu_2) = mu_1 - n1 . mu_2 (f_1 = mu_1 n1), n1 = (-e1y, e1x)
        "force": ((-e1y) * d[..., 3, 0] + e1x * d[..., 3, 1])[..., None],
    }


#: ``residuals(y) -> {pos, vel, acc, force}`` by the kinds of (link 1, link 2).
CONDITIONS = {
    ("force", "force"): lambda y: _constraint(y, False),
    ("force", "kinematic"): lambda y: _constraint(y, True),
    ("kinematic", "kinematic"): _both_kinematic,
}

_DRIVEN = {"force": "force-driven", "kinematic": "kinematically driven"}


def check_decomposition(decomposition):
    """Refuse a decomposition whose pair of link kinds has no conditions here, naming those that have."""
    dec = get_decomposition(decomposition)
    if dec.kinds not in CONDITIONS:
        have = ", ".join(d.name for d in DECOMPOSITIONS.values() if d.kinds in CONDITIONS)
        raise ParameterError(
            f"the double pendulum's coupling conditions are derived for {have}, not for {dec.name!r} "
            f"(link 1 {_DRIVEN[dec.kinds[0]]}, link 2 {_DRIVEN[dec.kinds[1]]}; docs/pendulum.md)"
        )
