# Gauss-Seidel (sequential) coupling next to the paper's Jacobi scheme (docs/gauss_seidel.md).
# The Gauss-Seidel figures, curves and runs are computed by the parts' own rules (figure ids
# <N>gs12 / <N>gs21, run names ..._gs12 / ..._gs21); here: the comparison of stable shares,
# the claims about the schemes (config/claims/*_gauss_seidel.yaml, same mechanism as the
# paper's) and the Gauss-Seidel section of the report.
from icosim.engine.schemes import SCHEMES  # noqa: E402

# -- stability ------------------------------------------------------------------------------------
# full panels of every figure that has a Gauss-Seidel scheme (all its schemes, Jacobi included)
GS_STABILITY_FIGURES = sorted(
    {fig for fid, (fig, scheme) in STABILITY_FIGURE_IDS.items() if scheme != "jacobi"},
    key=int,
)
GS_STABILITY_PANELS = [
    f"results/stability/fig{fid}/{pid}.nc"
    for (fid, pid), spec in STABILITY_PANELS.items()
    if STABILITY_FIGURE_IDS[fid][0] in GS_STABILITY_FIGURES
]
GS_STABILITY_FIGURE_FILES = [
    f"results/stability/figures/fig{fid}.png"
    for fid, (fig, scheme) in STABILITY_FIGURE_IDS.items()
    if scheme != "jacobi"
]
GS_STABILITY_SHARES = "results/stability/scheme_shares.nc"
GS_STABILITY_COMPARISON = "results/stability/figures/scheme_comparison.png"
GS_STABILITY_CLAIMS_FILE = STABILITY["claims"].get("gauss_seidel_file")
GS_STABILITY_CLAIMS = "results/stability/claims_gauss_seidel.json"
if GS_STABILITY_CLAIMS_FILE:
    load_claims(GS_STABILITY_CLAIMS_FILE)  # a malformed claim fails before any job runs


rule stability_scheme_shares:
    """Stable share per figure, row, k and scheme, from the full panels."""
    input:
        panels=[p for p in GS_STABILITY_PANELS if p.endswith("_full.nc")],
        lib=script_lib("stability_scheme_shares"),
    output:
        GS_STABILITY_SHARES,
    log:
        "logs/stability/scheme_shares.log",
    conda:
        "../envs/icosim.yaml"
    script:
        "../scripts/stability_scheme_shares.py"


rule stability_scheme_figure:
    """Jacobi against Gauss-Seidel: stable shares per (method, decomposition, k)."""
    input:
        shares=GS_STABILITY_SHARES,
        lib=script_lib("stability_scheme_figure"),
    output:
        png=report(
            GS_STABILITY_COMPARISON,
            caption="../report/scheme_comparison.rst",
            category="Gauss-Seidel",
            subcategory="Stability",
        ),
        pdf=GS_STABILITY_COMPARISON.replace(".png", ".pdf"),
    log:
        "logs/stability/scheme_figure.log",
    conda:
        "../envs/icosim.yaml"
    params:
        title="Stable shares, Jacobi and Gauss-Seidel (Figs. 9-15)",
        dpi=STABILITY["plot"]["dpi"],
    script:
        "../scripts/stability_scheme_figure.py"


