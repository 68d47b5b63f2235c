# Stability plots, paper Figs. 9-20: one job per panel (figure x row x k x view) writing
# results/stability/fig<figure>/r<row>_k<k>_<view>.nc, one plot job per figure, the paper's
# claims checked against the datasets, and the stability section of the report.  A figure
# computed with another coupling scheme (its `schemes:` list) has the figure id <figure>gs12
# or <figure>gs21 (icosim.engine.schemes.figure_id); the Gauss-Seidel parts are in gauss_seidel.smk.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.engine.schemes import FIGURE_ID_PATTERN, figure_id  # noqa: E402
from icosim.stability.panels import figure_panels, panel_id  # noqa: E402

validate_part(config["stability"], "stability.schema.yaml")

STABILITY = config["stability"]
# figure numbers are names ("9"), also if written unquoted in the YAML
STABILITY["figures"] = {str(fig): cfg for fig, cfg in STABILITY["figures"].items()}

# figure id -> (paper figure, scheme name): one workflow figure per configured scheme
STABILITY_FIGURE_IDS = {
    figure_id(fig, scheme): (fig, scheme)
    for fig, fig_cfg in STABILITY["figures"].items()
    for scheme in fig_cfg.get("schemes", ["jacobi"])
}
# (figure id, panel id) -> icosim.stability.panels.PanelSpec, for every configured panel.  Built
# here so that a parameter a method does not take fails before any job runs, naming the figure/row.
STABILITY_PANELS = {
    (spec.figure, panel_id(spec.row, spec.k, spec.view)): spec
    for fid, (fig, scheme) in STABILITY_FIGURE_IDS.items()
    for spec in figure_panels(
        fig,
        STABILITY["figures"][fig],
        grid=STABILITY["grid"],
        zoom_grid=STABILITY["zoom_grid"],
        precision=STABILITY["precision"],
        scheme=scheme,
    )
}


# figure -> its panel files (a figure's plot job gathers exactly these)
# The claims file is read here, so a malformed claim (unknown key, check parameter, op,
# relation, ...) fails before any job runs, naming the claim and the key.  A claim about a
# figure left out of the configuration is no error: it is reported undecided (no data).
STABILITY_CLAIMS_FILE = STABILITY["claims"]["file"]
load_claims(STABILITY_CLAIMS_FILE)

STABILITY_PANEL_FILES = {fid: [] for fid in STABILITY_FIGURE_IDS}
for fid, pid in STABILITY_PANELS:
    STABILITY_PANEL_FILES[fid].append(f"results/stability/fig{fid}/{pid}.nc")

# the paper's (Jacobi) figures: their claims and report section
STABILITY_ALL_PANELS = [
    f"results/stability/fig{fid}/{pid}.nc"
    for (fid, pid) in STABILITY_PANELS
    if fid in STABILITY["figures"]
]
STABILITY_FIGURES = [
    f"results/stability/figures/fig{fig}.{ext}"
    for fig in STABILITY["figures"]
    if figure_id(fig) in STABILITY_FIGURE_IDS
    for ext in ("png", "pdf")
]
STABILITY_CLAIMS = "results/stability/claims.json"
STABILITY_SECTION = "results/report/stability.html"


rule stability_sweep:
    """Spectral radius over the (lr1, li1) grid of one panel (float64 + mp rechecks)."""
    input:
        lib=engine_lib("stability_sweep"),
    output:
        "results/stability/fig{figure}/{panel}.nc",
    log:
        "logs/stability/sweep/fig{figure}_{panel}.log",
    wildcard_constraints:
        figure=FIGURE_ID_PATTERN,
        panel=r"r\d+_k\d+_(full|zoom)",
    conda:
        "../envs/icosim.yaml"
    params:
        # exactly this panel's parameters: editing another panel does not rerun this one
        panel=lambda w: STABILITY_PANELS[(w.figure, w.panel)].as_dict(),
    script:
        "../scripts/stability_sweep.py"


rule stability_figure:
    """One figure of the paper (rows x k, plus zooms) from its panels; PNG and PDF."""
    input:
        panels=lambda w: STABILITY_PANEL_FILES[w.figure],
        lib=script_lib("stability_figure"),
    output:
        png=report(
            "results/stability/figures/fig{figure}.png",
            caption="../report/stability_figure.rst",
            category="Stability (Figs. 9-20)",
            subcategory="Fig. {figure}",
            labels={"figure": "{figure}", "format": "PNG"},
        ),
        pdf="results/stability/figures/fig{figure}.pdf",
    log:
        "logs/stability/figure/fig{figure}.log",
    wildcard_constraints:
        figure=FIGURE_ID_PATTERN,
    conda:
        "../envs/icosim.yaml"
    params:
        title=lambda w: figure_title(
            w.figure, STABILITY_FIGURE_IDS, STABILITY["figures"]
        ),
        style=STABILITY["plot"]["style"],
        rho_max=STABILITY["plot"]["rho_max"],
        dots_stride=STABILITY["plot"]["dots_stride"],
        dpi=STABILITY["plot"]["dpi"],
    script:
        "../scripts/stability_figure.py"


rule stability_claims:
    """The paper's stability claims (config/claims/stability.yaml) evaluated on the datasets."""
    input:
        datasets=STABILITY_ALL_PANELS,
        claims=STABILITY_CLAIMS_FILE,
        lib=script_lib("claims"),
    output:
        json=STABILITY_CLAIMS,
        tsv=report(
            "results/stability/claims.tsv",
            caption="../report/stability_claims.rst",
            category="Stability (Figs. 9-20)",
            subcategory="Claims",
            labels={"table": "claims of Sects. 3.1-3.6 and 5"},
        ),
    log:
        "logs/stability/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        enforce_reference=STABILITY["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


rule stability_report_section:
    """HTML fragment of the report: decisions, precision and timing, claims, figures."""
    input:
        figures=[f for f in STABILITY_FIGURES if f.endswith(".png")],
        panels=STABILITY_ALL_PANELS,
        claims=STABILITY_CLAIMS,
        lib=script_lib("stability_report_section"),
    output:
        STABILITY_SECTION,
    log:
        "logs/stability/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        figures=STABILITY["figures"],
        grid=STABILITY["grid"],
        zoom_grid=STABILITY["zoom_grid"],
        precision=STABILITY["precision"],
        style=STABILITY["plot"]["style"],
        decisions=STABILITY.get("decisions", []),
    script:
        "../scripts/stability_report_section.py"


ALL_TARGETS.extend(STABILITY_FIGURES + [STABILITY_CLAIMS])
REPORT_SECTIONS["stability"] = STABILITY_SECTION
