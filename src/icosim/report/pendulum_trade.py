"""The speed-accuracy part of the pendulum section (the speed-accuracy trade, beyond the paper): orders, work-precision, stability limits,
subsystem tolerance and adaptive macro steps, with conclusions computed from the datasets.

Every number on the page is read from ``work_precision.nc``,
``stability_limit.nc``, ``tolerance.nc`` and ``adaptive.nc``; the rows and
counts behind the sentences that draw conclusions come from
:mod:`icosim.studies.trade.conclusions`, which the tests call on the same datasets.
"""

from __future__ import annotations

import math

import numpy as np

from ..studies.trade.conclusions import (
    LIMIT_AGREEMENT,
    ORDER_AGREEMENT,
    accuracy_rows,
    adaptive_summary,
    equal_error_table,
    limit_rows,
    limit_summary,
    order_rows,
    order_summary,
    tolerance_rows,
)
from .html import escape, figure_anchor, table
from .html import figure as _html_figure

__all__ = ["trade_section"]


def figure(png_path, caption_html: str) -> str:
    """A figure of the trade studies, with its anchor in the page (``pendulum-<stem>``)."""
    return _html_figure(png_path, caption_html, anchor=figure_anchor("pendulum", png_path))


def _f(x, spec=".2e"):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "–" if not math.isfinite(x) else format(x, spec)


def _order_text(order, status):
    return f"{order:.2f}" if status == "asymptotic" else (f"({order:.2f}) {status}" if math.isfinite(order) else status)


def _join(names):
    return ", ".join(f"<code>{escape(n)}</code>" for n in names) if names else "none"


