"""Snakemake job: the FMU section of the report (thin: icosim.report.fmi)."""

import logging

from icosim.claims.core import read_verdicts
from icosim.io.netcdf import atomic_path, open_dataset
from icosim.report.fmi import fmi_section

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
i = snakemake.input
html = fmi_section(
    validations=[open_dataset(path) for path in i.validations],
    orders=[open_dataset(path) for path in i.orders],
    claims=read_verdicts(i.claims),
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html, encoding="utf-8")
logging.info("section written: %d scenes, %d order cases", len(i.validations), len(i.orders))
