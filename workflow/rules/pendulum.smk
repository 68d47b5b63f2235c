# Double pendulum, paper Sect. 4 and Figs. 6-8: the monolithic reference, one co-simulation
# job per (method, decomposition, k) writing results/pendulum/<method>_<dec>_k<k>.nc, the
# errors and the claim of Sect. 4 in results/pendulum/summary.nc, one figure per k, and
# the pendulum section of the report.
from icosim.checks import load_claims  # noqa: E402
from icosim.pendulum.config import configured_runs  # noqa: E402
from icosim.pendulum.names import run_name  # noqa: E402

validate_part(config["pendulum"], "pendulum.schema.yaml")

PENDULUM = config["pendulum"]
# (method, decomposition, k) of every run; a method parameter it does not take, Baumgarte or
# the weighted multiplier with dd, or an end time off the macro grid fails here, naming it.
PENDULUM_RUNS = configured_runs(PENDULUM)
load_claims(PENDULUM["claims"])  # a malformed claims file fails before any job runs
PENDULUM_CLAIMS = "results/pendulum/claims.json"

PENDULUM_PAPER_FIGURE = {0: 6, 1: 7, 2: 8}  # Fig. 6-8 for k = 0, 1, 2
PENDULUM_DATASETS = [f"results/pendulum/{run_name(*r)}.nc" for r in PENDULUM_RUNS]
PENDULUM_REFERENCE = "results/pendulum/reference.nc"
PENDULUM_SUMMARY = "results/pendulum/summary.nc"
PENDULUM_FIGURES = [
    f"results/pendulum/figures/pendulum_k{k}.{ext}"
    for k in PENDULUM["k"]
    for ext in ("png", "pdf")
]
PENDULUM_ERROR_FIGURE = "results/pendulum/figures/pendulum_error.png"
PENDULUM_SECTION = "results/report/pendulum.html"
PENDULUM_DATASETS_OF_K = {
    int(k): [
        f"results/pendulum/{run_name(*r)}.nc" for r in PENDULUM_RUNS if r[2] == int(k)
    ]
    for k in PENDULUM["k"]
}


rule pendulum_reference:
    """Monolithic reference (minimal coordinates) on the macro-time grid."""
    input:
        lib=script_lib("pendulum_reference"),
    output:
        PENDULUM_REFERENCE,
    log:
        "logs/pendulum/reference.log",
    conda:
        "../envs/icosim.yaml"
    params:
        model=PENDULUM["model"],
        H=PENDULUM["H"],
        t_end=PENDULUM["t_end"],
        reference=PENDULUM["reference"],
    script:
        "../scripts/pendulum_reference.py"


rule pendulum_run:
    """One co-simulation run (method, decomposition, k; Jacobi) up to t_end or divergence."""
    input:
        lib=engine_lib("pendulum_run"),
    output:
        "results/pendulum/{method}_{decomposition}_k{k}.nc",
    log:
        "logs/pendulum/{method}_{decomposition}_k{k}.log",
    wildcard_constraints:
        method=METHOD_NAMES,
        decomposition="ff|fd|dd",
        k=r"\d+",
    conda:
        "../envs/icosim.yaml"
    params:
        model=PENDULUM["model"],
        H=PENDULUM["H"],
        t_end=PENDULUM["t_end"],
        method_params=lambda w: PENDULUM["methods"][w.method],
        integrator=PENDULUM["integrator"],
        sensitivities=PENDULUM["sensitivities"],
        corrector=PENDULUM["corrector"],
        divergence=PENDULUM["divergence"],
        scheme="jacobi",
    script:
        "../scripts/pendulum_run.py"


rule pendulum_summary:
    """Errors against the reference, the claim of Sect. 4 and the linear test model's rho, one row per run."""
    input:
        runs=PENDULUM_DATASETS,
        reference=PENDULUM_REFERENCE,
        claims=PENDULUM["claims"],
        lib=script_lib("pendulum_summary"),
    output:
        PENDULUM_SUMMARY,
    log:
        "logs/pendulum/summary.log",
    conda:
        "../envs/icosim.yaml"
    params:
        model=PENDULUM["model"],
        H=PENDULUM["H"],
        methods=PENDULUM["methods"],
    script:
        "../scripts/pendulum_summary.py"


rule pendulum_figure:
    """Fig. 6, 7 or 8 (k = 0, 1, 2): six panels over t, one line per configuration."""
    input:
        runs=lambda w: PENDULUM_DATASETS_OF_K[int(w.k)],
        reference=PENDULUM_REFERENCE,
        lib=script_lib("pendulum_figure"),
    output:
        png=report(
            "results/pendulum/figures/pendulum_k{k}.png",
            caption="../report/pendulum_figure.rst",
            category="Double pendulum (Figs. 6-8)",
            labels={"k": "{k}"},
        ),
        pdf="results/pendulum/figures/pendulum_k{k}.pdf",
    log:
        "logs/pendulum/figure_k{k}.log",
    wildcard_constraints:
        k=r"\d+",
    conda:
        "../envs/icosim.yaml"
    params:
        title=lambda w: (
            f"Fig. {PENDULUM_PAPER_FIGURE.get(int(w.k), '-')} (k = {w.k}): double pendulum, "
            f"H = {PENDULUM['H']:g} s"
        ),
        dpi=PENDULUM["plot"]["dpi"],
    script:
        "../scripts/pendulum_figure.py"


rule pendulum_error_figure:
    """|phi - phi_ref| of every run against the monolithic reference, one column per k."""
    input:
        runs=PENDULUM_DATASETS,
        reference=PENDULUM_REFERENCE,
        lib=script_lib("pendulum_error_figure"),
    output:
        PENDULUM_ERROR_FIGURE,
    log:
        "logs/pendulum/error_figure.log",
    conda:
        "../envs/icosim.yaml"
    params:
        dpi=PENDULUM["plot"]["dpi"],
    script:
        "../scripts/pendulum_error_figure.py"


rule pendulum_claims:
    """The claim of Sect. 4 (config/claims/pendulum.yaml) evaluated on the run summary."""
    input:
        datasets=[PENDULUM_SUMMARY],
        claims=PENDULUM["claims"],
        lib=script_lib("claims"),
    output:
        json=PENDULUM_CLAIMS,
        tsv="results/pendulum/claims.tsv",
    log:
        "logs/pendulum/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        # the pendulum's claim records no CI reference (config/pendulum.yaml has no enforce_reference)
        enforce_reference=False,
    script:
        "../scripts/claims.py"


rule pendulum_report_section:
    """HTML fragment of the report: set-up, dd formulation, claim verdicts, errors, figures."""
    input:
        figures=[f for f in PENDULUM_FIGURES if f.endswith(".png")],
        error_figure=PENDULUM_ERROR_FIGURE,
        summary=PENDULUM_SUMMARY,
        reference=PENDULUM_REFERENCE,
        claims=PENDULUM_CLAIMS,
        lib=script_lib("pendulum_report_section"),
    output:
        PENDULUM_SECTION,
    log:
        "logs/pendulum/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        config=PENDULUM,
        paper_figure=PENDULUM_PAPER_FIGURE,
    script:
        "../scripts/pendulum_report_section.py"


ALL_TARGETS.extend(
    PENDULUM_FIGURES + [PENDULUM_ERROR_FIGURE, PENDULUM_SUMMARY, PENDULUM_CLAIMS]
)
REPORT_SECTIONS["pendulum"] = PENDULUM_SECTION
