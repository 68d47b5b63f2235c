"""Certified stability verdicts: a proven enclosure of the spectral radius (ball arithmetic).

The amplification matrix is computed by the engine's own macro step in Arb ball
arithmetic (:class:`icosim.backend.Ball`), so each entry is a ball that contains
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
* ``unstable``: fewer than ``n`` roots in ``|z| < 1`` and none on ``|z| = 1``
  (proven: ``rho > 1``);
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
from dataclasses import dataclass
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal, localcontext
from fractions import Fraction

import numpy as np

from ..backend import Ball
from ..model import Coefficients, PhysicalModel, TestModel
from .matrix import amplification_matrix

__all__ = [
    "certify_spectral_radius",
    "certify_matrix",
    "SpectralCertificate",
    "roots_inside",
    "VERDICTS",
    "DEFAULT_BITS",
    "MAX_BITS",
]

#: The verdicts a certificate can give (``undecided``: the ball arithmetic lost every digit at the cap).
VERDICTS = ("stable", "unstable", "marginal", "undecided")
#: Working precision of the first attempt and the default cap (bits), doubled in between.
DEFAULT_BITS, MAX_BITS = 128, 1024


def roots_inside(coeffs, r=1):
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


def _arb_exact(q: Fraction):
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

    def lower(self, digits: int = 20) -> str:
        """``rho_lower`` as a decimal string, rounded down."""
        return _decimal(self.rho_lower, digits, up=False)

    def upper(self, digits: int = 20) -> str:
        """``rho_upper`` as a decimal string, rounded up (``"inf"`` if unbounded)."""
        return "inf" if self.rho_upper is None else _decimal(self.rho_upper, digits, up=True)

    @property
    def certified(self) -> bool:
        """A verdict proven by the enclosure: stable or unstable."""
        return self.verdict in ("stable", "unstable")


def _enclosure(coeffs, n, rho_approx: float, bits: int):
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


def certify_matrix(M, bits: int, *, final: bool = True) -> SpectralCertificate | None:
    """The certificate of a ball amplification matrix ``M`` computed at ``bits`` (inside that context).

    Returns None if the verdict is undecided at this precision and ``final``
    is False (the caller raises the precision); with ``final`` an undecided
    count is ``marginal`` (or ``undecided`` if ``M`` is not finite).
    """
    import flint

    n = M.shape[-1]
    if not all(x.is_finite() for x in M.ravel()):
        return SpectralCertificate("undecided", Fraction(0), None, bits) if final else None
    coeffs = flint.arb_mat(M.tolist()).charpoly().coeffs()
    count = roots_inside(coeffs, 1)
    if count is None and not final:
        return None
    verdict = "marginal" if count is None else "stable" if count == n else "unstable"
    mids = np.array([float(c.mid()) for c in coeffs])[::-1]
    rho_approx = float(np.max(np.abs(np.roots(mids)))) if n else 0.0
    lower, upper = _enclosure(coeffs, n, rho_approx, bits)
    if verdict == "stable":
        upper = Fraction(1) if upper is None else min(upper, Fraction(1))
    elif verdict == "unstable":
        lower = max(lower, Fraction(1))
    return SpectralCertificate(verdict, lower, upper, bits)


def certify_spectral_radius(
    model, method, decomposition, k, *, bits: int = DEFAULT_BITS, max_bits: int = MAX_BITS, **matrix_kw
) -> SpectralCertificate:
    """Prove ``rho < 1`` or ``rho > 1``, or report ``marginal``, for one parameter point.

    ``model`` is a :class:`~icosim.model.TestModel` (or ``PhysicalModel`` /
    ``Coefficients``) of one point whose attributes are taken exactly (floats,
    Fractions, decimal strings).  The working precision starts at ``bits`` and
    doubles until the verdict is decided or ``max_bits`` is reached.
    ``matrix_kw`` go to :func:`~icosim.stability.matrix.amplification_matrix`.

    >>> from icosim import TestModel, make_method
    >>> c = certify_spectral_radius(TestModel(-0.05, 0.5), make_method("weighted", a=1, b=1), "ff", 2)
    >>> c.verdict, c.lower(6), c.upper(6)
    ('unstable', '1.02323', '1.02324')
    >>> certify_spectral_radius(TestModel(0.0, 0.3), make_method("projection"), "ff", 1).verdict  # undamped
    'marginal'
    """
    b = int(bits)
    max_bits = max(int(max_bits), b)
    while True:
        be = Ball(b)
        with be.context():
            M = amplification_matrix(_exact_coefficients(model, be), method, decomposition, k, backend=be, **matrix_kw)
            cert = certify_matrix(M, b, final=b >= max_bits)
        if cert is not None:
            return cert
        b = min(2 * b, max_bits)


def _exact_coefficients(model, be):
    if isinstance(model, TestModel):
        values = (getattr(model, f) for f in ("lr1", "li1", "am21", "alr21", "ali21"))
        return TestModel(*(be.const(v) for v in values)).coefficients()
    if isinstance(model, PhysicalModel):
        model = model.coefficients()
    return Coefficients(*(be.const(getattr(model, f)) for f in ("k1", "delta1", "k2", "delta2", "am21")))
