"""Snakemake job: errors against the reference, the claim of Sect. 4 and the linear test model's
spectral radius at the pendulum's point (Sect. 3) per run -> NetCDF."""

import logging

from icosim import make_method
from icosim.datasets import config_json, open_dataset, provenance_attrs, write_netcdf
from icosim.claims import load_claims
from icosim.pendulum import PendulumParameters, linear_test_model_rho, run_name, summarize

snakemake = snakemake  # noqa: F821 (injected by Snakemake)

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params
claims = load_claims(snakemake.input.claims)
runs = [open_dataset(path) for path in snakemake.input.runs]
reference = open_dataset(snakemake.input.reference)
params = PendulumParameters(**p.model)
rho, model = {}, None
for ds in runs:
    name, dec, k = ds.attrs["method"], ds.attrs["decomposition"], int(ds.attrs["k"])
    rho[run_name(name, dec, k)], model = linear_test_model_rho(
        params, p.H, make_method(name, **p.methods[name]), dec, k
    )
ds = summarize(runs, reference, claims, rho_test_model=rho)
ds.attrs.update(
    provenance_attrs(
        {
            "claims": [c.as_dict() for c in claims],
            "runs": list(snakemake.input.runs),
            "model": dict(p.model),
            "H": p.H,
            "methods": p.methods,
        },
        title="Double pendulum (Sect. 4): errors and claim verdicts",
        command="snakemake rule pendulum_summary",
    )
)
ds.attrs["claims_json"] = config_json([c.as_dict() for c in claims])
ds.attrs["test_model_lr1"] = [float(v) for v in model.lr1]
ds.attrs["test_model_li1"] = [float(v) for v in model.li1]
ds.attrs["test_model_ratios"] = f"am21 = {model.am21:g}, alr21 = {model.alr21:g}, ali21 = {model.ali21:g}"
ds.attrs["test_model_point"] = (
    "lr1 = -d H / (2 m1); li1 = H omega for the modal frequencies of the pendulum linearised about its hanging "
    "rest (icosim.pendulum.pendulum_test_model); rho_test_model is the larger spectral radius of the two points"
)
write_netcdf(ds, snakemake.output[0])
for row in ds["run"].values:
    r = ds.sel(run=row)
    logging.info(
        "%-24s observed %-8s err phi1 %.2e phi2 %.2e rho %.6f",
        row,
        str(r["observed"].values),
        float(r["err_phi1"]),
        float(r["err_phi2"]),
        float(r["rho_test_model"]),
    )
