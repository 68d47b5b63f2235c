"""Snakemake job: errors against the reference, the claim of Sect. 4 and the linear test model's
spectral radius at the pendulum's point (Sect. 3) per run -> NetCDF (thin: icosim.studies.pendulum.summary)."""

import logging

from icosim.claims.registry import load_claims
from icosim.io.netcdf import open_dataset, write_netcdf
from icosim.job import start_job
from icosim.studies.pendulum.summary import summary_dataset

start_job(snakemake.log[0])
p = snakemake.params
ds = summary_dataset(
    [open_dataset(path) for path in snakemake.input.runs],
    open_dataset(snakemake.input.reference),
    load_claims(snakemake.input.claims),
    model=p.model,
    H=p.H,
    methods=p.methods,
    run_files=snakemake.input.runs,
    command="snakemake rule pendulum_summary",
)
write_netcdf(ds, snakemake.output[0])
for run in ds["run"].values:
    r = ds.sel(run=run)
    logging.info(
        "%-24s observed %-8s err phi1 %.2e phi2 %.2e rho %.6f",
        *(run, str(r["observed"].values), float(r["err_phi1"]), float(r["err_phi2"]), float(r["rho_test_model"])),
    )
