"""``icosim cosim`` on system files other tools wrote: OSP's quarter truck (its folder and its file) checked and
run; OMSimulator's DualMassOscillator by signal connections from an OSP file run; an SSP of signals without a
step size refused with status 2, and --check on a scene of signals whose units are missing: a row per unit."""

import re

import pytest
from helpers import ROOT
from toolchains import OUTSIDE

from icosim.cli import main
from icosim.io.netcdf import open_dataset

OSP = OUTSIDE / "osp-quarter-truck"


def test_an_ssp_system_of_signal_connections_without_a_step_or_with_check_is_refused_with_status_2(capsys, tmp_path):
    path = ROOT / "tests" / "data" / "omsimulator_ssp" / "LinearTransformation" / "SystemStructure.ssd"
    assert main(["cosim", str(path), "--check"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("icosim cosim: error: ") and "coupling: SSP 2.0 gives no step size" in err
    scene = tmp_path / "scene.yaml"
    scene.write_text(f"system: {path}\ncoupling: {{H: 0.1}}\nt_end: 1\n")
    assert main(["cosim", str(scene), "--check"]) == 2  # each unit's row: its file is not in the test data
    out = capsys.readouterr().out
    assert re.search(r"Add1: .*\n +open +refused +FMU file .*Add\.fmu does not exist", out) and out.endswith(
        "refused\n"
    )
    assert main(["cosim", str(scene), "--predict"]) == 2  # the system's units are not in the test data
    assert re.search(r"error: Add1: FMU file .*Add\.fmu does not exist", capsys.readouterr().err)


@pytest.mark.outside
def test_the_dual_mass_oscillator_by_signals_runs_from_a_scene(tmp_path):
    """OMSimulator's units and its test's four connections, held inputs, Jacobi, 1000 steps."""
    om = OUTSIDE / "omsimulator"
    scene = tmp_path / "scene.yaml"
    scene.write_text(
        f"subsystems:\n  system1: {{fmu: {om / 'DualMassOscillator.System1.fmu'}}}\n"
        f"  system2: {{fmu: {om / 'DualMassOscillator.System2.fmu'}, record: [mass2.s]}}\n"
        "connections:\n  - {from: system2.F, to: system1.F}\n  - {from: system1.x1, to: system2.x1}\n"
        "  - {from: system1.v1, to: system2.v1}\n  - {from: system1.a1, to: system2.a1}\n"
        "coupling: {H: 1.0e-3}\nt_end: 1\n"
    )
    out = tmp_path / "run.nc"
    assert main(["cosim", str(scene), "--out", str(out)]) == 0
    with open_dataset(out) as ds:
        assert ds.attrs["status"] == "completed" and ds.attrs["coupling"] == "explicit" and ds.sizes["time"] == 1001
        for name in ("system1.F", "system2.F", "system1.x1", "system2.x1", "system1.a1", "system2.mass2.s"):
            assert name in ds.data_vars, name
        assert float(ds["system1.x1"][0]) == 0.0 and float(ds["system2.mass2.s"][0]) == 0.5
        assert float(ds["system1.F"][0]) == float(ds["system2.F"][0]) == 5.0  # k2 x2_start at the start


@pytest.mark.outside
def test_the_osp_quarter_truck_passes_every_check_from_its_folder(capsys):
    assert main(["cosim", str(OSP), "--check"]) == 0
    out, err = capsys.readouterr()
    assert "note: the file gives no end time: the run ends 1 s after its start" in err
    assert (
        "ECCO step control: run as coupling.control {estimate: power-residual, H_min: 1e-05, H_max: 0.01, "
        "safety: 0.99, fac_min: 0.2, fac_max: 1.5, proportional_gain: 0.2, integral_gain: 0.15, "
        "relative_tolerance: 1e-06, absolute_tolerance: 1e-06} from the first step H = 0.0001 s"
    ) in err
    assert "joints chassis–wheel fd" in out and "H = 0.0001 s" in out and out.rstrip().endswith("every check passed")


@pytest.mark.outside
def test_the_osp_quarter_truck_runs_from_a_scene_naming_it(capsys, tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text(f"system: {OSP / 'OspSystemStructure.xml'}\nt_end: 0.01\n")
    out = tmp_path / "run.nc"
    assert main(["cosim", str(scene), "--out", str(out)]) == 0
    (steps,) = re.findall(r"completed: (\d+) macro steps to t = 0.01 s", capsys.readouterr().out)
    with open_dataset(out) as ds:  # the file's ECCO control: steps of varying size
        assert {"chassis.force", "chassis.velocity", "joint_force", "macro_step_size", "power_residual"} <= set(
            ds.data_vars
        )
        assert ds.sizes["time"] == int(steps) + 1 == ds.attrs["control_accepted_steps"] + 1
