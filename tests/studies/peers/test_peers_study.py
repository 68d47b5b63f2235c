"""The peers study's runs on the other tools' units (icosim.studies.peers.study), on a tiny configuration: every
configured run is in the dataset, its errors are its end values against the reference recomputed here -- the
DualMassOscillator's exact solution with the parameters of the Modelica source (not the units' model
descriptions the study reads), the quarter truck's reference extrapolated again from the dataset's own plain
reference runs -- and a master that is not installed is a run with the reason.

Marked ``peers`` (tests/toolchains.py): the outside units, fmpy and the peer packages.  No timing is asserted."""

import math

import numpy as np
import pytest
from toolchains import OUTSIDE

from icosim.problems.fmu.dual_mass import DualMass
from icosim.studies.peers import study
from icosim.studies.peers.config import system_runs

pytestmark = pytest.mark.peers

CFG = {
    "repeat": 1, "budget": 0.1, "warmup": 0.1, "levels": [1e-2, 1e-3, 1e-4],
    "systems": {
        "dual_mass": {"units_dir": str(OUTSIDE / "omsimulator"), "t_end": 0.1, "series": [
            {"master": "libcosim", "steps": [1e-3]}, {"master": "Ecos", "steps": [1e-3]},
            {"master": "FMPy", "steps": [1e-3]},
            {"master": "icosim", "k": 2, "tolerance": 1e-8, "sensitivities": "first-step", "steps": [1e-2]}]},
        "quarter_truck": {"units_dir": str(OUTSIDE / "osp-quarter-truck"), "t_end": 0.05,
                          "units": {"solver": "Euler", "time_step": 1e-5},
                          "reference": {"solver": "RK4", "steps": [1e-4, 5e-5, 2.5e-5]}, "series": [
            {"master": "libcosim", "algorithm": "fixed-step", "steps": [1e-3]},
            {"master": "libcosim", "algorithm": "ecco", "step": 1e-4, "tolerances": [1e-4]},
            {"master": "Ecos", "steps": [1e-3]}, {"master": "FMPy", "steps": [1e-3]},
            {"master": "icosim", "k": 1, "substeps": 4, "sensitivities": "first-step", "steps": [5e-3]}]},
    },
}  # fmt: skip


@pytest.fixture(scope="module")
def datasets():
    return {s: study.system_data(CFG, s).to_xarray() for s in CFG["systems"]}


def test_every_configured_run_is_in_the_dataset_with_one_dostep_per_unit_and_macro_step(datasets):
    for system, ds in datasets.items():
        assert list(ds["setting"].values) == [r["setting"] for r in system_runs(CFG, system)]
        for i, master in enumerate(ds["master"].values):
            status = str(ds["status"].values[i])
            if master == "FMPy" and system == "quarter_truck":
                assert status.startswith("not run: simulate_ssp"), status  # the reason, not a gap
                continue
            assert status == "completed", (system, master, status)
            if master in ("libcosim", "Ecos") and math.isnan(float(ds["tolerance"].values[i])):
                steps = CFG["systems"][system]["t_end"] / float(ds["step"].values[i])
                assert float(ds["do_steps"].values[i]) == pytest.approx(2 * steps)  # two units


def test_the_dual_mass_errors_are_the_end_values_against_the_modelica_equations(datasets):
    ds = datasets["dual_mass"]
    exact = DualMass.from_modelica(OUTSIDE / "omsimulator" / "DualMassOscillator.mo").exact(ds["t"].values)
    errors = np.abs(np.stack([ds["end_x1"].values, ds["end_x2"].values], axis=1) - exact[:, :2])
    assert np.allclose(errors.max(axis=1), ds["error"].values, rtol=1e-9, atol=1e-15)
    assert np.all(ds["error"].values > 0)


def test_the_truck_errors_are_the_end_values_against_the_extrapolated_reference(datasets):
    ds = datasets["quarter_truck"]
    h = ds["reference_step"].values
    r = h[:-1] / h[1:]
    ref = {}
    for q in ("x", "v", "a"):
        plain = ds[f"reference_plain_{q}"].values
        ref[q] = ((r * plain[1:] - plain[:-1]) / (r - 1))[-1]  # Richardson, first order
    assert ref["x"] == pytest.approx(ds.attrs["reference_x"], rel=1e-12)
    dt = ds["t"].values - CFG["systems"]["quarter_truck"]["t_end"]  # ECCO may end past the stop time
    x = ref["x"] + ref["v"] * dt + 0.5 * ref["a"] * dt**2
    done = ds["status"].values == "completed"
    assert np.allclose(np.abs(ds["end_x"].values - x)[done], ds["error"].values[done], rtol=1e-9, atol=1e-15)
    assert np.all(np.isnan(ds["error"].values[~done]))


def test_a_master_not_installed_is_a_run_with_the_reason(monkeypatch):
    versions = {"icosim": "0", "FMPy": "missing: fmpy (test)", "libcosim": "missing: libcosimpy (test)",
                "Ecos": "missing: ecospy (test)"}  # fmt: skip
    monkeypatch.setattr(study, "installed", lambda: versions)
    cfg = {**CFG, "systems": {"dual_mass": {**CFG["systems"]["dual_mass"],
                                            "series": CFG["systems"]["dual_mass"]["series"][:3]}}}  # fmt: skip
    ds = study.system_data(cfg, "dual_mass").to_xarray()
    assert list(ds["status"].values) == [versions[m] for m in ("libcosim", "Ecos", "FMPy")]
    assert np.all(np.isnan(ds["error"].values))


def test_the_sections_fastest_runs_and_losses_hold_on_the_measured_runs(datasets):
    """What the report says per level, checked run by run: each master's named run is its quickest with the error
    at most the level, and where icosim does not win the peer's run took less time."""
    from icosim.studies.peers.fastest import fastest, not_won, runs

    for ds in datasets.values():
        rows = [r for r in runs(ds) if r["status"] == "completed"]
        table = fastest(rows, ds.attrs["levels"])
        for e in table:
            for master, r in e["best"].items():
                within = [q["wall"] for q in rows if q["master"] == master and q["error"] <= e["level"]]
                assert r["error"] <= e["level"] and r["wall"] == min(within)
        for w in not_won(table):
            assert w["icosim"] is None or w["peer_run"]["wall"] < w["icosim"]["wall"]
