"""The ``icosim`` command.

``icosim rho`` prints the spectral radius of one parameter point of the test
model, decided by the precision policy (float64, rechecked at high precision
where float64 cannot be trusted) or, with ``--digits N``, computed at N
significant digits directly: then every number is taken as the decimal typed
(``--lr1 -0.3`` is -3/10, not the nearest double) and the result is printed
with N significant digits.  Negative values may follow their option with a
space, also in exponent notation (``--lr1 -1e-3``).  Bad input is reported as
``icosim rho: error: ...`` naming the argument, with exit status 2 and no
traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from fractions import Fraction

import mpmath

from . import methods
from .backend import FLOAT64_DIGITS
from .decompositions import DECOMPOSITIONS, get_decomposition
from .model import ParameterError

__all__ = ["main", "build_parser"]


def _float(text):
    """A finite float (NaN and infinity are refused)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _decimal(text):
    """A finite number, kept exactly as the decimal typed (a :class:`~fractions.Fraction`)."""
    _float(text)  # the same checks and messages as a float argument
    return Fraction(text.strip())


def _nonneg_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def _digits(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 16, got {text!r}") from None
    if value < 16:
        raise argparse.ArgumentTypeError(
            f"expected an integer >= 16 (float64 carries {FLOAT64_DIGITS}; omit --digits for it), got {text!r}"
        )
    return value


def _bits(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 128, got {text!r}") from None
    if value < 128:
        raise argparse.ArgumentTypeError(f"expected an integer >= 128 (the first attempt's precision), got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = argparse.ArgumentParser(
        prog="icosim",
        description="Implicit co-simulation methods with algebraic constraints (Schweizer et al.).",
    )
    parser.add_argument("--version", action="version", version=f"icosim {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    rho = sub.add_parser(
        "rho",
        help="spectral radius of one parameter point",
        description="Spectral radius of the co-simulation recurrence for one point of the test model (Eq. 71).",
    )
    g = rho.add_argument_group("method and layout")
    g.add_argument("--method", required=True, choices=tuple(methods.METHODS))
    g.add_argument("--decomposition", required=True, choices=tuple(DECOMPOSITIONS))
    g.add_argument("--k", required=True, type=_nonneg_int, help="approximation order (integer >= 0)")
    g = rho.add_argument_group("method parameters")
    with_index = ", ".join(spec.label for spec in methods.METHODS.values() if spec.takes_index)
    g.add_argument("--index", type=int, choices=methods.indices(), help=f"index of the formulation ({with_index})")
    for name, p in methods.parameters().items():  # every registered method's parameters
        g.add_argument(f"--{name}", type=_decimal, help=p.help)
    g = rho.add_argument_group("test-model parameters (Eq. 71)")
    g.add_argument("--lr1", required=True, type=_decimal, help="real part of subsystem 1's eigenvalue (<= 0)")
    g.add_argument("--li1", required=True, type=_decimal, help="imaginary part of subsystem 1's eigenvalue (>= 0)")
    g.add_argument("--am21", required=True, type=_decimal, help="mass ratio m2/m1 (> 0)")
    g.add_argument("--alr21", required=True, type=_decimal, help="damping ratio lr2/lr1 (>= 0)")
    g.add_argument("--ali21", required=True, type=_decimal, help="frequency ratio li2/li1 (>= 0)")
    g = rho.add_argument_group("precision and output")
    g.add_argument(
        "--digits",
        type=_digits,
        help="compute with mpmath at this many significant digits, the arguments taken as the decimals typed, "
        "and print rho with as many digits (default: the precision policy, float64 rechecked at 128 digits "
        "where float64 cannot be trusted)",
    )
    g.add_argument(
        "--certify",
        action="store_true",
        help="prove the verdict in ball arithmetic (python-flint Arb): stable (rho < 1), unstable (rho > 1) or "
        "marginal (the proven enclosure still contains 1 at --max-bits); prints the enclosure",
    )
    g.add_argument(
        "--max-bits",
        type=_bits,
        default=1024,
        help="largest working precision of the ball arithmetic, in bits (default 1024)",
    )
    g.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(subparser=None)
    rho.set_defaults(subparser=rho)
    from .commands import add_parsers  # icosim advise, icosim map

    add_parsers(sub, number=_float, nonneg_int=_nonneg_int, digits=_digits)
    return parser


def _method_from_args(args):
    spec = methods.get_spec(args.method)
    given = {name: getattr(args, name, None) for name in methods.argument_names()}
    given = {k: v for k, v in given.items() if v is not None}
    extra = sorted(set(given) - set(spec.arguments))
    if extra:
        allowed = ", ".join(f"--{a}" for a in spec.arguments) or "none"
        raise ParameterError(f"argument --{extra[0]}: not used by --method {args.method} (its parameters: {allowed})")
    return spec.make(**given)


def _rho(args, parser):
    from .model import TestModel
    from .stability import Certification, certify_spectral_radius, spectral_radius, spectral_radius_mp

    try:
        method = _method_from_args(args)
        decomposition = get_decomposition(args.decomposition)
        method.check_decomposition(decomposition)
        model = TestModel(args.lr1, args.li1, args.am21, args.alr21, args.ali21)
    except ParameterError as exc:
        parser.error(_argument_message(str(exc)))
    result = {}
    cert = None
    if args.certify or args.digits is not None:
        # the verdict is proven from the exact (typed) parameters, whatever precision the value is printed in
        # the enclosure narrowed to N digits (--digits N; else 17, a double's) where the arithmetic separates
        # the roots: its midpoint is then the value printed
        cert = certify_spectral_radius(
            model, method, decomposition, args.k, max_bits=args.max_bits, digits=args.digits or 17
        )
    if args.digits is not None:
        rho_mp = spectral_radius_mp(model, method, decomposition, args.k, args.digits)
        rho, rho_text = float(rho_mp), mpmath.nstr(rho_mp, args.digits, strip_zeros=False)
        digits, err, precision = args.digits, None, f"mpmath {args.digits} digits (requested)"
    elif cert is not None:
        rho = float((cert.rho_lower + cert.rho_upper) / 2) if cert.rho_upper is not None else float("nan")
        rho_text, digits, err = repr(rho), int(cert.bits * math.log10(2)), None
        precision = f"ball arithmetic {cert.bits} bits (requested)"
    else:
        res = spectral_radius(model, method, decomposition, args.k, certification=Certification(audit=0.0))
        rho, digits, err = float(res.rho), int(res.digits), float(res.err)
        rho_text = repr(rho)
        if str(res.arithmetic) == "float64":
            precision = "float64"
        else:
            precision = f"ball arithmetic {int(res.bits)} bits (float64 cannot decide)"
            cert = _certificate_of(res)
        verdict = str(res.verdict)
    if cert is not None:
        verdict = cert.verdict
        result.update(
            rho_lower=cert.lower(max(20, args.digits or 0)),
            rho_upper=cert.upper(max(20, args.digits or 0)),
            precision_bits=cert.bits,
        )
    result = {
        # a decimal string where a float would drop digits (more than 17 significant digits asked for)
        "rho": rho_text if args.digits is not None and args.digits > 17 else rho if math.isfinite(rho) else None,
        "rho_float": rho if math.isfinite(rho) else None,
        "verdict": verdict,
        "stable": verdict == "stable",
        "certified": cert is not None and cert.certified,
        "digits": digits,
        "precision": precision,
        "float64_error_estimate": err if err is None or math.isfinite(err) else None,
        **result,
        "method": method.name,
        "decomposition": decomposition.name,
        "k": args.k,
        "method_parameters": method.params,
        "model": {n: float(getattr(args, n)) for n in ("lr1", "li1", "am21", "alr21", "ali21")},
    }
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return 0
    print(f"rho = {rho_text}  ({_verdict_text(cert, verdict, precision, args.digits)})")
    return 0


def _verdict_text(cert, verdict, precision, digits) -> str:
    """The verdict, its proof (enclosure and bits) if there is one, and where the printed value comes from."""
    if cert is None:
        return f"{verdict}; decided by {precision}"
    n = max(12, min(digits or 0, 60))
    enclosure = f"rho in [{cert.lower(n)}, {cert.upper(n)}]"
    proof = {
        "stable": f"stable, proven: {enclosure}",
        "unstable": f"unstable, proven: {enclosure}",
        "marginal": f"marginal: the proven {enclosure} contains 1",
    }.get(verdict, f"{verdict}: {cert.reason}")
    proof += f" at {cert.bits} bits"
    value = f"value by {precision}" if precision.startswith("mpmath") else f"decided by {precision}"
    return f"{proof}; {value}"


def _certificate_of(res):
    """The certificate a policy result holds for its one point (bounds as exact rationals of the floats)."""
    from fractions import Fraction

    from .stability import SpectralCertificate

    upper = float(res.rho_upper)
    return SpectralCertificate(
        str(res.verdict),
        Fraction(float(res.rho_lower)) if math.isfinite(float(res.rho_lower)) else Fraction(0),
        Fraction(upper) if math.isfinite(upper) else None,
        int(res.bits),
    )


def _argument_message(text: str) -> str:
    """Messages from the library name parameters; make them read like argparse's."""
    for name in ("lr1", "li1", "am21", "alr21", "ali21") + methods.argument_names():
        if text.startswith(f"{name} "):  # also "a and b must be ..." -> --a
            return f"argument --{name}: {text}"
    if text.startswith("method "):
        return f"argument --method/--decomposition: {text}"
    return text


def _negative_values_attached(argv, parser) -> list:
    """``--lr1 -1e-3`` as ``--lr1=-1e-3``.

    argparse reads a token that starts with ``-`` as an option unless it looks
    like a plain negative number (``-1``, ``-.5``); exponent notation is not
    covered.  A token after an option that takes a value is joined to it when
    it parses as a number, so users can type numbers as they write them.
    """
    # options that take exactly one value (flags such as --json have nargs = 0)
    argv = list(argv)
    # the command's own options only: another command may take the same option with several values
    takes_value = {
        opt for action in _all_actions(parser, argv) if action.nargs is None for opt in action.option_strings
    }
    out, i = [], 0
    while i < len(argv):
        tok = argv[i]
        if tok in takes_value and i + 1 < len(argv) and argv[i + 1].startswith("-") and _is_number(argv[i + 1]):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
            continue
        out.append(tok)
        i += 1
    return out


def _all_actions(parser, argv=()):
    for action in parser._actions:
        yield action
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                if name in argv[:1]:
                    yield from _all_actions(sub)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def main(argv=None) -> int:
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else argv
    args = parser.parse_args(_negative_values_attached(argv, parser))
    if args.command == "rho":
        return _rho(args, args.subparser)
    if args.command in ("advise", "map"):
        from .commands import run

        return run(args)
    return 2  # pragma: no cover - argparse enforces a command


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
