"""Snakemake job: the convergence section of the report (thin: icosim.report.convergence, icosim.report.schemes)."""

import logging

from icosim.io.netcdf import atomic_path, open_dataset
from icosim.job import start_job
from icosim.report.convergence import convergence_section
from icosim.report.schemes import convergence_schemes
from icosim.studies.convergence.curves import curves
from icosim.verdicts import read_verdicts

start_job(snakemake.log[0])
i, p = snakemake.input, snakemake.params
claims = read_verdicts(i.claims)
panels = [open_dataset(path) for path in i.panels]
schemes = {ds.attrs["scheme"] for ds in panels}
jacobi_pngs = [f for f in i.figures if f.endswith("_jacobi.png")]
schemes_html = ""
if len(schemes) > 1:
    schemes_html = convergence_schemes(
        curves=curves(panels),
        claims=[c for c in claims if c.get("scope") == "beyond"],
        figure_pngs=[f for f in i.figures if f not in jacobi_pngs],
    )
html = convergence_section(
    setup=p.setup,
    step_sizes=p.step_sizes,
    stepping=p.stepping,
    fit=p.fit,
    startup_steps=p.startup_steps,
    unstable=p.unstable,
    targets=p.targets,
    figures=p.figures,
    panels=[ds for ds in panels if ds.attrs["scheme"] == "jacobi"],
    claims=[c for c in claims if c.get("scope", "paper") == "paper"],
    figure_pngs=jacobi_pngs,
    wp=open_dataset(i.wp),
    wp_png=i.wp_figure,
    schemes_html=schemes_html,
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html)
logging.info("section written: %d claims, %d figures", len(claims), len(i.figures))
