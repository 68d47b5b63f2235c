"""Snakemake job: the Gauss-Seidel section of the report (thin: icosim.report.gauss_seidel)."""

import logging

from icosim.claims.core import read_verdicts
from icosim.convergence.curves import curves
from icosim.io.netcdf import atomic_path, open_dataset
from icosim.report.gauss_seidel import gauss_seidel_section

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
i, p = snakemake.input, snakemake.params


def claims(paths):
    return read_verdicts(paths[0]) if paths else []


stability = convergence = pendulum = None
if i.shares:
    stability = {
        "shares": open_dataset(i.shares[0]),
        "claims": claims(i.stability_claims),
        "comparison_png": i.comparison[0],
        "figure_pngs": list(i.stability_figures),
        "figures_cfg": p.stability_figures,
    }
if i.convergence_panels:
    convergence = {
        "curves": curves([open_dataset(path) for path in i.convergence_panels]),
        "claims": claims(i.convergence_claims),
        "figure_pngs": list(i.convergence_figures),
    }
if i.pendulum_summary:
    pendulum = {
        "summary": open_dataset(i.pendulum_summary[0]),
        "claims": claims(i.pendulum_claims),
        "figure_pngs": list(i.pendulum_figures),
    }
html = gauss_seidel_section(stability=stability, convergence=convergence, pendulum=pendulum)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html)
logging.info(
    "section: stability %s, convergence %s, pendulum %s", *(x is not None for x in (stability, convergence, pendulum))
)
