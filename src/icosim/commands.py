"""``icosim advise`` and ``icosim map``: thin command-line wrappers of :mod:`icosim.advise` and :mod:`icosim.advise.maps`.

Both check every argument before any computation; bad input exits with
status 2 and one line ``icosim <command>: error: argument --<name>: ...``
naming the argument and the allowed values.  ``--json`` prints strict JSON
(no NaN or infinity: ``null``, with the reason next to it).
"""

from __future__ import annotations

import argparse
import re

from .engine import methods
from .engine.decompositions import DECOMPOSITIONS
from .engine.schemes import SCHEME_NAMES, get_scheme
from .engine.spectral.policy import POLICIES
from .errors import ParameterError
from .io.jsonio import dumps

__all__ = ["add_parsers", "add_scheme_arguments", "run"]

#: Negative numbers in exponent notation (``-1e-3``) are values, also for options taking two of them.
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 2, got {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"expected an integer >= 2, got {text!r}")
    return value


def advise_parameters() -> dict:
    """Method parameters ``icosim advise`` takes: those some configuration of :func:`icosim.advise.configurations` uses."""
    from .advise.core import _index_params

    used = {}
    for spec in methods.METHODS.values():
        for index in spec.indices:
            for name in _index_params(spec, index, {}):
                name = name.removesuffix("_bar")
                used.setdefault(name, methods.parameters()[name])
    return used


def add_scheme_arguments(group):
    """``--scheme`` and ``--first``, alike for every command that takes one coupling scheme."""
    group.add_argument(
        "--scheme",
        choices=("jacobi", "gauss-seidel"),
        default="jacobi",
        help="coupling scheme: jacobi (parallel, the paper's; default) or gauss-seidel (sequential)",
    )
    group.add_argument(
        "--first", type=int, choices=(1, 2), help="gauss-seidel: the subsystem that advances first (default 1)"
    )


def add_parsers(sub, *, number, order, digits):
    """Register ``advise`` and ``map`` on the ``icosim`` sub-command parsers.

    ``number``, ``order`` (k, within icosim's limit) and ``digits`` are the argument types of
    ``icosim rho`` (:mod:`icosim.cli`), so that every command takes and refuses numbers alike.
    """
    _float, _order, _digits = number, order, digits

    # -- advise ------------------------------------------------------------------------------------
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
    adv._negative_number_matcher = _NEGATIVE_NUMBER
    g = adv.add_argument_group("the two subsystems (SI units; overdamped subsystems accepted)")
    for name, text in (
        ("m1", "mass of subsystem 1 in kg (> 0)"),
        ("m2", "mass of subsystem 2 in kg (> 0)"),
        ("c1", "stiffness of subsystem 1 in N/m (>= 0)"),
        ("c2", "stiffness of subsystem 2 in N/m (>= 0)"),
        ("d1", "damping of subsystem 1 in N s/m (>= 0)"),
        ("d2", "damping of subsystem 2 in N s/m (>= 0)"),
    ):
        g.add_argument(f"--{name}", required=True, type=_float, help=text)
    g.add_argument(
        "--H", required=True, type=_float, nargs="+", metavar="H", help="macro step in s, or a range: H_LO H_HI"
    )
    g = adv.add_argument_group("schemes")
    g.add_argument("--methods", nargs="+", choices=tuple(methods.METHODS), help="default: every method")
    g.add_argument("--decompositions", nargs="+", choices=tuple(DECOMPOSITIONS), help="default: every one")
    g.add_argument("--k", nargs="+", type=_order, help="approximation orders (default: 0 1 2)")
    g.add_argument(
        "--couplings",
        nargs="+",
        choices=SCHEME_NAMES,
        help="coupling orders: jacobi (parallel, the paper's), gauss-seidel-12 (subsystem 1 first), "
        "gauss-seidel-21 (subsystem 2 first); default: every one",
    )
    units = {"s": "in s", "s2": "in s^2", "1": "dimensionless"}
    for name, p in advise_parameters().items():
        g.add_argument(
            f"--{name}",
            type=_float,
            help=f"{p.help} ({units[p.unit]}; default: {name}_bar = 1)" if p.scaling else f"{p.help} (default: 1)",
        )
    g = adv.add_argument_group("precision and output")
    g.add_argument("--scan", type=_positive_int, help="H grid points of the first scan over a range (default: 32)")
    g.add_argument("--rtol", type=_float, help="relative width of a refined transition (default: 1e-6)")
    g.add_argument(
        "--policy",
        choices=("auto", "float64"),
        default="auto",
        help="auto: float64, points it cannot decide certified in ball arithmetic (default); float64: no "
        "recheck, such points are 'undecided' (fast for undamped systems, where rho = 1 everywhere)",
    )
    g.add_argument("--json", action="store_true", help="print one JSON object")
    adv.set_defaults(subparser=adv)

    # -- map ---------------------------------------------------------------------------------------
    mp = sub.add_parser(
        "map",
        help="draw a stability map and write it as PNG, PDF and NetCDF",
        description="Stability map of one method over a (lr1, li1) grid, one panel per k: the report's panel "
        "computation and figure style, written as PNG and PDF and one NetCDF file per k with the pipeline's "
        "variable names; prints where the stable region ends.",
    )
    mp._negative_number_matcher = _NEGATIVE_NUMBER
    g = mp.add_argument_group("method and layout")
    g.add_argument("--method", required=True, choices=tuple(methods.METHODS))
    g.add_argument("--decomposition", required=True, choices=tuple(DECOMPOSITIONS))
    g.add_argument("--k", required=True, nargs="+", type=_order, help="approximation orders, one panel each")
    g.add_argument("--index", type=int, choices=methods.indices(), help="index of the formulation")
    add_scheme_arguments(g)
    for name, p in methods.parameters().items():
        g.add_argument(f"--{name}", type=_float, help=f"{p.help} (dimensionless, as in the paper's figures)")
    g = mp.add_argument_group("test-model parameters (Eq. 71) and grid")
    g.add_argument("--am21", type=_float, default=1.0, help="mass ratio m2/m1 (> 0; default 1)")
    g.add_argument("--alr21", type=_float, default=1.0, help="damping ratio lr2/lr1 (>= 0; default 1)")
    g.add_argument("--ali21", type=_float, default=1.0, help="frequency ratio li2/li1 (>= 0; default 1)")
    g.add_argument("--lr1", nargs=2, type=_float, default=[-2.0, 0.0], metavar=("LO", "HI"), help="default -2 0")
    g.add_argument("--li1", nargs=2, type=_float, default=[0.0, 2.0], metavar=("LO", "HI"), help="default 0 2")
    g.add_argument("--n", type=_positive_int, default=101, help="grid points per axis (default 101)")
    g = mp.add_argument_group("precision and output")
    g.add_argument(
        "--policy",
        choices=POLICIES,
        default="auto",
        help="precision policy: auto (float64, certified where it cannot decide; default), float64, certify (every "
        "point proven), mp (every point with mpmath at --digits)",
    )
    g.add_argument("--digits", type=_digits, default=128, help="digits of --policy mp (default: 128)")
    g.add_argument("--out", default="icosim_map", help="output prefix: PREFIX.png, PREFIX.pdf, PREFIX_k<k>.nc")
    g.add_argument("--style", choices=("field", "dots"), default="field", help="figure style (as the report's)")
    g.add_argument("--title", default=None, help="figure title (default: method, parameters, ratios)")
    g.add_argument("--json", action="store_true", help="print one JSON object")
    mp.set_defaults(subparser=mp)


