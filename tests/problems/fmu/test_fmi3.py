"""FMI 3.0: the force-driven test unit as an FMI 3.0 co-simulation unit (fmus/msd_fmi3, the same model code).
FMI 3.0 has no input derivatives, so it takes the sub-step route: bit for bit what the FMI 2.0 unit does on that
route, and coupled with the FMI 2.0 unit it follows the built-in model to second order in the sub-step."""

import numpy as np
import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.problems.fmu.run import run_scene

pytestmark = pytest.mark.fmu

SCENE = ROOT / "config" / "scenes" / "two_mass_fmi3.yaml"


def write(tmp_path, name, edit=None, steps=40):
    data = yaml.safe_load(SCENE.read_text())
    for sub in data["subsystems"].values():
        sub["fmu"] = str((SCENE.parent / sub["fmu"]).resolve())
    data["t_end"] = steps * data["coupling"]["H"]
    if edit:
        edit(data)
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def test_fmi3_unit_is_read_as_fmi3(tmp_path):
    run = run_scene(write(tmp_path, "fmi3.yaml"))
    body1 = run.units["body1"]
    assert body1["fmi_version"] == "3.0" and body1["model_name"] == "msd_fmi3"
    assert body1["guid"] == "{8c4e810f-3df3-4a00-8276-176fa3c9f001}"  # the instantiation token
    assert body1["inputs"] == "substeps (16)" and run.units["body2"]["inputs"] == "derivatives"


def test_fmi3_unit_equals_the_fmi2_unit_on_the_sub_step_route(tmp_path):
    def fmi2(data):
        data["subsystems"]["body1"]["fmu"] = str(ROOT / "fmus" / "msd")

    def both_substeps(data):
        data["coupling"]["inputs"] = "substeps"

    a = run_scene(write(tmp_path, "a.yaml", both_substeps))
    b = run_scene(write(tmp_path, "b.yaml", lambda d: (fmi2(d), both_substeps(d))))
    assert a.units["body1"]["fmi_version"] == "3.0" and b.units["body1"]["fmi_version"] == "2.0"
    np.testing.assert_array_equal(a.states, b.states)


def test_fmi3_unit_with_the_fmi2_unit_converges_with_the_sub_steps(tmp_path):
    """Against the FMI 2.0 pair with exact inputs (the built-in model to 1e-13,
    tests/problems/fmu/test_linear_scenes.py)."""

    def exact(data):
        data["subsystems"]["body1"]["fmu"] = str(ROOT / "fmus" / "msd")

    reference = run_scene(write(tmp_path, "ref.yaml", exact)).states[..., 0]
    errors = []
    for n in (8, 16):
        run = run_scene(write(tmp_path, f"n{n}.yaml", lambda d, n=n: d["coupling"].update(substeps=n)))
        errors.append(np.max(np.abs(run.states[..., 0] - reference)) / np.max(np.abs(reference)))
    assert errors[1] < 1e-5 and 3 < errors[0] / errors[1] < 5


def test_fmi3_refused_step(capsys, tmp_path):
    def fail(data):
        data["subsystems"]["body1"]["start"]["fail_time"] = 0.005

    out = tmp_path / "run.nc"
    assert main(["cosim", str(write(tmp_path, "fail.yaml", fail)), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "unit body1 refused macro step 6 at t = 0.005 s (doStep returned discard)" in err
    assert not out.exists()
