# Convergence plots, paper Figs. 21-23 (Sect. 3.7): one job per panel (figure x decomposition x
# column) writing results/convergence/<dec>/fig<figure>_<panel>.nc, one plot job per figure and
# decomposition, the work-precision timing and diagram, the paper's order claims checked
# against the datasets, and the convergence section of the report.  A figure computed with a
# Gauss-Seidel scheme (its `schemes:` list) has the figure id <figure>gs12 or <figure>gs21
# (icosim.engine.schemes.figure_id); its claims and report section are in gauss_seidel.smk.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.convergence.config import (
    check_claims_against_config,
    study_from_config,
)  # noqa: E402
from icosim.convergence.panels import figure_layout, figure_panels  # noqa: E402
from icosim.convergence.work_precision import resolve_scheme  # noqa: E402
from icosim.engine.schemes import FIGURE_ID_PATTERN, figure_id  # noqa: E402

validate_part(config["convergence"], "convergence.schema.yaml")

CONVERGENCE = config["convergence"]
# Model, initial conditions, end time and step sizes are checked here (H_min >= H_max, H_max
# beyond the end time, x0 = v0 = 0, ...): a bad value fails before any job, naming its key.
study_from_config(CONVERGENCE)
CONV_SETUP = {
    **CONVERGENCE["model"],
    **CONVERGENCE["initial_conditions"],
    "end_time": CONVERGENCE["end_time"],
    "growth_bound": CONVERGENCE["unstable"]["growth_bound"],
}

# figure id -> (paper figure, scheme name): one workflow figure per configured scheme
CONV_FIGURE_IDS = {
    figure_id(fig, scheme): (str(fig), scheme)
    for fig, fig_cfg in CONVERGENCE["figures"].items()
    for scheme in fig_cfg.get("schemes", ["jacobi"])
}
# (decomposition, figure id, panel) -> icosim.convergence.panels.PanelSpec.  Built here so that a
# parameter a method does not take fails before any job runs, naming the figure.
CONV_PANELS = {
    (spec.decomposition, spec.figure, spec.panel): spec
    for fid, (fig, scheme) in CONV_FIGURE_IDS.items()
    for spec in figure_panels(
        fig, CONVERGENCE["figures"][fig], CONVERGENCE["k"], scheme
    )
}
CONV_WP_ENTRIES = [
    entry
    for scheme in CONVERGENCE["work_precision"]["schemes"]
    for entry in resolve_scheme(scheme, CONVERGENCE["figures"], CONVERGENCE["k"])
]
# A malformed claims file, or a claim that selects no configured curve, fails here, naming
# the claim id and key (not in the claims job after every panel has run).
CONV_CLAIMS_FILE = CONVERGENCE["claims"]["file"]
check_claims_against_config(load_claims(CONV_CLAIMS_FILE), CONVERGENCE)


CONV_PANEL_FILE = (
    "results/convergence/{}/fig{}_{}.nc"  # decomposition, figure id, panel
)
# the paper's (Jacobi) figures: their claims, work-precision and report section
CONV_ALL_PANELS = [
    CONV_PANEL_FILE.format(*key)
    for key in CONV_PANELS
    if CONV_FIGURE_IDS[key[1]][1] == "jacobi"
]
# (decomposition, figure id) -> the panel files one figure is drawn from
CONV_FIGURE_PANELS = {
    key[:2]: [CONV_PANEL_FILE.format(*k) for k in CONV_PANELS if k[:2] == key[:2]]
    for key in CONV_PANELS
}
CONV_FIGURES = sorted(
    {
        f"results/convergence/figures/fig{fid}_{dec}.png"
        for dec, fid, _ in CONV_PANELS
        if CONV_FIGURE_IDS[fid][1] == "jacobi"
    }
)
CONV_WP = "results/convergence/work_precision.nc"
CONV_WP_FIGURE = "results/convergence/figures/work_precision.png"
CONV_CLAIMS = "results/convergence/claims.json"
CONV_SECTION = "results/report/convergence.html"


rule convergence_panel:
    """NRMSE of Eq. (72) over H for every row (index) and k of one figure column."""
    input:
        lib=engine_lib("convergence_panel"),
    output:
        "results/convergence/{dec}/fig{figure}_{panel}.nc",
    log:
        "logs/convergence/panel/{dec}_fig{figure}_{panel}.log",
    wildcard_constraints:
        dec="ff|fd|dd",
        figure=FIGURE_ID_PATTERN,
    conda:
        "../envs/icosim.yaml"
    params:
        # exactly this panel's parameters: editing another panel does not rerun this one
        panel=lambda w: CONV_PANELS[(w.dec, w.figure, w.panel)].as_dict(),
        setup=CONV_SETUP,
        step_sizes=CONVERGENCE["step_sizes"],
        stepping=CONVERGENCE["stepping"],
        startup_steps=CONVERGENCE["startup_steps"],
        spectral_policy=CONVERGENCE["unstable"]["spectral_policy"],
        digits=CONVERGENCE["unstable"]["digits"],
        fit=CONVERGENCE["fit"],
    script:
        "../scripts/convergence_panel.py"


