"""Argument types and helpers every sub-command shares, so that every command takes and refuses input alike.

Bad input exits with status 2 and one line ``icosim <command>: error: argument --<name>: ...``
naming the argument and the allowed values (argparse's own format).
"""

from __future__ import annotations

import argparse
import math
import re
from fractions import Fraction

from ..engine.backends import FLOAT64_DIGITS
from ..engine.bounds import MAX_BITS_LIMIT, MAX_DIGITS, MAX_K, MAX_SECONDS, check_k
from ..engine.schemes import SCHEMES
from ..errors import ParameterError

__all__ = [
    "number",
    "decimal",
    "positive_number",
    "order",
    "digits",
    "bits",
    "seconds",
    "positive_int",
    "NEGATIVE_NUMBER",
    "add_scheme_arguments",
    "scheme_or_order",
    "CHAIN_ONLY",
    "add_chain_arguments",
    "two_unit_arguments",
    "fail",
]

#: Negative numbers in exponent notation (``-1e-3``) are values, also for options taking two of them.
NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def number(text):
    """A finite float (NaN and infinity are refused)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def positive_number(text):
    """A finite float > 0."""
    value = number(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def decimal(text):
    """A finite number, kept exactly as the decimal typed (a :class:`~fractions.Fraction`)."""
    number(text)  # the same checks and messages as a float argument
    return Fraction(text.strip())


def _nonneg_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def order(text):
    """An approximation order k in 0 .. icosim.engine.bounds.MAX_K."""
    try:
        return check_k(_nonneg_int(text), "k")
    except ParameterError as exc:
        raise argparse.ArgumentTypeError(f"expected an integer in 0..{MAX_K} (the largest k), got {text!r}") from exc


def digits(text):
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


def bits(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer in 128..{MAX_BITS_LIMIT}, got {text!r}") from None
    if not 128 <= value <= MAX_BITS_LIMIT:
        raise argparse.ArgumentTypeError(
            f"expected an integer in 128..{MAX_BITS_LIMIT} (the first attempt's precision .. the limit), got {text!r}"
        )
    return value


def seconds(text):
    value = number(text)
    if not 0 < value <= MAX_SECONDS:
        raise argparse.ArgumentTypeError(f"expected a number of seconds in (0, {MAX_SECONDS:g}], got {text!r}")
    return value


def positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 2, got {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"expected an integer >= 2, got {text!r}")
    return value


def add_scheme_arguments(group):
    """``--scheme``, alike for every command that takes one coupling scheme (the registry's names)."""
    group.add_argument(
        "--scheme",
        choices=tuple(SCHEMES),
        default="jacobi",
        help="coupling scheme: jacobi (parallel, the paper's; default), gauss-seidel-12 (sequential, subsystem 1 "
        "first), gauss-seidel-21 (subsystem 2 first), or a variant (docs/gauss_seidel.md)",
    )


#: What a scheme argument takes for a chain only (``--chain``): the kinds and an order of units by commas.
CHAIN_ONLY = "with --chain: gauss-seidel-forward, gauss-seidel-reverse, orders like 3,1,2"


def scheme_or_order(text):
    """A scheme for two subsystems or a chain: a registered name or ``gauss-seidel-<order>``, and for a chain also
    ``gauss-seidel-forward``, ``gauss-seidel-reverse`` or the units' numbers separated by commas (``3,1,2``);
    which of them suits the problem is decided when it is known (:func:`icosim.advise.chains.chain_scheme`)."""
    from ..advise.chains import SCHEME_KINDS, UNIT_ORDER
    from ..engine.schemes import get_scheme

    if text in SCHEME_KINDS or UNIT_ORDER.fullmatch(text):
        return text
    try:
        get_scheme(text)
    except ParameterError:
        allowed = ", ".join(repr(name) for name in SCHEMES)
        raise argparse.ArgumentTypeError(
            f"invalid choice: {text!r} (choose from {allowed}, gauss-seidel-<order>; {CHAIN_ONLY})"
        ) from None
    return text


def add_chain_arguments(parser, *, H: bool = True):
    """``--chain FILE`` (and, for ``rho``, ``--H``) on a command's parser."""
    g = parser.add_argument_group(
        "a chain instead of two subsystems",
        "A YAML file {segments: [...], joints: ...} (docs/cli.md, config/chains/example3.yaml): one segment per "
        "unit, one decomposition for every joint or a list of one per joint.",
    )
    g.add_argument("--chain", metavar="FILE", help="the chain's YAML file (replaces the two-unit arguments)")
    if H:
        g.add_argument("--H", type=number, help="macro step in s (with --chain)")


def two_unit_arguments(args, parser, names) -> None:
    """Without ``--chain``: every one of ``names`` is required (argparse's message); a chain's ``--H`` of ``rho``
    does not apply."""
    if missing := [f"--{n}" for n in names if getattr(args, n, None) is None]:
        parser.error(f"the following arguments are required: {', '.join(missing)} (or --chain FILE)")
    if "decomposition" in names and getattr(args, "H", None) is not None:
        parser.error("argument --H: applies to --chain only (the test model's parameters are dimensionless)")


def fail(parser, text: str):
    """``parser.error`` with the message attributed to the argument it names (the first option word in it)."""
    if not text.startswith("argument "):
        options = {s.lstrip("-") for a in parser._actions for s in a.option_strings}
        for word in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", text):
            if word in options:
                text = f"argument --{word}: {text}"
                break
    parser.error(text)
