"""Orders of convergence of the pendulum over H, decided only where the local slopes have settled.

The rule is the linear study's (the convergence study's floor-free order fit): the order is the least-squares slope
of ``log error`` over ``log H`` on the **smallest-H decade** ``[H_min, 10 H_min]``
of the usable step sizes, and it counts as *asymptotic* only if every local
slope (between neighbouring step sizes) in that decade lies within
``tolerance`` (0.1) of it; otherwise it is *pre-asymptotic* (undecided).  A
curve unstable at its smallest step sizes has no asymptotic range (``unstable as
H -> 0``).

One addition the pendulum needs (its errors are measured against a numerical
reference in float64, so they have a floor): errors below ``floor`` (a number
or one per step size, :func:`error_floor`) are not data.  Such step sizes are
left out before the decade is chosen, so the decade is the smallest-H decade
*above the floor* (status ``at the error floor`` when none is left, ``no
stable decade above the floor`` when that decade reaches unstable step sizes).
The decade rule itself is the linear study's function
(:func:`icosim.order_fit.asymptotic_order`, here also named :func:`decade_order`).

>>> import numpy as np
>>> H = np.geomspace(1e-4, 2e-2, 12)
>>> f = pendulum_order(H, 3 * H**2 + 1e3 * H**4)
>>> f.status, round(f.order, 2)
('asymptotic', 2.0)
>>> pendulum_order(H, np.maximum(H**3, 1e-13), floor=1e-11).H_min > 2e-4   # the floor is left out
True
>>> pendulum_order(H, H**2 + 1e7 * H**4).status  # both terms equal at H = 3e-4
'pre-asymptotic'
"""

from __future__ import annotations

import numpy as np

from ...order_fit import STATUSES as LINEAR_STATUSES
from ...order_fit import AsymptoticOrder, local_slopes
from ...order_fit import asymptotic_order as decade_order

__all__ = ["AsymptoticOrder", "decade_order", "pendulum_order", "error_floor", "local_slopes", "STATUSES"]

#: Why an order is or is not evidence; only ``asymptotic`` orders decide.  The linear study's statuses and the
#: two the pendulum's error floor adds.
STATUSES = LINEAR_STATUSES + ("at the error floor", "no stable decade above the floor")


def error_floor(n_steps, *, reference_accuracy: float = 0.0, factor: float = 10.0, rounding: str = "random walk"):
    """Errors below which a step size is not data: ``factor (rounding of N steps + reference_accuracy)``.

    ``rounding`` bounds the rounding error of ``N`` float64 macro steps of an
    O(1) solution: ``"random walk"``, ``eps sqrt(N)``, where each step rounds
    differently (the pendulum: its measured plateau, 1.3e-14 to 2.6e-14 rad
    for N = 400 to 2000 with a 1e-14 reference, is of that size);
    ``"linear"``, ``eps N``, where one rounded matrix is applied N times
    (the linear model's amplification matrix; the rule the linear study used
    before its errors were computed floor-free).  ``reference_accuracy`` is the reference's own error
    (zero for an exact one).
    """
    n = np.asarray(n_steps, float)
    growth = {"random walk": np.sqrt(n), "linear": n}
    if rounding not in growth:
        raise ValueError(f"rounding must be one of {', '.join(growth)}, got {rounding!r}")
    return factor * (np.finfo(float).eps * growth[rounding] + reference_accuracy)


def pendulum_order(
    H, error, unstable=None, *, floor: float = 0.0, decades=1.0, tolerance=0.1, min_points=3
) -> AsymptoticOrder:
    """:func:`decade_order` on the step sizes whose error is at least ``floor`` (the others are not data).

    Stable step sizes below the floor are dropped; unstable ones are kept, so
    that a curve unstable as ``H -> 0`` is still called so (if its smallest
    step sizes are unstable).  ``used`` refers to the input order.
    """
    H = np.asarray(H, float)
    e = np.asarray(error, float)
    bad = np.zeros(H.shape, bool) if unstable is None else np.asarray(unstable, bool)
    bad = bad | ~(np.isfinite(e) & (e > 0))
    keep = bad | (e >= np.broadcast_to(np.asarray(floor, float), H.shape))
    if not np.any(keep & ~bad) and np.any(~bad):
        nan = float("nan")
        return AsymptoticOrder(
            nan,
            "at the error floor",
            nan,
            nan,
            nan,
            0,
            np.zeros(H.shape, bool),
            f"every error is below the floor (at most {float(np.max(floor)):.3g})",
        )
    idx = np.flatnonzero(keep)
    fit = decade_order(H[idx], e[idx], bad[idx], decades=decades, tolerance=tolerance, min_points=min_points)
    used = np.zeros(H.shape, bool)
    used[idx] = fit.used
    status, reason = fit.status, fit.reason
    dropped = ~keep
    if status == "unstable as H -> 0" and not bad[np.argmin(H)] and np.any(dropped):
        # the smallest step sizes are stable but at the floor: the instability lies above them
        status = "no stable decade above the floor"
        reason = f"the smallest-H decade above the error floor reaches unstable step sizes ({fit.reason})"
    return AsymptoticOrder(fit.order, status, fit.spread, fit.H_min, fit.H_max, fit.n_points, used, reason)
