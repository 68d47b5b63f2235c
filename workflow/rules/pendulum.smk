# Double pendulum, paper Sect. 4 and Figs. 6-8: the monolithic reference, the co-simulation runs
# (one job per (method, decomposition) runs every scheme and k, writing
# results/pendulum/runs/<scheme>/<method>_<dec>_k<k>.nc), the errors of every run and the claims in
# results/pendulum/summary.nc, the figures (one job per scheme draws every k), and the pendulum
# section of the report.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.problems.pendulum.config import (  # noqa: E402
    configured_runs,
    configured_schemes,
    run_settings,
    study_methods,
    trade_plan,
)
from icosim.problems.pendulum.names import TRADE_FIGURE_DATASETS  # noqa: E402

validate_part(config["pendulum"], "pendulum.schema.yaml")

PENDULUM = config["pendulum"]
# (method, decomposition, k) of every run and the schemes each is run with; a method parameter it
# does not take, a decomposition without coupling conditions for the pendulum, or an end time off
# the macro grid fails here, naming it.
PENDULUM_RUNS = configured_runs(PENDULUM)
PENDULUM_SCHEMES = configured_schemes(PENDULUM)
PENDULUM_PAIRS = list(dict.fromkeys((m, d) for m, d, _ in PENDULUM_RUNS))
load_claims(PENDULUM["claims"]["file"])  # a malformed claims file fails before any job runs
PENDULUM_CLAIMS = "results/pendulum/claims.json"

PENDULUM_PAPER_FIGURE = {0: 6, 1: 7, 2: 8}  # Fig. 6-8 for k = 0, 1, 2
PENDULUM_RUN = "results/pendulum/runs/{scheme}/{method}_{decomposition}_k{k}.nc"
PENDULUM_DATASETS = {
    scheme: [
        PENDULUM_RUN.format(scheme=scheme, method=m, decomposition=d, k=k)
        for m, d, k in PENDULUM_RUNS
    ]
    for scheme in PENDULUM_SCHEMES
}
PENDULUM_ALL_RUNS = [path for runs in PENDULUM_DATASETS.values() for path in runs]
PENDULUM_REFERENCE = "results/pendulum/reference.nc"
# numba's compiled integrator, compiled once before the runs: input of every rule that runs it, as
# ancient() (a recompiled cache changes no run, so it reruns none)
PENDULUM_KERNELS = "results/pendulum/kernels.json"
PENDULUM_SUMMARY = "results/pendulum/summary.nc"
PENDULUM_FIGURE = "results/pendulum/figures/pendulum_k{k}_{scheme}.{ext}"
PENDULUM_FIGURES = {
    scheme: [
        PENDULUM_FIGURE.format(k=k, scheme=scheme, ext=ext)
        for k in PENDULUM["k"]
        for ext in ("png", "pdf")
    ]
    for scheme in PENDULUM_SCHEMES
}
PENDULUM_ERROR_FIGURE = "results/pendulum/figures/pendulum_error.png"
PENDULUM_SECTION = "results/report/pendulum.html"


# -- speed-accuracy trade (beyond the paper): error over H, work-precision, stability limit in H,
# subsystem tolerance, adaptive macro steps.  One job per (method, decomposition) writes a sweep
# and a limits dataset per scheme (every k), then merges; figures and the report section read only
# the datasets.
TRADE = PENDULUM["trade"]
# groups and configuration labels; bad schemes, end times off the H grid or invalid
# tolerance/adaptive configurations fail here, naming the key
TRADE_PLAN = trade_plan(PENDULUM)
TRADE_PAIRS = list(dict.fromkeys((m, d) for _, m, d in TRADE_PLAN["groups"]))
TRADE_DIR = "results/pendulum/trade"
TRADE_GROUP = "results/pendulum/trade/{study}/{scheme}/{method}_{decomposition}.nc"
# study (sweep, limits) -> its per-scheme datasets, one per (scheme, method, decomposition)
TRADE_GROUP_FILES = {
    study: [
        TRADE_GROUP.format(study=study, scheme=s, method=m, decomposition=d)
        for s, m, d in TRADE_PLAN["groups"]
    ]
    for study in ("sweep", "limits")
}


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
    output:
        PENDULUM_REFERENCE,
    log:
        "logs/pendulum/reference.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("pendulum_reference"),
        model=PENDULUM["model"],
        H=PENDULUM["H"],
        t_end=PENDULUM["t_end"],
        reference=PENDULUM["reference"],
    script:
        "../scripts/pendulum_reference.py"


rule pendulum_kernels:
    """Compile the links' integrator (numba) into its disk cache, once: the runs load it from there,
    where runs starting together on a cold cache (a fresh clone) would each compile it (~10 CPU-s)."""
    output:
        PENDULUM_KERNELS,
    log:
        "logs/pendulum/kernels.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("pendulum_kernels"),
    priority: 20  # before the long jobs: every co-simulation run waits for it
    script:
        "../scripts/pendulum_kernels.py"


