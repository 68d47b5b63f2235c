"""``icosim map``: a stability map drawn and written as PNG, PDF and NetCDF.

A thin command-line wrapper of :mod:`icosim.advise.maps`: every argument is checked before any
computation; bad input exits with status 2 and one line ``icosim map: error: argument
--<name>: ...``.  ``--json`` prints strict JSON (no NaN or infinity: ``null``, with the reason
next to it).
"""

from __future__ import annotations

from ..engine import methods
from ..engine.decompositions import DECOMPOSITIONS
from ..engine.schemes import get_scheme
from ..engine.spectral.policy import POLICIES
from ..engine.stages import check
from ..errors import ParameterError
from ..io.jsonio import dumps
from .arguments import NEGATIVE_NUMBER, add_scheme_arguments, digits, fail, number, order, positive_int

__all__ = ["add_parser", "run"]


def add_parser(sub):
    """Register ``map`` on the ``icosim`` sub-command parsers."""
    mp = sub.add_parser(
        "map",
        help="draw a stability map and write it as PNG, PDF and NetCDF",
        description="Stability map of one method over a (lr1, li1) grid, one panel per k: the report's panel "
        "computation and figure style, written as PNG and PDF and one NetCDF file per k with the pipeline's "
        "variable names; prints where the stable region ends.",
    )
    mp._negative_number_matcher = NEGATIVE_NUMBER
    g = mp.add_argument_group("method and layout")
    g.add_argument("--method", required=True, choices=tuple(methods.METHODS))
    g.add_argument("--decomposition", required=True, choices=tuple(DECOMPOSITIONS))
    g.add_argument("--k", required=True, nargs="+", type=order, help="approximation orders, one panel each")
    g.add_argument("--index", type=int, choices=methods.indices(), help="index of the formulation")
    add_scheme_arguments(g)
    for name, p in methods.parameters().items():
        g.add_argument(f"--{name}", type=number, help=f"{p.help} (dimensionless, as in the paper's figures)")
    g = mp.add_argument_group("test-model parameters (Eq. 71) and grid")
    g.add_argument("--am21", type=number, default=1.0, help="mass ratio m2/m1 (> 0; default 1)")
    g.add_argument("--alr21", type=number, default=1.0, help="damping ratio lr2/lr1 (>= 0; default 1)")
    g.add_argument("--ali21", type=number, default=1.0, help="frequency ratio li2/li1 (>= 0; default 1)")
    g.add_argument("--lr1", nargs=2, type=number, default=[-2.0, 0.0], metavar=("LO", "HI"), help="default -2 0")
    g.add_argument("--li1", nargs=2, type=number, default=[0.0, 2.0], metavar=("LO", "HI"), help="default 0 2")
    g.add_argument("--n", type=positive_int, default=101, help="grid points per axis (default 101)")
    g = mp.add_argument_group("precision and output")
    g.add_argument(
        "--policy",
        choices=POLICIES,
        default="auto",
        help="precision policy: auto (float64, certified where it cannot decide; default), float64, certify (every "
        "point proven), mp (every point with mpmath at --digits)",
    )
    g.add_argument("--digits", type=digits, default=128, help="digits of --policy mp (default: 128)")
    g.add_argument("--out", default="icosim_map", help="output prefix: PREFIX.png, PREFIX.pdf, PREFIX_k<k>.nc")
    g.add_argument("--style", choices=("field", "dots"), default="field", help="figure style (as the report's)")
    g.add_argument("--title", default=None, help="figure title (default: method, parameters, ratios)")
    g.add_argument("--json", action="store_true", help="print one JSON object")
    mp.set_defaults(subparser=mp)
    return mp


def run(args, parser) -> int:
    """``icosim map``: check the arguments (exit 2 naming the bad one), then compute, draw and write."""
    import numpy as np

    from ..advise import Progress
    from ..advise.maps import (
        boundary_extent,
        map_figure,
        map_panels,
        map_specs,
        marginal_extent,
        stable_extent,
        write_map,
    )
    from ..problems.linear.model import TestModel
    from ..studies.stability.panels import grid_axis

    given = {name: getattr(args, name) for name in methods.argument_names() if getattr(args, name) is not None}
    grid = dict(
        ratios=(args.am21, args.alr21, args.ali21),
        lr1=args.lr1,
        li1=args.li1,
        n=args.n,
        digits=args.digits,
        policy=args.policy,
    )
    grid["scheme"] = get_scheme(args.scheme).name
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
            check(get_scheme(s.scheme), s.decomposition)
        for name in ("lr1", "li1"):
            try:
                grid_axis(getattr(args, name), args.n)
            except ParameterError as exc:
                raise ParameterError(f"argument --{name}: {exc}") from None
        # the corners of the grid as test-model points: signs of lr1, li1 and the ratios, named
        TestModel(max(args.lr1), min(args.li1), args.am21, args.alr21, args.ali21)
        TestModel(min(args.lr1), max(args.li1), args.am21, args.alr21, args.ali21)
    except ParameterError as exc:
        fail(parser, str(exc))
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
        print(dumps({"files": paths, "title": title, "panels": summary}))
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
