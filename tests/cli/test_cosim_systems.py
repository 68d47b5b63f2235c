"""``icosim cosim`` on system files other tools wrote: OSP's quarter truck (its folder and its file) checked and
run, an SSP with a signal connection refused with status 2 naming the connection."""

import re

import pytest
from helpers import ROOT
from toolchains import OUTSIDE

from icosim.cli import main
from icosim.io.netcdf import open_dataset

OSP = OUTSIDE / "osp-quarter-truck"


def test_an_ssp_system_with_a_signal_connection_is_refused_with_status_2(capsys):
    path = ROOT / "tests" / "data" / "omsimulator_ssp" / "LinearTransformation" / "SystemStructure.ssd"
    assert main(["cosim", str(path), "--check"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("icosim cosim: error: ") and "connection Gain1.y -> Add1.u1" in err
    assert "signal connections" in err


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