def trade_section(*, work_precision, stability_limit, tolerance, adaptive, figure_pngs: dict) -> str:
    """The HTML of the speed-accuracy part (a subsection of the pendulum section)."""
    wp, lim, tol, ad = work_precision, stability_limit, tolerance, adaptive
    T = float(wp.attrs["t_end"])
    H = wp["H"].values
    parts = ["<h3>Speed–accuracy trade</h3>"]
    parts.append(
        f"<p><b>What was measured.</b> Every configuration above ({wp.sizes['config']} in all) at "
        f"{len(H)} macro steps H = {', '.join(_f(h, 'g') for h in H)} s over the same end time "
        f"T = {T:g} s, subsystems by Radau IIA at rtol = {_f(wp.attrs.get('rtol'), 'g')}, "
        f"atol = {_f(wp.attrs.get('atol'), 'g')}. Per run: the error against the monolithic reference "
        f"({escape(str(wp.attrs.get('reference_method')))}, rtol {_f(wp.attrs.get('reference_rtol'), 'g')}; its own "
        f"error estimated at {_f(wp.attrs.get('reference_accuracy'))} rad), max and time-weighted RMS over φ1 and φ2 at "
        "the macro nodes; the joint drift max |g<sub>c</sub>|; CPU seconds of the macro steps (process time, the least of "
        "up to three runs for runs under 0.1 s); macro steps, subsystem (Radau) steps, right-hand-side and Jacobian "
        "evaluations (dataset <code>results/pendulum/work_precision.nc</code>).</p>"
    )

    # orders
    rows = order_rows(wp)
    osum = order_summary(rows)
    parts.append(
        "<h4>Error over H and orders</h4>"
        f"<p>Orders follow the linear study's rule: the slope of log error over log H on the smallest-H decade "
        f"of stable step sizes, asymptotic only if every local slope there lies within "
        f"{_f(wp.attrs.get('fit_tolerance'), 'g')} of it, otherwise pre-asymptotic (undecided). Errors below the floor "
        f"{_f(wp.attrs.get('fit_floor_factor'), 'g')}·(ε·√N + reference error) (N macro steps; for the linear "
        f"model, stepped with one rounded matrix, {_f(wp.attrs.get('fit_floor_factor'), 'g')}·ε·N) are not data and "
        "are left out first. "
        "The linear model's orders are those of the paper's convergence test model (Sect. 3.7) with the same scheme, "
        "step sizes and rule (its own point at the pendulum's parameters has identical subsystems, for which the "
        "force/force coupling force vanishes and the co-simulation is exact).</p>"
        f"<p><b>Result:</b> {osum['asymptotic']} of {osum['n']} configurations have an asymptotic order; "
        f"{osum['compared']} can be compared with an asymptotic linear order, and {osum['agree']} of them agree "
        f"within {ORDER_AGREEMENT} (disagreeing: {_join(osum['disagree'])}).</p>"
    )
    parts.append(
        table(
            ["configuration", "order (pendulum)", "decade [s]", "order (linear model)", "agree", "why undecided"],
            [
                [
                    r["config"],
                    _order_text(r["order"], r["status"]),
                    f"{_f(r['H_min'], '.0e')}–{_f(r['H_max'], '.0e')}" if math.isfinite(r["H_min"]) else "–",
                    _order_text(r["order_linear"], r["status_linear"]),
                    "–" if r["agree"] is None else ("yes" if r["agree"] else "no"),
                    r["reason"],
                ]
                for r in rows
            ],
        )
    )
    if "error_over_H" in figure_pngs:
        parts.append(
            figure(
                figure_pngs["error_over_H"],
                f"Error over H (T = {T:g} s), one panel per k; × marks step sizes where the run diverged. The legend "
                "gives the asymptotic order or why there is none.",
            )
        )

    # work-precision
    acc = accuracy_rows(wp)
    integs = [str(i) for i in wp["integrator"].values]
    sentences = []
    for r in acc:
        if not r["config"]:
            sentences.append(f"at {_f(r['level'], '.0e')} rad no co-simulation run of the grid is accurate enough")
            continue
        rel = "; ".join(
            f"{_f(r['cpu'] / r['cpu_' + i], '.1f')}× monolithic {i}" if math.isfinite(r["cpu_" + i]) else f"{i}: none"
            for i in integs
        )
        note = (
            " — a configuration unstable as H → 0, stable only in a band of larger H" if r["unstable_small_H"] else ""
        )
        sentences.append(
            f"at {_f(r['level'], '.0e')} rad the cheapest is <code>{escape(r['config'])}</code> at H = {_f(r['H'], 'g')} s "
            f"({_f(r['cpu'], '.3f')} CPU s; {rel}){note}"
        )
    parts.append(
        "<h4>Work-precision</h4>"
        "<p>Error against CPU seconds, one line per configuration and each point one H; baselines: the monolithic "
        "pendulum over tolerances with the links' own Radau IIA and with DOP853 (error at their accepted steps). "
        "<b>Per accuracy level</b> (the cheapest stable run of the grid with max error at most the level): "
        + "; ".join(sentences)
        + ".</p>"
    )
    parts.append(
        table(
            ["max error ≤ [rad]", "cheapest co-simulation", "H [s]", "CPU s"]
            + [f"monolithic {i}: CPU s (tol)" for i in integs],
            [
                [_f(r["level"], ".0e"), r["config"] or "–", _f(r["H"], "g"), _f(r["cpu"], ".4f")]
                + [f"{_f(r['cpu_' + i], '.4f')} ({_f(r['tol_' + i], '.0e')})" for i in integs]
                for r in acc
            ],
        )
    )
    if "work_precision" in figure_pngs:
        parts.append(
            figure(
                figure_pngs["work_precision"],
                "Work-precision. Upper row: co-simulation over H (one line per configuration) and the monolithic "
                "baselines over tolerance. Lower row: adaptive (triangles, dashed) against fixed H (circles) on the "
                f"adaptive study's horizon T = {float(ad.attrs.get('t_end', math.nan)):g} s, against CPU seconds and "
                "against macro steps (accepted + rejected).",
            )
        )

    # stability limit
    lrows = limit_rows(lim)
    scan = [float(h) for h in np.atleast_1d(lim.attrs.get("scan", [math.nan]))]
    T_lim = float(lim.attrs.get("t_end", math.nan))
    lsum = limit_summary(lrows, scan[0], T_lim)
    parts.append(
        "<h4>Stability limit in H</h4>"
        f"<p>Largest stable H per configuration: scan H = {', '.join(_f(h, 'g') for h in scan)} s upward, then bisect "
        f"between the last stable and the first unstable H to {100 * float(lim.attrs.get('resolution', math.nan)):g} % "
        f"(stable: no divergence or failure within {float(lim.attrs.get('t_end', math.nan)):g} s, the bounds of the "
        "runs above). Predicted: the same search on ρ ≤ 1 of the linear test model at the pendulum's points "
        "(λ̄<sub>r1</sub> = −dH/(2m), λ̄<sub>i1</sub> = Hω for both modal frequencies, the mapping of the ρ ≈ 1.13 check; "
        "the method's SI parameters scaled by H). H_max is the upper edge of the first stable band at or above the first "
        "scan point.</p>"
        "<p><b>Result.</b> "
        f"<i>Limits set by growth</i> (the first unstable run exceeded |λ<sub>c</sub>| or |ω|): "
        f"{_join(lsum['growth_limited'])}; where the linear model has a limit too, measured/predicted = "
        + (", ".join(f"{_f(r, '.2f')} (<code>{escape(c)}</code>)" for c, r in lsum["growth_compared"]) or "–")
        + f", i.e. agreement within a factor {LIMIT_AGREEMENT} for {len(lsum['growth_agree'])} of "
        f"{len(lsum['growth_compared'])}. <i>Limits set by the constraint bound</i> |g<sub>c</sub>| &gt; "
        "1 cm after the corrector, at large H, where a run may be inaccurate rather than growing: "
        f"{_join(lsum['constraint_limited'])}. Stable up to the last scan point: measured "
        f"{_join(lsum['censored'])}; predicted {_join(lsum['censored_linear'])}. Unstable at the first scan point "
        f"H = {_f(scan[0], 'g')} s, with a stable band above it: measured {_join(lsum['unstable_at_scan0'])}; "
        f"predicted {_join(lsum['unstable_at_scan0_linear'])}. "
        + (
            "Where the measured band starts below the predicted one, the linear model's growth over the "
            f"{T_lim:g} s horizon at the measured lower edge is "
            + ", ".join(f"{_f(g, '.1e')} (<code>{escape(c)}</code>)" for c, g in lsum["band_growth"].items())
            + ": too little to reach the bounds from errors of 1e-9 rad, so divergence within the horizon cannot "
            "see that instability. "
            if lsum["band_growth"]
            else ""
        )
        + "What is measured is divergence within a finite horizon.</p>"
    )
    parts.append(
        table(
            [
                "configuration",
                "H_max measured [s]",
                "search",
                "stable from [s]",
                "H_max linear [s]",
                "search (linear)",
                "measured / linear",
                "ρ linear at measured H_max",
                "runs",
                "at the first unstable H",
                "limited by",
            ],
            [
                [
                    r["config"],
                    _f(r["H_max"], ".4g"),
                    r["status"],
                    _f(r["H_band_low"], "g"),
                    _f(r["H_max_linear"], ".4g"),
                    r["status_linear"]
                    + (
                        f" (upper end {r['verdict_linear']})" if r.get("verdict_linear") not in ("", "unstable") else ""
                    ),
                    _f(r["ratio"], ".2f"),
                    _f(r["rho_at_H_max"], ".4f"),
                    r["n_runs"],
                    r["reason"],
                    r["limited_by"],
                ]
                for r in lrows
            ],
        )
    )
    if "stability_limit" in figure_pngs:
        parts.append(
            figure(
                figure_pngs["stability_limit"],
                "Largest stable H: measured (bisection on divergence) against the linear test model's prediction "
                "(dataset <code>results/pendulum/stability_limit.nc</code>).",
            )
        )

    # tolerance
    trows = tolerance_rows(tol)
    decided = [r for r in trows if not r["at_floor"]]
    never = bool(decided) and all(
        math.isfinite(r["sufficient"]) and r["sufficient"] >= r["rtol_loose"] * (1 - 1e-12) for r in decided
    )
    floor_cases = [f"{r['config']} at H = {r['H']:g} s" for r in trows if r["at_floor"]]
    parts.append(
        "<h4>Subsystem tolerance</h4>"
        f"<p>At fixed H, the links' Radau IIA at rtol = atol from {_f(trows[0]['rtol_loose'], '.0e')} to "
        f"{_f(trows[0]['rtol_tight'], '.0e')}: the error against the reference and the <i>integration effect</i>, "
        "max |φ(rtol) − φ(tightest rtol)| over the macro nodes, the part of the error the tolerance controls. The "
        f"integration error stops mattering where the effect falls below {100 * float(tol.attrs.get('share', 0.01)):g} % "
        "of the error. "
        + (
            "<b>Result:</b> it never matters here: at every H and configuration the effect stays below that share from "
            "the loosest tolerance on, so the coupling error is what the error-over-H study measures; a tighter "
            "tolerance only costs Radau substeps (table)."
            + (
                f" Not decided where the error itself is at the error floor ({escape('; '.join(floor_cases))}): "
                "there both numbers are rounding."
                if floor_cases
                else ""
            )
            if never
            else "<b>Result:</b> the loosest sufficient tolerance per configuration and H is in the table."
        )
        + "</p>"
    )
    parts.append(
        table(
            [
                "configuration",
                "H [s]",
                "error (tightest rtol) [rad]",
                "error (loosest rtol) [rad]",
                "largest integration effect [rad]",
                "loosest sufficient rtol",
                "Radau steps per macro step (loose → tight)",
                "CPU s (loose → tight)",
            ],
            [
                [
                    r["config"],
                    _f(r["H"], "g"),
                    _f(r["error_tight"]),
                    _f(r["error_loose"]),
                    _f(r["effect_max"]),
                    "error at the floor" if r["at_floor"] else _f(r["sufficient"], ".0e"),
                    f"{r['substeps_loose']:.2f} → {r['substeps_tight']:.2f}",
                    f"{r['cpu_loose']:.3f} → {r['cpu_tight']:.3f}",
                ]
                for r in trows
            ],
        )
    )
    if "tolerance" in figure_pngs:
        parts.append(figure(figure_pngs["tolerance"], "Error (solid) and integration effect (dashed) over rtol."))

    # adaptive
    asum = adaptive_summary(ad, lim)
    erows = equal_error_table(ad)
    verdicts = []
    for lab, s in asum.items():
        if s["compared"] == 0:
            verdicts.append(f"<code>{escape(lab)}</code>: no adaptive error is bracketed by the fixed-H runs")
            continue
        verdicts.append(
            f"<code>{escape(lab)}</code>: fewer macro steps than fixed H at equal error in {s['fewer']} of "
            f"{s['compared']} comparisons (adaptive/fixed {_f(s['ratio_min'], '.2f')}–{_f(s['ratio_max'], '.2f')}; "
            f"{int(s['rejected'])} rejected steps in all; largest H_max/H_min of a run {_f(s['H_spread_max'], '.1f')}; "
            f"drift within tolerance: {'yes' if s['drift_ok'] else 'no'})"
        )
        if s["not_fewer"]:
            worst = max(s["not_fewer"], key=lambda r: r["H_max_used"])
            kinds = {
                how: ", ".join(
                    f"{r['tol']:g}" for r in s["not_fewer"] if (r["how"] == "not bracketed") == (how == "nb")
                )
                for how in ("nb", "no")
            }
            which = " or ".join(
                f"{'not bracketed' if how == 'nb' else 'not cheaper'} (tol = {tols})"
                for how, tols in kinds.items()
                if tols
            )
            limit, H_top = s["H_limit"], _f(worst["H_max_used"], ".2g")
            n_rej = int(max(r["n_rejected"] for r in s["not_fewer"]))
            if math.isfinite(limit) and worst["H_max_used"] > limit:
                verdicts[-1] += (
                    f"; where it is {which}, its accepted steps reach {H_top} s, above the stability limit "
                    f"{_f(limit, '.2g')} s measured for fixed H, and up to {n_rej} steps were rejected: in smooth "
                    "stretches the controller lets H grow past the limit, the estimate then grows with the "
                    "instability and forces rejections and a drop of H (the jagged step sizes in the figure), "
                    "which costs the steps the adaptivity saved"
                )
            else:
                verdicts[-1] += f"; {which}: largest step {H_top} s, up to {n_rej} rejected"
    ctl = escape(str(ad.attrs.get("controller_json", "")))
    parts.append(
        "<h4>Adaptive macro steps</h4>"
        "<p>Beyond the paper: the macro step is chosen by a PI controller (Gustafsson's, as in Hairer & Wanner) on "
        "the predictor–corrector difference of the coupling variables, "
        "max |e<sub>c</sub> − e<sub>p</sub>| / (tol (1 + |e<sub>c</sub>|)), which scales like H<sup>k+1</sup>, together "
        f"with the joint drift |g<sub>c</sub>| ≤ {_f(ad.attrs.get('drift_tol'), 'g')} m; a step with error norm above 1 "
        "(or beyond the divergence bounds) is rejected and retried smaller; Lagrange extrapolation and interpolation run "
        f"through the actual, non-equidistant macro nodes. Controller: {ctl}; first step "
        f"{_f(ad.attrs.get('H0'), 'g')} s. Fixed-H runs of the same configurations over the same horizon "
        f"T = {float(ad.attrs.get('t_end', math.nan)):g} s give the comparison at equal error (log-log interpolation "
        "between the two fixed H that bracket the adaptive run's error; the adaptive cost counts rejected steps).</p>"
        "<p><b>Result:</b> " + "; ".join(verdicts) + ".</p>"
    )
    parts.append(
        table(
            [
                "configuration",
                "tol",
                "max error [rad]",
                "max drift [m]",
                "accepted",
                "rejected",
                "fixed H at equal error (steps)",
                "fewer",
                "CPU s",
                "CPU s fixed at equal error",
            ],
            [
                [
                    r["config"],
                    _f(r["tol"], ".0e"),
                    _f(r["error_max"]),
                    _f(r["drift_max"]),
                    int(r["n_accepted"]),
                    int(r["n_rejected"]),
                    _f(r["n_fixed"], ".0f") if r["how"] == "interpolated" else r["how"],
                    "–" if r["fewer"] is None else ("yes" if r["fewer"] else "no"),
                    _f(r["cpu"], ".3f"),
                    _f(r["cpu_fixed"], ".3f"),
                ]
                for r in erows
            ],
        )
    )
    if "adaptive" in figure_pngs:
        parts.append(figure(figure_pngs["adaptive"], "Accepted macro-step sizes over time, one line per tolerance."))
    return "".join(parts)
