"""Snakemake job: the paper's convergence claims evaluated on the panel datasets -> JSON."""

import json
import logging

import yaml

from icosim.convergence import evaluate_claims
from icosim.datasets import atomic_path, open_dataset

snakemake = snakemake  # noqa: F821 (injected by Snakemake)

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
with open(snakemake.input.claims) as fh:
    claims = yaml.safe_load(fh)
results = evaluate_claims(claims, [open_dataset(p) for p in snakemake.input.panels])
mismatch = []
for claim, res in zip(claims["claims"], results):
    logging.info("%s: %s (reference %s)", res["id"], res["verdict"], res["reference"])
    if claim.get("ci") and res["reference"] is not None and res["verdict"] != res["reference"]:
        mismatch.append(f"{res['id']}: {res['verdict']} (reference {res['reference']})")
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(json.dumps({"tolerance": claims.get("tolerance"), "claims": results}, indent=1, default=str))
if snakemake.params.enforce_reference and mismatch:
    raise SystemExit("claims differ from their full-run reference verdicts: " + "; ".join(mismatch))
