"""Faults of a unit (fmus/faulty, a unit that fails on purpose): a step that warns, is discarded, errs or fails
fatally, an output that is not finite, a step that never returns, a crash of the process, a state that is not
restored, a unit that refuses to initialise.  Each stops ``icosim cosim`` with one line naming the unit, the
call and the macro step (status 2), and no dataset is left; a warning is counted and the run goes on."""

import os

import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.io.netcdf import open_dataset

FMUS = ROOT / "fmus"
pytestmark = [pytest.mark.fmu, pytest.mark.skipif(not hasattr(os, "fork"), reason="the supervised run needs os.fork")]


def scene(tmp_path, fault, fault_time=0.005, **top):
    faulty = {"fmu": str(FMUS / "faulty"), "start": {"m": 1.0, "c": 1000.0, "d": 2.0, "x0": 0.1, "fault": fault,
              "fault_time": fault_time}, "position": "x", "velocity": "v", "acceleration": "a", "force": "lambda",
              "force_sign": 1}  # fmt: skip
    other = {"fmu": str(FMUS / "msd"), "start": {"m": 2.0, "c": 500.0, "d": 1.0, "x0": 0.1}, "position": "x",
             "velocity": "v", "acceleration": "a", "force": "lambda", "force_sign": -1}  # fmt: skip
    data = {"subsystems": {"faulty": faulty, "other": other}, "t_end": 0.02,
            "coupling": {"method": "baumgarte", "index": 1, "mu": 1e-3, "decomposition": "ff", "k": 1, "H": 1e-3}}  # fmt: skip
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data | top))
    return path


def run(capsys, tmp_path, path):
    out = tmp_path / "run.nc"
    status = main(["cosim", str(path), "--out", str(out)])
    captured = capsys.readouterr()
    return status, captured.out, captured.err.strip(), out


@pytest.mark.parametrize(
    "fault, needles",
    [
        (2, ["unit faulty refused macro step 6 at t = 0.005 s (doStep returned discard)", "step rejected"]),
        (3, ["unit faulty refused macro step 6", "(doStep returned error)", "the unit said:"]),
        (4, ["unit faulty refused macro step 6", "(doStep returned fatal)", "the unit said:"]),
        (5, ["unit faulty returned acceleration a = nan in macro step 6", "although its input was finite"]),
        (6, ["unit faulty returned position x = inf in macro step 6"]),
        (9, ["faulty: rollback: its position", "differs after a repeated step"]),
        (10, ["faulty: could not be initialised", "no licence for this unit"]),
    ],
)
def test_a_unit_fault_is_named_and_nothing_is_written(capsys, tmp_path, fault, needles):
    status, _, err, out = run(capsys, tmp_path, scene(tmp_path, fault, fault_time=0.0 if fault >= 9 else 0.005))
    assert status == 2 and len(err.splitlines()) == 1 and err.startswith("icosim cosim: error: "), err
    for needle in needles:
        assert needle in err, err
    assert not out.exists() and not list(tmp_path.glob(".run.nc*"))


def test_a_warning_is_counted_and_the_run_goes_on(capsys, tmp_path):
    status, text, _, out = run(capsys, tmp_path, scene(tmp_path, 1))
    assert status == 0 and "warnings (first:" in text
    attrs = open_dataset(out).attrs
    assert attrs["faulty_warnings"] == 15 * 3  # macro steps 6 .. 20, three doStep calls each, warn
    assert attrs["other_warnings"] == 0


def test_a_unit_that_hangs_is_stopped_after_the_call_limit(capsys, tmp_path):
    status, _, err, out = run(capsys, tmp_path, scene(tmp_path, 7, limits={"call_seconds": 1.0}))
    assert status == 2
    assert "unit faulty did not return from fmi2DoStep within 1 s (macro step 6, t = 0.005 s)" in err
    assert "limits.call_seconds" in err and "no dataset written" in err
    assert not out.exists() and not list(tmp_path.glob(".run.nc*"))


def test_a_unit_that_crashes_the_process_is_named(capsys, tmp_path):
    status, _, err, out = run(capsys, tmp_path, scene(tmp_path, 8))
    assert status == 2
    assert "unit faulty crashed the process in fmi2DoStep (SIGSEGV, macro step 6, t = 0.005 s)" in err
    assert not out.exists() and not list(tmp_path.glob(".run.nc*"))
