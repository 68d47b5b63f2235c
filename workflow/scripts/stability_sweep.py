"""Snakemake job: one stability panel -> NetCDF (thin: the work is icosim.stability.datasets)."""

import json
import logging

from icosim.io.netcdf import provenance_attrs, write_netcdf
from icosim.stability.datasets import stability_panel
from icosim.stability.panels import PanelSpec

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
params = snakemake.params.panel
logging.info("panel parameters: %s", json.dumps(params, sort_keys=True))

spec = PanelSpec.from_params(params)
title = f"Fig. {spec.figure}, row {spec.row}, k = {spec.k} ({spec.view}): spectral radius over (lr1, li1)"
ds = stability_panel(spec, provenance=provenance_attrs(params, title=title, command="snakemake rule stability_sweep"))
write_netcdf(ds, snakemake.output[0])

a = ds.attrs
logging.info(
    "%d points, %d stable, %d marginal, %d certified (%d audited, %d overturned); float64 %.2f s, certify %.2f s",
    a["n_points"],
    a["n_stable"],
    a["n_marginal"],
    a["n_certified"],
    a["n_audited"],
    a["n_overturned"],
    a["seconds_float64"],
    a["seconds_certify"],
)
