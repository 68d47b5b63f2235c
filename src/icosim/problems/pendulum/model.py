"""Parameters of the double pendulum, its joint points and the joint constraint (docs/pendulum.md).

>>> p = PendulumParameters()
>>> bool(abs(joint_constraint(p, p.initial_state())).max() < 1e-15)
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...errors import ParameterError

__all__ = ["PendulumParameters", "joint_points", "joint_constraint"]


@dataclass(frozen=True)
class PendulumParameters:
    """Physical parameters and initial angles (SI units), defaults from Sect. 4."""

    m1: float = 1.0
    m2: float = 1.0
    J1: float = 1.0 / 12.0
    J2: float = 1.0 / 12.0
    l1: float = 1.0
    l2: float = 1.0
    g: float = 9.81
    d: float = 2.0
    phi1_0: float = math.pi / 4
    phi2_0: float = -math.pi / 4

    def __post_init__(self):
        for name in ("m1", "m2", "J1", "J2", "l1", "l2"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"pendulum parameter {name} must be a finite number > 0, got {v!r}")
        for name in ("g", "d", "phi1_0", "phi2_0"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ParameterError(f"pendulum parameter {name} must be a finite number, got {v!r}")
        if self.d < 0:
            raise ParameterError(f"pendulum parameter d must be >= 0, got {self.d!r}")

    @property
    def JO1(self) -> float:
        """Moment of inertia of link 1 about its ground pin."""
        return self.J1 + self.m1 * self.l1**2 / 4

    def initial_state(self) -> np.ndarray:
        """Consistent co-simulation state at rest: ``(phi1, w1, x2, y2, phi2, vx2, vy2, w2)``."""
        e1 = np.array([math.cos(self.phi1_0), math.sin(self.phi1_0)])
        e2 = np.array([math.cos(self.phi2_0), math.sin(self.phi2_0)])
        s2 = self.l1 * e1 + self.l2 / 2 * e2
        return np.array([self.phi1_0, 0.0, s2[0], s2[1], self.phi2_0, 0.0, 0.0, 0.0])


def joint_points(p: PendulumParameters, state):
    """Joint point of link 1 and of link 2 (each ``(..., 2)``) for a co-simulation state."""
    if np.ndim(state) == 1:  # one state (the projection's iterations): scalar arithmetic, same values
        phi1, x2, y2, phi2 = (float(state[j]) for j in (0, 2, 3, 4))
        P1 = np.array([p.l1 * math.cos(phi1), p.l1 * math.sin(phi1)])
        P2 = np.array([x2 - p.l2 / 2 * math.cos(phi2), y2 - p.l2 / 2 * math.sin(phi2)])
        return P1, P2
    phi1, x2, y2, phi2 = state[..., 0], state[..., 2], state[..., 3], state[..., 4]
    P1 = np.stack([p.l1 * np.cos(phi1), p.l1 * np.sin(phi1)], axis=-1)
    P2 = np.stack([x2 - p.l2 / 2 * np.cos(phi2), y2 - p.l2 / 2 * np.sin(phi2)], axis=-1)
    return P1, P2


def joint_constraint(p: PendulumParameters, state):
    """``(g_cax, g_cay)`` of Sect. 4 for a co-simulation state."""
    P1, P2 = joint_points(p, state)
    return P1 - P2
