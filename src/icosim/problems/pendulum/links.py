"""The two links as subsystems: force-driven or kinematically driven on acceleration level.

Link 1 is pinned to ground (state ``(phi1, omega1)``), link 2 is a free body (state
``(x_S2, y_S2, phi2, vx, vy, omega2)``).  A link is its parameters and its kind; its right-hand side for an
input polynomial (force ``lambda`` or joint acceleration ``a_tilde``) and its outputs at the joint (position,
velocity, acceleration and the joint force it sees) are compiled
(:mod:`icosim.problems.pendulum.integrator.compiled_links`; their numpy reference is
``tests/reference_links.py``).  Equations in docs/pendulum.md.
"""

from __future__ import annotations

from .model import PendulumParameters

__all__ = ["Link1", "Link2"]


class Link1:
    """Link 1 pinned to ground: state ``(phi1, omega1)``."""

    n = 2

    def __init__(self, p: PendulumParameters, kind: str):
        self.p, self.kind = p, kind


class Link2:
    """Free link 2: state ``(x_S2, y_S2, phi2, vx, vy, omega2)``."""

    n = 6

    def __init__(self, p: PendulumParameters, kind: str):
        self.p, self.kind = p, kind
