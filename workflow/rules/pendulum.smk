# Double pendulum, paper Sect. 4 and Figs. 6-8: the monolithic reference, one co-simulation
# job per (method, decomposition) writing results/pendulum/<method>_<dec>_k<k>.nc per k, the
# errors and the claim of Sect. 4 in results/pendulum/summary.nc, one figure per k, and
# the pendulum section of the report.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.pendulum.config import (  # noqa: E402
    configured_runs,
    run_settings,
    study_methods,
    trade_plan,
)
from icosim.pendulum.names import TRADE_FIGURE_DATASETS, run_name  # noqa: E402

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
# numba's compiled integrator, compiled once before the runs: input of every rule that runs it, as
# ancient() (a recompiled cache changes no run, so it reruns none)
PENDULUM_KERNELS = "results/pendulum/kernels.json"
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


# -- speed-accuracy trade (beyond the paper): error over H, work-precision, stability limit in H,
# subsystem tolerance, adaptive macro steps.  One sweep job and one limit job per group
# (scheme, method, decomposition; every k), then merges; figures and the report section
# read only the datasets.
TRADE = PENDULUM["trade"]
# groups and configuration labels; bad schemes, end times off the H grid or invalid
# tolerance/adaptive configurations fail here, naming the key
TRADE_PLAN = trade_plan(PENDULUM)
TRADE_GROUPS = {"_".join(g): g for g in TRADE_PLAN["groups"]}
TRADE_DIR = "results/pendulum/trade"
PENDULUM_WORK_PRECISION = "results/pendulum/work_precision.nc"
PENDULUM_STABILITY_LIMIT = "results/pendulum/stability_limit.nc"
PENDULUM_ADAPTIVE = "results/pendulum/adaptive.nc"
PENDULUM_TOLERANCE = "results/pendulum/tolerance.nc"
TRADE_FIGURE_NAMES = list(TRADE_FIGURE_DATASETS)
TRADE_FIGURES = {
    name: f"results/pendulum/figures/{name}.png" for name in TRADE_FIGURE_NAMES
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


rule pendulum_kernels:
    """Compile the links' integrator (numba) into its disk cache, once: the runs load it from there,
    where runs starting together on a cold cache (a fresh clone) would each compile it (~10 CPU-s)."""
    input:
        lib=script_lib("pendulum_kernels"),
    output:
        PENDULUM_KERNELS,
    log:
        "logs/pendulum/kernels.log",
    conda:
        "../envs/icosim.yaml"
    script:
        "../scripts/pendulum_kernels.py"


rule pendulum_run:
    """The co-simulation runs of one (method, decomposition), every k (Jacobi), each up to t_end or
    divergence: one job, since the runs are short and a job's start-up (interpreter, imports, the
    compiled integrator) cost about as much as a CI-length run."""
    input:
        lib=engine_lib("pendulum_run"),
        kernels=ancient(PENDULUM_KERNELS),
    output:
        expand("results/pendulum/{{method}}_{{decomposition}}_k{k}.nc", k=PENDULUM["k"]),
    log:
        "logs/pendulum/{method}_{decomposition}.log",
    wildcard_constraints:
        method=METHOD_NAMES,
        decomposition="ff|fd|dd",
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
        work_precision=PENDULUM_WORK_PRECISION,
        stability_limit=PENDULUM_STABILITY_LIMIT,
        tolerance=PENDULUM_TOLERANCE,
        adaptive=PENDULUM_ADAPTIVE,
        trade_figures=list(TRADE_FIGURES.values()),
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


rule pendulum_sweep:
    """Error over H of one group (scheme, method, decomposition): every k and H over one end time."""
    input:
        lib=engine_lib("pendulum_sweep"),
        kernels=ancient(PENDULUM_KERNELS),
    output:
        f"{TRADE_DIR}/sweep/{{group}}.nc",
    log:
        "logs/pendulum/sweep_{group}.log",
    wildcard_constraints:
        group="|".join(TRADE_GROUPS),
    conda:
        "../envs/icosim.yaml"
    params:
        settings=lambda w: run_settings(PENDULUM, [TRADE_GROUPS[w.group][1]]),
        scheme=lambda w: TRADE_GROUPS[w.group][0],
        method=lambda w: TRADE_GROUPS[w.group][1],
        decomposition=lambda w: TRADE_GROUPS[w.group][2],
        k=PENDULUM["k"],
        H=TRADE["error_over_H"]["H"],
        t_end=TRADE["error_over_H"]["t_end"],
        integrator=TRADE["error_over_H"]["integrator"],
        timing=TRADE["error_over_H"]["timing"],
        reference=TRADE["reference"],
    script:
        "../scripts/pendulum_sweep.py"


rule pendulum_baselines:
    """Monolithic pendulum over tolerances (Radau IIA, DOP853) and the linear test model's errors."""
    input:
        lib=engine_lib("pendulum_baselines"),
    output:
        monolithic=f"{TRADE_DIR}/monolithic.nc",
        linear=f"{TRADE_DIR}/linear_orders.nc",
    log:
        "logs/pendulum/baselines.log",
    conda:
        "../envs/icosim.yaml"
    params:
        settings=run_settings(PENDULUM),
        configs=[list(c) for c in TRADE_PLAN["configs"]],
        H=TRADE["error_over_H"]["H"],
        t_end=TRADE["error_over_H"]["t_end"],
        monolithic=TRADE["monolithic"],
        linear_orders=TRADE["linear_orders"],
        reference=TRADE["reference"],
    script:
        "../scripts/pendulum_baselines.py"


rule pendulum_work_precision:
    """work_precision.nc: the sweep groups, orders (pendulum and linear model), monolithic baselines."""
    input:
        sweeps=expand(f"{TRADE_DIR}/sweep/{{group}}.nc", group=TRADE_GROUPS),
        monolithic=f"{TRADE_DIR}/monolithic.nc",
        linear=f"{TRADE_DIR}/linear_orders.nc",
        lib=script_lib("pendulum_work_precision"),
    output:
        PENDULUM_WORK_PRECISION,
    log:
        "logs/pendulum/work_precision.log",
    conda:
        "../envs/icosim.yaml"
    params:
        fit=TRADE["fit"],
        accuracy_levels=TRADE["accuracy_levels"],
    script:
        "../scripts/pendulum_work_precision.py"


rule pendulum_limits:
    """Largest stable H of one group: bisection on divergence, and the linear test model's prediction."""
    input:
        lib=engine_lib("pendulum_limits"),
        kernels=ancient(PENDULUM_KERNELS),
    output:
        f"{TRADE_DIR}/limits/{{group}}.nc",
    log:
        "logs/pendulum/limits_{group}.log",
    wildcard_constraints:
        group="|".join(TRADE_GROUPS),
    conda:
        "../envs/icosim.yaml"
    params:
        settings=lambda w: run_settings(PENDULUM, [TRADE_GROUPS[w.group][1]]),
        scheme=lambda w: TRADE_GROUPS[w.group][0],
        method=lambda w: TRADE_GROUPS[w.group][1],
        decomposition=lambda w: TRADE_GROUPS[w.group][2],
        k=PENDULUM["k"],
        limits=TRADE["stability_limit"],
    script:
        "../scripts/pendulum_limits.py"


rule pendulum_stability_limit:
    """stability_limit.nc: the groups' measured and predicted limits over config."""
    input:
        groups=expand(f"{TRADE_DIR}/limits/{{group}}.nc", group=TRADE_GROUPS),
        lib=script_lib("pendulum_stability_limit"),
    output:
        PENDULUM_STABILITY_LIMIT,
    log:
        "logs/pendulum/stability_limit.log",
    conda:
        "../envs/icosim.yaml"
    script:
        "../scripts/pendulum_stability_limit.py"


rule pendulum_tolerance:
    """Error over the links' Radau tolerance at fixed H for a few configurations."""
    input:
        lib=engine_lib("pendulum_tolerance"),
        kernels=ancient(PENDULUM_KERNELS),
    output:
        PENDULUM_TOLERANCE,
    log:
        "logs/pendulum/tolerance.log",
    conda:
        "../envs/icosim.yaml"
    params:
        settings=run_settings(PENDULUM, study_methods(PENDULUM, "tolerance")),
        tolerance=TRADE_PLAN["tolerance"],
        t_end=TRADE["error_over_H"]["t_end"],
        reference=TRADE["reference"],
    script:
        "../scripts/pendulum_tolerance.py"


rule pendulum_adaptive:
    """Adaptive macro steps (PI control of the predictor-corrector estimate) against fixed H."""
    input:
        lib=engine_lib("pendulum_adaptive"),
        kernels=ancient(PENDULUM_KERNELS),
    output:
        PENDULUM_ADAPTIVE,
    log:
        "logs/pendulum/adaptive.log",
    conda:
        "../envs/icosim.yaml"
    params:
        settings=run_settings(PENDULUM, study_methods(PENDULUM, "adaptive")),
        adaptive=TRADE_PLAN["adaptive"],
        reference=TRADE["reference"],
    script:
        "../scripts/pendulum_adaptive.py"


rule pendulum_trade_figure:
    """One figure of the trade (TRADE_FIGURES): work-precision, error over H, stability limit,
    tolerance or adaptive; each job starts as soon as the datasets it draws exist."""
    input:
        unpack(
            lambda w: {
                stem: f"results/pendulum/{stem}.nc"
                for stem in TRADE_FIGURE_DATASETS[w.name]
            }
        ),
        lib=script_lib("pendulum_trade_figure"),
    output:
        png=report(
            "results/pendulum/figures/{name}.png",
            caption="../report/pendulum_trade_figure.rst",
            category="Double pendulum: speed-accuracy trade",
            labels={"figure": "{name}"},
        ),
        pdf="results/pendulum/figures/{name}.pdf",
    log:
        "logs/pendulum/trade_figure_{name}.log",
    wildcard_constraints:
        name="|".join(TRADE_FIGURE_NAMES),
    conda:
        "../envs/icosim.yaml"
    params:
        dpi=PENDULUM["plot"]["dpi"],
    script:
        "../scripts/pendulum_trade_figure.py"


ALL_TARGETS.extend(
    PENDULUM_FIGURES
    + [PENDULUM_ERROR_FIGURE, PENDULUM_SUMMARY, PENDULUM_CLAIMS]
    + [
        PENDULUM_WORK_PRECISION,
        PENDULUM_STABILITY_LIMIT,
        PENDULUM_ADAPTIVE,
        PENDULUM_TOLERANCE,
    ]
    + list(TRADE_FIGURES.values())
)
REPORT_SECTIONS["pendulum"] = PENDULUM_SECTION
