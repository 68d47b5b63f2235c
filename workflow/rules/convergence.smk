# Convergence plots, paper Figs. 21-23 (Sect. 3.7): the NRMSE of Eq. (72) over H.  A panel is one
# (scheme, decomposition, column) of a figure: results/convergence/fig<figure>/<scheme>/<dec>_<panel>.nc
# with every row (index) and k of the column.  One job per figure and scheme computes its panels (the
# jobs are long: they run first), one job per figure draws it for every decomposition and scheme; the
# work-precision timing and diagram, the claims of the part in one job, and the report section follow.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.studies.convergence.config import (  # noqa: E402
    check_claims_against_config,
    study_from_config,
)
from icosim.studies.convergence.panels import figure_layout, figure_panels  # noqa: E402
from icosim.studies.convergence.work_precision import resolve_configuration  # noqa: E402

validate_part(config["convergence"], "convergence.schema.yaml")

CONVERGENCE = config["convergence"]
CONVERGENCE["figures"] = {str(fig): cfg for fig, cfg in CONVERGENCE["figures"].items()}
# Model, initial conditions, end time and step sizes are checked here (H_min >= H_max, H_max
# beyond the end time, x0 = v0 = 0, ...): a bad value fails before any job, naming its key.
study_from_config(CONVERGENCE)
CONV_SETUP = {
    **CONVERGENCE["model"],
    **CONVERGENCE["initial_conditions"],
    "end_time": CONVERGENCE["end_time"],
    "growth_bound": CONVERGENCE["unstable"]["growth_bound"],
}
CONV_PANEL = "results/convergence/fig{figure}/{scheme}/{dec}_{panel}.nc"
CONV_PLOT = "results/convergence/figures/fig{figure}_{dec}_{scheme}{kind}.{ext}"

# (figure, scheme) -> its panels (icosim.studies.convergence.panels.PanelSpec).  Built here so that a
# parameter a method does not take fails before any job runs, naming the figure.
CONV_PANELS = {}
for _fig, _cfg in CONVERGENCE["figures"].items():
    for _spec in figure_panels(_fig, _cfg, CONVERGENCE["k"]):
        CONV_PANELS.setdefault((_fig, _spec.scheme), []).append(_spec)


CONV_FILES = {
    key: [
        CONV_PANEL.format(
            figure=s.figure, scheme=s.scheme, dec=s.decomposition, panel=s.panel
        )
        for s in specs
    ]
    for key, specs in CONV_PANELS.items()
}
CONV_ALL_PANELS = [path for files in CONV_FILES.values() for path in files]
# figure -> [(decomposition, scheme)] it is drawn for
CONV_DRAWN = {
    fig: list(
        dict.fromkeys(
            (s.decomposition, s.scheme)
            for (f, _), specs in CONV_PANELS.items()
            if f == fig
            for s in specs
        )
    )
    for fig in CONVERGENCE["figures"]
}
CONV_FIGURES = {
    fig: [
        CONV_PLOT.format(figure=fig, dec=dec, scheme=scheme, kind=kind, ext=ext)
        for dec, scheme in CONV_DRAWN[fig]
        for kind in ("", "_slopes")
        for ext in ("png", "pdf")
    ]
    for fig in CONVERGENCE["figures"]
}
CONV_WP_ENTRIES = [
    entry
    for configuration in CONVERGENCE["work_precision"]["configurations"]
    for entry in resolve_configuration(
        configuration, CONVERGENCE["figures"], CONVERGENCE["k"]
    )
]
# A malformed claims file, or a claim that selects no configured curve, fails here, naming
# the claim id and key (not in the claims job after every panel has run).
CONV_CLAIMS_FILE = CONVERGENCE["claims"]["file"]
check_claims_against_config(load_claims(CONV_CLAIMS_FILE), CONVERGENCE)
CONV_WP = "results/convergence/work_precision.nc"
CONV_WP_FIGURE = "results/convergence/figures/work_precision.png"
CONV_CLAIMS = "results/convergence/claims.json"
CONV_SECTION = "results/report/convergence.html"


