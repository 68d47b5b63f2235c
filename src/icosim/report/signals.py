"""The signal-coupling study's section of the report: OMSimulator's DualMassOscillator on its Model Exchange units,
coupled by its signal connections and by a joint, the error against the exact solution over H with its order, the
predicted spectral radius against the growth measured on the runs, what the data cannot decide, and the claims.

Everything shown comes from the case datasets the workflow wrote (``results/signals/<case>.nc``,
:mod:`icosim.studies.signals.study`) and the claim verdicts; nothing is computed again here.
"""

from __future__ import annotations

import math

from ..verdicts import verdict_counts
from . import html as rp
from .claims import claims_table

__all__ = ["signals_section", "case_rows", "growth_rows", "undecided_items"]

esc = rp.escape
_num = rp.number


def _coupling(a) -> str:
    if a["by"] == "joint":
        extra = ", ".join(f"{k[6:]} {v:g}" for k, v in a.items() if k.startswith("param_"))
        return f"joint, {a['method']}" + (f" ({extra})" if extra else "") + f", fd, {a['scheme']}"
    return f"connections, {'implicit' if a['implicit'] == 'yes' else 'explicit'}, {a['scheme']}"


def case_rows(cases) -> list:
    """One row per case: coupling, k, step sizes, errors at the smallest and largest H, order, prediction."""
    rows = []
    for ds in cases:
        a = ds.attrs
        H, err = ds["H"].values, ds["error"].values
        verdicts = sorted({str(v) for v in ds["predicted_verdict"].values})
        rho = ds["predicted_rho"].values
        prediction = (
            f"ρ {_num(min(rho), '.6f')} … {_num(max(rho), '.6f')} ({', '.join(verdicts)}); largest stable H "
            f"{_num(a['predicted_H_max'])} s"
            if all(math.isfinite(float(r)) for r in rho)
            else f"undecided: {a['prediction_reason']}"
        )
        rows.append(
            [
                f"<b>{esc(a['case'])}</b>",
                esc(_coupling(a)),
                str(a["k"]),
                esc(f"{H.min():.4g} … {H.max():.4g} s ({H.size}), t_end = {a['t_end']:g} s"),
                _num(err[0]),
                _num(err[-1]),
                esc(f"{a['order']:.3f} ({a['order_status']})"),
                esc(prediction),
            ]
        )
    return rows


def growth_rows(cases) -> list:
    """One row per growth run: case, H, predicted rho and verdict, measured growth, deviation in ``rho - 1``."""
    rows = []
    for ds in cases:
        if "growth_H" not in ds.coords:
            continue
        for h, rho, v, g in zip(*(ds[n].values for n in ("growth_H", "growth_rho", "growth_verdict",
                                                           "measured_growth"))):  # fmt: skip
            rho, g = float(rho), float(g)
            dev = abs(g - rho) / abs(rho - 1) if math.isfinite(rho) and math.isfinite(g) and rho != 1 else math.nan
            rows.append([esc(ds.attrs["case"]), f"{float(h):g} s", f"{_num(rho, '.6f')} ({v})",
                         _num(g, ".6f"), _num(dev)])  # fmt: skip
    return rows


def undecided_items(cases) -> list:
    """What the datasets cannot decide, from their own attributes."""
    items = []
    joints = [ds for ds in cases if ds.attrs["by"] == "joint"]
    if joints:
        items.append(
            "the joint's stability: " + esc(joints[0].attrs["prediction_reason"]) + "; no growth run is made for it"
        )
    if not any(ds.attrs["implicit"] == "yes" for ds in cases):
        items.append("implicit coupling of the connections: no implicit case is configured")
    items.append(
        "cost: a joint's macro step takes more unit steps than a connection's (predictor, corrector, the "
        "perturbed steps of the sensitivities); the errors are compared at equal H, not at equal work"
    )
    items.append(
        "the units as Co-Simulation: not in the study (OpenModelica's explicit Euler at the communication step "
        "adds an error of the coupling's own order, so the coupling's order cannot be read off them)"
    )
    not_asymptotic = [ds.attrs["case"] for ds in cases if ds.attrs["order_status"] != "asymptotic"]
    if not_asymptotic:
        items.append("the order of " + esc(", ".join(not_asymptotic)) + ": not asymptotic on its step sizes")
    return items


def signals_section(*, cases, claims, figure) -> str:
    """The section as an HTML fragment (``id="signals"``); ``figure``: the study's PNG."""
    n = verdict_counts(claims)
    amplitude = cases[0].attrs["amplitude"] if cases else math.nan
    intro = (
        "<p>OMSimulator's DualMassOscillator (its two units as Model Exchange, integrated far below the coupling's "
        "error) coupled by its four signal connections (docs/signals.md) and, for comparison, by a joint (System2 "
        "driven by mass 1's motion, fd). Each case runs over a list of macro steps H from the exact coupling "
        "history; the error is the largest displacement error of either mass against the exact solution of "
        f"the Modelica equations, relative to the amplitude ({_num(amplitude)} m); the order is read off the "
        "smallest-H decade. For the connections the spectral radius ρ is predicted from the units identified at "
        "their start, and at larger H the growth per macro step is measured on a run of the units. "
        f"Claims: {n['pass']} pass, {n['fail']} fail, {n['undecided']} undecided.</p>"
    )
    fig = rp.figure(
        figure,
        "Left: the error over H per case (solid: Jacobi connections, dotted: Gauss–Seidel connections, dashed: "
        "joint), coloured by k. Right: the growth per macro step measured on a run against the ρ predicted before "
        "it; on the diagonal they are equal.",
        alt="signal coupling study",
        anchor=rp.figure_anchor("signals", figure),
    )
    table = rp.table(
        ["case", "coupling", "k", "step sizes", "error, smallest H", "error, largest H", "order", "prediction"],
        case_rows(cases),
        raw_columns=tuple(range(8)),
    )
    growth = growth_rows(cases)
    growth_html = (
        "<h3>Predicted ρ against measured growth</h3>"
        + rp.table(["case", "H", "predicted ρ", "measured growth", "|growth − ρ| / |ρ − 1|"], growth, raw_columns=(0,))
        if growth
        else ""
    )
    cannot = (
        "<h3>What the data cannot decide</h3><ul>" + "".join(f"<li>{i}</li>" for i in undecided_items(cases)) + "</ul>"
    )
    body = (
        intro
        + fig
        + "<h3>Cases</h3>"
        + table
        + growth_html
        + cannot
        + "<h3>Claims</h3>"
        + claims_table(claims, part="signals")
    )
    return rp.section("Signal coupling: the DualMassOscillator by connections and by a joint", body, "signals")
