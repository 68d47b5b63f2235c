"""``icosim advise``: which configurations are stable for a two-mass system, and up to which macro step.

A thin command-line wrapper of :mod:`icosim.advise`: every argument is checked before any
computation; bad input exits with status 2 and one line ``icosim advise: error: argument
--<name>: ...``.  ``--json`` prints strict JSON (no NaN or infinity: ``null``, with the reason
next to it).
"""

from __future__ import annotations

from ..engine import methods
from ..engine.decompositions import DECOMPOSITIONS
from ..engine.schemes import get_scheme
from ..errors import ParameterError
from ..io.jsonio import dumps
from .arguments import (
    CHAIN_ONLY,
    NEGATIVE_NUMBER,
    add_chain_arguments,
    fail,
    number,
    order,
    positive_int,
    scheme_or_order,
    two_unit_arguments,
)

__all__ = ["add_parser", "run", "advise_parameters", "scan_settings", "print_advice"]


def advise_parameters() -> dict:
    """Method parameters ``icosim advise`` takes: those some configuration of :func:`icosim.advise.configurations` uses."""
    from ..advise.core import index_parameters

    used = {}
    for spec in methods.METHODS.values():
        for index in spec.indices:
            for name in index_parameters(spec, index, {}):
                name = name.removesuffix("_bar")
                used.setdefault(name, methods.parameters()[name])
    return used


def add_parser(sub):
    """Register ``advise`` on the ``icosim`` sub-command parsers."""
    adv = sub.add_parser(
        "advise",
        help="which schemes are stable for my two-mass system, and up to which macro step",
        description="Every coupling method, index, decomposition and approximation order k for a physical "
        "two-mass system: the dimensionless parameters, rho at one macro step H (or the largest stable H in a "
        "range), and a ranking of the stable schemes.",
        epilog="Method parameters not given are 1 in the paper's dimensionless form: mu = H (mu_bar = 1), "
        "a = b = 1 (Figs. 9-15).  Over an H range stability is scanned on a log-spaced grid and every "
        "stable/unstable transition is bracketed to a relative width --rtol; stability need not be monotone in "
        "H, and the output says where it is not.",
    )
    adv._negative_number_matcher = NEGATIVE_NUMBER
    g = adv.add_argument_group(
        "the two subsystems (SI units; overdamped subsystems accepted; required without --chain)"
    )
    for name, text in (
        ("m1", "mass of subsystem 1 in kg (> 0)"),
        ("m2", "mass of subsystem 2 in kg (> 0)"),
        ("c1", "stiffness of subsystem 1 in N/m (>= 0)"),
        ("c2", "stiffness of subsystem 2 in N/m (>= 0)"),
        ("d1", "damping of subsystem 1 in N s/m (>= 0)"),
        ("d2", "damping of subsystem 2 in N s/m (>= 0)"),
    ):
        g.add_argument(f"--{name}", type=number, help=text)
    g.add_argument(
        "--H", required=True, type=number, nargs="+", metavar="H", help="macro step in s, or a range: H_LO H_HI"
    )
    g = adv.add_argument_group("schemes")
    g.add_argument("--methods", nargs="+", choices=tuple(methods.METHODS), help="default: every method")
    g.add_argument("--decompositions", nargs="+", choices=tuple(DECOMPOSITIONS), help="default: every one")
    g.add_argument("--k", nargs="+", type=order, help="approximation orders (default: 0 1 2)")
    g.add_argument(
        "--schemes",
        nargs="+",
        type=scheme_or_order,
        help="coupling schemes: jacobi (parallel, the paper's), gauss-seidel-12 (subsystem 1 first), "
        "gauss-seidel-21 (subsystem 2 first), or a variant; default: every one but the variants.  With --chain: "
        "jacobi, gauss-seidel-forward (units 1 -> N), gauss-seidel-reverse (N -> 1) or orders of the units such as "
        "3,1,2; default: those three",
    )
    units = {"s": "in s", "s2": "in s^2", "1": "dimensionless"}
    for name, p in advise_parameters().items():
        g.add_argument(
            f"--{name}",
            type=number,
            help=f"{p.help} ({units[p.unit]}; default: {name}_bar = 1)" if p.scaling else f"{p.help} (default: 1)",
        )
    g = adv.add_argument_group("precision and output")
    g.add_argument("--scan", type=positive_int, help="H grid points of the first scan over a range (default: 32)")
    g.add_argument("--rtol", type=number, help="relative width of a refined transition (default: 1e-6)")
    g.add_argument(
        "--policy",
        choices=("auto", "float64"),
        default="auto",
        help="auto: float64, points it cannot decide certified in ball arithmetic (default); float64: no "
        "recheck, such points are 'undecided' (fast for undamped systems, where rho = 1 everywhere)",
    )
    g.add_argument("--json", action="store_true", help="print one JSON object")
    add_chain_arguments(adv, H=False)
    adv.set_defaults(subparser=adv)
    return adv


def scan_settings(args) -> dict:
    """``n_scan``, ``rtol`` and ``policy`` of the arguments, checked with ``--H``
    (:func:`icosim.advise.check_settings`; a :class:`~icosim.errors.ParameterError` naming the argument)."""
    from ..advise import DEFAULT_RTOL, DEFAULT_SCAN, check_settings

    settings = {"n_scan": args.scan or DEFAULT_SCAN, "rtol": args.rtol or DEFAULT_RTOL, "policy": args.policy}
    check_settings(args.H, **settings)
    if len(args.H) == 1 and (args.scan is not None or args.rtol is not None):
        raise ParameterError("scan and --rtol apply to an H range (--H H_LO H_HI) only")
    return settings


def print_advice(args, n_configurations: int, compute, text) -> int:
    """``compute(progress)``'s table printed as JSON records or as ``text(table)``, a progress bar meanwhile."""
    from ..advise import Progress, advice_records

    bar = Progress(n_configurations)
    try:
        df = compute(bar)
    finally:
        bar.close()
    print(dumps(advice_records(df)) if args.json else text(df))
    return 0


def run(args, parser) -> int:
    """``icosim advise``: check the arguments (exit 2 naming the bad one), then answer."""
    from ..advise import DEFAULT_K, TwoMassSystem, advice_text, advise, configurations

    if len(args.H) > 2:
        parser.error(f"argument --H: give one macro step or a range H_LO H_HI, got {len(args.H)} values")
    params = {name: getattr(args, name) for name in advise_parameters() if getattr(args, name) is not None}
    two_unit_arguments(args, parser, ("m1", "m2", "c1", "c2", "d1", "d2"))
    for text in args.schemes or ():
        try:
            get_scheme(text)
        except ParameterError:
            parser.error(f"argument --schemes: {text!r} names a chain's scheme: {CHAIN_ONLY}")
    try:
        system = TwoMassSystem(args.m1, args.m2, args.c1, args.c2, args.d1, args.d2)
        settings = scan_settings(args)
        configuration_list = configurations(
            methods=args.methods,
            decompositions=args.decompositions,
            k=args.k or DEFAULT_K,
            params=params,
            schemes=args.schemes,
        )
    except ParameterError as exc:
        fail(parser, str(exc))
    if not configuration_list:
        parser.error("argument --decompositions: none of the methods asked for is defined for these decompositions")

    def compute(bar):
        return advise(system, args.H, configuration_list=configuration_list, progress=bar, **settings)

    return print_advice(args, len(configuration_list), compute, advice_text)
