# Stability plots, paper Figs. 9-20 (and the project's own figures): the spectral radius over the
# (lr1, li1) plane, one panel per (scheme, row, k, view).  One job per figure computes every panel of
# it (imports and start-up are paid once per figure, not per panel) and writes one dataset per panel,
# results/stability/fig<figure>/<scheme>/r<row>_k<k>_<view>.nc; one job per figure draws it for
# every scheme; the claims (the paper's and the project's) are checked in one job; the scheme
# comparison and the report section follow.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.studies.stability.checks import PANEL_VARIABLES  # noqa: E402
from icosim.studies.stability.panels import figure_panels, panel_id  # noqa: E402

validate_part(config["stability"], "stability.schema.yaml")

STABILITY = config["stability"]
# figure ids are names ("9"), also if written unquoted in the YAML
STABILITY["figures"] = {str(fig): cfg for fig, cfg in STABILITY["figures"].items()}
STABILITY_PANEL = "results/stability/fig{figure}/{scheme}/{panel}.nc"
STABILITY_PLOT = "results/stability/figures/fig{figure}_{scheme}.{ext}"

# figure -> its panels (icosim.studies.stability.panels.PanelSpec), every scheme.  Built here so that a
# parameter a method does not take fails before any job runs, naming the figure and row.
STABILITY_PANELS = {
    fig: figure_panels(
        fig,
        cfg,
        grid=STABILITY["grid"],
        zoom_grid=STABILITY["zoom_grid"],
        precision=STABILITY["precision"],
    )
    for fig, cfg in STABILITY["figures"].items()
}


# figure -> its panel files, in the order of STABILITY_PANELS[figure]
STABILITY_FILES = {
    fig: [
        STABILITY_PANEL.format(
            figure=s.figure, scheme=s.scheme, panel=panel_id(s.row, s.k, s.view)
        )
        for s in specs
    ]
    for fig, specs in STABILITY_PANELS.items()
}
# figure -> the schemes it is drawn with, in the order configured
STABILITY_SCHEMES = {
    fig: list(dict.fromkeys(s.scheme for s in specs))
    for fig, specs in STABILITY_PANELS.items()
}
STABILITY_ALL_PANELS = [path for files in STABILITY_FILES.values() for path in files]
STABILITY_FIGURES = {
    fig: [
        STABILITY_PLOT.format(figure=fig, scheme=scheme, ext=ext)
        for scheme in STABILITY_SCHEMES[fig]
        for ext in ("png", "pdf")
    ]
    for fig in STABILITY["figures"]
}
# A malformed claim (unknown key, check parameter, op, relation, ...) fails here, naming the claim
# and the key.  A claim about a figure left out of the configuration is no error: it is reported
# undecided (no data).
STABILITY_CLAIMS_FILE = STABILITY["claims"]["file"]
load_claims(STABILITY_CLAIMS_FILE)
STABILITY_CLAIMS = "results/stability/claims.json"
# the comparison of schemes: figures computed with more than one scheme
STABILITY_COMPARED = [fig for fig in STABILITY["figures"] if len(STABILITY_SCHEMES[fig]) > 1]
STABILITY_SHARES = "results/stability/scheme_shares.nc"
STABILITY_COMPARISON = "results/stability/figures/scheme_comparison.{ext}"
STABILITY_SECTION = "results/report/stability.html"


for _fig in STABILITY["figures"]:

    rule:
        name:
            f"stability_panels_fig{_fig}"
        output:
            STABILITY_FILES[_fig],
        log:
            f"logs/stability/panels/fig{_fig}.log",
        conda:
            "../envs/icosim.yaml"
        params:
            library=engine_library("stability_panels"),
            # exactly this figure's panels: editing another figure does not rerun this one
            panels=[spec.as_dict() for spec in STABILITY_PANELS[_fig]],
        priority: 5  # the panels (seconds each) before the figures: the run ends on short jobs
        script:
            "../scripts/stability_panels.py"

    rule:
        name:
            f"stability_figure_fig{_fig}"
        input:
            panels=STABILITY_FILES[_fig],
        output:
            STABILITY_FIGURES[_fig],
        log:
            f"logs/stability/figure/fig{_fig}.log",
        conda:
            "../envs/icosim.yaml"
        params:
            library=script_library("stability_figure"),
            titles={
                scheme: figure_title(_fig, scheme, STABILITY["figures"][_fig]["title"])
                for scheme in STABILITY_SCHEMES[_fig]
            },
            style=STABILITY["plot"]["style"],
            rho_max=STABILITY["plot"]["rho_max"],
            dots_stride=STABILITY["plot"]["dots_stride"],
            dpi=STABILITY["plot"]["dpi"],
        script:
            "../scripts/stability_figure.py"


