"""Snakemake job: one co-simulation run of the double pendulum -> NetCDF (the work is icosim.pendulum)."""

import json
import logging

from icosim import make_method
from icosim.datasets import provenance_attrs, write_netcdf
from icosim.pendulum import PendulumParameters, run_cosimulation, run_dataset

snakemake = snakemake  # noqa: F821 (injected by Snakemake)

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
w, p = snakemake.wildcards, snakemake.params
method_name, decomposition, k = w.method, w.decomposition, int(w.k)
job = {
    "method": method_name,
    "decomposition": decomposition,
    "k": k,
    "method_params": dict(p.method_params),
    "model": dict(p.model),
    "H": p.H,
    "t_end": p.t_end,
    "integrator": dict(p.integrator),
    "sensitivities": dict(p.sensitivities),
    "corrector": dict(p.corrector),
    "divergence": dict(p.divergence),
}
logging.info("run: %s", json.dumps(job, sort_keys=True))

method = make_method(method_name, **p.method_params)
result = run_cosimulation(
    PendulumParameters(**p.model),
    method,
    decomposition,
    k,
    H=p.H,
    t_end=p.t_end,
    **p.integrator,
    **p.sensitivities,
    **p.corrector,
    **p.divergence,
)
settings = {
    "H": p.H,
    "t_end": p.t_end,
    "integrator": "Radau IIA (3 stages, order 5), icosim.radau, batched",
    "rtol": p.integrator["rtol"],
    "atol": p.integrator["atol"],
    "newton_tol": p.integrator["newton_tol"],
    "fd_step": p.sensitivities["fd_step"],
    "corrector_iterations": p.corrector["iterations"],
    "corrector_tol": p.corrector["tol"],
    **{f"bound_{key}": value for key, value in p.divergence.items()},
}
title = f"Double pendulum (Sect. 4): {method_name} {decomposition} k = {k}"
ds = run_dataset(
    result,
    method,
    decomposition,
    k,
    settings,
    provenance_attrs(job, title=title, command="snakemake rule pendulum_run"),
)
write_netcdf(ds, snakemake.output[0])
logging.info(
    "%d macro steps in %.2f s; diverged=%d at t=%s (%s); %s",
    result.stats["macro_steps"],
    result.wall_time,
    result.diverged,
    result.t_diverged,
    result.reason or "-",
    result.stats,
)
