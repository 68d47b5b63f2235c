"""The FMU section of the report: each scene's run next to the prediction made before it and the built-in
model, the convergence orders over H on the units, and the part's claims.

Everything shown comes from the datasets the workflow wrote (``results/fmi/validation/<scene>.nc``,
``results/fmi/orders/<case>.nc``, :mod:`icosim.studies.fmi.validation`) and the claim verdicts; nothing is computed
again here.
"""

from __future__ import annotations

import math

from ..verdicts import verdict_counts
from . import html as rp
from .claims import claims_table

__all__ = ["fmi_section", "scene_rows", "order_rows", "scene_verdicts"]

esc = rp.escape
_num = rp.number


def scene_verdicts(claims) -> dict:
    """Scene -> ``[(claim id, pass/fail/undecided), ...]``: the claims whose rows name the scene."""
    out = {}
    for c in claims:
        for row in (c.get("numbers") or {}).get("rows", []):
            if "scene" in row:
                verdict = {True: "pass", False: "fail"}.get(row.get("holds"), "undecided")
                out.setdefault(row["scene"], []).append((c["id"], verdict))
    return out


def scene_rows(validations, claims) -> list:
    """One row per scene: units, coupling, prediction, measured growth, difference to the built-in model,
    verdicts of the claims that read it."""
    verdicts = scene_verdicts(claims)
    rows = []
    for ds in validations:
        a = ds.attrs
        rho = float(ds["predicted_rho"])
        prediction = (
            f"{_num(rho, '.10g')} ({esc(a['predicted_verdict'])})"
            if math.isfinite(rho)
            else esc(a["predicted_verdict"])
        )
        diff = float(ds["builtin_difference"])
        if a["builtin"] == "none":
            builtin = "no built-in model"
        elif a["builtin"] == "pendulum":
            builtin = f"{_num(diff)} m (joint force {_num(ds['builtin_force_difference'])} relative), built-in pendulum"
        else:
            builtin = f"{_num(diff)} relative, built-in linear model"
        mine = verdicts.get(a["scene"], [])
        verdict = "<br>".join(f"{rp.verdict_badge(v)} {esc(cid)}" for cid, v in mine) if mine else "no claim reads it"
        rows.append(
            [
                f"<b>{esc(a['scene'])}</b>",
                esc(a["units"]),
                esc(f"{a['method']}, {a['decomposition']}, k = {a['k']}, {a['scheme']}, H = {a['H']:g} s"),
                esc(f"{a['status']}, {a['macro_steps']} macro steps, {a['do_step_calls']} doStep calls"),
                prediction,
                _num(ds["measured_growth"], ".10g"),
                esc(builtin),
                verdict,
            ]
        )
    return rows


def _prediction_rows(validations) -> list:
    rows = []
    for ds in validations:
        if "predicted_for" not in ds.dims or not math.isfinite(float(ds["predicted_rho"])):
            continue
        cells = [
            f"{_num(r, '.10g')} ({esc(str(v))})" if math.isfinite(float(r)) else esc(str(v))
            for r, v in zip(ds["scheme_rho"].values, ds["scheme_verdict"].values)
        ]
        rows.append(
            [
                esc(ds.attrs["scene"]),
                "; ".join(f"{esc(str(s))}: {c}" for s, c in zip(ds["predicted_for"].values, cells)),
            ]
        )
    return rows


def order_rows(orders) -> list:
    """One row per order case: step sizes, errors at the smallest H, both orders and their status."""
    rows = []
    for ds in orders:
        a = ds.attrs
        H = ds["H"].values
        rows.append(
            [
                esc(a["case"]),
                esc(f"{H.min():.3g} … {H.max():.3g} s ({H.size} sizes), t_end = {a['t_end']:g} s"),
                _num(ds["error_fmu"].values[0]),
                _num(ds["error_builtin"].values[0]),
                esc(f"{a['order_fmu']:.3f} ({a['status_fmu']})"),
                esc(f"{a['order_builtin']:.3f} ({a['status_builtin']})"),
                _num(ds["difference"].max()),
            ]
        )
    return rows


def fmi_section(*, validations, orders, claims) -> str:
    """The section as an HTML fragment (``id="fmi"``)."""
    n = verdict_counts(claims)
    intro = (
        "<p>The coupling methods on co-simulation units (FMUs, docs/fmi.md): each scene of "
        "<code>config/fmi.yaml</code> is run through the engine's one macro step on its units and checked. "
        "Before the run its units are identified as linear single-mass oscillators from two probing steps each, "
        "and the spectral radius ρ of the scene's coupling is predicted (<code>icosim cosim --predict</code>); "
        "after it the growth per macro step is measured on the run (the largest amplitude over the last eighth "
        "against that over the eighth after the middle) and the trajectory compared with the built-in model "
        "from the same start at the same dimensionless point. "
        f"Claims: {n['pass']} pass, {n['fail']} fail, {n['undecided']} undecided.</p>"
    )
    scenes = rp.table(
        [
            "scene",
            "units",
            "coupling",
            "run",
            "predicted ρ (scene's scheme)",
            "measured growth per macro step",
            "max difference to the built-in model",
            "verdict",
        ],
        scene_rows(validations, claims),
        raw_columns=(0, 1, 2, 3, 4, 5, 6, 7),
    )
    predictions = _prediction_rows(validations)
    every_scheme = (
        "<h3>Predicted ρ for every scheme</h3>" + rp.table(["scene", "ρ per scheme"], predictions, raw_columns=(0, 1))
        if predictions
        else ""
    )
    order_table = (
        "<h3>Convergence orders over H on the units</h3><p>Configurations of the linear convergence study "
        "(Sect. 3.7) on the test units, from the exact start: the largest position error against the exact "
        "monolithic solution, of the FMU runs and of the built-in model on the same step sizes, and the order "
        "read off the smallest-H decade (the linear study's rule).</p>"
        + rp.table(
            [
                "case",
                "step sizes",
                "error at the smallest H (FMU, m)",
                "error at the smallest H (built-in, m)",
                "order (FMU)",
                "order (built-in)",
                "max FMU − built-in (relative)",
            ],
            order_rows(orders),
            raw_columns=tuple(range(7)),
        )
        if orders
        else ""
    )
    body = (
        intro
        + "<h3>Scenes</h3>"
        + scenes
        + every_scheme
        + order_table
        + "<h3>Claims</h3>"
        + claims_table(claims, part="fmi")
    )
    return rp.section("FMU scenes: the methods on co-simulation units", body, "fmi")
