"""Snakemake job: the signal-coupling study's section of the report (thin: icosim.report.signals)."""

import logging

from icosim.io.netcdf import atomic_path, open_dataset
from icosim.job import start_job
from icosim.report.signals import signals_section
from icosim.verdicts import read_verdicts

start_job(snakemake.log[0])
i = snakemake.input
html = signals_section(cases=[open_dataset(path) for path in i.cases], claims=read_verdicts(i.claims), figure=i.figure)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html, encoding="utf-8")
logging.info("section written: %d cases", len(i.cases))
