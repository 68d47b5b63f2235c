"""The ``icosim`` command.

``icosim rho`` prints the spectral radius of one parameter point of the test
model with its verdict proven in ball arithmetic (stable, unstable, or
marginal), every number taken as the decimal typed (``--lr1 -0.3`` is -3/10,
not the nearest double) and the value printed with the digits that are proven
(17, or ``--digits N``): :mod:`icosim.rho_command`.  Negative values may follow
their option with a space, also in exponent notation (``--lr1 -1e-3``).  Bad
input -- including input beyond a limit of :mod:`icosim.engine.bounds` -- is reported
as ``icosim rho: error: ...`` naming the argument, with exit status 2, before
any work and without a traceback.
"""

from __future__ import annotations

import argparse
import math
import sys
from fractions import Fraction

from .commands import add_parsers, add_scheme_arguments
from .engine import methods
from .engine.backends import FLOAT64_DIGITS
from .engine.bounds import MAX_BITS_LIMIT, MAX_DIGITS, MAX_GUARD_BITS, MAX_K, MAX_SECONDS, check_derived, check_k
from .engine.decompositions import DECOMPOSITIONS, get_decomposition
from .engine.schemes import get_scheme
from .errors import ParameterError
from .io.jsonio import dumps

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


def _order(text):
    """An approximation order k in 0 .. icosim.engine.bounds.MAX_K."""
    try:
        return check_k(_nonneg_int(text), "k")
    except ParameterError as exc:
        raise argparse.ArgumentTypeError(f"expected an integer in 0..{MAX_K} (the largest k), got {text!r}") from exc


def _digits(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer in 16..{MAX_DIGITS}, got {text!r}") from None
    if value < 16:
        raise argparse.ArgumentTypeError(
            f"expected an integer in 16..{MAX_DIGITS} (float64 carries {FLOAT64_DIGITS}; omit --digits for it), "
            f"got {text!r}"
        )
    if value > MAX_DIGITS:
        raise argparse.ArgumentTypeError(
            f"expected an integer in 16..{MAX_DIGITS} (the largest --digits), got {text!r}"
        )
    return value


def _bits(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer in 128..{MAX_BITS_LIMIT}, got {text!r}") from None
    if not 128 <= value <= MAX_BITS_LIMIT:
        raise argparse.ArgumentTypeError(
            f"expected an integer in 128..{MAX_BITS_LIMIT} (the first attempt's precision .. the limit), got {text!r}"
        )
    return value


def _seconds(text):
    value = _float(text)
    if not 0 < value <= MAX_SECONDS:
        raise argparse.ArgumentTypeError(f"expected a number of seconds in (0, {MAX_SECONDS:g}], got {text!r}")
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
    g.add_argument("--k", required=True, type=_order, help=f"approximation order (integer 0..{MAX_K})")
    add_scheme_arguments(g)
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
    g = rho.add_argument_group(
        "precision and output",
        "The verdict is always proven in ball arithmetic (python-flint Arb) from the decimals as typed: stable "
        "(rho < 1), unstable (rho > 1), or marginal (the proven enclosure still contains 1 at --max-bits). "
        f"Limits: k <= {MAX_K}, --digits <= {MAX_DIGITS}, --max-bits <= {MAX_BITS_LIMIT}, guard bits for heavily "
        f"damped subsystems <= {MAX_GUARD_BITS}; a point needing more is 'undecided' with the reason.",
    )
    g.add_argument(
        "--digits",
        type=_digits,
        help="print rho with this many significant digits, all proven (the enclosure narrowed to them; default 17)",
    )
    g.add_argument("--certify", action="store_true", help="also print the proven enclosure of rho in the text output")
    g.add_argument(
        "--max-bits",
        type=_bits,
        default=1024,
        help=f"largest working precision of the ball arithmetic, in bits (default 1024, at most {MAX_BITS_LIMIT})",
    )
    g.add_argument(
        "--timeout",
        type=_seconds,
        help="give up after this many seconds of wall time: the verdict is then 'undecided' (reason timeout)",
    )
    g.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(subparser=None)
    rho.set_defaults(subparser=rho)
    add_parsers(sub, number=_float, order=_order, digits=_digits)  # icosim advise, icosim map
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
    from .engine.model import TestModel
    from .rho_command import rho_answer, rho_text

    if args.first is not None and args.scheme != "gauss-seidel":
        parser.error("argument --first: only used with --scheme gauss-seidel")
    scheme = get_scheme(args.scheme, args.first)
    try:
        method = _method_from_args(args)
        decomposition = get_decomposition(args.decomposition)
        method.check_decomposition(decomposition)
        model = TestModel(args.lr1, args.li1, args.am21, args.alr21, args.ali21)
        check_derived(model)  # k = lr^2 + li^2, ... finite in float64
    except ParameterError as exc:
        parser.error(_argument_message(str(exc)))
    answer = rho_answer(
        model,
        method,
        decomposition,
        args.k,
        digits=args.digits,
        max_bits=args.max_bits,
        timeout=args.timeout,
        scheme=scheme,
    )
    result = {
        **answer,
        "method": method.name,
        "decomposition": decomposition.name,
        "k": args.k,
        "scheme": scheme.name,
        "first": getattr(scheme, "first", None),  # the subsystem that advances first (Gauss-Seidel only)
        "method_parameters": method.params,
        "model": {n: float(getattr(args, n)) for n in ("lr1", "li1", "am21", "alr21", "ali21")},
    }
    if args.json:
        print(dumps(result))
    else:
        print(rho_text(answer, show_enclosure=args.certify, scheme=scheme))
    return 0


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