def _fail(parser, text: str):
    """``parser.error`` with the message attributed to the argument it names (the first option word in it)."""
    if not text.startswith("argument "):
        options = {s.lstrip("-") for a in parser._actions for s in a.option_strings}
        for word in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", text):
            if word in options:
                text = f"argument --{word}: {text}"
                break
    parser.error(text)


def run(args) -> int:
    return {"advise": _advise, "map": _map}[args.command](args, args.subparser)


def _dumps(obj) -> str:
    return dumps(obj)  # strict JSON


# -- advise ----------------------------------------------------------------------------------------


def _advise(args, parser) -> int:
    from .advise import (
        DEFAULT_K,
        DEFAULT_RTOL,
        DEFAULT_SCAN,
        Progress,
        TwoMassSystem,
        advice_records,
        advice_text,
        advise,
        check_settings,
        configurations,
    )

    if len(args.H) > 2:
        parser.error(f"argument --H: give one macro step or a range H_LO H_HI, got {len(args.H)} values")
    params = {name: getattr(args, name) for name in advise_parameters() if getattr(args, name) is not None}
    try:
        system = TwoMassSystem(args.m1, args.m2, args.c1, args.c2, args.d1, args.d2)
        check_settings(args.H, n_scan=args.scan or DEFAULT_SCAN, rtol=args.rtol or DEFAULT_RTOL, policy=args.policy)
        if len(args.H) == 1 and (args.scan is not None or args.rtol is not None):
            raise ParameterError("scan and --rtol apply to an H range (--H H_LO H_HI) only")
        configuration_list = configurations(
            methods=args.methods,
            decompositions=args.decompositions,
            k=args.k or DEFAULT_K,
            params=params,
            couplings=args.couplings,
        )
    except ParameterError as exc:
        _fail(parser, str(exc))
    if not configuration_list:
        parser.error("argument --decompositions: none of the methods asked for is defined for these decompositions")
    bar = Progress(len(configuration_list))
    try:
        df = advise(
            system,
            args.H,
            configuration_list=configuration_list,
            n_scan=args.scan or DEFAULT_SCAN,
            rtol=args.rtol or DEFAULT_RTOL,
            policy=args.policy,
            progress=bar,
        )
    finally:
        bar.close()
    print(_dumps(advice_records(df)) if args.json else advice_text(df))
    return 0


# -- map -------------------------------------------------------------------------------------------


