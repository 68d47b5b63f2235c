"""Order of convergence over the asymptotic range.

Order fit
---------
The order is the slope of ``log(nrmse)`` over ``log(H)`` (:func:`scipy.stats.linregress`)
over the *asymptotic range*: the stable points at the small-``H`` end, after
leaving out the round-off floor (:func:`fit_order`).

An error ``3 H^2`` that levels off at ``1e-9`` for the smallest ``H`` gives
order 2 over the nine larger step sizes; the flat point is left out:

>>> import numpy as np
>>> H = np.geomspace(1e-5, 1e-2, 10)
>>> f = fit_order(H, np.maximum(3 * H**2, 1e-9), n_steps=1 / H)
>>> round(f.order, 6), f.n_points, bool(f.used[0])
(2.0, 9, False)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.stats

__all__ = ["OrderFit", "fit_order", "local_slopes"]


# --------------------------------------------------------------------------- order fit
@dataclass
class OrderFit:
    """Slope of ``log nrmse`` over ``log H`` and the range it was fitted on."""

    order: float
    stderr: float
    intercept: float
    rvalue: float
    H_min: float
    H_max: float
    n_points: int
    used: np.ndarray  # mask over the input points
    reason: str = ""

    @property
    def ok(self) -> bool:
        return bool(np.isfinite(self.order))


def local_slopes(H, error):
    """Slopes ``d log(error) / d log(H)`` between neighbouring points (sorted by H)."""
    H = np.asarray(H, float)
    e = np.asarray(error, float)
    order = np.argsort(H)
    with np.errstate(all="ignore"):
        return np.diff(np.log(e[order])) / np.diff(np.log(H[order]))


def fit_order(
    H,
    error,
    n_steps=None,
    *,
    min_points: int = 4,
    tolerance: float = 0.25,
    min_order: float = 0.5,
    floor_factor: float = 10.0,
) -> OrderFit:
    """Order of convergence over the asymptotic range, stopping before the round-off floor.

    Procedure (points = finite, positive errors, i.e. stable runs):

    1. Points with ``error < floor_factor * eps * N_total`` are left out: the
       rounding of ``N_total`` float64 steps alone may reach that size.
    2. Starting at the smallest ``H``, take the window of the ``min_points``
       smallest remaining sizes.  It is *consistent* if every local slope in it
       is within ``tolerance`` of the window's least-squares slope, and that
       slope is at least ``min_order`` (an error that no longer decreases with
       ``H`` is the round-off floor, not convergence).  While it is not, drop
       the smallest ``H`` (round-off floor or the end of a transition) and
       retry.
    3. Grow the window toward larger ``H`` one point at a time while it stays
       consistent: the pre-asymptotic range ends where the local slope starts
       to depart from the fitted one.

    The slope of the final window (``scipy.stats.linregress`` of
    ``log error`` on ``log H``) is the order.  If no consistent window of
    ``min_points`` exists the order is NaN and ``reason`` says why.
    """
    H = np.asarray(H, float)
    e = np.asarray(error, float)
    used = np.zeros(H.shape, dtype=bool)
    nan_fit = lambda reason: OrderFit(np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, 0, used, reason)  # noqa: E731
    ok = np.isfinite(e) & (e > 0) & np.isfinite(H) & (H > 0)
    if n_steps is not None:
        floor = floor_factor * np.finfo(float).eps * np.asarray(n_steps, float)
        below = ok & (e < floor)
        ok &= ~below
    if np.sum(ok) < min_points:
        return nan_fit(f"fewer than {min_points} stable points above the round-off floor")
    idx = np.flatnonzero(ok)
    idx = idx[np.argsort(H[idx])]  # ascending H
    logH, loge = np.log(H[idx]), np.log(e[idx])

    def consistent(lo, hi):
        fit = scipy.stats.linregress(logH[lo:hi], loge[lo:hi])
        slopes = np.diff(loge[lo:hi]) / np.diff(logH[lo:hi])
        return fit.slope >= min_order and np.all(np.abs(slopes - fit.slope) <= tolerance), fit

    lo = 0
    while lo + min_points <= idx.size:
        good, fit = consistent(lo, lo + min_points)
        if good:
            break
        lo += 1
    else:
        return nan_fit(f"no {min_points} consecutive stable points with consistent local slopes")
    hi = lo + min_points
    while hi < idx.size:
        good, trial = consistent(lo, hi + 1)
        if not good:
            break
        fit, hi = trial, hi + 1
    sel = idx[lo:hi]
    used[sel] = True
    return OrderFit(
        order=float(fit.slope),
        stderr=float(fit.stderr),
        intercept=float(fit.intercept),
        rvalue=float(fit.rvalue),
        H_min=float(H[sel].min()),
        H_max=float(H[sel].max()),
        n_points=int(sel.size),
        used=used,
    )
