"""The peers study's configurations as the workflow merges them, and small datasets of the study made by hand (icosim.studies.peers.study.system_dataset): the report's, the
figure's and the claims' tests read them, with numbers chosen in the test, not measured."""

from __future__ import annotations

import copy
import math

import yaml
from helpers import ROOT

from icosim.studies.peers.study import system_dataset


def merged(base: dict, over: dict) -> dict:
    """``over`` merged into a copy of ``base`` as Snakemake merges config files (mappings key by key)."""
    out = copy.deepcopy(base)
    for key, value in over.items():
        out[key] = merged(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


#: The study's default configuration and the CI one merged over it.
DEFAULT = yaml.safe_load((ROOT / "config" / "peers.yaml").read_text())["peers"]
CI = merged(DEFAULT, yaml.safe_load((ROOT / "config" / "ci" / "peers.yaml").read_text())["peers"])

LEVELS = [1e-2, 1e-3, 1e-4]
INFO = {"cpu_seconds": 1.0, "load_start": [0.5, 0.5, 0.5], "load_end": [0.5, 0.5, 0.5], "reference": "exact",
        "version_icosim": "0", "version_libcosim": "0", "version_Ecos": "0", "version_FMPy": "missing: fmpy (test)"}  # fmt: skip


def run(master, step, error, wall, do_steps, macro_steps, *, series=None, status="completed", check_steps=0.0,
        interface="co-simulation", tolerance=math.nan):  # fmt: skip
    """A DualMassOscillator run whose x1 is ``error`` above its reference (x2 on it)."""
    series = series or f"{master}, fixed step"
    out = {"master": master, "series": series, "setting": f"{series}, h = {step:g}", "step": step,
           "tolerance": tolerance, "interface": interface, "status": status}  # fmt: skip
    if status == "completed":
        out |= {"t": 1.0, "x1": 0.25 + error, "x2": 0.5, "reference": {"x1": 0.25, "x2": 0.5}, "wall": wall,
                "timed_runs": 3, "do_steps": do_steps, "macro_steps": macro_steps, "check_steps": check_steps}  # fmt: skip
    return out


def dataset(rows, levels=LEVELS):
    """The DualMassOscillator dataset of ``rows`` as the figure, the report and the claims read it (xarray)."""
    cfg = {"repeat": 3, "budget": 1.0, "warmup": 0.1, "levels": levels,
           "systems": {"dual_mass": {"units_dir": ".", "t_end": 1.0, "series": []}}}  # fmt: skip
    return system_dataset(cfg, "dual_mass", rows, None, INFO).to_xarray()
