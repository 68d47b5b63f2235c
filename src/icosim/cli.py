"""The ``icosim`` command.

``icosim rho`` prints the spectral radius of one parameter point of the test
model, decided by the precision policy (float64, rechecked at high precision
where float64 cannot be trusted) or, with ``--digits``, computed at that
precision directly.  Bad input is reported as ``icosim rho: error: ...``
naming the argument, with exit status 2 and no traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

from . import methods
from .backend import FLOAT64_DIGITS
from .decompositions import DECOMPOSITIONS, get_decomposition
from .model import ParameterError
from .schemes import get_scheme

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
    g.add_argument(
        "--scheme",
        choices=("jacobi", "gauss-seidel"),
        default="jacobi",
        help="coupling scheme: jacobi (parallel, the paper's; default) or gauss-seidel (sequential)",
    )
    g.add_argument(
        "--first",
        type=int,
        choices=(1, 2),
        help="gauss-seidel: the subsystem that advances first (default 1)",
    )
    g = rho.add_argument_group("method parameters")
    with_index = ", ".join(spec.label for spec in methods.METHODS.values() if spec.takes_index)
    g.add_argument("--index", type=int, choices=methods.indices(), help=f"index of the formulation ({with_index})")
    for name, p in methods.parameters().items():  # every registered method's parameters
        g.add_argument(f"--{name}", type=_float, help=p.help)
    g = rho.add_argument_group("test-model parameters (Eq. 71)")
    g.add_argument("--lr1", required=True, type=_float, help="real part of subsystem 1's eigenvalue (<= 0)")
    g.add_argument("--li1", required=True, type=_float, help="imaginary part of subsystem 1's eigenvalue (>= 0)")
    g.add_argument("--am21", required=True, type=_float, help="mass ratio m2/m1 (> 0)")
    g.add_argument("--alr21", required=True, type=_float, help="damping ratio lr2/lr1 (>= 0)")
    g.add_argument("--ali21", required=True, type=_float, help="frequency ratio li2/li1 (>= 0)")
    g = rho.add_argument_group("precision and output")
    g.add_argument(
        "--digits",
        type=_digits,
        help="compute with mpmath at this many significant digits (default: the precision policy, "
        "float64 rechecked at 128 digits where float64 cannot be trusted)",
    )
    g.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(subparser=None)
    rho.set_defaults(subparser=rho)
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
    from .stability import is_stable, spectral_radius, spectral_radius_mp

    if args.first is not None and args.scheme != "gauss-seidel":
        parser.error("argument --first: only used with --scheme gauss-seidel")
    scheme = get_scheme(args.scheme, args.first)
    try:
        method = _method_from_args(args)
        decomposition = get_decomposition(args.decomposition)
        method.check_decomposition(decomposition)
        model = TestModel(args.lr1, args.li1, args.am21, args.alr21, args.ali21)
    except ParameterError as exc:
        parser.error(_argument_message(str(exc)))
    if args.digits is not None:
        rho = float(spectral_radius_mp(model, method, decomposition, args.k, args.digits, scheme=scheme))
        digits, err, precision = args.digits, None, f"mpmath {args.digits} digits (requested)"
    else:
        res = spectral_radius(model, method, decomposition, args.k, scheme=scheme)
        rho, digits = float(res.rho), int(res.digits)
        err = float(res.err)
        precision = "float64" if digits == FLOAT64_DIGITS else f"mpmath {digits} digits (float64 not trusted)"
    stable = bool(is_stable(rho, digits))
    result = {
        "rho": rho,
        "digits": digits,
        "precision": precision,
        "stable": stable,
        "float64_error_estimate": err if err is None or math.isfinite(err) else None,
        "method": method.name,
        "decomposition": decomposition.name,
        "k": args.k,
        "scheme": scheme.name,
        "method_parameters": method.params,
        "model": {n: getattr(args, n) for n in ("lr1", "li1", "am21", "alr21", "ali21")},
    }
    if args.json:
        print(json.dumps(result))
    else:
        order = "" if scheme.name == "jacobi" else f"{scheme.label}; "
        print(f"rho = {rho!r}  ({'stable' if stable else 'unstable'}; {order}decided by {precision})")
    return 0


def _argument_message(text: str) -> str:
    """Messages from the library name parameters; make them read like argparse's."""
    for name in ("lr1", "li1", "am21", "alr21", "ali21") + methods.argument_names():
        if text.startswith(f"{name} "):  # also "a and b must be ..." -> --a
            return f"argument --{name}: {text}"
    if text.startswith("method "):
        return f"argument --method/--decomposition: {text}"
    return text


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command == "rho":
        return _rho(args, args.subparser)
    return 2  # pragma: no cover - argparse enforces a command


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
