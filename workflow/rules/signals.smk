# The signal-coupling study (docs/signals.md): OMSimulator's DualMassOscillator on its Model Exchange units, by its
# signal connections and by a joint.  One job per case and k (results/signals/<case>.nc: errors over H, order,
# predicted rho, measured growth), one figure from all cases, the claims (config/claims/signals.yaml) and the
# report section.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.studies.signals.config import check_cases, unit_paths  # noqa: E402

validate_part(config["signals"], "signals.schema.yaml")

SIGNALS = config["signals"]
# case -> its settings; a case whose scene the scene checks refuse stops here, naming the case and the key
SIGNALS_CASES = check_cases(SIGNALS)
load_claims(SIGNALS["claims"]["file"])  # a malformed claims file fails before any job runs
# the units are the other tools' (../shared/outside): inputs where they are, else the job names what is missing
SIGNALS_UNITS = [
    str(p) for p in unit_paths(SIGNALS, workflow.basedir).values() if p.is_file()
]
SIGNALS_CASE = "results/signals/{case}.nc"
SIGNALS_FILES = expand(SIGNALS_CASE, case=SIGNALS_CASES)
SIGNALS_FIGURE = "results/signals/figures/signals.{ext}"
SIGNALS_PNG = SIGNALS_FIGURE.format(ext="png")
SIGNALS_CLAIMS = "results/signals/claims.json"
SIGNALS_SECTION = "results/report/signals.html"


rule signals_case:
    """One case of the study over its H: the error against the exact solution, its order, the predicted rho and
    the growth measured on runs at growth_H."""
    input:
        units=SIGNALS_UNITS,
    output:
        SIGNALS_CASE,
    log:
        "logs/signals/{case}.log",
    wildcard_constraints:
        case="|".join(SIGNALS_CASES),
    conda:
        "../envs/fmi.yaml"
    params:
        library=engine_library("signals_case"),
        case=lambda w: SIGNALS_CASES[w.case],
        config={
            key: SIGNALS[key]
            for key in (
                "units_dir",
                "units",
                "start",
                "tolerance",
                "t_end",
                "fit",
                "growth_steps",
            )
        },
    script:
        "../scripts/signals_case.py"


rule signals_figure:
    """The study's figure: error over H per case, predicted rho against measured growth."""
    input:
        SIGNALS_FILES,
    output:
        png=SIGNALS_PNG,
        pdf=SIGNALS_FIGURE.format(ext="pdf"),
    log:
        "logs/signals/figure.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("signals_figure"),
        title="DualMassOscillator: signal connections and a joint against the exact solution",
        dpi=110,
    script:
        "../scripts/signals_figure.py"


rule signals_claims:
    """The study's claims (config/claims/signals.yaml) on its case datasets."""
    input:
        datasets=SIGNALS_FILES,
        claims=SIGNALS["claims"]["file"],
    output:
        json=SIGNALS_CLAIMS,
        tsv="results/signals/claims.tsv",
    log:
        "logs/signals/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("claims"),
        enforce_reference=SIGNALS["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


rule signals_report_section:
    """HTML fragment of the report: the figure, the cases, prediction against growth, what the data cannot
    decide, the claims."""
    input:
        cases=SIGNALS_FILES,
        figure=SIGNALS_PNG,
        claims=SIGNALS_CLAIMS,
    output:
        SIGNALS_SECTION,
    log:
        "logs/signals/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("signals_report_section"),
    script:
        "../scripts/signals_report_section.py"


ALL_TARGETS.extend([*SIGNALS_FILES, SIGNALS_PNG, SIGNALS_CLAIMS])
REPORT_SECTIONS["signals"] = SIGNALS_SECTION
