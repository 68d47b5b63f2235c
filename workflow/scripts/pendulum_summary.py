"""Snakemake job: errors against the reference and the claim of Sect. 4 per run -> NetCDF."""

import logging

from icosim.datasets import config_json, open_dataset, provenance_attrs, write_netcdf
from icosim.pendulum import load_claims, summarize

snakemake = snakemake  # noqa: F821 (injected by Snakemake)

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
claims = load_claims(snakemake.input.claims)
runs = [open_dataset(path) for path in snakemake.input.runs]
reference = open_dataset(snakemake.input.reference)
ds = summarize(runs, reference, claims)
ds.attrs.update(
    provenance_attrs(
        {"claims": claims, "runs": list(snakemake.input.runs)},
        title="Double pendulum (Sect. 4): errors and claim verdicts",
        command="snakemake rule pendulum_summary",
    )
)
ds.attrs["claims_json"] = config_json(claims)
write_netcdf(ds, snakemake.output[0])
for row in ds["run"].values:
    r = ds.sel(run=row)
    logging.info(
        "%-24s observed %-8s err phi1 %.2e phi2 %.2e",
        row,
        str(r["observed"].values),
        float(r["err_phi1"]),
        float(r["err_phi2"]),
    )
