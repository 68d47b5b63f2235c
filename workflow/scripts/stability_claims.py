"""Snakemake job: evaluate the paper's stability claims on the panel datasets.

Writes every verdict (pass / fail / undecided, with the numbers measured) as JSON
and TSV.  The data stand: a claim the data contradict is reported, not an error.
With ``enforce_reference`` (the CI configuration) the job fails if a claim marked
``ci: true`` gets a verdict other than its recorded full-resolution ``reference``,
i.e. if the reduced grid no longer reproduces what the full grid decided.
"""

import csv
import json
import logging

from icosim.claims import evaluate, load_claims
from icosim.datasets import atomic_path, open_dataset

snakemake = snakemake  # noqa: F821 (injected by Snakemake)

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
datasets = [open_dataset(path) for path in snakemake.input.panels]
claims = load_claims(snakemake.input.claims)
verdicts = evaluate(claims, datasets)

for v in verdicts:
    logging.info("%-9s %-45s %s", v.verdict, v.claim.id, v.measured)

mismatched = [v for v in verdicts if v.claim.ci and v.matches_reference is False]
if snakemake.params.enforce_reference and mismatched:
    lines = [
        f"  {v.claim.id}: verdict {v.verdict}, reference {v.claim.reference} ({v.measured})"
        for v in mismatched
    ]
    raise SystemExit(
        "claims marked ci: true did not reproduce their full-resolution reference verdict:\n"
        + "\n".join(lines)
    )

records = [v.as_dict() for v in verdicts]
with atomic_path(snakemake.output.json) as tmp:
    tmp.write_text(json.dumps({"claims": records}, indent=1, default=float))
with atomic_path(snakemake.output.tsv) as tmp, open(tmp, "w", newline="") as fh:
    w = csv.writer(fh, delimiter="\t")
    w.writerow(["id", "source", "figures", "statement", "verdict", "reference", "measured"])
    for r in records:
        w.writerow(
            [
                r["id"],
                r["source"],
                " ".join(r["figures"]),
                r["statement"],
                r["verdict"],
                r["reference"] or "",
                r["measured"],
            ]
        )
logging.info(
    "%d claims: %s",
    len(records),
    {k: sum(r["verdict"] == k for r in records) for k in ("pass", "fail", "undecided")},
)