rule stability_gauss_seidel_claims:
    """Claims about the Gauss-Seidel schemes (config/claims/stability_gauss_seidel.yaml) on the panels."""
    input:
        datasets=GS_STABILITY_PANELS,
        claims=GS_STABILITY_CLAIMS_FILE or [],
        lib=script_lib("claims"),
    output:
        json=GS_STABILITY_CLAIMS,
        tsv="results/stability/claims_gauss_seidel.tsv",
    log:
        "logs/stability/claims_gauss_seidel.log",
    conda:
        "../envs/icosim.yaml"
    params:
        enforce_reference=STABILITY["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


# -- convergence ------------------------------------------------------------------------------
GS_CONV_PANELS = [
    CONV_PANEL_FILE.format(*key)
    for key in CONV_PANELS
    if any(
        s != "jacobi"
        for f, s in CONV_FIGURE_IDS.values()
        if f == CONV_FIGURE_IDS[key[1]][0]
    )
]
GS_CONV_FIGURES = sorted(
    {
        f"results/convergence/figures/fig{fid}_{dec}.png"
        for dec, fid, _ in CONV_PANELS
        if CONV_FIGURE_IDS[fid][1] != "jacobi"
    }
)
GS_CONV_CLAIMS_FILE = CONVERGENCE["claims"].get("gauss_seidel_file")
GS_CONV_CLAIMS = "results/convergence/claims_gauss_seidel.json"
if GS_CONV_CLAIMS_FILE:
    # a malformed claim fails here
    GS_CONV_CLAIM_LIST = load_claims(GS_CONV_CLAIMS_FILE)
    if GS_CONV_FIGURES:  # the claims select Gauss-Seidel curves: only if there are any
        check_claims_against_config(GS_CONV_CLAIM_LIST, CONVERGENCE)


rule convergence_gauss_seidel_claims:
    """Claims about the Gauss-Seidel schemes (config/claims/convergence_gauss_seidel.yaml) on the panels."""
    input:
        datasets=GS_CONV_PANELS,
        claims=GS_CONV_CLAIMS_FILE or [],
        lib=script_lib("claims"),
    output:
        json=GS_CONV_CLAIMS,
        tsv="results/convergence/claims_gauss_seidel.tsv",
    log:
        "logs/convergence/claims_gauss_seidel.log",
    conda:
        "../envs/icosim.yaml"
    params:
        enforce_reference=CONVERGENCE["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


# -- pendulum ----------------------------------------------------------------------------------
from icosim.pendulum.config import configured_schemes  # noqa: E402

GS_SUFFIX_SCHEME = {SCHEMES[s].suffix: s for s in SCHEMES if s != "jacobi"}
GS_PENDULUM_SCHEMES = [s for s in configured_schemes(PENDULUM) if s != "jacobi"]
GS_PENDULUM_DATASETS = [
    f"results/pendulum/{run_name(*r, scheme)}.nc"
    for scheme in GS_PENDULUM_SCHEMES
    for r in PENDULUM_RUNS
]
GS_PENDULUM_SUMMARY = "results/pendulum/summary_gauss_seidel.nc"
GS_PENDULUM_CLAIMS_FILE = PENDULUM.get("gauss_seidel_claims")
GS_PENDULUM_CLAIMS = "results/pendulum/claims_gauss_seidel.json"
GS_PENDULUM_FIGURES = [
    f"results/pendulum/figures/pendulum_k{k}_{SCHEMES[s].suffix}.png"
    for s in GS_PENDULUM_SCHEMES
    for k in PENDULUM["k"]
]
if GS_PENDULUM_CLAIMS_FILE:
    load_claims(GS_PENDULUM_CLAIMS_FILE)  # a malformed claim fails before any job runs


rule pendulum_gs_run:
    """The Gauss-Seidel runs of one (method, decomposition, order), every k (as pendulum_run)."""
    input:
        lib=engine_lib("pendulum_run"),
        kernels=ancient(PENDULUM_KERNELS),
    output:
        expand("results/pendulum/{{method}}_{{decomposition}}_k{k}_{{gs}}.nc", k=PENDULUM["k"]),
    log:
        "logs/pendulum/{method}_{decomposition}_{gs}.log",
    wildcard_constraints:
        method=METHOD_NAMES,
        decomposition="ff|fd|dd",
        gs="gs12|gs21",
    conda:
        "../envs/icosim.yaml"
    params:
        k=PENDULUM["k"],
        model=PENDULUM["model"],
        H=PENDULUM["H"],
        t_end=PENDULUM["t_end"],
        method_params=lambda w: PENDULUM["methods"][w.method],
        integrator=PENDULUM["integrator"],
        sensitivities=PENDULUM["sensitivities"],
        corrector=PENDULUM["corrector"],
        divergence=PENDULUM["divergence"],
        scheme=lambda w: GS_SUFFIX_SCHEME[w.gs],
    script:
        "../scripts/pendulum_run.py"


rule pendulum_gs_summary:
    """Every run (Jacobi and Gauss-Seidel): errors, the Gauss-Seidel claims per run, the test model's rho."""
    input:
        runs=PENDULUM_DATASETS + GS_PENDULUM_DATASETS,
        reference=PENDULUM_REFERENCE,
        claims=GS_PENDULUM_CLAIMS_FILE or PENDULUM["claims"],
        lib=script_lib("pendulum_summary"),
    output:
        GS_PENDULUM_SUMMARY,
    log:
        "logs/pendulum/summary_gauss_seidel.log",
    conda:
        "../envs/icosim.yaml"
    params:
        model=PENDULUM["model"],
        H=PENDULUM["H"],
        methods=PENDULUM["methods"],
    script:
        "../scripts/pendulum_summary.py"


rule pendulum_gauss_seidel_claims:
    """Claims about the Gauss-Seidel runs (config/claims/pendulum_gauss_seidel.yaml) on their summary."""
    input:
        datasets=[GS_PENDULUM_SUMMARY],
        claims=GS_PENDULUM_CLAIMS_FILE or [],
        lib=script_lib("claims"),
    output:
        json=GS_PENDULUM_CLAIMS,
        tsv="results/pendulum/claims_gauss_seidel.tsv",
    log:
        "logs/pendulum/claims_gauss_seidel.log",
    conda:
        "../envs/icosim.yaml"
    params:
        enforce_reference=False,
    script:
        "../scripts/claims.py"


rule pendulum_gs_figure:
    """Figs. 6-8 with a Gauss-Seidel scheme: six panels over t, one line per configuration."""
    input:
        runs=lambda w: [
            f"results/pendulum/{run_name(*r, GS_SUFFIX_SCHEME[w.gs])}.nc"
            for r in PENDULUM_RUNS
            if r[2] == int(w.k)
        ],
        reference=PENDULUM_REFERENCE,
        lib=script_lib("pendulum_figure"),
    output:
        png="results/pendulum/figures/pendulum_k{k}_{gs}.png",
        pdf="results/pendulum/figures/pendulum_k{k}_{gs}.pdf",
    log:
        "logs/pendulum/figure_k{k}_{gs}.log",
    wildcard_constraints:
        k=r"\d+",
        gs="gs12|gs21",
    conda:
        "../envs/icosim.yaml"
    params:
        title=lambda w: (
            f"Fig. {PENDULUM_PAPER_FIGURE.get(int(w.k), '-')} (k = {w.k}), "
            f"{SCHEME_LABELS[GS_SUFFIX_SCHEME[w.gs]]}: double pendulum, H = {PENDULUM['H']:g} s"
        ),
        dpi=PENDULUM["plot"]["dpi"],
    script:
        "../scripts/pendulum_figure.py"


# -- the report section ------------------------------------------------------------------------
GS_HAS = {
    "stability": bool(GS_STABILITY_FIGURES),
    "convergence": bool(GS_CONV_FIGURES),
    "pendulum": bool(GS_PENDULUM_SCHEMES),
}
S, C, P = GS_HAS["stability"], GS_HAS["convergence"], GS_HAS["pendulum"]
# what the section is built from; a part without Gauss-Seidel results contributes nothing
GS_SECTION_INPUTS = dict(
    shares=[GS_STABILITY_SHARES] if S else [],
    comparison=[GS_STABILITY_COMPARISON] if S else [],
    stability_figures=GS_STABILITY_FIGURE_FILES if S else [],
    stability_claims=[GS_STABILITY_CLAIMS] if S and GS_STABILITY_CLAIMS_FILE else [],
    convergence_panels=GS_CONV_PANELS if C else [],
    convergence_figures=GS_CONV_FIGURES if C else [],
    convergence_claims=[GS_CONV_CLAIMS] if C and GS_CONV_CLAIMS_FILE else [],
    pendulum_summary=[GS_PENDULUM_SUMMARY] if P else [],
    pendulum_figures=GS_PENDULUM_FIGURES if P else [],
    pendulum_claims=[GS_PENDULUM_CLAIMS] if P and GS_PENDULUM_CLAIMS_FILE else [],
)
GS_SECTION = "results/report/gauss_seidel.html"


rule gauss_seidel_report_section:
    """HTML fragment of the report: Jacobi against Gauss-Seidel in stability, convergence and the pendulum."""
    input:
        **GS_SECTION_INPUTS,
        lib=script_lib("gauss_seidel_report_section"),
    output:
        GS_SECTION,
    log:
        "logs/report/gauss_seidel_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        stability_figures=STABILITY["figures"],
    script:
        "../scripts/gauss_seidel_report_section.py"


GS_TARGETS = [
    f for files in GS_SECTION_INPUTS.values() for f in files if not f.endswith(".nc")
]
GS_TARGETS += [GS_PENDULUM_SUMMARY] if P else []
ALL_TARGETS.extend(GS_TARGETS)
if any(GS_HAS.values()):
    REPORT_SECTIONS["gauss_seidel"] = GS_SECTION
