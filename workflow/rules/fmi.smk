# FMU scenes (docs/fmi.md): the test units built once from source (results/fmi/units/), one job per scene that
# runs it (results/fmi/<scene>.nc) and checks it against the prediction before the run and the built-in model
# (results/fmi/validation/<scene>.nc), one job per order case (results/fmi/orders/<case>.nc), the claims
# (config/claims/fmi.yaml) and the report section.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.studies.fmi.config import order_cases, scene_files, unit_inputs, unit_sources  # noqa: E402

validate_part(config["fmi"], "fmi.schema.yaml")

FMI = config["fmi"]
# scene -> its file; a scene that fails the scene schema stops here, naming the file and the key
FMI_SCENES = scene_files(FMI, workflow.basedir)
FMI_UNIT_SOURCES = unit_sources(FMI, workflow.basedir)
FMI_CASES = order_cases(FMI)
load_claims(FMI["claims"]["file"])  # a malformed claims file fails before any job runs
FMI_UNITS = "results/fmi/units/units.json"
FMI_RUN = "results/fmi/{scene}.nc"
FMI_VALIDATION = "results/fmi/validation/{scene}.nc"
FMI_ORDERS = "results/fmi/orders/{case}.nc"
FMI_RUNS = expand(FMI_RUN, scene=FMI_SCENES)
FMI_VALIDATIONS = expand(FMI_VALIDATION, scene=FMI_SCENES)
FMI_ORDER_FILES = expand(FMI_ORDERS, case=FMI_CASES)
FMI_CLAIMS = "results/fmi/claims.json"
FMI_SECTION = "results/report/fmi.html"


rule fmi_units:
    """The test units the scenes and the order cases name, built from source with fmpy (CMake and a C
    compiler; the Python unit exported with pythonfmu) into results/fmi/units/, once per content."""
    input:
        sources=unit_inputs(FMI_UNIT_SOURCES, workflow.basedir),
    output:
        FMI_UNITS,
    log:
        "logs/fmi/units.log",
    conda:
        "../envs/fmi.yaml"
    params:
        library=script_library("fmi_units"),
        sources=FMI_UNIT_SOURCES,
    script:
        "../scripts/fmi_units.py"


rule fmi_scene:
    """One scene run on its units, and checked: the spectral radius predicted before the run, the growth
    measured on it, the difference to the built-in model."""
    input:
        scene=lambda w: FMI_SCENES[w.scene],
        units=FMI_UNITS,
        # a scene checked against the built-in pendulum runs its compiled integrator: it waits for the one
        # compile job, as every pendulum run does (two jobs on a cold cache would each compile)
        kernels=lambda w: [ancient(PENDULUM_KERNELS)] if FMI["scenes"][w.scene]["builtin"] == "pendulum" else [],
    output:
        run=FMI_RUN,
        validation=FMI_VALIDATION,
    log:
        "logs/fmi/scenes/{scene}.log",
    wildcard_constraints:
        scene="|".join(FMI_SCENES),
    conda:
        "../envs/fmi.yaml"
    params:
        library=engine_library("fmi_scene"),
        builtin=lambda w: FMI["scenes"][w.scene]["builtin"],
    script:
        "../scripts/fmi_scene.py"


rule fmi_orders:
    """One configuration of the linear convergence study on the units over H, and on the built-in model."""
    input:
        units=FMI_UNITS,
    output:
        FMI_ORDERS,
    log:
        "logs/fmi/orders/{case}.log",
    wildcard_constraints:
        case="|".join(FMI_CASES),
    conda:
        "../envs/fmi.yaml"
    params:
        library=engine_library("fmi_orders"),
        case=lambda w: FMI_CASES[w.case],
        model=FMI["orders"]["model"],
        x0=FMI["orders"]["x0"],
        t_end=FMI["orders"]["t_end"],
        fit=FMI["orders"]["fit"],
        units_dir=FMI["units_dir"],
    script:
        "../scripts/fmi_orders.py"


rule fmi_claims:
    """The FMU claims (config/claims/fmi.yaml) on the scene checks and the order cases."""
    input:
        datasets=FMI_VALIDATIONS + FMI_ORDER_FILES,
        claims=FMI["claims"]["file"],
    output:
        json=FMI_CLAIMS,
        tsv="results/fmi/claims.tsv",
    log:
        "logs/fmi/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("claims"),
        enforce_reference=FMI["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


rule fmi_report_section:
    """HTML fragment of the report: every scene with its prediction, growth and built-in difference; orders;
    claims."""
    input:
        validations=FMI_VALIDATIONS,
        orders=FMI_ORDER_FILES,
        claims=FMI_CLAIMS,
    output:
        FMI_SECTION,
    log:
        "logs/fmi/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("fmi_report_section"),
    script:
        "../scripts/fmi_report_section.py"


ALL_TARGETS.extend([FMI_UNITS, *FMI_RUNS, *FMI_VALIDATIONS, *FMI_ORDER_FILES, FMI_CLAIMS])
REPORT_SECTIONS["fmi"] = FMI_SECTION
