"""The coupling schemes compared, in each part's section of the report: from the data.

Everything shown comes from generated files: the stable shares
(:func:`icosim.studies.stability.comparison.scheme_shares`), the convergence panels of
every scheme, the pendulum summary of every run, the claims beyond the paper
(scope ``beyond``) and the figures of the other schemes.  Each function returns
the subsection of one part; a part computed with one scheme has none.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..engine.graph import CouplingGraph
from ..engine.schemes import SCHEMES
from ..engine.stages import plan
from ..labels import figure_label
from ..verdicts import verdict_counts
from .claims import claims_table
from .html import escape, figure, table

__all__ = [
    "stability_schemes",
    "convergence_schemes",
    "pendulum_schemes",
    "schemes_intro",
    "share_cells",
    "order_rows",
    "pendulum_rows",
]

LABEL = {name: s.label for name, s in SCHEMES.items()}


def _fmt(x, spec):
    return "–" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


# -- stability ------------------------------------------------------------------------------------
def share_cells(shares) -> list:
    """One record per (figure, k): mean stable share over the rows per scheme, and the grid resolution."""
    out = []
    schemes = [str(s) for s in shares["scheme"].values]
    n = int(np.max(shares["n_points"].values))
    resolution = 1.0 / (math.isqrt(n) - 1) if n > 1 else math.nan
    for fig in shares["figure"].values:
        for k in shares["k"].values:
            cell = shares["stable_share"].sel(figure=fig, k=k)
            means = {s: float(np.nanmean(cell.sel(scheme=s).values)) for s in schemes}
            out.append(
                {
                    "figure": str(fig),
                    "method": str(shares["method"].sel(figure=fig).values),
                    "decomposition": str(shares["decomposition"].sel(figure=fig).values),
                    "k": int(k),
                    "shares": means,
                    "resolution": resolution,
                }
            )
    return out


def _effect(cells, scheme):
    """(cells where ``scheme`` is more stable than Jacobi, less stable, neither) beyond the grid resolution."""
    better, worse, same = [], [], []
    for c in cells:
        if scheme not in c["shares"] or "jacobi" not in c["shares"]:
            continue
        d = c["shares"][scheme] - c["shares"]["jacobi"]
        (better if d > c["resolution"] else worse if d < -c["resolution"] else same).append((c, d))
    return better, worse, same


def _most_stable(c):
    """The scheme with the largest share, or "tie" if another is within the grid resolution of it."""
    ranked = sorted(c["shares"].items(), key=lambda kv: -kv[1])
    if len(ranked) > 1 and ranked[0][1] - ranked[1][1] <= c["resolution"]:
        return "tie (within the grid resolution)"
    return LABEL[ranked[0][0]]


def _cell_name(c):
    return f"{figure_label(c['figure'])} ({c['method']}, {c['decomposition']}) k = {c['k']}"


#: the paper's two subsystems (the schemes' integrations per step do not depend on the decomposition)
PAIR = CouplingGraph.pair("ff")


def schemes_intro(schemes) -> str:
    """What the schemes compared are, in one paragraph (the Gauss-Seidel derivation: docs/gauss_seidel.md)."""
    others = [s for s in schemes if s != "jacobi"]
    costs = ", ".join(f"{escape(LABEL[s])} {plan(SCHEMES[s], PAIR).integrations}" for s in schemes)
    return (
        "<p>The paper analyses the Jacobi (parallel) scheme; here the same data are computed with "
        + ", ".join(escape(LABEL[s]) for s in others)
        + ". In a Gauss–Seidel (sequential) scheme the first subsystem advances once with the extrapolated coupling "
        "variables and its state is final; the corrected coupling variables are formed from its finished outputs "
        "(algebraic gradients only) and the second subsystem's full gradients, and only the second subsystem is "
        "corrected, with the interpolation polynomial. The first subsystem's outputs at the end of the step "
        "(acceleration, coupling force) are re-evaluated with the corrected coupling variables; the variants "
        "<i>as integrated</i> leave them as they were (docs/gauss_seidel.md). Subsystem integrations per macro "
        f"step: {costs}.</p>"
    )


def _claims_html(claims) -> str:
    counts = verdict_counts(claims)
    return (
        f"<p>Claims beyond the paper (scope <code>beyond</code> in the part's claims file, stated from these data): "
        f"{counts['pass']} pass, {counts['fail']} fail, {counts['undecided']} undecided.</p>"
        + claims_table(claims, note_header="why")
    )


def stability_schemes(*, shares, claims, comparison_png, figure_pngs, figures_cfg) -> str:
    """The stability part's comparison of schemes: the mean stable shares per (figure, k), the comparison
    figure, the claims beyond the paper and the figures of the other schemes (``fig<N>_<scheme>.png``)."""
    cells = share_cells(shares)
    schemes = [str(s) for s in shares["scheme"].values]
    rows = [[_cell_name(c)] + [_fmt(c["shares"].get(s), ".0%") for s in schemes] + [_most_stable(c)] for c in cells]
    effects = []
    for s in schemes:
        if s == "jacobi":
            continue
        better, worse, same = _effect(cells, s)
        worst = sorted(worse, key=lambda cd: cd[1])[:4]
        effects.append(
            f"<li><b>{escape(LABEL[s])}</b> has a larger mean stable share than Jacobi in {len(better)} of "
            f"{len(cells)} (figure, k) cells"
            + (": " + "; ".join(f"{escape(_cell_name(c))} {d:+.0%}" for c, d in better) if better else "")
            + f"; a smaller one in {len(worse)}"
            + (
                " (largest losses: " + "; ".join(f"{escape(_cell_name(c))} {d:+.0%}" for c, d in worst) + ")"
                if worst
                else ""
            )
            + f"; a mean share equal to Jacobi's within the grid resolution (an area, not the same points) in "
            f"{len(same)}.</li>"
        )
    body = [
        "<h3>Coupling schemes</h3>",
        schemes_intro(schemes),
        "<p>Each figure computed with several schemes has the same panels, grids and precision policy for each. "
        "Shares below are the mean over a figure's rows of the share of stable grid points.</p><ul>"
        + "".join(effects)
        + "</ul>",
        figure(
            comparison_png,
            "Stable shares per method, decomposition and k, one bar per scheme (Jacobi grey); bars are the mean over a "
            "figure's rows, markers each row.",
            alt="scheme comparison",
        ),
        table(["figure, k"] + [LABEL[s] for s in schemes] + ["most stable"], rows),
        _claims_html(claims),
    ]
    for png in figure_pngs:
        fig, scheme = Path(png).stem.removeprefix("fig").split("_", 1)
        title = figures_cfg.get(fig, {}).get("title", "")
        body.append(
            figure(
                png,
                f"<b>{escape(figure_label(fig))}, {escape(LABEL[scheme])}</b>: {escape(title)}. Same rows, columns, "
                "grids and colours as the Jacobi figure above.",
                alt=f"{figure_label(fig)}, {scheme}",
            )
        )
    return "".join(body)


# -- convergence ----------------------------------------------------------------------------------
def order_rows(curves) -> tuple:
    """``(schemes, rows)``: per curve of the paper's figures the fitted order under each scheme.

    ``curves`` are records of :func:`icosim.studies.convergence.curves.curves` of every scheme's panels.
    A row is ``(label, {scheme: order or "unstable" or None})``.
    """
    from ..studies.convergence.curves import curve_label

    table_, schemes = {}, []
    for rec in curves:
        fig, scheme = rec["figure"], rec["scheme"]
        if scheme not in schemes:
            schemes.append(scheme)
        label = f"{figure_label(fig)}: " + curve_label(rec)
        value = "unstable" if bool(np.all(rec["unstable"])) else rec["order"]
        table_.setdefault(label, {})[scheme] = value
    order = [s for s in SCHEMES if s in schemes]
    return order, list(table_.items())


def _order_text(v):
    if v is None:
        return "–"
    if v == "unstable":
        return "unstable"
    return _fmt(float(v), ".2f") if math.isfinite(float(v)) else "no fit"


def convergence_schemes(*, curves, claims, figure_pngs) -> str:
    """The convergence part's comparison of schemes: the fitted order of every curve under each scheme, the
    claims beyond the paper and the figures of the other schemes (``fig<N>_<dec>_<scheme>.png``)."""
    schemes, rows = order_rows(curves)
    body = [
        "<h3>Coupling schemes</h3>",
        schemes_intro(schemes),
        "<p>Every curve computed with each scheme, with the same step sizes, fit and instability rules. Fitted order "
        "of Eq. (72) per curve; <i>unstable</i>: unstable at every step size; <i>no fit</i>: too few stable step "
        "sizes. docs/gauss_seidel.md derives O(H<sup>k+1</sup>) for every stable Gauss–Seidel curve in ff: the "
        "leading subsystem's extrapolated coupling force and the corrected subsystem's interpolated one differ by "
        "O(H<sup>k+1</sup>), an impulse defect O(H<sup>k+2</sup>) per step. In fd and dd (a kinematically driven "
        "subsystem) the order is measured, not derived.</p>",
        table(
            ["curve"] + [LABEL[s] for s in schemes],
            [[label] + [_order_text(v.get(s)) for s in schemes] for label, v in rows],
        ),
        _claims_html(claims),
    ]
    for png in figure_pngs:
        stem = Path(png).stem
        fig, dec, scheme = stem.removeprefix("fig").split("_")
        body.append(
            figure(
                png,
                f"<b>{escape(figure_label(fig))} ({escape(dec)}), {escape(LABEL[scheme])}</b>: NRMSE of Eq. (72) over "
                "H, one curve per k; × marks unstable step sizes; filled points are the fitted range.",
                alt=stem,
            )
        )
    return "".join(body)


# -- pendulum ----------------------------------------------------------------------------------
def pendulum_rows(summary) -> tuple:
    """``(schemes, rows)``: per configuration and k the outcome of each scheme's run.

    A row is ``((method, decomposition, k), {scheme: record})`` with the record's
    ``status``, ``t_end`` (diverged or failed at, else the last time), ``err_phi``,
    ``rho_test_model`` and ``reason``.
    """
    out, schemes = {}, []
    for i in range(summary.sizes["run"]):
        r = summary.isel(run=i)
        s = str(r["scheme"].values)
        if s not in schemes:
            schemes.append(s)
        key = (str(r["method"].values), str(r["decomposition"].values), int(r["k"].values))
        status = str(r["status"].values)
        t_stop = float(r["t_" + status].values) if status in ("diverged", "failed") else float(r["t_last"].values)
        out.setdefault(key, {})[s] = {
            "status": status,
            "t": t_stop,
            "err_phi": max(float(r["err_phi1"].values), float(r["err_phi2"].values)),
            "rho_test_model": float(r["rho_test_model"].values) if "rho_test_model" in r else math.nan,
            "reason": str(r["reason"].values),
        }
    return [s for s in SCHEMES if s in schemes], list(out.items())


def pendulum_schemes(*, summary, claims, figure_pngs) -> str:
    """The pendulum part's comparison of schemes: every configuration's outcome under each scheme, the claims
    beyond the paper and the figures of the other schemes (``pendulum_k<k>_<scheme>.png``)."""
    schemes, rows = pendulum_rows(summary)
    cells = []
    for (m, d, k), by in rows:
        row = [f"{m} {d} k = {k}"]
        for s in schemes:
            rec = by.get(s)
            if rec is None:
                row.append("–")
                continue
            if rec["status"] == "stable":
                text = f"stable, |Δφ| ≤ {_fmt(rec['err_phi'], '.1e')} rad"
            else:
                text = f"{rec['status']} at t = {rec['t']:.3f} s ({rec['reason']})"
            row.append(text + f"; ρ(test model) = {_fmt(rec['rho_test_model'], '.4f')}")
        cells.append(row)
    n = {s: sum(1 for _, by in rows if by.get(s, {}).get("status") == "stable") for s in schemes}
    body = [
        "<h3>Coupling schemes</h3>",
        schemes_intro(schemes),
        "<p>Every configuration of Figs. 6–8 run with each scheme (link 1 is subsystem 1), the same integrator, "
        "sensitivities, end time and divergence bounds. Stable runs up to the end time: "
        + ", ".join(f"{escape(LABEL[s])} {n[s]} of {len(rows)}" for s in schemes)
        + ". ρ(test model): the spectral radius of the linear test model at the pendulum's points for the same "
        "scheme (as above). With link 2 first the position- and velocity-level conditions are singular for the "
        "pendulum (link 1 has one degree of freedom; docs/gauss_seidel.md, Sect. 5).</p>",
        table(["run"] + [LABEL[s] for s in schemes], cells),
        _claims_html(claims),
    ]
    for png in figure_pngs:
        stem = Path(png).stem
        k, scheme = stem.removeprefix("pendulum_k").split("_", 1)
        body.append(
            figure(
                png,
                f"<b>k = {escape(k)}, {escape(LABEL[scheme])}</b>: the pendulum with this scheme, one line per "
                "configuration (up to divergence), the monolithic reference dashed.",
                alt=stem,
            )
        )
    return "".join(body)
