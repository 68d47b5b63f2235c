# The report: reports/icosim_report.html assembles the parts' sections (each an HTML
# fragment registered in REPORT_SECTIONS by its rules file) in the order of
# config["report"]["sections"], skipping parts that registered none, plus provenance.
# `snakemake --report` additionally collects the figures marked with report(...).
import hashlib
import json

REPORT_HTML = "reports/icosim_report.html"


# part -> section fragment, in the configured order; parts without a section are skipped
REPORT_PARTS = {
    part: REPORT_SECTIONS[part]
    for part in config["report"]["sections"]
    if part in REPORT_SECTIONS
}


rule report:
    """Self-contained HTML page: every part's section (figures, claims) and provenance."""
    input:
        sections=list(REPORT_PARTS.values()),
        # each part's claim verdicts (results/<part>/claims.json): the summary at the top of the page
        claims=[f"results/{part}/claims.json" for part in REPORT_PARTS],
        configfiles=[
            f for f in dict.fromkeys(workflow.configfiles) if os.path.exists(f)
        ],
    output:
        REPORT_HTML,
    log:
        "logs/report/report.log",
    conda:
        "../envs/icosim.yaml"
    params:
        library=script_library("report_page"),
        title=config["report"]["title"],
        parts=list(REPORT_PARTS),
        claim_parts=list(REPORT_PARTS),
        skipped=[p for p in config["report"]["sections"] if p not in REPORT_SECTIONS],
        # effective (merged) configuration of each part: its hash changes exactly when it does
        config_sha256={
            part: hashlib.sha256(
                json.dumps(config.get(part), sort_keys=True).encode()
            ).hexdigest()
            for part in ["report"] + list(config["report"]["sections"])
            if part in config
        },
        precision=config["stability"]["precision"],
    script:
        "../scripts/report_page.py"