def _map(args, parser) -> int:
    import numpy as np

    from .advise import Progress
    from .advise.maps import (
        boundary_extent,
        map_figure,
        map_panels,
        map_specs,
        marginal_extent,
        stable_extent,
        write_map,
    )
    from .engine.model import TestModel
    from .stability.panels import grid_axis

    given = {name: getattr(args, name) for name in methods.argument_names() if getattr(args, name) is not None}
    grid = dict(
        ratios=(args.am21, args.alr21, args.ali21),
        lr1=args.lr1,
        li1=args.li1,
        n=args.n,
        digits=args.digits,
        policy=args.policy,
    )
    if args.first is not None and args.scheme != "gauss-seidel":
        parser.error("argument --first: only used with --scheme gauss-seidel")
    grid["scheme"] = get_scheme(args.scheme, args.first).name
    try:
        spec = methods.get_spec(args.method)
        extra = sorted(set(given) - set(spec.arguments))
        if extra:
            allowed = ", ".join(f"--{a}" for a in spec.arguments) or "none"
            raise ParameterError(
                f"argument --{extra[0]}: not used by --method {args.method} (its parameters: {allowed})"
            )
        specs = map_specs(args.method, given, args.decomposition, args.k, **grid)
        for s in specs:
            s.coupling_method().check_decomposition(DECOMPOSITIONS[s.decomposition])
        for name in ("lr1", "li1"):
            try:
                grid_axis(getattr(args, name), args.n)
            except ParameterError as exc:
                raise ParameterError(f"argument --{name}: {exc}") from None
        # the corners of the grid as test-model points: signs of lr1, li1 and the ratios, named
        TestModel(max(args.lr1), min(args.li1), args.am21, args.alr21, args.ali21)
        TestModel(min(args.lr1), max(args.li1), args.am21, args.alr21, args.ali21)
    except ParameterError as exc:
        _fail(parser, str(exc))
    bar = Progress(len(args.k), label="panels")
    try:
        panels = map_panels(args.method, given, args.decomposition, args.k, command="icosim map", progress=bar, **grid)
    finally:
        bar.close()
    attrs = panels[0].attrs
    params = ", ".join(f"{k} = {v:g}" for k, v in methods.make_method(args.method, **given).params.items())
    title = (
        args.title
        if args.title is not None
        else (
            f"{spec.label}{f' ({params})' if params else ''}, {args.decomposition}"
            f"{'' if grid['scheme'] == 'jacobi' else ', ' + get_scheme(grid['scheme']).label}; "
            f"am21 = {attrs['am21']:g}, alr21 = {attrs['alr21']:g}, ali21 = {attrs['ali21']:g}"
        )
    )
    paths = write_map(panels, map_figure(panels, title=title, style=args.style), args.out)
    summary = []
    for ds in panels:
        extent = stable_extent(ds)
        summary.append(
            {
                "k": int(ds.attrs["k"]),
                "n_points": int(ds.attrs["n_points"]),
                "n_stable": int(ds.attrs["n_stable"]),
                "n_high_precision": int(ds.attrs["n_high_precision"]),
                "n_certified": int(ds.attrs["n_certified"]),
                "n_marginal": int(ds.attrs["n_marginal"]),
                "boundary": boundary_extent(ds),
                "marginal": marginal_extent(ds),
                "rows": extent.to_dict(orient="records"),
            }
        )
    if args.json:
        print(_dumps({"files": paths, "title": title, "panels": summary}))
        return 0
    print(f"{title}\nwrote {', '.join(paths)}")
    for p in summary:
        b = p["boundary"]
        where = (
            "no rho = 1 boundary on the grid"
            if b["n_points"] == 0
            else f"rho = 1 boundary within lr1 in [{b['lr1'][0]:g}, {b['lr1'][1]:g}], li1 in [{b['li1'][0]:g}, {b['li1'][1]:g}]"
        )
        m = p["marginal"]
        if m["n_points"]:
            where += (
                f"; {m['n_points']} marginal (rho = 1 within the proof) in lr1 [{m['lr1'][0]:g}, {m['lr1'][1]:g}], "
                f"li1 [{m['li1'][0]:g}, {m['li1'][1]:g}]"
            )
        print(
            f"k = {p['k']}: {p['n_stable']} of {p['n_points']} grid points stable "
            f"({p['n_stable'] / p['n_points']:.1%}; {p['n_certified']} certified in ball arithmetic); {where}"
        )
        rows = p["rows"]
        step = max(1, int(np.ceil((len(rows) - 1) / 10)))
        shown = rows[::step] + ([rows[-1]] if (len(rows) - 1) % step else [])
        print("  li1      stable for lr1 in")
        for r in shown:
            runs = " and ".join(f"[{lo:g}, {hi:g}]" for lo, hi in r["stable_lr1"]) or "none"
            print(f"  {r['li1']:<8.4g} {runs}")
    if step > 1:
        print(f"(every {step}th li1 row shown; --json lists all)")
    return 0
