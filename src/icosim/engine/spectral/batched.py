"""Certificates of many points of one panel at once, each the one the point gets alone.

:func:`icosim.engine.spectral.certified.certify_spectral_radius` certifies one point: its ball
amplification matrix by the macro step, then the Schur-Cohn counts of its characteristic polynomial.
The macro step of one point in ball arithmetic costs mostly Python calls, not arithmetic, so the
points of a panel that share a working precision (the same guard bits, the same pass of the
``bits``-then-``max_bits`` schedule) have their matrices computed in one batched macro step: a
leading axis of object arrays, the same ball operations on every point as alone, hence the same balls
and the same certificates.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from ..backends import Ball
from ..bounds import MAX_GUARD_BITS, MAX_SECONDS, time_budget
from .certified import DEFAULT_BITS, MAX_BITS, SpectralCertificate, certify_matrix, certify_spectral_radius
from .matrix import amplification_matrix

if TYPE_CHECKING:
    from ..methods.base import CouplingMethod
    from .family import LinearFamily

__all__ = ["certify_spectral_radii"]


def certify_spectral_radii(
    points: Sequence[LinearFamily],
    method: CouplingMethod,
    *,
    bits: int = DEFAULT_BITS,
    max_bits: int = MAX_BITS,
    max_guard_bits: int = MAX_GUARD_BITS,
    point_seconds: float = 0.0,
    **matrix_kw: Any,
) -> list:
    """:func:`~icosim.engine.spectral.certified.certify_spectral_radius` of many points of one panel, each as alone.

    ``points`` are single-point families (:meth:`~icosim.engine.spectral.family.LinearFamily.point`) of one kind.

    Returns one entry per point: its :class:`SpectralCertificate`, or the exception that left it
    undecided.  The points that share a working precision (the same guard bits, the same pass of the
    ``bits``-then-``max_bits`` schedule) have their ball amplification matrices computed in one
    batched macro step: the same ball operations on every point as alone (the batch is a leading axis
    of object arrays), so every ball, hence every certificate, is identical; only the per-call
    overhead of the step is shared.  Each point's certificate (characteristic polynomial and
    Schur-Cohn counts) is then formed alone, within its wall-time budget ``point_seconds`` (0: none).
    A batch that fails or runs past ``point_seconds`` per point falls back to the points one by one,
    each within its own budget, exactly as :func:`certify_spectral_radius`.
    """
    out: list = [None] * len(points)
    b0, cap = int(bits), max(int(max_bits), int(bits))
    groups: dict = {}  # guard bits -> indices of the points
    for i, point in enumerate(points):
        try:
            guard = point.guard_bits()
        except Exception as exc:  # noqa: BLE001 -- one point's failure must not abort the others
            out[i] = exc
            continue
        if guard > max_guard_bits:
            why = f"needs {guard} guard bits for exp(-decay) entries, more than the cap of {max_guard_bits}"
            out[i] = SpectralCertificate("undecided", Fraction(0), None, 0, reason=why, cause="precision_cap")
            continue
        groups.setdefault(guard, []).append(i)

    def alone(i: int) -> None:
        try:
            with time_budget(point_seconds):
                out[i] = certify_spectral_radius(
                    points[i],
                    method,
                    bits=bits,
                    max_bits=max_bits,
                    max_guard_bits=max_guard_bits,
                    **matrix_kw,
                )
        except Exception as exc:  # noqa: BLE001
            out[i] = exc

    for guard, todo in groups.items():
        b = b0
        while todo:
            be = Ball(b + guard)
            try:
                budget = min(point_seconds * len(todo), MAX_SECONDS) if point_seconds else 0
                with time_budget(budget), be.context():
                    batch = type(points[todo[0]]).stack([points[i] for i in todo], be)
                    Ms = amplification_matrix(batch, method, backend=be, exact=True, **matrix_kw)
            except Exception:  # noqa: BLE001 -- the batch cannot tell which point failed: each alone
                for i in todo:
                    alone(i)
                break
            undecided = []
            for i, M in zip(todo, Ms):
                try:
                    with time_budget(point_seconds), be.context():
                        cert = certify_matrix(M, b + guard, final=b >= cap)
                except Exception as exc:  # noqa: BLE001
                    out[i] = exc
                    continue
                if cert is None:
                    undecided.append(i)
                else:
                    out[i] = cert
            # the points undecided at ``bits`` go straight to the cap, as in certify_spectral_radius
            todo, b = undecided, cap
    return out