rule pendulum_run:
    """The co-simulation runs of one (method, decomposition), every scheme and k, each up to t_end or
    divergence: one job, since the runs are short and a job's start-up (interpreter, imports, the
    compiled integrator) costs about as much as a CI-length run."""
    input:
        kernels=ancient(PENDULUM_KERNELS),
    output:
        expand(
            PENDULUM_RUN,
            scheme=PENDULUM_SCHEMES,
            method="{method}",
            decomposition="{decomposition}",
            k=PENDULUM["k"],
        ),
    log:
        "logs/pendulum/runs/{method}_{decomposition}.log",
    wildcard_constraints:
        method=METHOD_NAMES,
        decomposition=DECOMPOSITION_NAMES,
    priority: 10  # long: start them first
    conda:
        "../envs/icosim.yaml"
    params:
        library=engine_library("pendulum_run"),
        schemes=PENDULUM_SCHEMES,
        k=PENDULUM["k"],
        model=PENDULUM["model"],
        H=PENDULUM["H"],
        t_end=PENDULUM["t_end"],
        method_params=lambda w: PENDULUM["methods"][w.method],
        integrator=PENDULUM["integrator"],
        sensitivities=PENDULUM["sensitivities"],
        corrector=PENDULUM["corrector"],
        divergence=PENDULUM["divergence"],
    script:
        "../scripts/pendulum_run.py"


rule pendulum_summary:
    """Errors against the reference, the claims' expectations and the linear test model's rho, one row per run
    (every scheme)."""
    input:
        runs=PENDULUM_ALL_RUNS,
        reference=PENDULUM_REFERENCE,
        claims=PENDULUM["claims"]["file"],
    output:
        PENDULUM_SUMMARY,
    log:
        "logs/pendulum/summary.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("pendulum_summary"),
        model=PENDULUM["model"],
        H=PENDULUM["H"],
        methods=PENDULUM["methods"],
    script:
        "../scripts/pendulum_summary.py"


rule pendulum_figure:
    """Figs. 6, 7 and 8 (k = 0, 1, 2) with one scheme: six panels over t, one line per configuration."""
    input:
        runs=lambda w: PENDULUM_DATASETS[w.scheme],
        reference=PENDULUM_REFERENCE,
    output:
        expand(PENDULUM_FIGURE, k=PENDULUM["k"], scheme="{scheme}", ext=("png", "pdf")),
    log:
        "logs/pendulum/figure_{scheme}.log",
    wildcard_constraints:
        scheme=SCHEME_NAMES,
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("pendulum_figure"),
        k=PENDULUM["k"],
        titles=lambda w: [
            figure_title(
                PENDULUM_PAPER_FIGURE.get(int(k), "-"),
                w.scheme,
                f"double pendulum, H = {PENDULUM['H']:g} s",
                f" (k = {k})",
            )
            for k in PENDULUM["k"]
        ],
        dpi=PENDULUM["plot"]["dpi"],
    script:
        "../scripts/pendulum_figure.py"


rule pendulum_error_figure:
    """|phi - phi_ref| of every run of the paper's scheme against the monolithic reference, one column per k."""
    input:
        runs=PENDULUM_DATASETS["jacobi"],
        reference=PENDULUM_REFERENCE,
    output:
        PENDULUM_ERROR_FIGURE,
    log:
        "logs/pendulum/error_figure.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("pendulum_error_figure"),
        dpi=PENDULUM["plot"]["dpi"],
    script:
        "../scripts/pendulum_error_figure.py"


