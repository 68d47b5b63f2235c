"""Snakemake job: draw one convergence figure from its panel datasets, once per decomposition and scheme."""

import logging

from icosim.figures import save_figure
from icosim.figures.convergence import DRAWN_VARIABLES, convergence_figure, row_title, slope_figure
from icosim.io.netcdf import open_variables
from icosim.job import start_job

start_job(snakemake.log[0])
p = snakemake.params
# only the variables drawn, without xarray (icosim.io.netcdf.open_variables)
panels = [open_variables(path, DRAWN_VARIABLES) for path in snakemake.input.panels]
outputs = iter(snakemake.output)
for drawn in p.drawn:
    datasets = {
        ds.attrs["panel"]: ds
        for ds in panels
        if ds.attrs["decomposition"] == drawn["decomposition"] and ds.attrs["scheme"] == drawn["scheme"]
    }
    layout = [[(panel, int(index)) for panel, index in col] for col in drawn["layout"]]
    rows = [row_title(datasets[panel].attrs["method"], index) for panel, index in layout[0]]
    title = drawn["title"]
    fig = convergence_figure(datasets, layout, columns=p.columns, rows=rows, title=title, guide_orders=p.guide_orders)
    save_figure(fig, next(outputs), next(outputs), dpi=p.dpi)
    slopes = slope_figure(
        datasets, layout, columns=p.columns, rows=rows, title=f"{title}: local slopes", tolerance=p.tolerance
    )
    save_figure(slopes, next(outputs), next(outputs), dpi=p.dpi)
    logging.info("%s, %s: drew %d panels", drawn["decomposition"], drawn["scheme"], len(datasets))
