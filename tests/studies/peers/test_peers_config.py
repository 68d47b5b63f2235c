"""The peers study's configuration (icosim.studies.peers.config): the configured series expand into the runs of
each system, and a master, key or value the study does not know is refused, naming the series and the allowed
values.  No unit is opened."""

import math

import pytest
from peers_data import CI, DEFAULT

from icosim.problems.fmu.errors import SceneError
from icosim.studies.peers.config import CANNOT_RUN, check_config, system_runs


@pytest.mark.parametrize("cfg", [DEFAULT, CI], ids=["default", "ci"])
def test_every_configured_value_is_a_run_and_every_master_of_the_study_appears(cfg):
    runs = check_config(cfg)
    for system, system_cfg in cfg["systems"].items():
        expected = sum(len(s.get("tolerances", s.get("steps"))) for s in system_cfg["series"])
        assert len(runs[system]) == expected
        assert {r["master"] for r in runs[system]} == {"libcosim", "Ecos", "FMPy", "icosim"}
        assert len({r["setting"] for r in runs[system]}) == expected
    assert ("quarter_truck", "FMPy") in CANNOT_RUN  # a row with the reason, not a gap


def test_ecco_runs_at_its_initial_step_with_the_tolerance_varied():
    cfg = {"systems": {"quarter_truck": {"t_end": 1.0, "series": [
        {"master": "libcosim", "algorithm": "ecco", "step": 1e-4, "tolerances": [1e-4, 1e-6]}]}}}  # fmt: skip
    runs = system_runs(cfg, "quarter_truck")
    assert [(r["step"], r["tolerance"]) for r in runs] == [(1e-4, 1e-4), (1e-4, 1e-6)]
    assert all(math.isnan(r["tolerance"]) for r in system_runs(DEFAULT, "dual_mass"))


def _one(system, series, t_end=1.0):
    return {"systems": {system: {"t_end": t_end, "series": [series]}}}


@pytest.mark.parametrize(
    ("system", "series", "message"),
    [
        ("dual_mass", {"master": "OMSimulator", "steps": [1e-3]}, "allowed: libcosim, Ecos, FMPy, icosim"),
        ("dual_mass", {"master": "libcosim", "algorithm": "ecco", "tolerances": [1e-4]}, "ecco runs on quarter_truck"),
        ("dual_mass", {"master": "Ecos", "steps": [1e-3], "substeps": 4}, "unknown key 'substeps'"),
        ("dual_mass", {"master": "icosim", "steps": [1e-2]}, "series[0].k: required"),
        ("dual_mass", {"master": "icosim", "k": 1, "sensitivities": "never", "steps": [1e-2]}, "allowed: each-step"),
        ("dual_mass", {"master": "Ecos", "steps": [3e-3]}, "does not divide t_end"),
        ("dual_mass", {"master": "Ecos", "steps": []}, "a non-empty list"),
        ("quarter_truck", {"master": "libcosim", "algorithm": "ecco", "tolerances": [1e-4]}, "step: required"),
        (
            "quarter_truck",
            {"master": "libcosim", "algorithm": "adaptive", "steps": [1e-3]},
            "allowed: fixed-step, ecco",
        ),
    ],
)
def test_a_series_the_study_does_not_know_is_refused_by_name(system, series, message):
    with pytest.raises(SceneError, match="peers.systems") as err:
        system_runs(_one(system, series), system)
    assert message in str(err.value)


def test_a_run_configured_twice_and_an_unknown_system_are_refused():
    twice = {"systems": {"dual_mass": {"t_end": 1.0, "series": [{"master": "Ecos", "steps": [1e-3]},
                                                               {"master": "Ecos", "steps": [1e-3]}]}}}  # fmt: skip
    with pytest.raises(SceneError, match="configured twice"):
        system_runs(twice, "dual_mass")
    with pytest.raises(SceneError, match="allowed: quarter_truck, dual_mass"):
        system_runs({"systems": {"pendulum": {}}}, "pendulum")
