"""Snakemake job (every part): the paper's claims evaluated on the part's datasets.

Writes every verdict (pass / fail / undecided, with the numbers measured) as JSON
and TSV.  The data stand: a claim the data contradict is reported, not an error.
With ``enforce_reference`` (the CI configuration) the job fails, before writing
anything, if a claim marked ``ci: true`` gets a verdict other than its recorded
full-resolution ``reference``: the reduced run no longer reproduces the full one.
"""

import logging

from icosim.claims.registry import evaluate, load_claims
from icosim.io.netcdf import open_dataset, open_variables
from icosim.job import start_job
from icosim.verdicts import enforce_references, verdict_counts, write_verdicts

start_job(snakemake.log[0])
claims = load_claims(snakemake.input.claims)
# a part whose checks name the variables they read (params.variables) has only those read
variables = getattr(snakemake.params, "variables", None)
datasets = [open_variables(p, variables) if variables else open_dataset(p) for p in snakemake.input.datasets]
verdicts = evaluate(claims, datasets)
for v in verdicts:
    logging.info("%-9s %-45s (reference %s) %s", v.verdict, v.claim.id, v.claim.reference, v.measured)
enforce_references(verdicts, snakemake.params.enforce_reference)
records = write_verdicts(verdicts, snakemake.output.json, snakemake.output.tsv)
logging.info("%d claims: %s", len(records), verdict_counts(records))