rule stability_scheme_shares:
    """Stable share per figure, row, k and scheme, from the full panels of the figures with several schemes."""
    input:
        panels=[
            path
            for fig in STABILITY_COMPARED
            for s, path in zip(STABILITY_PANELS[fig], STABILITY_FILES[fig])
            if s.view == "full"
        ],
    output:
        STABILITY_SHARES,
    log:
        "logs/stability/scheme_shares.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("stability_scheme_shares"),
    script:
        "../scripts/stability_scheme_shares.py"


rule stability_scheme_figure:
    """The schemes side by side: stable shares per (method, decomposition, k)."""
    input:
        shares=STABILITY_SHARES,
    output:
        png=report(
            STABILITY_COMPARISON.format(ext="png"),
            caption="../report/scheme_comparison.rst",
            category="Stability (Figs. 9-20)",
            subcategory="Coupling schemes",
        ),
        pdf=STABILITY_COMPARISON.format(ext="pdf"),
    log:
        "logs/stability/scheme_figure.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("stability_scheme_figure"),
        title="Stable shares of the coupling schemes",
        dpi=STABILITY["plot"]["dpi"],
    script:
        "../scripts/stability_scheme_figure.py"


rule stability_claims:
    """The stability claims (config/claims/stability.yaml: the paper's and the project's) on the panels."""
    input:
        datasets=STABILITY_ALL_PANELS,
        claims=STABILITY_CLAIMS_FILE,
    output:
        json=STABILITY_CLAIMS,
        tsv=report(
            "results/stability/claims.tsv",
            caption="../report/stability_claims.rst",
            category="Stability (Figs. 9-20)",
            subcategory="Claims",
            labels={"table": "claims of Sects. 3.1-3.6 and 5, and beyond the paper"},
        ),
    log:
        "logs/stability/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("claims"),
        enforce_reference=STABILITY["claims"]["enforce_reference"],
        # the variables the stability checks read: the claims job reads no others
        variables=list(PANEL_VARIABLES),
    script:
        "../scripts/claims.py"


STABILITY_COMPARISON_INPUTS = (
    dict(
        shares=STABILITY_SHARES,
        comparison=STABILITY_COMPARISON.format(ext="png"),
    )
    if STABILITY_COMPARED
    else {}
)


rule stability_report_section:
    """HTML fragment of the report: decisions, precision and timing, claims, figures, the schemes compared."""
    input:
        **STABILITY_COMPARISON_INPUTS,
        figures=[f for files in STABILITY_FIGURES.values() for f in files if f.endswith(".png")],
        panels=STABILITY_ALL_PANELS,
        claims=STABILITY_CLAIMS,
    output:
        STABILITY_SECTION,
    log:
        "logs/stability/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("stability_report_section"),
        figures=STABILITY["figures"],
        grid=STABILITY["grid"],
        zoom_grid=STABILITY["zoom_grid"],
        precision=STABILITY["precision"],
        style=STABILITY["plot"]["style"],
        decisions=STABILITY.get("decisions", []),
    script:
        "../scripts/stability_report_section.py"


# every panel dataset is a target too: a missing one is built again, and what is built from it after it
ALL_TARGETS.extend(
    STABILITY_ALL_PANELS
    + [f for files in STABILITY_FIGURES.values() for f in files]
    + [STABILITY_CLAIMS]
)
if STABILITY_COMPARED:
    ALL_TARGETS.extend(STABILITY_COMPARISON.format(ext=e) for e in ("png", "pdf"))
REPORT_SECTIONS["stability"] = STABILITY_SECTION
