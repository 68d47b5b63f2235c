"""Snakemake job: the panels of one convergence figure and scheme (rows x k of each column) -> one NetCDF each
(thin: icosim.studies.convergence.datasets)."""

import json
import logging

from icosim.io.netcdf import provenance_attrs, write_netcdf
from icosim.job import start_job
from icosim.labels import figure_label
from icosim.studies.convergence.datasets import curve_summaries, run_panel_data
from icosim.studies.convergence.experiment import Setup, step_counts
from icosim.studies.convergence.panels import PanelSpec
from icosim.studies.convergence.study import Study

start_job(snakemake.log[0])
p = snakemake.params
setup = Setup(**p.setup)
n_steps = step_counts(setup.end_time, p.step_sizes["H_min"], p.step_sizes["H_max"], p.step_sizes["num"])
study = Study(setup, n_steps, spectral_policy=p.spectral_policy, digits=p.digits, startup_steps=p.startup_steps)
shared = {k: p[k] for k in ("setup", "step_sizes", "stepping", "startup_steps", "spectral_policy", "digits", "fit")}
for panel, path in zip(p.panels, snakemake.output, strict=True):
    job = {"panel": panel, **shared}
    logging.info("panel parameters: %s", json.dumps(job, sort_keys=True))
    spec = PanelSpec.from_dict(panel)
    title = (
        f"{figure_label(spec.figure)} ({spec.decomposition}, {spec.scheme}), panel {spec.panel}: "
        "NRMSE of Eq. (72) over the macro-step size"
    )
    provenance = provenance_attrs(job, title=title, command=f"snakemake rule {snakemake.rule}")
    ds = run_panel_data(spec, study, p.fit, stepping=p.stepping, provenance=provenance)
    write_netcdf(ds, path)
    for label, order, status, unstable in curve_summaries(ds):
        logging.info("%s: order %.3f (%s), %d unstable", label, order, status, unstable)
    logging.info("%s: %.2f s", path, ds.attrs["seconds_total"])
