"""Snakemake job: the convergence section of the report (thin: icosim.report.convergence)."""

import logging

from icosim.claims.core import read_verdicts
from icosim.io.netcdf import atomic_path, open_dataset
from icosim.report.convergence import convergence_section

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params
claims = read_verdicts(snakemake.input.claims)
html = convergence_section(
    setup=p.setup,
    step_sizes=p.step_sizes,
    stepping=p.stepping,
    fit=p.fit,
    startup_steps=p.startup_steps,
    unstable=p.unstable,
    targets=p.targets,
    figures=p.figures,
    panels=[open_dataset(path) for path in snakemake.input.panels],
    claims=claims,
    figure_pngs=list(snakemake.input.figures),
    wp=open_dataset(snakemake.input.wp),
    wp_png=snakemake.input.wp_figure,
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html)
logging.info("section written: %d claims, %d figures", len(claims), len(snakemake.input.figures))