rule convergence_figure:
    """One convergence figure (rows = index, columns = parameter set) for one decomposition."""
    input:
        panels=lambda w: CONV_FIGURE_PANELS[(w.dec, w.figure)],
        lib=script_lib("convergence_figure"),
    output:
        png=report(
            "results/convergence/figures/fig{figure}_{dec}.png",
            caption="../report/convergence_figure.rst",
            category="Convergence (Figs. 21-23)",
            subcategory="Fig. {figure}",
            labels={"figure": "{figure}", "decomposition": "{dec}"},
        ),
        pdf="results/convergence/figures/fig{figure}_{dec}.pdf",
        slopes_png="results/convergence/figures/fig{figure}_{dec}_slopes.png",
        slopes_pdf="results/convergence/figures/fig{figure}_{dec}_slopes.pdf",
    log:
        "logs/convergence/figure/fig{figure}_{dec}.log",
    wildcard_constraints:
        dec="ff|fd|dd",
        figure=FIGURE_ID_PATTERN,
    conda:
        "../envs/icosim.yaml"
    params:
        title=lambda w: figure_title(
            w.figure, CONV_FIGURE_IDS, CONVERGENCE["figures"], f" ({w.dec})"
        ),
        layout=lambda w: figure_layout(
            CONV_FIGURE_IDS[w.figure][0],
            CONVERGENCE["figures"][CONV_FIGURE_IDS[w.figure][0]],
            w.dec,
            CONVERGENCE["k"],
        ),
        columns=lambda w: CONVERGENCE["figures"][CONV_FIGURE_IDS[w.figure][0]][
            "columns"
        ],
        guide_orders=CONVERGENCE["plot"]["guide_orders"],
        tolerance=CONVERGENCE["fit"]["tolerance"],
        dpi=CONVERGENCE["plot"]["dpi"],
    script:
        "../scripts/convergence_figure.py"


rule convergence_work_precision:
    """CPU time of the engine's co-simulation stepping per simulated second, per scheme and H."""
    input:
        panels=sorted(
            {
                CONV_PANEL_FILE.format(e["decomposition"], e["figure"], e["panel"])
                for e in CONV_WP_ENTRIES
            }
        ),
        lib=engine_lib("convergence_work_precision"),
    output:
        CONV_WP,
    log:
        "logs/convergence/work_precision.log",
    conda:
        "../envs/icosim.yaml"
    params:
        entries=CONV_WP_ENTRIES,
        setup=CONV_SETUP,
        steps=CONVERGENCE["work_precision"]["steps"],
        repeats=CONVERGENCE["work_precision"]["repeats"],
        warmup_steps=CONVERGENCE["work_precision"]["warmup_steps"],
    script:
        "../scripts/convergence_work_precision.py"


rule convergence_work_precision_figure:
    """Work-precision diagram: log-log CPU time per simulated second over NRMSE."""
    input:
        wp=CONV_WP,
        lib=script_lib("convergence_work_precision_figure"),
    output:
        png=report(
            CONV_WP_FIGURE,
            caption="../report/convergence_work_precision.rst",
            category="Convergence (Figs. 21-23)",
            subcategory="Work-precision",
        ),
        pdf=CONV_WP_FIGURE.replace(".png", ".pdf"),
    log:
        "logs/convergence/work_precision_figure.log",
    conda:
        "../envs/icosim.yaml"
    params:
        dpi=CONVERGENCE["plot"]["dpi"],
    script:
        "../scripts/convergence_work_precision_figure.py"


rule convergence_claims:
    """The paper's order claims (config/claims/convergence.yaml) evaluated on the datasets."""
    input:
        datasets=CONV_ALL_PANELS,
        claims=CONV_CLAIMS_FILE,
        lib=script_lib("claims"),
    output:
        json=CONV_CLAIMS,
        tsv="results/convergence/claims.tsv",
    log:
        "logs/convergence/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        enforce_reference=CONVERGENCE["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


rule convergence_report_section:
    """HTML fragment of the report: decisions, figures, claims table, work-precision."""
    input:
        figures=CONV_FIGURES,
        slopes=[f.replace(".png", "_slopes.png") for f in CONV_FIGURES],
        wp_figure=CONV_WP_FIGURE,
        wp=CONV_WP,
        claims=CONV_CLAIMS,
        panels=CONV_ALL_PANELS,
        lib=script_lib("convergence_report_section"),
    output:
        CONV_SECTION,
    log:
        "logs/convergence/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        setup=CONV_SETUP,
        step_sizes=CONVERGENCE["step_sizes"],
        stepping=CONVERGENCE["stepping"],
        startup_steps=CONVERGENCE["startup_steps"],
        fit=CONVERGENCE["fit"],
        unstable=CONVERGENCE["unstable"],
        targets=CONVERGENCE["work_precision"]["targets"],
        figures=CONVERGENCE["figures"],
    script:
        "../scripts/convergence_report_section.py"


ALL_TARGETS.extend(CONV_FIGURES + [CONV_WP_FIGURE, CONV_CLAIMS])
REPORT_SECTIONS["convergence"] = CONV_SECTION
