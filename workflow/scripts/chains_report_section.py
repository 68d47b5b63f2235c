"""Snakemake job: the chain study's section of the report (thin: icosim.report.chains)."""

import logging

from icosim.io.netcdf import atomic_path, open_dataset
from icosim.job import start_job
from icosim.report.chains import chains_section
from icosim.verdicts import read_verdicts

start_job(snakemake.log[0])
i = snakemake.input
html = chains_section(
    stability=open_dataset(i.stability),
    convergence=open_dataset(i.convergence),
    placement=open_dataset(i.placement),
    claims=read_verdicts(i.claims),
    figures=dict(zip(("stability", "convergence", "placement"), i.figures)),
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html, encoding="utf-8")
logging.info("section written")
