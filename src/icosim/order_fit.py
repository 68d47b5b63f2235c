"""Orders of convergence, decided only in the asymptotic range.

Shared by the studies that fit orders: the convergence study of the linear model
(:mod:`icosim.studies.convergence.datasets`) and the pendulum's speed-accuracy study
(:mod:`icosim.studies.trade.orders`, which adds its error floor), so neither imports the other.

An order of convergence is a statement about ``H -> 0``.  With floor-free
errors (:mod:`icosim.studies.convergence.errors`) the smallest step sizes are the best
evidence, so the order is read off the **smallest-H decade** of a curve: the
least-squares slope of ``log error`` over ``log H`` on ``[H_min, 10 H_min]``.
It counts as *asymptotic* only if every local slope (between neighbouring step
sizes) in that decade lies within ``tolerance`` (0.1 by default) of it;
otherwise the curve is still turning and its order is *pre-asymptotic* -- a
claim about it is undecided, never passed or failed.  A curve that is unstable
at its smallest step sizes has no asymptotic range (``unstable as H -> 0``);
one unstable everywhere has no order at all.

An error ``H^2 + c H^4`` over ``[1e-4, 1e-1]``: with ``c = 1e3`` the ``H^4``
term is negligible in the smallest decade and the order is 2; with ``c = 1e6``
both terms are equal at ``H = 1e-3`` and the curve is still turning there:

>>> import numpy as np
>>> H = np.geomspace(1e-4, 1e-1, 16)
>>> f = asymptotic_order(H, H**2 + 1e3 * H**4)
>>> f.status, round(f.order, 3)
('asymptotic', 2.0)
>>> asymptotic_order(H, H**2 + 1e6 * H**4).status
'pre-asymptotic'
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["AsymptoticOrder", "asymptotic_order", "local_slopes", "STATUSES"]

#: Why an order is or is not evidence; only ``asymptotic`` orders decide a claim.
STATUSES = ("asymptotic", "pre-asymptotic", "unstable as H -> 0", "unstable at every H", "too few points")


def local_slopes(H, error):
    """Slopes ``d log(error) / d log(H)`` between neighbouring step sizes.

    Returns ``(H_mid, slope)`` in increasing ``H``: ``H_mid`` is the geometric
    mean of each neighbouring pair; a slope is NaN where either error is not a
    finite positive number (an unstable run).
    """
    H = np.asarray(H, float)
    e = np.asarray(error, float)
    order = np.argsort(H)
    H, e = H[order], e[order]
    good = np.isfinite(e) & (e > 0)
    log_e = np.log(np.where(good, e, 1.0))
    log_e[~good] = np.nan
    return np.sqrt(H[:-1] * H[1:]), np.diff(log_e) / np.diff(np.log(H))


@dataclass(frozen=True)
class AsymptoticOrder:
    """The order read off the smallest-H decade, and whether it is evidence.

    ``order`` is the least-squares slope over ``[H_min, H_max]`` (the decade),
    reported whenever that decade is stable, also when it is pre-asymptotic;
    ``spread`` is the largest deviation of a local slope there from it;
    ``used`` marks the step sizes of the decade (in the order given).
    """

    order: float
    status: str
    spread: float
    H_min: float
    H_max: float
    n_points: int
    used: np.ndarray
    reason: str = ""

    @property
    def decided(self) -> bool:
        """True if the order is asymptotic: evidence for or against a claim."""
        return self.status == "asymptotic"


def asymptotic_order(
    H, error, unstable=None, *, decades: float = 1.0, tolerance: float = 0.1, min_points: int = 3
) -> AsymptoticOrder:
    """Decide the order of convergence from the smallest-H ``decades`` of a curve.

    Parameters
    ----------
    H, error : step sizes (any order) and the error at each (NaN where none).
    unstable : mask of step sizes where the run is unstable (their values are
        not errors); non-finite errors count as unstable too.
    decades : width of the window at the small-H end.
    tolerance : largest deviation of a local slope in the window from the
        window's fitted slope for the order to count as asymptotic.
    min_points : fewest step sizes in the window.
    """
    H = np.asarray(H, float)
    e = np.asarray(error, float)
    bad = np.zeros(H.shape, bool) if unstable is None else np.asarray(unstable, bool).copy()
    bad |= ~(np.isfinite(e) & (e > 0))
    used = np.zeros(H.shape, bool)
    nan = float("nan")

    def undecided(status, reason, n=0):
        return AsymptoticOrder(nan, status, nan, nan, nan, n, used, reason)

    if bad.all():
        return undecided("unstable at every H", "no stable step size")
    order = np.argsort(H)
    if bad[order[0]]:
        first_ok = H[order][np.argmax(~bad[order])]
        return undecided(
            "unstable as H -> 0", f"unstable at the smallest step sizes (stable only from H = {first_ok:.3g} s)"
        )
    window = order[H[order] <= H[order[0]] * 10**decades * (1 + 1e-9)]
    if bad[window].any():
        return undecided("unstable as H -> 0", "unstable step sizes inside the smallest-H decade")
    if window.size < min_points:
        return undecided(
            "too few points", f"{window.size} step sizes in the smallest-H decade, need {min_points}", window.size
        )
    log_H, log_e = np.log(H[window]), np.log(e[window])
    slope = float(np.polyfit(log_H, log_e, 1)[0])
    slopes = np.diff(log_e) / np.diff(log_H)
    spread = float(np.max(np.abs(slopes - slope)))
    used[window] = True
    status, reason = "asymptotic", ""
    if spread > tolerance:
        status = "pre-asymptotic"
        reason = (
            f"local slopes {slopes.min():.2f} to {slopes.max():.2f} in the smallest-H decade differ from "
            f"their fit {slope:.2f} by up to {spread:.3f} > {tolerance:g}"
        )
    return AsymptoticOrder(
        slope, status, spread, float(H[window[0]]), float(H[window[-1]]), int(window.size), used, reason
    )
