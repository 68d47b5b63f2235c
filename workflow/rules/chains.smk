# The chain study (docs/chain_study.md): N units joined in a row.  One job per part computes its dataset
# (results/chains/<part>.nc: stability, convergence, placement), one job per part draws it, the claims
# (config/claims/chains.yaml) are checked in one job, and the report section follows.
from icosim.claims.registry import load_claims  # noqa: E402
from icosim.studies.chains.config import check_config  # noqa: E402

CHAINS = config["chains"]
# a wrong key or value stops the run here, naming the key and the values allowed
check_config(CHAINS)
load_claims(CHAINS["claims"]["file"])  # a malformed claims file fails before any job runs
CHAINS_PARTS = ["stability", "convergence", "placement"]
CHAINS_DATASET = "results/chains/{part}.nc"
CHAINS_DATASETS = expand(CHAINS_DATASET, part=CHAINS_PARTS)
CHAINS_FIGURE = "results/chains/figures/{part}.{ext}"
CHAINS_PNGS = expand(CHAINS_FIGURE, part=CHAINS_PARTS, ext="png")
CHAINS_CLAIMS = "results/chains/claims.json"
CHAINS_SECTION = "results/report/chains.html"
# what each part's dataset rests on: its own keys and the shared ones (editing the convergence part does not
# rerun the stability search)
CHAINS_INPUTS = {
    "stability": ["units", "methods", "stability"],
    "convergence": ["units", "methods", "convergence"],
    "placement": ["units", "methods", "stability", "placement"],
}


rule chains_dataset:
    """One part of the chain study as a NetCDF dataset."""
    output:
        CHAINS_DATASET,
    log:
        "logs/chains/{part}.log",
    wildcard_constraints:
        part="|".join(CHAINS_PARTS),
    priority: 15  # the stability part is the longest job of the workflow: started late, it would run alone at the end
    conda:
        "../envs/icosim.yaml"
    params:
        library=engine_library("chains_dataset"),
        config=lambda w: {
            key: (CHAINS[key] if key in CHAINS_INPUTS[w.part] else {})
            for key in ("units", "methods", "stability", "convergence", "placement")
        },
    script:
        "../scripts/chains_dataset.py"


rule chains_figure:
    """One figure of the chain study from its dataset."""
    input:
        CHAINS_DATASET,
    output:
        png=CHAINS_FIGURE.replace("{ext}", "png"),
        pdf=CHAINS_FIGURE.replace("{ext}", "pdf"),
    log:
        "logs/chains/figure_{part}.log",
    wildcard_constraints:
        part="|".join(CHAINS_PARTS),
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("chains_figure"),
        titles={
            "stability": "Chains: largest stable macro step against the number of units",
            "convergence": "Chains: convergence against the two-unit case",
            "placement": "Chains: where a heavy or stiff unit sits",
        },
        dpi=110,
    script:
        "../scripts/chains_figure.py"


rule chains_claims:
    """The chain study's claims (config/claims/chains.yaml) on its datasets."""
    input:
        datasets=CHAINS_DATASETS,
        claims=CHAINS["claims"]["file"],
    output:
        json=CHAINS_CLAIMS,
        tsv="results/chains/claims.tsv",
    log:
        "logs/chains/claims.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("claims"),
        enforce_reference=CHAINS["claims"]["enforce_reference"],
    script:
        "../scripts/claims.py"


rule chains_report_section:
    """HTML fragment of the report: what was computed, the figures, the orders and the claims."""
    input:
        stability="results/chains/stability.nc",
        convergence="results/chains/convergence.nc",
        placement="results/chains/placement.nc",
        figures=CHAINS_PNGS,
        claims=CHAINS_CLAIMS,
    output:
        CHAINS_SECTION,
    log:
        "logs/chains/report_section.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("chains_report_section"),
    script:
        "../scripts/chains_report_section.py"


ALL_TARGETS.extend([*CHAINS_DATASETS, *CHAINS_PNGS, CHAINS_CLAIMS])
REPORT_SECTIONS["chains"] = CHAINS_SECTION
