"""``icosim rho``: the spectral radius of one parameter point, its verdict proven.

Every answer of the command rests on ball arithmetic
(:func:`icosim.problems.linear.spectral.certify_spectral_radius`): the parameters are taken
exactly as typed (``--lr1 -0.3`` is -3/10, not the nearest double), the verdict is proven (stable,
unstable, or marginal: the enclosure still contains 1 at ``--max-bits``), and
the value printed is the midpoint of the proven enclosure narrowed to the
digits asked for (17 by default, a double's; ``--digits N``), showing only
digits that are proven.  So the verdict never depends on the precision asked
for, and a value is never printed to more digits than are known.  float64's own
value and error estimate are shown beside it for comparison.

Bad input -- including input beyond a limit of :mod:`icosim.engine.bounds` -- is reported
as ``icosim rho: error: ...`` naming the argument, with exit status 2, before
any work and without a traceback.  A point that cannot be decided (a precision beyond a cap,
the time budget ``--timeout``, every digit lost at the cap) is ``undecided`` with the reason:
exit status 0, ``"rho": null``.
"""

from __future__ import annotations

import math
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal, localcontext
from fractions import Fraction

import numpy as np

from ..engine import methods
from ..engine.bounds import MAX_BITS_LIMIT, MAX_DIGITS, MAX_GUARD_BITS, MAX_K, check_derived, time_budget
from ..engine.decompositions import DECOMPOSITIONS, get_decomposition
from ..engine.schemes import JACOBI, get_scheme
from ..engine.spectral.policy import reason_code
from ..engine.stages import check
from ..errors import ParameterError, PointTimeout
from ..io.jsonio import dumps
from .arguments import (
    CHAIN_ONLY,
    add_chain_arguments,
    bits,
    decimal,
    digits,
    order,
    scheme_or_order,
    seconds,
    two_unit_arguments,
)

__all__ = ["add_parser", "run", "rho_answer", "rho_text"]


def add_parser(sub):
    """Register ``rho`` on the ``icosim`` sub-command parsers."""
    rho = sub.add_parser(
        "rho",
        help="spectral radius of one parameter point",
        description="Spectral radius of the co-simulation recurrence for one point of the test model (Eq. 71).",
    )
    g = rho.add_argument_group("method and layout")
    g.add_argument("--method", required=True, choices=tuple(methods.METHODS))
    g.add_argument(
        "--decomposition", choices=tuple(DECOMPOSITIONS), help="the joint's decomposition (required without --chain)"
    )
    g.add_argument("--k", required=True, type=order, help=f"approximation order (integer 0..{MAX_K})")
    g.add_argument(
        "--scheme",
        type=scheme_or_order,
        default="jacobi",
        help="coupling scheme: jacobi (parallel, the paper's; default), gauss-seidel-12 (sequential, subsystem 1 "
        "first), gauss-seidel-21 (subsystem 2 first), or a variant (docs/gauss_seidel.md); with --chain also "
        "gauss-seidel-forward (units 1 -> N), gauss-seidel-reverse (N -> 1) or an order of the units such as 3,1,2",
    )
    g = rho.add_argument_group("method parameters")
    with_index = ", ".join(spec.label for spec in methods.METHODS.values() if spec.takes_index)
    g.add_argument("--index", type=int, choices=methods.indices(), help=f"index of the formulation ({with_index})")
    for name, p in methods.parameters().items():  # every registered method's parameters
        g.add_argument(f"--{name}", type=decimal, help=p.help)
    g = rho.add_argument_group("test-model parameters (Eq. 71; required without --chain)")
    g.add_argument("--lr1", type=decimal, help="real part of subsystem 1's eigenvalue (<= 0)")
    g.add_argument("--li1", type=decimal, help="imaginary part of subsystem 1's eigenvalue (>= 0)")
    g.add_argument("--am21", type=decimal, help="mass ratio m2/m1 (> 0)")
    g.add_argument("--alr21", type=decimal, help="damping ratio lr2/lr1 (>= 0)")
    g.add_argument("--ali21", type=decimal, help="frequency ratio li2/li1 (>= 0)")
    add_chain_arguments(rho)
    g = rho.add_argument_group(
        "precision and output",
        "The verdict is always proven in ball arithmetic (python-flint Arb) from the decimals as typed: stable "
        "(rho < 1), unstable (rho > 1), or marginal (the proven enclosure still contains 1 at --max-bits). "
        f"Limits: k <= {MAX_K}, --digits <= {MAX_DIGITS}, --max-bits <= {MAX_BITS_LIMIT}, guard bits for heavily "
        f"damped subsystems <= {MAX_GUARD_BITS}; a point needing more is 'undecided' with the reason.",
    )
    g.add_argument(
        "--digits",
        type=digits,
        help="print rho with this many significant digits, all proven (the enclosure narrowed to them; default 17)",
    )
    g.add_argument("--certify", action="store_true", help="also print the proven enclosure of rho in the text output")
    g.add_argument(
        "--max-bits",
        type=bits,
        default=1024,
        help=f"largest working precision of the ball arithmetic, in bits (default 1024, at most {MAX_BITS_LIMIT})",
    )
    g.add_argument(
        "--timeout",
        type=seconds,
        help="give up after this many seconds of wall time: the verdict is then 'undecided' (reason timeout)",
    )
    g.add_argument("--json", action="store_true", help="print one JSON object")
    rho.set_defaults(subparser=rho)
    return rho


