"""The convergence section of the report (Figs. 21-23): decisions, claims per curve, figures, work-precision.

Everything shown comes from generated files -- the figures, the claim verdicts,
the work-precision dataset and the panel datasets -- and from the
configuration (the decisions).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..studies.convergence.curves import fastest_configurations
from ..studies.convergence.experiment import Setup, oscillation_summary, step_counts
from ..verdicts import verdict_counts
from . import html as rp
from .claims import claims_table

__all__ = ["convergence_section", "work_cost_table"]

esc = rp.escape

#: What each stepping computes, for the decisions list.
STEPPING_TEXT = {
    "error": " — the co-simulation error itself is propagated, e_N+1 = M e_N + D z_N, with the one-step defect D "
    "of the macro step on the exact solution formed in Arb ball arithmetic (proven to 2^-40 relative per row) and "
    "then rounded (icosim.studies.convergence.errors): float64 carries the error, not the difference of two O(1) numbers, "
    "so there is no round-off floor. Checked against 40-digit mpmath time stepping (tests).",
    "matrix": " — the float64 state is iterated with the amplification matrix and the exact solution subtracted "
    "(a round-off floor near NRMSE ~ 1e-11).",
    "simulate": " — icosim.engine.run.simulate in float64 (a round-off floor near NRMSE ~ 1e-11).",
}


def _bits(panels) -> str:
    bits = sorted({int(b) for ds in panels if "defect_bits" in ds for b in np.unique(ds["defect_bits"].values) if b})
    return ", ".join(str(b) for b in bits) or "—"


def work_cost_table(wp):
    """Per configuration of the work-precision dataset: median ms per macro step and the counted work (a DataFrame)."""
    work = wp[["subsystem_integrations_per_step", "coupling_solves_per_step", "projections_per_step"]]
    cost = work.reset_coords(drop=True).to_dataframe().astype(int).astype(str)
    cost.insert(0, "ms", wp["cpu_seconds_per_step"].median(dim="H", skipna=True).to_pandas())
    cost["ms"] = cost["ms"].map(lambda t: f"{1e3 * t:.3g}" if np.isfinite(t) else "— (unstable at every H)")
    cost = cost.reset_index().astype({"configuration": str})
    cost.columns = ["configuration", "ms per macro step", "subsystem integrations", "coupling solves", "projections"]
    return cost


def convergence_section(
    *,
    setup: dict,
    step_sizes: dict,
    stepping: str,
    fit: dict,
    startup_steps: int = 50,
    unstable: dict,
    targets: list,
    figures: dict,
    panels: list,
    claims: list,
    figure_pngs: list,
    wp,
    wp_png,
    schemes_html: str = "",
) -> str:
    """The section as an HTML fragment.

    ``setup`` (model, initial conditions, end time, growth bound), ``step_sizes``,
    ``stepping``, ``fit``, ``unstable``, ``targets`` (work-precision target
    errors) and ``figures`` are the configuration (``convergence:``);
    ``panels`` the panel datasets, ``claims`` the verdict records, ``figure_pngs``
    the figures (``.../fig<figure>_<dec>.png``, each with its slope figure
    ``..._slopes.png`` beside it) in the order shown, ``wp`` the
    work-precision dataset and ``wp_png`` its figure.
    """
    s = setup
    n_steps = step_counts(s["end_time"], step_sizes["H_min"], step_sizes["H_max"], step_sizes["num"])
    H = s["end_time"] / n_steps
    seconds = sum(ds.attrs["seconds_total"] for ds in panels)
    n_curves = sum(ds.sizes["index"] * ds.sizes["k"] for ds in panels)
    n_unstable = sum(int(ds["unstable"].sum()) for ds in panels)
    n_runs = sum(int(ds["unstable"].size) for ds in panels)
    n_marginal = sum(int((ds["spectral_verdict"] == "marginal").sum()) for ds in panels if "spectral_verdict" in ds)
    osc = oscillation_summary(Setup(**s))
    if osc["overdamped"]:
        horizon = (
            f"the rigidly coupled system is overdamped (decay rate {osc['delta']:.3g} 1/s), "
            f"the amplitude decays to {100 * osc['decay']:.2g} % of its start"
        )
    else:
        horizon = (
            f"{osc['periods']:.2g} periods of the coupled oscillation (ω = {osc['omega']:.3g} rad/s), "
            f"amplitude decaying to {100 * osc['decay']:.2g} % (decay rate {osc['delta']:.3g} 1/s)"
        )

    decisions = [
        f"Model (Sect. 3.7): m1 = {s['m1']:g} kg, m2 = {s['m2']:g} kg, c1 = {s['c1']:g} N/m, c2 = {s['c2']:g} N/m, "
        f"d1 = {s['d1']:g} Ns/m, d2 = {s['d2']:g} Ns/m; macro-step size H in seconds.",
        f"Initial conditions (not given in the paper; our choice): x1 = x2 = {s['x0']:g} m, v1 = v2 = {s['v0']:g} m/s at t = 0, "
        f"consistent with the rigid link; end time T = {s['end_time']:g} s: {horizon} (every NRMSE denominator, the variance "
        "of the reference, must stay well away from zero).",
        "Coupling-variable history: the exact monolithic coupling variables (multiplier λ and/or acceleration) at "
        "T_0, T_−1, …, T_−k (icosim.problems.linear.exact.consistent_start); both subsystems start at the exact state.",
        f"Step sizes: {len(H)} sizes H = T/N_total from {H.min():.3g} s to {H.max():.3g} s "
        f"({np.log10(H.max() / H.min()):.1f} decades; N_total from {n_steps.min()} to {n_steps.max()}).",
        "Eq. (72), whose extraction is garbled (two brackets closed by ]^(1/2), one opened), is read as one square root of the "
        "sum of the four normalised squared-error ratios of x1, x2, v1, v2, sums over N = 1 … N_total; the other reading "
        "(two roots added) differs by at most √2 and cannot change an order. Both can be rebuilt from the datasets: "
        "nrmse_x (x1, x2) and nrmse_v (v1, v2) are stored, nrmse = √(nrmse_x² + nrmse_v²), the other reading "
        "nrmse_x + nrmse_v. nrmse_lambda is the same measure for the constraint force λ_c against the exact "
        "multiplier (ff, fd), where the paper warns of index-3 chattering.",
        f"Stepping: '{stepping}'"
        + STEPPING_TEXT.get(stepping, "")
        + (f" The defects were proven at {_bits(panels)} bits." if stepping == "error" else ""),
        f"Unstable: a run is stopped once |state| exceeds {unstable['growth_bound']:g} × the initial amplitude, and is "
        "also unstable where the spectral radius of the recurrence at that H exceeds 1"
        + (
            ": proven from the same ball amplification matrix as the defect (icosim.engine.spectral.certified, "
            f"{n_marginal} of {n_runs} runs marginal: the enclosure contains 1)."
            if stepping == "error"
            else f" (policy '{unstable['spectral_policy']}')."
        )
        + f" {n_unstable} of {n_runs} runs were unstable; they are drawn as × at the top of a panel, never as an error.",
        f"Orders decided in the asymptotic range (icosim.order_fit.asymptotic_order): the order of a curve is the "
        f"least-squares slope of log NRMSE over log H on its smallest-H decade (at least {fit['min_points']} stable step "
        f"sizes), and counts only if every local slope there is within ±{fit['tolerance']:g} of it; otherwise the curve is "
        "pre-asymptotic and a claim about it is undecided, never passed or failed. A curve unstable at its smallest step "
        "sizes has no asymptotic range; one unstable at every step size has no order (n/a for an order claim). Each "
        "dataset stores the local slopes (local_slope over H_mid), the order, its status and its range.",
        f"Start-up transient: nrmse_startup holds the share of Eq. (72)'s sums from the first {startup_steps} macro steps "
        "(over the whole run's denominators, so nrmse² = startup² + rest²), and nrmse_second_half Eq. (72) over "
        "T_N in (T/2, T]; their orders separate a start-up transient from the smooth global error.",
    ]
    body = [
        "<h3>What was computed</h3><ul>" + "".join(f"<li>{esc(d)}</li>" for d in decisions) + "</ul>",
        f"<p>{n_curves} curves in {len(panels)} panel datasets (results/convergence/&lt;decomposition&gt;/fig*.nc), "
        f"{seconds:.0f} s of compute in the panel jobs.</p>",
    ]

    # -- claims -------------------------------------------------------------------------------------
    rows = []
    for c in claims:
        first = True
        for r in c["numbers"]["rows"]:
            order = r["order"]
            if order is None or not np.isfinite(order):
                measured = "—"
            else:
                measured = f"{order:.2f} on [{r['fit_H_min']:.2g}, {r['fit_H_max']:.2g}] s"
            status = r["order_status"] + (
                f": {r['reason']}" if r.get("reason") and r["order_status"] != "asymptotic" else ""
            )
            slopes = "—" if not r["local_slopes"] else f"{r['local_slopes'][0]:.2f} … {r['local_slopes'][1]:.2f}"
            rows.append(
                [
                    esc(c["id"]) if first else "",
                    esc(r["curve"]),
                    esc(r["claimed"]),
                    measured,
                    esc(status),
                    slopes,
                    _fmt(r["order_second_half"]),
                    _fmt(r.get("order_startup")),
                    esc(r["stable_H"]),
                    rp.verdict_badge(r["verdict"]),
                ]
            )
            first = False
    counts = verdict_counts(claims)
    tolerances = sorted({c["numbers"]["tolerance"] for c in claims})
    body.append(
        f"<h3>The paper's claims</h3><p>{len(claims)} claims (config/claims/convergence.yaml), each checked on "
        f"every curve it covers: {counts['pass']} pass, {counts['fail']} fail, {counts['undecided']} undecided. An order "
        f"passes if the asymptotic order is within ±{', '.join(f'{t:g}' for t in tolerances)} of the claim and fails "
        "otherwise; a pre-asymptotic curve leaves it undecided; a curve unstable at every step size is n/a. 'unstable' "
        "passes if every step size is unstable. Where the data disagree with the paper, the data stand and the "
        "explanation column says why (each explanation is checked by a test against these data).</p>"
        + claims_table(claims, note_header="explanation", part="convergence")
        + "<p>Per curve: the order over the smallest-H decade and its status; the local slopes over all stable step "
        "sizes; the orders of Eq. (72) over the second half of the run and of the start-up share (diagnostics of a "
        "start-up transient).</p>"
        + rp.table(
            [
                "claim",
                "curve",
                "paper",
                "order (decade)",
                "status",
                "local slopes",
                "second half",
                "start-up",
                "stable H",
                "verdict",
            ],
            rows,
            raw_columns=(9,),
        )
    )

    # -- figures --------------------------------------------------------------------------------------
    for png in figure_pngs:
        stem = Path(png).stem  # fig21_ff_jacobi
        fig, dec, _ = stem[3:].split("_")
        cfg = figures[fig]
        paper = {"21": "Fig. 21", "22": "Fig. 22", "23": "Fig. 23"}.get(fig, f"Fig. {fig}")
        shown = "as in the paper" if dec == "ff" else "not shown in the paper"
        body.append(
            rp.figure_pair(
                png,
                str(png).replace(".png", "_slopes.png"),
                f"<b>{paper}, {esc(dec)}</b> ({shown}): {esc(cfg['title'])}. Left: NRMSE over H; filled points: the "
                "smallest-H decade the order is read off, order p (or why it is not asymptotic) in the legend; ×: "
                "unstable at that H; dotted: O(H^p). Right: local slopes between neighbouring step sizes; the band "
                "marks the decade at the order ± the tolerance.",
                anchor=rp.figure_anchor("convergence", png),
                paper_figures=[fig],
                claims_html=rp.used_by("convergence", [c["id"] for c in claims if fig in c["figures"]]),
            )
        )

    # -- work-precision -------------------------------------------------------------------------------
    body.append(
        "<h3>Work-precision</h3><p>"
        + esc(
            f"Timed: {wp.attrs['timed']}; CPU time ({wp.attrs['timer']}), minimum of {wp.attrs['repeats']} runs of "
            f"{wp.attrs['steps']} macro steps after {wp.attrs['warmup_steps']} warm-up steps, per step, times T/H for one simulated "
            "second. Every macro step of the linear model costs the same, so the time per simulated second is the time per step "
            "divided by H. Unstable step sizes are left out. The NRMSE is taken from the panel datasets."
        )
        + "</p><p><b>Caveat.</b> "
        + esc(
            "The subsystems of the test model are integrated exactly, so what is timed is the coupling algorithm's Python "
            "overhead, nearly equal for all configurations: the diagram is close to NRMSE over 1/H and says little about "
            "numerically integrated subsystems. For those, weigh the counted work per macro step below (subsystem "
            "integrations, coupling-condition solves, projections) with their cost there."
        )
        + "</p>"
    )
    body.append(
        rp.figure(
            wp_png,
            "CPU time per simulated second over NRMSE; one line per configuration, each point one H.",
            anchor=rp.figure_anchor("convergence", wp_png),
        )
    )
    table_rows = []
    for entry in fastest_configurations(wp, targets):
        rk = entry["ranking"]
        if rk:
            best = rk[0]
            runner = "; ".join(f"{lab.split(' ', 1)[1]} ({sec:.3g} s)" for lab, sec, _ in rk[1:3])
            table_rows.append(
                [
                    entry["decomposition"],
                    f"{entry['target']:.0e}",
                    best[0].split(" ", 1)[1],
                    f"{best[1]:.3g}",
                    f"{best[2]:.3g}",
                    runner or "—",
                ]
            )
        else:
            table_rows.append([entry["decomposition"], f"{entry['target']:.0e}", "none reaches it", "—", "—", "—"])
    body.append(
        "<p>Which configuration reaches a given error fastest (least CPU time per simulated second among the measured step "
        "sizes with NRMSE ≤ target):</p>"
        + rp.table(
            ["decomposition", "target NRMSE", "fastest configuration", "CPU s per simulated s", "at H (s)", "next two"],
            table_rows,
        )
        + "<p>Cost of one macro step (median over H) and the work it consists of (counted on the engine's macro "
        "step):</p>" + rp.table(work_cost_table(wp))
    )

    return rp.section("Convergence (Figs. 21–23)", "".join(body) + schemes_html, anchor="convergence")


def _fmt(x) -> str:
    return "—" if x is None or not np.isfinite(x) else f"{x:.2f}"
