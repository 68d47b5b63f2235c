# Work-precision against the peers (docs/benchmarks.md): icosim beside libcosim, Ecos and FMPy on the same unit
# files.  One job per system (results/peers/<system>.nc: per run its error against the reference, the minimum
# wall time of the timed runs, its doSteps and status), one figure from both, the claims
# (config/claims/peers.yaml) and the report section.
from icosim.studies.peers.config import SYSTEMS as PEERS_KNOWN, check_config as peers_check  # noqa: E402
from icosim.studies.peers.config import unit_dir as peers_unit_dir  # noqa: E402

validate_part(config["peers"], "peers.schema.yaml")

PEERS = config["peers"]
# system -> its runs; a master, key or value the study does not know stops here, naming it
PEERS_RUNS = peers_check(PEERS)
load_claims(PEERS["claims"]["file"])  # a malformed claims file fails before any job runs
PEERS_SYSTEMS = list(PEERS["systems"])
PEERS_DATASET = "results/peers/{system}.nc"
PEERS_FILES = expand(PEERS_DATASET, system=PEERS_SYSTEMS)
PEERS_FIGURE = "results/peers/figures/peers.{ext}"
PEERS_PNG = PEERS_FIGURE.format(ext="png")
PEERS_CLAIMS = "results/peers/claims.json"
PEERS_SECTION = "results/report/peers.html"


rule peers_system:
    """Every run of one system: error against the reference, minimum wall time, doSteps, status.  Two threads:
    on the two-core machines it is measured on, no other job's work is in its wall times (Snakemake lowers them
    to --cores where fewer are given)."""
    input:
        # the system's unit files where they are (else the job names what is missing)
        units=lambda w: [
            str(peers_unit_dir(PEERS["systems"][w.system], workflow.basedir) / name)
            for name in PEERS_KNOWN[w.system][1]
            if (peers_unit_dir(PEERS["systems"][w.system], workflow.basedir) / name).is_file()
        ],
    output:
        PEERS_DATASET,
    log:
        "logs/peers/{system}.log",
    wildcard_constraints:
        system="|".join(PEERS_SYSTEMS),
    threads: 2
    conda:
        "../envs/fmi.yaml"
    params:
        library=engine_library("peers_system"),
        config=lambda w: {
            key: PEERS[key] for key in ("repeat", "budget", "warmup", "levels")
        }
        | {"systems": {w.system: PEERS["systems"][w.system]}},
    script:
        "../scripts/peers_system.py"


rule peers_figure:
    """The study's figure: per system, wall time and doSteps against the error."""
    input:
        PEERS_FILES,
    output:
        png=PEERS_PNG,
        pdf=PEERS_FIGURE.format(ext="pdf"),
    log:
        "logs/peers/figure.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("peers_figure"),
        title="Work-precision against the peers on the same unit files",
        dpi=110,
    script:
        "../scripts/peers_figure.py"


rule peers_claims:
    """The study's claims (config/claims/peers.yaml) on its system datasets."""
    input:
        datasets=PEERS_FILES,
        claims=PEERS["claims"]["file"],
    output:
        json=PEERS_CLAIMS,
        tsv="results/peers/claims.tsv",
    log:
        "logs/peers/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("claims"),
        enforce_reference=PEERS["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


rule peers_report_section:
    """HTML fragment of the report: the figure, the runs, who reaches each error fastest, where icosim does not
    win and why, the claims."""
    input:
        systems=PEERS_FILES,
        figure=PEERS_PNG,
        claims=PEERS_CLAIMS,
    output:
        PEERS_SECTION,
    log:
        "logs/peers/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("peers_report_section"),
    script:
        "../scripts/peers_report_section.py"


ALL_TARGETS.extend([*PEERS_FILES, PEERS_PNG, PEERS_CLAIMS])
REPORT_SECTIONS["peers"] = PEERS_SECTION