def _method_from_args(args):
    spec = methods.get_spec(args.method)
    given = {name: getattr(args, name, None) for name in methods.argument_names()}
    given = {k: v for k, v in given.items() if v is not None}
    extra = sorted(set(given) - set(spec.arguments))
    if extra:
        allowed = ", ".join(f"--{a}" for a in spec.arguments) or "none"
        raise ParameterError(f"argument --{extra[0]}: not used by --method {args.method} (its parameters: {allowed})")
    return spec.make(**given)


def run(args, parser) -> int:
    """``icosim rho``: check the arguments (exit 2 naming the bad one), then answer."""
    from ..problems.linear.model import TestModel

    two_unit_arguments(args, parser, ("decomposition",) + MODEL_NAMES)
    try:
        scheme = get_scheme(args.scheme)
    except ParameterError:
        parser.error(f"argument --scheme: {args.scheme!r} names a chain's scheme: {CHAIN_ONLY}")
    try:
        method = _method_from_args(args)
        decomposition = get_decomposition(args.decomposition)
        method.check_decomposition(decomposition)
        check(scheme, decomposition)
        model = TestModel(args.lr1, args.li1, args.am21, args.alr21, args.ali21)
        check_derived(model)  # k = lr^2 + li^2, ... finite in float64
    except ParameterError as exc:
        parser.error(_argument_message(str(exc)))
    answer = rho_answer(model, method, decomposition, args.k, scheme=scheme, **precision(args))
    result = {
        **answer,
        "method": method.name,
        "decomposition": decomposition.name,
        "k": args.k,
        "scheme": scheme.name,
        "method_parameters": method.params,
        "model": {n: float(getattr(args, n)) for n in MODEL_NAMES},
    }
    if args.json:
        print(dumps(result))
    else:
        print(rho_text(answer, show_enclosure=args.certify, scheme=scheme))
    return 0


def precision(args) -> dict:
    """The precision and time budget the arguments ask for (:func:`family_answer`'s keywords)."""
    return {"digits": args.digits, "max_bits": args.max_bits, "timeout": args.timeout}


def _argument_message(text: str) -> str:
    """Messages from the library name parameters; make them read like argparse's."""
    for name in MODEL_NAMES + methods.argument_names():
        if text.startswith(f"{name} "):  # also "a and b must be ..." -> --a
            return f"argument --{name}: {text}"
    if text.startswith("method "):
        return f"argument --method/--decomposition: {text}"
    if text.startswith("scheme "):
        return f"argument --scheme/--decomposition: {text}"
    return text


#: Digits the value is narrowed to without ``--digits`` (a double's 17 significant digits).
DEFAULT_DIGITS = 17


def rho_answer(model, method, decomposition, k, *, digits=None, max_bits=1024, timeout=None, scheme=JACOBI) -> dict:
    """The command's answer as a JSON-ready dict (strict: no NaN or infinity; ``None`` with ``reason``).

    ``model`` is a :class:`~icosim.problems.linear.model.TestModel` of one point (Fractions kept exact); ``scheme`` the
    coupling scheme (:mod:`icosim.engine.schemes`), used by the proof and by float64 alike.
    """
    from ..problems.linear.family import TwoMass

    def floats():
        return TwoMass(type(model)(*(float(getattr(model, n)) for n in MODEL_NAMES)), decomposition, k)

    family = TwoMass(model, decomposition, k)
    return family_answer(family, method, floats, digits=digits, max_bits=max_bits, timeout=timeout, scheme=scheme)


#: The parameters of the test model (Eq. 71), as the command takes them.
MODEL_NAMES = ("lr1", "li1", "am21", "alr21", "ali21")


def family_answer(family, method, float_family, *, digits=None, max_bits=1024, timeout=None, scheme=JACOBI) -> dict:
    """:func:`rho_answer` for the one point of any :class:`~icosim.engine.spectral.family.LinearFamily` (a chain's
    too): the proof on ``family``, float64's value and error estimate on ``float_family()`` (the same point in
    floats; called inside the time budget, an error there leaves float64's value out)."""
    from ..engine.spectral.certified import certify_spectral_radius

    scheme = get_scheme(scheme)

    want = digits or DEFAULT_DIGITS
    out = {"rho": None, "rho_float": None, "verdict": "undecided", "stable": False, "certified": False}
    out.update(digits=-1, precision="", reason="", reason_code="none", rho_lower=None, rho_upper=None)
    out.update(precision_bits=None)
    out.update(rho_decimal=None, rho_float64=None, float64_error_estimate=None)
    try:
        with time_budget(timeout):
            out["rho_float64"], out["float64_error_estimate"] = _float64(float_family, method, scheme)
            cert = certify_spectral_radius(family, method, max_bits=max_bits, digits=want, scheme=scheme)
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


def _float64(float_family, method, scheme=JACOBI):
    """float64's value and error estimate for comparison (None where float64 gives nothing finite)."""
    from ..engine.spectral.radius import spectral_radius_float64

    try:
        with np.errstate(all="ignore"):
            r, e = spectral_radius_float64(float_family(), method, scheme=scheme)
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
