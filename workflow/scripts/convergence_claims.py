"""Snakemake job: the paper's convergence claims evaluated on the panel datasets -> JSON.

With ``enforce_reference`` (the CI configuration) the job fails, before writing
anything, if a claim marked ``ci: true`` gets a verdict other than its recorded
full-run ``reference``: a failed job leaves no complete-looking result.
"""

import json
import logging

from icosim.convergence import evaluate_claims, load_claims
from icosim.datasets import atomic_path, open_dataset

snakemake = snakemake  # noqa: F821 (injected by Snakemake)

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
claims = load_claims(snakemake.input.claims)
results = evaluate_claims(claims, [open_dataset(p) for p in snakemake.input.panels])
mismatch = []
for claim, res in zip(claims["claims"], results):
    logging.info("%s: %s (reference %s)", res["id"], res["verdict"], res["reference"])
    if claim.get("ci") and res["reference"] is not None and res["verdict"] != res["reference"]:
        mismatch.append(f"{res['id']}: {res['verdict']} (reference {res['reference']})")
if snakemake.params.enforce_reference and mismatch:
    raise SystemExit("claims differ from their full-run reference verdicts: " + "; ".join(mismatch))
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(json.dumps({"tolerance": claims["tolerance"], "claims": results}, indent=1, default=str))
