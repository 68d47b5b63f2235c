"""``icosim rho``: the spectral radius of one parameter point, its verdict proven.

Every answer of the command rests on ball arithmetic
(:func:`icosim.engine.spectral.certify_spectral_radius`): the parameters are taken
exactly as typed (``--lr1 -0.3`` is -3/10), the verdict is proven (stable,
unstable, or marginal: the enclosure still contains 1 at ``--max-bits``), and
the value printed is the midpoint of the proven enclosure narrowed to the
digits asked for (17 by default, a double's; ``--digits N``), showing only
digits that are proven.  So the verdict never depends on the precision asked
for, and a value is never printed to more digits than are known.  float64's own
value and error estimate are shown beside it for comparison.

A point that cannot be decided (a precision beyond a cap, the time budget
``--timeout``, every digit lost at the cap) is ``undecided`` with the reason:
exit status 0, ``"rho": null``.  Bad input never gets here (exit 2 first).
"""

from __future__ import annotations

import math
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal, localcontext
from fractions import Fraction

import numpy as np

from .engine.bounds import time_budget
from .engine.schemes import JACOBI, get_scheme
from .engine.spectral.policy import reason_code
from .errors import PointTimeout

__all__ = ["rho_answer", "rho_text"]

#: Digits the value is narrowed to without ``--digits`` (a double's 17 significant digits).
DEFAULT_DIGITS = 17


def rho_answer(model, method, decomposition, k, *, digits=None, max_bits=1024, timeout=None, scheme=JACOBI) -> dict:
    """The command's answer as a JSON-ready dict (strict: no NaN or infinity; ``None`` with ``reason``).

    ``model`` is a :class:`~icosim.engine.model.TestModel` of one point (Fractions kept exact); ``scheme`` the
    coupling scheme (:mod:`icosim.engine.schemes`), used by the proof and by float64 alike.
    """
    from .engine.spectral import certify_spectral_radius

    scheme = get_scheme(scheme)

    want = digits or DEFAULT_DIGITS
    out = {"rho": None, "rho_float": None, "verdict": "undecided", "stable": False, "certified": False}
    out.update(digits=-1, precision="", reason="", reason_code="none", rho_lower=None, rho_upper=None)
    out.update(precision_bits=None)
    out.update(rho_decimal=None, rho_float64=None, float64_error_estimate=None)
    try:
        with time_budget(timeout):
            out["rho_float64"], out["float64_error_estimate"] = _float64(model, method, decomposition, k, scheme)
            cert = certify_spectral_radius(
                model, method, decomposition, k, max_bits=max_bits, digits=want, scheme=scheme
            )
    except (ArithmeticError, ValueError) as exc:  # a timeout, a cap, an overflow: undecided, with the reason
        out["reason"], out["reason_code"] = str(exc), reason_code(exc)
        out["precision"] = "none (undecided)"
        return out
    out["verdict"], out["stable"], out["certified"] = cert.verdict, cert.verdict == "stable", cert.certified
    out["precision_bits"] = cert.bits
    if cert.verdict == "undecided":
        out["reason"], out["reason_code"] = cert.reason, cert.cause or "precision_cap"
        out["precision"] = f"ball arithmetic {cert.bits} bits (undecided)"
        return out
    proven = _proven_digits(cert)
    shown = min(proven, want)
    out["rho_lower"], out["rho_upper"] = cert.lower(max(20, want)), _upper(cert, max(20, want))
    out["digits"] = shown
    out["precision"] = f"ball arithmetic {cert.bits} bits"
    if cert.rho_upper is None:  # nothing bounds rho from above: only the lower bound is known
        out["reason"] = "rho is proven > 1 but not bounded above at this precision"
        return out
    mid = (cert.rho_lower + cert.rho_upper) / 2
    out["rho_float"] = float(mid)
    if shown > 0:
        out["rho_decimal"] = _significant(mid, shown)  # exactly the digits that are proven
        # a decimal string where a float would drop digits (more than 17 asked for), else the float of those digits
        out["rho"] = out["rho_decimal"] if digits and digits > 17 else float(out["rho_decimal"])
    if shown < want:
        why = (
            "a marginal enclosure is kept as decided at the cap"
            if cert.verdict == "marginal"
            else "a cluster of roots, or digits lost to the guard bits of heavily damped subsystems"
        )
        out["reason"] = f"{shown} of the {want} digits asked for are proven at {cert.bits} bits ({why})"
    return out