rule pendulum_claims:
    """The pendulum claims (config/claims/pendulum.yaml: Sect. 4 and the project's) on the run summary."""
    input:
        datasets=[PENDULUM_SUMMARY],
        claims=PENDULUM["claims"]["file"],
    output:
        json=PENDULUM_CLAIMS,
        tsv="results/pendulum/claims.tsv",
    log:
        "logs/pendulum/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("claims"),
        enforce_reference=PENDULUM["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


rule pendulum_report_section:
    """HTML fragment of the report: set-up, dd formulation, claim verdicts, errors, figures, the schemes compared."""
    input:
        figures=[f for f in PENDULUM_FIGURES["jacobi"] if f.endswith(".png")],
        scheme_figures=[
            f
            for scheme, files in PENDULUM_FIGURES.items()
            if scheme != "jacobi"
            for f in files
            if f.endswith(".png")
        ],
        error_figure=PENDULUM_ERROR_FIGURE,
        summary=PENDULUM_SUMMARY,
        reference=PENDULUM_REFERENCE,
        claims=PENDULUM_CLAIMS,
        work_precision=PENDULUM_WORK_PRECISION,
        stability_limit=PENDULUM_STABILITY_LIMIT,
        tolerance=PENDULUM_TOLERANCE,
        adaptive=PENDULUM_ADAPTIVE,
        trade_figures=list(TRADE_FIGURES.values()),
    output:
        PENDULUM_SECTION,
    log:
        "logs/pendulum/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("pendulum_report_section"),
        config=PENDULUM,
        paper_figure=PENDULUM_PAPER_FIGURE,
    script:
        "../scripts/pendulum_report_section.py"


rule pendulum_trade_group:
    """The trade studies of one (method, decomposition), for every scheme: error over H (every k and H over
    one end time) and the largest stable H (bisection on divergence, and the linear test model's
    prediction).  One job for both: each pays about a CPU-second of start-up (interpreter, imports,
    the compiled integrator)."""
    input:
        kernels=ancient(PENDULUM_KERNELS),
    output:
        sweep=expand(
            TRADE_GROUP,
            study="sweep",
            scheme=PENDULUM_SCHEMES,
            method="{method}",
            decomposition="{decomposition}",
        ),
        limits=expand(
            TRADE_GROUP,
            study="limits",
            scheme=PENDULUM_SCHEMES,
            method="{method}",
            decomposition="{decomposition}",
        ),
    log:
        "logs/pendulum/trade/{method}_{decomposition}.log",
    wildcard_constraints:
        method=METHOD_NAMES,
        decomposition=DECOMPOSITION_NAMES,
    priority: 10  # long: start them first
    conda:
        "../envs/icosim.yaml"
    params:
        library=engine_library("pendulum_trade_group"),
        settings=lambda w: run_settings(PENDULUM, [w.method]),
        schemes=PENDULUM_SCHEMES,
        k=PENDULUM["k"],
        H=TRADE["error_over_H"]["H"],
        t_end=TRADE["error_over_H"]["t_end"],
        integrator=TRADE["error_over_H"]["integrator"],
        timing=TRADE["error_over_H"]["timing"],
        reference=TRADE["reference"],
        limits=TRADE["stability_limit"],
    script:
        "../scripts/pendulum_trade_group.py"


rule pendulum_baselines:
    """Monolithic pendulum over tolerances (the links' compiled Radau IIA, DOP853) and the linear test
    model's errors."""
    input:
        kernels=ancient(PENDULUM_KERNELS),
    output:
        monolithic=f"{TRADE_DIR}/monolithic.nc",
        linear=f"{TRADE_DIR}/linear_orders.nc",
    log:
        "logs/pendulum/baselines.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=engine_library("pendulum_baselines"),
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
        sweeps=TRADE_GROUP_FILES["sweep"],
        monolithic=f"{TRADE_DIR}/monolithic.nc",
        linear=f"{TRADE_DIR}/linear_orders.nc",
    output:
        PENDULUM_WORK_PRECISION,
    log:
        "logs/pendulum/work_precision.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("pendulum_work_precision"),
        fit=TRADE["fit"],
        accuracy_levels=TRADE["accuracy_levels"],
    script:
        "../scripts/pendulum_work_precision.py"


rule pendulum_stability_limit:
    """stability_limit.nc: the groups' measured and predicted limits over config."""
    input:
        groups=TRADE_GROUP_FILES["limits"],
    output:
        PENDULUM_STABILITY_LIMIT,
    log:
        "logs/pendulum/stability_limit.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("pendulum_stability_limit"),
    script:
        "../scripts/pendulum_stability_limit.py"


rule pendulum_tolerance:
    """Error over the links' Radau tolerance at fixed H for a few configurations."""
    input:
        kernels=ancient(PENDULUM_KERNELS),
    output:
        PENDULUM_TOLERANCE,
    log:
        "logs/pendulum/tolerance.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=engine_library("pendulum_tolerance"),
        settings=run_settings(PENDULUM, study_methods(PENDULUM, "tolerance")),
        tolerance=TRADE_PLAN["tolerance"],
        t_end=TRADE["error_over_H"]["t_end"],
        reference=TRADE["reference"],
    script:
        "../scripts/pendulum_tolerance.py"


rule pendulum_adaptive:
    """Adaptive macro steps (PI control of the predictor-corrector estimate) against fixed H."""
    input:
        kernels=ancient(PENDULUM_KERNELS),
    output:
        PENDULUM_ADAPTIVE,
    log:
        "logs/pendulum/adaptive.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=engine_library("pendulum_adaptive"),
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
        library=script_library("pendulum_trade_figure"),
        dpi=PENDULUM["plot"]["dpi"],
    script:
        "../scripts/pendulum_trade_figure.py"


# every run and trade-group dataset is a target too: a missing one is built again, and what is built
# from it after it
ALL_TARGETS.extend(
    PENDULUM_ALL_RUNS
    + [f for files in TRADE_GROUP_FILES.values() for f in files]
    + [f for files in PENDULUM_FIGURES.values() for f in files]
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
