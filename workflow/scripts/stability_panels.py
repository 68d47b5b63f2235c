"""Snakemake job: every panel of one figure -> one NetCDF each (thin: the work is icosim.studies.stability.datasets)."""

import json
import logging

from icosim.io.netcdf import provenance_attrs, write_netcdf
from icosim.job import start_job
from icosim.labels import figure_label
from icosim.studies.stability.datasets import stability_panel_data
from icosim.studies.stability.panels import PanelSpec

start_job(snakemake.log[0])
for params, path in zip(snakemake.params.panels, snakemake.output, strict=True):
    logging.info("panel parameters: %s", json.dumps(params, sort_keys=True))
    spec = PanelSpec.from_params(params)
    title = (
        f"{figure_label(spec.figure)} ({spec.scheme}), row {spec.row}, k = {spec.k} ({spec.view}): "
        "spectral radius over (lr1, li1)"
    )
    provenance = provenance_attrs(params, title=title, command=f"snakemake rule {snakemake.rule}")
    ds = stability_panel_data(spec, provenance=provenance)
    write_netcdf(ds, path)
    a = ds.attrs
    logging.info(
        "%s: %d points, %d stable, %d marginal, %d certified (%d audited, %d overturned); float64 %.2f s, certify %.2f s",
        path,
        a["n_points"],
        a["n_stable"],
        a["n_marginal"],
        a["n_certified"],
        a["n_audited"],
        a["n_overturned"],
        a["seconds_float64"],
        a["seconds_certify"],
    )
