"""Snakemake job: assemble reports/icosim_report.html from the parts' sections (thin: icosim.report.page)."""

import logging
from pathlib import Path

from icosim.io.netcdf import atomic_path
from icosim.job import start_job
from icosim.report.page import git_commit_text, report_page, utc_now
from icosim.verdicts import read_verdicts

start_job(snakemake.log[0])
p = snakemake.params
commit_text = git_commit_text()
html = report_page(
    title=p.title,
    parts=p.parts,
    skipped=p.skipped,
    sections=[Path(path).read_text() for path in snakemake.input.sections],
    configfiles=list(snakemake.input.configfiles),
    config_sha256=p.config_sha256,
    precision=p.precision,
    commit_text=commit_text,
    generated=utc_now(),
    claims={part: read_verdicts(path) for part, path in zip(p.claim_parts, snakemake.input.claims)},
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html)
logging.info("report with sections %s (skipped: %s), commit %s", p.parts, p.skipped, commit_text)
