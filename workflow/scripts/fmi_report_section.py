"""Snakemake job: the FMU section of the report (thin: icosim.report.fmi)."""

import logging

from icosim.io.netcdf import atomic_path, open_dataset
from icosim.job import start_job
from icosim.report.fmi import fmi_section
from icosim.verdicts import read_verdicts

start_job(snakemake.log[0])
i = snakemake.input
html = fmi_section(
    validations=[open_dataset(path) for path in i.validations],
    orders=[open_dataset(path) for path in i.orders],
    claims=read_verdicts(i.claims),
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html, encoding="utf-8")
logging.info("section written: %d scenes, %d order cases", len(i.validations), len(i.orders))
