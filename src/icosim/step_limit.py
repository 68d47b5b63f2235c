"""The largest stable step size of a predicate ``stable(H)``: a scan, then a bisection.

Shared by the studies that search a stability limit: the pendulum's (:mod:`icosim.studies.trade.stability_limit`,
measured and predicted) and the chains' (:mod:`icosim.studies.chains.stability`, on the spectral radius), so neither
imports the other.

1. scan the step sizes ``scan`` in increasing order until the first stable one and, after it, the first unstable
   one (the scan stops there);
2. bisect (geometric midpoints) between the last stable and the first unstable scan point until their ratio is
   at most ``1 + resolution``.

``H_max`` is the last stable step size found: the upper edge of the first stable band at or above ``scan[0]``.  If
``scan[0]`` is already unstable, the band's lower edge lies above it (``H_band_low`` is its first stable scan
point).  If no scan point is unstable, ``H_max`` is censored at the largest scan point.

>>> lim = stability_limit(lambda H: H <= 0.0123, [1e-3, 1e-2, 1e-1], resolution=0.02)
>>> lim.status, round(lim.H_max / 0.0123, 2) <= 1.0, lim.H_unstable / lim.H_max <= 1.02
('bisected', True, True)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

__all__ = ["Limit", "stability_limit", "halvings", "LIMIT_STATUSES"]

#: ``bisected``: a bracket refined to the resolution; ``stable up to the cap``: no unstable scan
#: point (H_max censored); ``no stable step size``: every scan point unstable.
LIMIT_STATUSES = ("bisected", "stable up to the cap", "no stable step size")


@dataclass
class Limit:
    """Result of :func:`stability_limit` (module docstring)."""

    H_max: float
    H_unstable: float
    H_band_low: float
    status: str
    evaluations: list = field(default_factory=list)  # (H, stable, info) in the order evaluated
    rho_linear: dict = field(default_factory=dict)  # the linear model's rho at this search's H_max, H_band_low

    @property
    def n_evaluations(self) -> int:
        return len(self.evaluations)


def halvings(lo: float, hi: float, depth: int, resolution: float) -> list[float]:
    """The step sizes the next ``depth`` halvings of the bracket ``(lo, hi)`` can check, whichever way each goes:
    the midpoint, then those of both halves, formed as the bisection forms them (the same floats).

    >>> [round(h, 4) for h in halvings(0.01, 0.04, 2, resolution=0.02)]
    [0.02, 0.0141, 0.0283]
    """
    if depth <= 0 or not hi / lo > 1 + resolution:
        return []
    mid = math.sqrt(lo * hi)
    return [mid] + halvings(lo, mid, depth - 1, resolution) + halvings(mid, hi, depth - 1, resolution)


def stability_limit(stable, scan, *, resolution: float = 0.02, batch=None, ahead: int = 2) -> Limit:
    """Upper edge of the first stable band of ``stable(H)`` at or above ``scan[0]`` (module docstring).

    ``stable(H)`` returns a bool or ``(bool, info)``.  ``batch(Hs)``, if given, returns those outcomes (an
    iterable, or a sequence) for a list of step sizes at once (``stable`` is then not called): the scan in one
    call, and the bisection the step sizes of its next ``ahead`` halvings in one call (:func:`halvings`), checking
    only those on its path, so the step sizes checked and the result are those of ``stable`` one at a time -- if
    an outcome does not depend on the other step sizes of its batch.  Of a sequence only the outcomes of the step
    sizes checked are read (by index), so one that computes an outcome when it is read spends nothing on the
    others.

    >>> one = stability_limit(lambda H: H <= 0.0123, [1e-3, 1e-2, 1e-1], resolution=0.02)
    >>> many = stability_limit(None, [1e-3, 1e-2, 1e-1], resolution=0.02, batch=lambda Hs: [H <= 0.0123 for H in Hs])
    >>> one.evaluations == many.evaluations
    True
    """
    if not resolution > 0:
        raise ValueError(f"resolution must be > 0, got {resolution!r}")
    scan = sorted(float(h) for h in scan)
    evals = []
    known = {}

    def check(H, ahead_of=None):
        if H not in known:
            todo = [H] if batch is None else [h for h in (ahead_of or [H]) if h not in known]
            outs = [stable(H)] if batch is None else batch(todo)
            if not isinstance(outs, Sequence):  # an iterable of outcomes: read whole
                outs = list(outs)
            known.update((h, (outs, i)) for i, h in enumerate(todo))
        outs, i = known[H]
        out = outs[i]  # read only for the step sizes checked
        ok, info = out if isinstance(out, tuple) else (out, None)
        evals.append((H, bool(ok), info))
        return bool(ok)

    nan = math.nan
    first_stable = None
    lo = hi = None
    for H in scan:
        ok = check(H, scan)
        if first_stable is None:
            if ok:
                first_stable = lo = H
            continue
        if ok:
            lo = H
        else:
            hi = H
            break
    if first_stable is None:
        return Limit(nan, scan[0], nan, "no stable step size", evals)
    if hi is None:
        return Limit(lo, nan, first_stable, "stable up to the cap", evals)
    while hi / lo > 1 + resolution:
        mid = math.sqrt(lo * hi)
        if check(mid, halvings(lo, hi, ahead, resolution)):
            lo = mid
        else:
            hi = mid
    return Limit(lo, hi, first_stable, "bisected", evals)
