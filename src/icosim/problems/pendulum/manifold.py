"""Mass-weighted projection of positions and velocities onto the joint constraint (step 4).

With ``q = (phi_1, x_S2, y_S2, phi_2)`` and ``M = diag(J_O, m_2, m_2, J_2)`` the
positions minimise ``(q - q*)^T M (q - q*)`` subject to ``g_c(q) = 0``
(Gauss-Newton on the KKT conditions), then the velocities are projected
linearly onto ``G(q) q' = 0`` in the same metric: the generalisation of
Eq. (30) (docs/pendulum.md).
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import StepFailure
from .model import PendulumParameters

__all__ = ["project_state", "ProjectionError"]


def _constraint_jacobian(p, q):
    """``G = d g_c / d q`` for ``q = (phi1, x2, y2, phi2)``, shape (2, 4)."""
    phi1, phi2 = float(q[0]), float(q[3])
    return np.array(
        [
            [-p.l1 * math.sin(phi1), -1.0, 0.0, -p.l2 / 2 * math.sin(phi2)],
            [p.l1 * math.cos(phi1), 0.0, -1.0, p.l2 / 2 * math.cos(phi2)],
        ]
    )


class ProjectionError(StepFailure):
    """The projection onto the joint constraint did not converge (or met a singular system)."""


def project_state(p: PendulumParameters, state, *, tol: float = 1e-14, max_iter: int = 20):
    """Mass-weighted projection of positions, then velocities, onto ``g_c = 0``, ``g_c' = 0``.

    Raises :class:`ProjectionError` if Gauss-Newton does not bring ``|g_c|`` to
    ``tol`` (m) within ``max_iter`` iterations: an unprojected state is never returned.
    """
    pos, vel = [0, 2, 3, 4], [1, 5, 6, 7]
    q_star = state[pos]
    Minv = 1.0 / np.array([p.JO1, p.m2, p.m2, p.J2])
    q = q_star.copy()
    g = None
    try:
        for _ in range(max_iter + 1):
            g = _constraint(p, q)
            gx, gy = g.tolist()
            if not (math.isfinite(gx) and math.isfinite(gy)) or max(abs(gx), abs(gy)) <= tol:
                break
            G = _constraint_jacobian(p, q)
            # KKT fixed point: q = q* - M^-1 G^T nu, linearised g(q) + G (q_new - q) = 0
            nu = np.linalg.solve((G * Minv) @ G.T, g + G @ (q_star - q))
            q = q_star - Minv * (G.T @ nu)
        gx, gy = g.tolist()
        if not (abs(gx) <= tol and abs(gy) <= tol):  # also catches nan
            raise ProjectionError(
                f"projection: |g_c| = {np.max(np.abs(g)):.3g} m > {tol:g} m after {max_iter} Gauss-Newton iterations"
            )
        G = _constraint_jacobian(p, q)
        v = state[vel]
        nu = np.linalg.solve((G * Minv) @ G.T, G @ v)
    except np.linalg.LinAlgError as exc:
        raise ProjectionError(f"projection: singular constraint Jacobian ({exc})") from exc
    out = state.copy()
    out[pos] = q
    out[vel] = v - Minv * (G.T @ nu)
    return out


def _constraint(p, q):
    """``g_c`` at the positions ``q = (phi1, x2, y2, phi2)``: :func:`~.model.joint_constraint`'s arithmetic."""
    phi1, x2, y2, phi2 = q.tolist()
    return np.array(
        [
            p.l1 * math.cos(phi1) - (x2 - p.l2 / 2 * math.cos(phi2)),
            p.l1 * math.sin(phi1) - (y2 - p.l2 / 2 * math.sin(phi2)),
        ]
    )
