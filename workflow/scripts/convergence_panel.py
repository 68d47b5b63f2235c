"""Snakemake job: one convergence panel (rows x k of one column) -> NetCDF (thin: icosim.convergence.datasets)."""

import json
import logging

from icosim.convergence.curves import curve_label, curves
from icosim.convergence.datasets import run_panel
from icosim.convergence.experiment import Setup, step_counts
from icosim.convergence.panels import PanelSpec
from icosim.convergence.study import Study
from icosim.io.netcdf import provenance_attrs, write_netcdf

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params
job = {
    k: p[k] for k in ("panel", "setup", "step_sizes", "stepping", "startup_steps", "spectral_policy", "digits", "fit")
}
logging.info("panel parameters: %s", json.dumps(job, sort_keys=True))

spec = PanelSpec.from_dict(p.panel)
setup = Setup(**p.setup)
n_steps = step_counts(setup.end_time, p.step_sizes["H_min"], p.step_sizes["H_max"], p.step_sizes["num"])
study = Study(setup, n_steps, spectral_policy=p.spectral_policy, digits=p.digits, startup_steps=p.startup_steps)
title = f"Fig. {spec.figure} ({spec.decomposition}), panel {spec.panel}: NRMSE of Eq. (72) over the macro-step size"
ds = run_panel(
    spec,
    study,
    p.fit,
    stepping=p.stepping,
    provenance=provenance_attrs(job, title=title, command="snakemake rule convergence_panel"),
)
write_netcdf(ds, snakemake.output[0])

for rec in curves([ds]):
    logging.info(
        "%s: order %.3f (%s), %d unstable", curve_label(rec), rec["order"], rec["order_status"], rec["unstable"].sum()
    )
logging.info("%.2f s", ds.attrs["seconds_total"])