def rho_text(answer: dict, *, show_enclosure: bool = False, scheme=JACOBI) -> str:
    """One line: the value, the verdict and its proof (and the enclosure with ``show_enclosure``); a scheme
    other than Jacobi is named."""
    a = answer
    scheme = get_scheme(scheme)
    order = "" if scheme.name == "jacobi" else f"{scheme.label}; "
    if a["rho"] is None and a["verdict"] == "undecided":
        return f"rho undecided  ({order}{a['reason']})"
    value = a["rho_decimal"] or ("not bounded" if a["rho_upper"] is None else "no digit proven")
    lo, hi = a["rho_lower"], a["rho_upper"]
    n = max(12, min(a["digits"] + 1, 60))
    low = _rounded(lo, n, up=False)
    enclosure = f"rho in [{low}, {_rounded(hi, n, up=True)}]" if hi is not None else f"rho >= {low}"
    proof = {
        "stable": f"stable, proven: {enclosure}" if show_enclosure else "stable, proven",
        "unstable": f"unstable, proven: {enclosure}" if show_enclosure else "unstable, proven",
        "marginal": f"marginal: the proven {enclosure} contains 1",
    }[a["verdict"]]
    f64 = a["rho_float64"]
    f64_text = "" if f64 is None else f"; float64 gives {f64!r}"
    note = f"; {a['reason']}" if a["reason"] else ""
    return f"rho = {value}  ({order}{proof} at {a['precision_bits']} bits, {a['digits']} digits{f64_text}{note})"


def _float64(model, method, decomposition, k, scheme=JACOBI):
    """float64's value and error estimate for comparison (None where float64 gives nothing finite)."""
    from .engine.spectral import spectral_radius_float64

    try:
        with np.errstate(all="ignore"):
            floats = type(model)(*(float(getattr(model, n)) for n in ("lr1", "li1", "am21", "alr21", "ali21")))
            r, e = spectral_radius_float64(floats, method, decomposition, k, scheme=scheme)
    except PointTimeout:  # the command's time budget, not float64's failure
        raise
    except (ArithmeticError, ValueError, np.linalg.LinAlgError):  # float64 cannot even form the point
        return None, None
    return _finite(r), _finite(e)


def _finite(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _upper(cert, digits):
    return None if cert.rho_upper is None else cert.upper(digits)


def _proven_digits(cert) -> int:
    """Significant digits the enclosure's midpoint is known to: ``floor(log10(mid / half-width))``."""
    if cert.rho_upper is None:
        return 0
    mid = (cert.rho_lower + cert.rho_upper) / 2
    half = (cert.rho_upper - cert.rho_lower) / 2
    if half == 0:
        return 10**6
    if mid == 0 or half >= abs(mid):
        return 0
    ratio = abs(mid) / half  # exact; log10 of its (big) integer parts, no float underflow
    return max(0, math.floor(math.log10(ratio.numerator) - math.log10(ratio.denominator)))


def _significant(q: Fraction, digits: int) -> str:
    """``q`` rounded to ``digits`` significant digits, as a decimal string."""
    with localcontext() as ctx:
        ctx.prec = max(digits, 1)
        return str(+(Decimal(q.numerator) / Decimal(q.denominator)))


def _rounded(text: str | None, n: int, up: bool) -> str:
    """A decimal bound shortened to ``n`` significant digits, rounded outward (display only)."""
    if text is None:
        return "inf"
    with localcontext() as ctx:
        ctx.prec, ctx.rounding = n, (ROUND_CEILING if up else ROUND_FLOOR)
        return str(+Decimal(text))
