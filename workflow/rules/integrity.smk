# Datasets lost since an earlier run are built again, with what is built from them.  Included after
# every rule: it reads the rules' inputs and outputs.
#
# quarantine_corrupt (common.smk) set aside every dataset that failed its SHA-256 (x.nc.corrupt); a
# dataset deleted by hand leaves its sidecar (x.nc.sha256).  Snakemake does not rerun a job whose output
# is missing when everything built from it is present and up to date, so the outputs of the jobs that
# read a lost dataset are removed: a target that needs them (a one-figure target, the claims, `all`)
# builds the dataset again first, and what is downstream of them follows as usual.  Every dataset is
# also a target of `all` (the parts' ALL_TARGETS), so `snakemake -c2` builds a missing one without a trace.
from icosim.io.integrity import lost_datasets, outputs_built_from  # noqa: E402

if workflow.is_main_process:
    _RULE_FILES = [
        (
            [str(f) for f in r.input if isinstance(f, str)],
            [str(f) for f in r.output],
        )
        for r in workflow.rules
    ]
    for _lost in lost_datasets("results"):
        _built = [p for p in outputs_built_from(_lost, _RULE_FILES) if Path(p).exists()]
        for _out in _built:
            Path(_out).unlink()
        logger.warning(
            f"icosim: {_lost} is missing: it will be recomputed"
            + (f", and {len(_built)} outputs built from it ({', '.join(_built)})" if _built else "")
        )
