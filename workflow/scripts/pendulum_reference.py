"""Snakemake job: the monolithic reference of the double pendulum -> NetCDF."""

import json
import logging

from icosim.io.netcdf import provenance_attrs, write_netcdf
from icosim.job import start_job
from icosim.problems.pendulum.model import PendulumParameters
from icosim.studies.pendulum.datasets import reference_dataset_data

start_job(snakemake.log[0])
p = snakemake.params
job = {"model": dict(p.model), "H": p.H, "t_end": p.t_end, "reference": dict(p.reference)}
logging.info("reference: %s", json.dumps(job, sort_keys=True))

prov = provenance_attrs(
    job, title="Double pendulum (Sect. 4): monolithic reference", command="snakemake rule pendulum_reference"
)
ds = reference_dataset_data(PendulumParameters(**p.model), p.H, p.t_end, prov, **p.reference)
write_netcdf(ds, snakemake.output[0])
logging.info("%d points, %.2f s", ds.dims["t"], ds.attrs["wall_time_s"])
