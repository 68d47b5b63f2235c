"""Snakemake job: the peers study's section of the report (thin: icosim.report.peers)."""

import logging

from icosim.io.netcdf import atomic_path, open_dataset
from icosim.job import start_job
from icosim.report.peers import peers_section
from icosim.verdicts import read_verdicts

start_job(snakemake.log[0])
i = snakemake.input
html = peers_section(systems=[open_dataset(p) for p in i.systems], claims=read_verdicts(i.claims), figure=i.figure)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html, encoding="utf-8")
logging.info("section written: %d systems", len(i.systems))
