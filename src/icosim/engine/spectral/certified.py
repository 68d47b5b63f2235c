"""Certified stability verdicts: a proven enclosure of the spectral radius (ball arithmetic).

The amplification matrix is computed by the engine's own macro step in Arb ball
arithmetic (:class:`icosim.engine.backends.Ball`), so each entry is a ball that contains
the exact entry for the exact parameters.  Its characteristic polynomial
``p(z) = det(z I - M)`` (Arb, ball coefficients) is then examined with the
Schur-Cohn-Marden test (Marden, *Geometry of polynomials*, Thm. 42.1): with
``f(z) = p(r z)``, ``T f = conj(a_0) f - a_n f*`` and ``delta_j = (T^j f)(0)``,
if no ``delta_j`` is zero then ``p`` has no root on ``|z| = r`` and exactly as
many roots in ``|z| < r`` as there are negative partial products
``delta_1 ... delta_j``.  In ball arithmetic a ``delta_j`` whose ball contains
0 makes the count *undecided* at this precision; a decided count is a proof.

Why the characteristic polynomial and not eigenvalue enclosures: the reduced
state carries structurally zero eigenvalues that form a Jordan block (several
per scheme), and Arb's eigenvalue routines (also with ``multiple=True``) cannot
isolate such a cluster.  The Schur-Cohn recursion handles it without special
cases: a root at 0 only makes ``|a_0| < |a_n|``.

Verdicts, with no tolerance conventions:

* ``stable``: all ``n`` roots in ``|z| < 1`` (proven: ``rho < 1``);
* ``unstable``: fewer than ``n`` roots in ``|z| < 1`` and none on ``|z| = 1``,
  or a root proven outside a radius above 1 (proven: ``rho > 1``; the second
  form decides schemes with a root exactly on the circle besides a larger one);
* ``marginal``: the count at ``r = 1`` stays undecided up to the precision cap
  (for example ``rho = 1`` exactly on the undamped axis with identical
  subsystems, or the Jordan block at 1 at the origin).

The enclosure ``[rho_lower, rho_upper]`` is found the same way at radii
``r`` just below and above an approximation of ``rho``: ``rho_upper`` is a
radius with all roots proven inside, ``rho_lower`` one with a root proven
outside.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal, localcontext
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backends import Ball
from ..bounds import MAX_GUARD_BITS
from .matrix import amplification_matrix

if TYPE_CHECKING:
    from flint import arb

    from ..methods.base import CouplingMethod
    from .family import LinearFamily

__all__ = [
    "certify_spectral_radius",
    "certify_matrix",
    "SpectralCertificate",
    "roots_inside",
    "VERDICTS",
    "DEFAULT_BITS",
    "MAX_BITS",
    "MAX_GUARD_BITS",
]

#: The verdicts a certificate can give (``undecided``: the ball arithmetic lost every digit at the cap).
VERDICTS = ("stable", "unstable", "marginal", "undecided")
#: Working precision of the first attempt and the default cap (bits), the only second attempt; both on top of
#: the guard bits a heavily damped subsystem needs (the family's ``guard_bits``), themselves capped.
DEFAULT_BITS, MAX_BITS = 128, 1024


def roots_inside(coeffs: Sequence[arb], r: arb | int = 1) -> int | None:
    """Number of roots of ``sum a_k z^k`` (real balls, ``a_n`` certainly nonzero) in ``|z| < r``,
    or ``None`` if the ball arithmetic cannot decide it (a ``delta_j`` contains 0).

    >>> from flint import arb
    >>> roots_inside([arb(-0.25), arb(0), arb(1)])  # z^2 - 1/4: both roots inside the unit circle
    2
    >>> roots_inside([arb(-4), arb(0), arb(1)]), roots_inside([arb(-1), arb(0), arb(1)])  # outside; on it
    (0, None)
    """
    from flint import arb

    r = arb(r) if not isinstance(r, arb) else r
    a = [c * r**k for k, c in enumerate(coeffs)]
    n = len(a) - 1
    count, sign = 0, 1
    for deg in range(n, 0, -1):
        a0, an = a[0], a[deg]
        # T f = a_0 f - a_deg f*  (real coefficients); its z^deg coefficient cancels exactly
        a = [a0 * a[j] - an * a[deg - j] for j in range(deg)]
        delta = a[0]
        if delta > 0:
            pass
        elif delta < 0:
            sign = -sign
        else:
            return None
        count += sign < 0
    return count


def _dyadic(x: Fraction, bits: int, up: bool) -> Fraction:
    """``x`` rounded up or down to a multiple of ``2**-bits`` (exact in Arb)."""
    scaled = x * 2**bits
    m = math.ceil(scaled) if up else math.floor(scaled)
    return Fraction(m, 2**bits)


def _arb_exact(q: Fraction) -> arb:
    from flint import arb

    # denominator is a power of two: exact at any working precision that holds the numerator
    return arb(q.numerator) / q.denominator


def _decimal(q: Fraction, digits: int, up: bool) -> str:
    """``q`` as a decimal string of ``digits`` significant digits, rounded toward +/- infinity."""
    with localcontext() as ctx:
        ctx.prec = digits
        ctx.rounding = ROUND_CEILING if up else ROUND_FLOOR
        return str(Decimal(q.numerator) / Decimal(q.denominator))


@dataclass(frozen=True)
class SpectralCertificate:
    """A proven statement about the spectral radius ``rho`` of one parameter point.

    ``rho_lower <= rho <= rho_upper`` (exact rationals; ``rho_upper`` is None
    when nothing bounds it), ``verdict`` is ``stable`` (``rho < 1`` proven),
    ``unstable`` (``rho > 1`` proven), ``marginal`` (the enclosure still
    contains 1 at the precision cap, e.g. ``rho = 1`` exactly) or
    ``undecided`` (the ball arithmetic lost every digit up to the cap);
    ``bits`` is the precision that decided it (or the cap).
    """

    verdict: str
    rho_lower: Fraction
    rho_upper: Fraction | None
    bits: int
    reason: str = ""
    cause: str = ""  # for ``undecided``: a code of icosim.engine.spectral.policy.REASONS

    def lower(self, digits: int = 20) -> str:
        """``rho_lower`` as a decimal string, rounded down."""
        return _decimal(self.rho_lower, digits, up=False)

    def upper(self, digits: int = 20) -> str:
        """``rho_upper`` as a decimal string, rounded up (``"inf"`` if unbounded)."""
        return "inf" if self.rho_upper is None else _decimal(self.rho_upper, digits, up=True)

    @property
    def certified(self) -> bool:
        """The verdict rests on the proven enclosure: stable, unstable, or marginal (1 proven inside it)."""
        return self.verdict in ("stable", "unstable", "marginal")

    @property
    def proven(self) -> bool:
        """A proven side of 1: stable or unstable."""
        return self.verdict in ("stable", "unstable")


def _enclosure(coeffs: Sequence[arb], n: int, rho_approx: float, bits: int) -> tuple[Fraction, Fraction | None]:
    """``(lower, upper)`` proven bounds on the largest root modulus, tightest found near ``rho_approx``.

    Radii just above and below the approximation are tried, moving away by
    2^-j for decreasing j until the count of roots inside is decided; the
    approximation comes from float64 root finding, so j starts at 48 (about
    its accuracy): the enclosure is ~1e-14 relative or wider, never narrower.
    """
    lower, upper = Fraction(0), None
    approx = Fraction(max(rho_approx, 0.0))
    steps = range(min(bits // 2, 48), -1, -4)
    for j in steps:
        step = Fraction(1, 2**j)
        r = _dyadic(approx * (1 + step) + (step if approx == 0 else 0), bits, up=True)
        if r > 0 and roots_inside(coeffs, _arb_exact(r)) == n:
            upper = r
            break
    for j in steps:
        r = _dyadic(approx * (1 - Fraction(1, 2**j)), bits, up=False)
        if r <= 0:
            break
        count = roots_inside(coeffs, _arb_exact(r))
        if count is not None and count < n:
            lower = r
            break
    return lower, upper


def _refine(
    coeffs: Sequence[arb], n: int, lower: Fraction, upper: Fraction, digits: int, bits: int
) -> tuple[Fraction, Fraction]:
    """Narrow ``[lower, upper]`` (a proven enclosure) to a relative width of ``10**-digits`` by bisection, or
    until no count inside it is decided (a cluster of roots, or the working precision's limit).

    Where the midpoint's count is undecided (a root modulus there: ``rho = 1``
    exactly is the midpoint of a symmetric start) the thirds are tried.
    """
    target = Fraction(1, 10**digits)
    while upper - lower > target * upper:
        width, moved = upper - lower, False
        for t in (Fraction(1, 2), Fraction(1, 3), Fraction(2, 3)):
            r = _dyadic(lower + t * width, bits, up=True)
            if not lower < r < upper:
                continue
            count = roots_inside(coeffs, _arb_exact(r))
            if count is not None:
                lower, upper = (r, upper) if count < n else (lower, r)
                moved = True
                break
        if not moved:
            break
    return lower, upper


def _approximate_rho(coeffs: Sequence[arb]) -> float:
    """Largest root modulus of the polynomial's midpoints (float64 roots; only a starting point for the proof).

    The coefficients are scaled by the largest one first, so huge ones do not overflow float64."""
    scale = max((abs(c.mid()) for c in coeffs), key=lambda a: float(a.log()) if a > 0 else -math.inf)
    mids = np.array([float((c / scale).mid()) if scale > 0 else 0.0 for c in coeffs])[::-1]
    if not np.all(np.isfinite(mids)) or not np.any(mids):
        return 1.0
    with np.errstate(all="ignore"):
        try:
            roots = np.roots(mids)
        except np.linalg.LinAlgError:  # the monic companion matrix overflows: a tiny leading coefficient
            roots = np.array([np.inf])
    if roots.size and np.all(np.isfinite(roots)):
        return float(np.max(np.abs(roots)))
    return _fujiwara_bound(coeffs)


def _fujiwara_bound(coeffs: Sequence[arb]) -> float:
    """Fujiwara's bound ``2 max |c_(n-i)/c_n|^(1/i)`` on the root moduli, in ball arithmetic (no overflow),
    as a float64 capped at 1e300 (a starting radius, not a proof)."""
    n = len(coeffs) - 1
    lead = abs(coeffs[-1].mid())
    if n < 1 or not lead > 0:
        return 1.0
    exps = [
        float(((abs(coeffs[n - i].mid()) / lead).log() / i).mid()) for i in range(1, n + 1) if coeffs[n - i].mid() != 0
    ]
    if not exps:
        return 0.0
    return float(min(2 * math.exp(min(max(exps), 690.0)), 1e300))


def certify_matrix(
    M: np.ndarray, bits: int, *, final: bool = True, digits: int | None = None
) -> SpectralCertificate | None:
    """The certificate of a ball amplification matrix ``M`` computed at ``bits`` (inside that context).

    Returns None if the verdict is undecided at this precision and ``final``
    is False (the caller raises the precision); with ``final`` an undecided
    count is ``marginal`` (or ``undecided`` if ``M`` is not finite).  With
    ``digits`` the enclosure is narrowed by bisection to that many significant
    digits where the arithmetic can decide (by default it is ~1e-14 wide: the
    verdict needs no more).
    """
    import flint

    n = M.shape[-1]
    if not all(x.is_finite() for x in M.ravel()):
        why = (
            f"the ball amplification matrix is not finite at {bits} bits: the coupling's linear system is singular "
            "at this point (a pivot is exactly 0), or every digit was lost"
        )
        return (
            SpectralCertificate("undecided", Fraction(0), None, bits, reason=why, cause="not_finite") if final else None
        )
    coeffs = flint.arb_mat(M.tolist()).charpoly().coeffs()
    count = roots_inside(coeffs, 1)
    rho_approx = _approximate_rho(coeffs) if n else 0.0
    lower, upper = _enclosure(coeffs, n, rho_approx, bits)
    if count is None and lower > 1:
        # a root on the unit circle leaves the count undecided, but a root proven outside it decides rho > 1
        count = n - 1
    if count is None and not final:
        return None
    verdict = "marginal" if count is None else "stable" if count == n else "unstable"
    if verdict == "stable":
        upper = Fraction(1) if upper is None else min(upper, Fraction(1))
    elif verdict == "unstable":
        lower = max(lower, Fraction(1))
    if digits is not None and upper is not None and verdict != "marginal":  # a marginal enclosure stays as decided
        lower, upper = _refine(coeffs, n, lower, upper, digits, bits)
    return SpectralCertificate(verdict, lower, upper, bits)


def certify_spectral_radius(
    family: LinearFamily,
    method: CouplingMethod,
    *,
    bits: int = DEFAULT_BITS,
    max_bits: int = MAX_BITS,
    max_guard_bits: int = MAX_GUARD_BITS,
    digits: int | None = None,
    **matrix_kw: Any,
) -> SpectralCertificate:
    """Prove ``rho < 1`` or ``rho > 1``, or report ``marginal``, for the one point of ``family``.

    The point's parameters are taken exactly (floats, Fractions, decimal strings:
    :meth:`~icosim.engine.spectral.family.LinearFamily.problem`).  The working precision starts at ``bits``
    (plus the family's :meth:`~icosim.engine.spectral.family.LinearFamily.guard_bits`); if that does not decide the verdict, it is
    computed once more at ``max_bits`` (plus the same guard); a point needing more than
    ``max_guard_bits`` guard bits is ``undecided`` at once, with the reason.
    ``digits``: narrow a proven (stable or unstable) enclosure to that many
    significant digits, at a working precision high enough for them (a cluster
    of roots, e.g. a multiple root, stops the narrowing where the arithmetic
    cannot separate it).  The verdict itself never depends on ``digits``: it
    comes from the ``bits``-then-``max_bits`` schedule, and a marginal
    enclosure is kept as decided there.  ``matrix_kw`` go to :func:`~icosim.engine.spectral.matrix.amplification_matrix`.

    >>> from icosim import TestModel, make_method
    >>> from icosim.problems.linear.family import TwoMass
    >>> c = certify_spectral_radius(TwoMass(TestModel(-0.05, 0.5), "ff", 2), make_method("weighted", a=1, b=1))
    >>> c.verdict, c.lower(6), c.upper(6)
    ('unstable', '1.02323', '1.02324')
    >>> certify_spectral_radius(TwoMass(TestModel(0.0, 0.3), "ff", 1), make_method("projection")).verdict  # undamped
    'marginal'
    """
    guard = family.guard_bits()
    if guard > max_guard_bits:
        why = f"needs {guard} guard bits for exp(-decay) entries, more than the cap of {max_guard_bits}"
        return SpectralCertificate("undecided", Fraction(0), None, 0, reason=why, cause="precision_cap")

    def matrix(b: int) -> np.ndarray:
        return amplification_matrix(family, method, backend=Ball(b + guard), exact=True, **matrix_kw)

    # the verdict comes from the same schedule whatever the digits asked for: ``bits``, then the cap
    b, max_bits = int(bits), max(int(max_bits), int(bits))
    while True:
        M = matrix(b)
        with Ball(b + guard).context():
            cert = certify_matrix(M, b + guard, final=b >= max_bits)
        if cert is not None:
            break
        # straight to the cap: a count undecided at ``bits`` means rho within ~2^-bits of 1 or a cluster of roots on
        # the circle, which in the paper's planes is rho = 1 exactly (marginal at any precision); the steps in
        # between would cost more than the cap itself (measured: 1.2-1.7 ms at 128 bits, 1.4-2.2 ms at 1024)
        b = max_bits
    if digits is None or not cert.proven or cert.rho_upper is None:
        # a marginal enclosure is kept as decided at the cap: narrowed further it could exclude 1, and the verdict
        # would then depend on the digits asked for
        return cert
    # narrowing a proven enclosure: at the precision the digits need (a side of 1 is kept by intersection)
    b_digits = max(b, math.ceil(digits * math.log2(10)) + 32)
    M = matrix(b_digits) if b_digits > b else M
    with Ball(b_digits + guard).context():
        import flint

        coeffs = flint.arb_mat(M.tolist()).charpoly().coeffs()
        lower, upper = _refine(coeffs, M.shape[-1], cert.rho_lower, cert.rho_upper, digits, b_digits + guard)
    return SpectralCertificate(cert.verdict, lower, upper, b_digits + guard if b_digits > b else cert.bits)
