"""The pendulum section of the report (Sect. 4, Figs. 6-8): set-up, decisions, claim run by run, errors, figures.

Everything shown comes from generated files -- the run summary, the claim
verdicts and the figures -- and from the configuration (``pendulum:``).
"""

from __future__ import annotations

import math

from .claims import claims_table
from .html import escape, figure, figure_anchor, section, table, used_by, verdict_badge
from .pendulum_trade import trade_section

__all__ = ["pendulum_section", "trade_section"]


def fmt(x, spec=".2e"):
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def pendulum_section(
    *,
    config: dict,
    paper_figure: dict,
    summary,
    claims: list,
    figure_pngs: list,
    error_png,
    trade_html: str = "",
    schemes_html: str = "",
) -> str:
    """The section as an HTML fragment.

    ``config`` is the configuration (``pendulum:``), ``paper_figure`` maps
    ``k`` to the paper's figure number, ``summary`` is the run summary
    (:func:`icosim.studies.pendulum.summary.summarize`), ``claims`` the verdict
    records, ``figure_pngs`` the figures (``.../pendulum_k<k>_<scheme>.png``) and
    ``error_png`` the error figure; ``schemes_html`` (:func:`icosim.report.schemes.pendulum_schemes`)
    and ``trade_html`` (:func:`trade_section`) are appended.
    """
    cfg = config
    paper_figure = {int(k): v for k, v in paper_figure.items()}
    runs = [
        (str(m), str(d), int(k))
        for m, d, k in zip(summary["method"].values, summary["decomposition"].values, summary["k"].values)
    ]

    # one entry per run: (method, decomposition, k) and the summary row
    summary_rows = [
        ([str(r["method"].values), str(r["decomposition"].values), int(r["k"])], r)
        for r in (summary.isel(run=i) for i in range(summary.sizes["run"]))
    ]

    m, integ, sens, corr, div, ref = (
        cfg[key] for key in ("model", "integrator", "sensitivities", "corrector", "divergence", "reference")
    )
    methods = "; ".join(
        f"<b>{escape(name)}</b>: "
        + (", ".join(f"{escape(str(k))} = {escape(str(v))}" for k, v in params.items()) or "no parameters")
        for name, params in cfg["methods"].items()
    )
    mode = (
        "semi-implicit (one corrector step, as in the paper)"
        if corr["iterations"] == 1
        else f"fully implicit: up to {corr['iterations']} corrector steps, residual tolerance {corr['tol']}"
    )
    n_div = int(summary["diverged"].sum())
    n_failed = int(summary["failed"].sum())
    lr1 = [float(v) for v in summary.attrs["test_model_lr1"]]
    li1 = [float(v) for v in summary.attrs["test_model_li1"]]
    t_div = [float(t) for t in summary["t_diverged"].values if not math.isnan(float(t))]
    setup = f"""
<p>Two rigid links (m = {m["m1"]:g} kg, J = {m["J1"]:.5g} kg m², l = {m["l1"]:g} m), gravity {m["g"]:g} m/s² in −y,
damping d<sub>x</sub> = d<sub>y</sub> = {m["d"]:g} N s/m at each centre of mass, φ1(0) = {m["phi1_0"]:.6g} rad,
φ2(0) = {m["phi2_0"]:.6g} rad, at rest. Link 1 (pinned to ground) is subsystem 1, link 2 subsystem 2.
Macro step H = {cfg["H"]:g} s, <b>end time {cfg["t_end"]:g} s</b> (the paper gives none; it is chosen so
that an instability like the one of Fig. 8 shows well inside the horizon: here the earliest divergence is at
t = {fmt(min(t_div), ".3f") if t_div else "–"} s). {n_div} of {len(runs)} runs diverged, {n_failed} failed
(a subsystem integration, the projection or the coupling solve could not be computed: such a run says nothing about
stability and its verdict is <i>undecided</i>).</p>
<p><b>Method parameters</b> (a choice; SI units, so the Baumgarte μ is in seconds, μ/H = 1; the run datasets
store it as <code>method_mu</code> with <code>method_mu_units = "s"</code>, unlike the stability datasets'
dimensionless μ̄): {methods}.
Corrector: {escape(mode)}.</p>
<p><b>Subsystem integration</b>: Radau IIA (3 stages, order 5) with step-size control, rtol = {integ["rtol"]:g},
atol = {integ["atol"]:g} (as in the paper), simplified Newton to {integ["newton_tol"]:g} of the error scale
(<code>icosim.problems.pendulum.integrator.compiled</code>: scipy's Radau algorithm, batched over initial values and inputs with a shared step
sequence, compiled with numba). <b>Sensitivities</b> of the outputs to the new coupling values e<sub>N+1</sub>: forward differences,
re-integrating each subsystem with the interpolation polynomial through e<sub>N+1</sub> + h<sub>j</sub>
(h<sub>j</sub> = {sens["fd_step"]:g}·max(1, |e<sub>j</sub>|)), predictor and perturbations in one batched call per
subsystem. <b>Reference</b>: the monolithic pendulum in minimal coordinates (φ1, φ2), scipy {escape(ref["method"])},
rtol = atol = {ref["rtol"]:g}. <b>Divergence</b>: a run stops at the first macro step with a non-finite value,
|g<sub>c</sub>| &gt; {div["max_constraint"]:g} m, |λ<sub>c</sub>| &gt; {div["max_multiplier"]:g} N or
|ω| &gt; {div["max_rate"]:g} rad/s; its dataset ends at the step before (attributes status = diverged,
diverged = 1, t_diverged, reason). A step that cannot be computed ends the run likewise with status = failed
(failed = 1, t_failed, reason). The finite-difference batch shares one Radau step sequence while the corrector
integrates alone; the two sequences coincide whenever a macro step is a single Radau step (attribute n_split counts
the integrations where they may not: then linearisation and corrector differ by O(rtol)).</p>
<p><b>Link to Sect. 3.</b> The paper explains the instability of the weighted multiplier at k = 2 by the stability
plot of the linear test model near the origin, at λ̄<sub>r1</sub> = −dH/(2m). Column ρ<sub>test</sub> below is the
spectral radius of the test model (Eq. 71) with the method's dimensionless parameters (β̄ = β/H, γ̄ = γ/H²) at
λ̄<sub>r1</sub> = {", ".join(f"{v:.3g}" for v in sorted(set(lr1)))} and λ̄<sub>i1</sub> = H·ω =
{", ".join(f"{v:.3g}" for v in li1)} for the modal frequencies ω of the pendulum linearised about its hanging rest,
with {escape(summary.attrs["test_model_ratios"])} (the larger ρ of the points is shown): ρ &gt; 1 predicts an
instability growing by the factor ρ per macro step.</p>
<p><b>Decompositions.</b> ff: both links force-driven by λ<sub>c</sub> (2 unknowns, the joint constraint on the
method's levels). fd: link 1 force-driven by λ<sub>c</sub>, link 2 kinematically driven on acceleration level by
the joint acceleration ã (2D, multipliers μ<sub>2</sub>); 4 unknowns, conditions: constraint (2) and
μ<sub>2</sub> − λ<sub>c</sub> = 0 (2). <b>dd (our formulation)</b>: link 1 has one degree of freedom, its joint point
moves on a circle and the normal component of its acceleration, −l<sub>1</sub>ω<sub>1</sub>², is fixed by its state.
Link 1 therefore follows only the tangential component of ã through one rheonomic constraint
n<sub>1</sub>·(P<sub>1</sub>'' − ã) = 0 with one multiplier μ<sub>1</sub> (tangential joint force; the normal
joint force is carried by its ground pin); link 2 follows all of ã. Unknowns ã (2); conditions (2): the tangential
force balance n<sub>1</sub>·μ<sub>2</sub> − μ<sub>1</sub> = 0 and the normal kinematic compatibility
e<sub>1</sub>·(P<sub>1</sub>'' − P<sub>2</sub>'') = 0, i.e. e<sub>1</sub>·ã = −l<sub>1</sub>ω<sub>1</sub>² (the
acceleration-level joint constraint in the direction link 1 cannot be driven in). λ<sub>c</sub> reported for dd is
μ<sub>2</sub>. <b>Projection</b>: mass-weighted (M = diag(J<sub>O1</sub>, m<sub>2</sub>, m<sub>2</sub>, J<sub>2</sub>)
for q = (φ1, x<sub>S2</sub>, y<sub>S2</sub>, φ2)) projection of the positions onto g<sub>c</sub> = 0 (Gauss-Newton on
the KKT conditions) and of the velocities onto ġ<sub>c</sub> = 0, the generalisation of Eq. (30).</p>
"""

    claim_html = ["<h3>The paper's claim</h3>" + claims_table(claims, part="pendulum")]
    for claim in claims:
        claim_html.append(f"<p>Claim <b>{escape(claim['id'])}</b>, run by run:</p>")
        rows = [
            key
            + [
                str(r[f"expected_{claim['id']}"].values),
                str(r["observed"].values),
                verdict_badge(str(r[f"verdict_{claim['id']}"].values)),
                fmt(float(r["rho_test_model"]), ".6f"),
                fmt(float(r["t_diverged"]), ".3f"),
                fmt(float(r["t_failed"]), ".3f"),
                "" if str(r["reason"].values) == "none" else str(r["reason"].values),
            ]
            for key, r in summary_rows
        ]
        claim_html.append(
            table(
                [
                    "method",
                    "decomposition",
                    "k",
                    "expected",
                    "observed",
                    "verdict",
                    "ρ_test (Sect. 3)",
                    "t_diverged [s]",
                    "t_failed [s]",
                    "reason",
                ],
                rows,
                raw_columns=(5,),
            )
        )

    err_rows = [
        key
        + [
            fmt(float(r[name]), spec)
            for name, spec in (
                ("t_last", ".3f"),
                ("err_phi1", ".2e"),
                ("err_phi2", ".2e"),
                ("err_lambda", ".2e"),
                ("max_g", ".2e"),
                ("max_g_corrector", ".2e"),
                ("wall_time_s", ".1f"),
            )
        ]
        for key, r in summary_rows
    ]
    errors = (
        "<p>Errors against the monolithic reference, maxima over the computed part of each run (up to t_end or to the "
        "last step before divergence or failure); max |g<sub>c</sub>| of the stored states and after the corrector (before projection).</p>"
        + table(
            [
                "method",
                "dec.",
                "k",
                "t_last [s]",
                "max|Δφ1| [rad]",
                "max|Δφ2| [rad]",
                "max|Δλ_c| [N]",
                "max|g_c| [m]",
                "max|g_c| corrector [m]",
                "wall [s]",
            ],
            err_rows,
        )
    )

    figs = []
    for path in figure_pngs:
        k = int(path.rsplit("_k", 1)[1].split("_")[0])  # pendulum_k<k>_<scheme>.png
        figs.append(
            figure(
                path,
                f"Fig. {paper_figure.get(k, '–')} of the paper (k = {k}): φ1, φ2, g<sub>cax</sub>, g<sub>cay</sub>, λ<sub>cax</sub>, λ<sub>cay</sub> over t; grey: monolithic reference.",
                alt=f"pendulum k={k}",
                anchor=figure_anchor("pendulum", path),
                paper_figures=[str(paper_figure[k])] if k in paper_figure else [],
                claims_html=used_by(
                    "pendulum", [c["id"] for c in claims if str(paper_figure.get(k)) in map(str, c["figures"])]
                ),
            )
        )
    figs.append(
        figure(
            error_png,
            "Error of φ1 and φ2 against the monolithic reference (log scale), one column per k.",
            anchor=figure_anchor("pendulum", error_png),
        )
    )

    return section(
        "Double pendulum (Sect. 4, Figs. 6–8)",
        setup + "".join(claim_html) + errors + "".join(figs) + schemes_html + trade_html,
        "pendulum",
    )