for (_fig, _scheme), _specs in CONV_PANELS.items():

    rule:
        name:
            f"convergence_panels_fig{_fig}_{_scheme}"
        output:
            CONV_FILES[(_fig, _scheme)],
        log:
            f"logs/convergence/panels/fig{_fig}_{_scheme}.log",
        priority: 10  # the longest jobs of the workflow: start them first
        conda:
            "../envs/icosim.yaml"
        params:
            library=engine_library("convergence_panels"),
            # exactly this figure's panels with this scheme: editing another does not rerun these
            panels=[spec.as_dict() for spec in _specs],
            setup=CONV_SETUP,
            step_sizes=CONVERGENCE["step_sizes"],
            stepping=CONVERGENCE["stepping"],
            startup_steps=CONVERGENCE["startup_steps"],
            spectral_policy=CONVERGENCE["unstable"]["spectral_policy"],
            digits=CONVERGENCE["unstable"]["digits"],
            fit=CONVERGENCE["fit"],
        script:
            "../scripts/convergence_panels.py"


for _fig, _cfg in CONVERGENCE["figures"].items():

    rule:
        name:
            f"convergence_figure_fig{_fig}"
        input:
            panels=[
                path for (f, _), files in CONV_FILES.items() if f == _fig for path in files
            ],
        output:
            CONV_FIGURES[_fig],
        log:
            f"logs/convergence/figure/fig{_fig}.log",
        conda:
            "../envs/icosim.yaml"
        params:
            library=script_library("convergence_figure"),
            # per drawn (decomposition, scheme): title and where each cell's curves are stored
            drawn=[
                {
                    "decomposition": dec,
                    "scheme": scheme,
                    "title": figure_title(_fig, scheme, _cfg["title"], f" ({dec})"),
                    "layout": figure_layout(_fig, _cfg, dec, CONVERGENCE["k"]),
                }
                for dec, scheme in CONV_DRAWN[_fig]
            ],
            columns=_cfg["columns"],
            guide_orders=CONVERGENCE["plot"]["guide_orders"],
            tolerance=CONVERGENCE["fit"]["tolerance"],
            dpi=CONVERGENCE["plot"]["dpi"],
        script:
            "../scripts/convergence_figure.py"


rule convergence_work_precision:
    """CPU time of the engine's co-simulation stepping per simulated second, per configuration and H."""
    input:
        panels=sorted(
            {
                CONV_PANEL.format(
                    figure=e["figure"],
                    scheme=e["scheme"],
                    dec=e["decomposition"],
                    panel=e["panel"],
                )
                for e in CONV_WP_ENTRIES
            }
        ),
    output:
        CONV_WP,
    log:
        "logs/convergence/work_precision.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=engine_library("convergence_work_precision"),
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
        library=script_library("convergence_work_precision_figure"),
        dpi=CONVERGENCE["plot"]["dpi"],
    script:
        "../scripts/convergence_work_precision_figure.py"


rule convergence_claims:
    """The convergence claims (config/claims/convergence.yaml: the paper's and the project's) on the panels."""
    input:
        datasets=CONV_ALL_PANELS,
        claims=CONV_CLAIMS_FILE,
    output:
        json=CONV_CLAIMS,
        tsv="results/convergence/claims.tsv",
    log:
        "logs/convergence/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("claims"),
        enforce_reference=CONVERGENCE["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


rule convergence_report_section:
    """HTML fragment of the report: decisions, figures, claims table, work-precision, the schemes compared."""
    input:
        figures=[
            f
            for files in CONV_FIGURES.values()
            for f in files
            if f.endswith(".png") and not f.endswith("_slopes.png")
        ],
        slopes=[f for files in CONV_FIGURES.values() for f in files if f.endswith("_slopes.png")],
        wp_figure=CONV_WP_FIGURE,
        wp=CONV_WP,
        claims=CONV_CLAIMS,
        panels=CONV_ALL_PANELS,
    output:
        CONV_SECTION,
    log:
        "logs/convergence/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("convergence_report_section"),
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


# every panel dataset is a target too: a missing one is built again, and what is built from it after it
ALL_TARGETS.extend(
    CONV_ALL_PANELS
    + [f for files in CONV_FIGURES.values() for f in files]
    + [CONV_WP_FIGURE, CONV_CLAIMS]
)
REPORT_SECTIONS["convergence"] = CONV_SECTION
