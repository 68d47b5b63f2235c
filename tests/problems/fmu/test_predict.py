"""``icosim cosim --predict``: the units identified from probing steps (m, c, d of the linear test units to
1e-10) and the spectral radius of the scene's coupling for every scheme, as for the parameters typed in."""

import json

import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.problems.fmu.predict import predict_scene
from icosim.problems.fmu.scene import load_scene
from icosim.problems.linear.model import PhysicalModel
from icosim.problems.linear.spectral import spectral_radius_float64

pytestmark = pytest.mark.fmu

SCENES = ROOT / "config" / "scenes"


@pytest.mark.parametrize("name", ["two_mass_ff", "two_mass_fd", "two_mass_dd", "two_mass_python", "two_mass_fmi3"])
def test_prediction_matches_the_parameters_typed_in(name):
    scene = load_scene(SCENES / f"{name}.yaml")
    answer = predict_scene(scene)
    starts = [sub["start"] for sub in scene.data["subsystems"].values()]
    for unit, start in zip(answer["units"].values(), starts):
        # probing steps move a unit by about 1 % of its position scale: c and d come from those changes, which
        # carry the rounding of the outputs two orders of magnitude up
        for key in ("m", "c", "d"):
            assert unit[key] == pytest.approx(start[key], rel=1e-10)
        assert unit["misfit"] < 1e-11
    true = PhysicalModel(
        m1=starts[0]["m"], m2=starts[1]["m"], c1=starts[0]["c"], c2=starts[1]["c"], d1=starts[0]["d"],
        d2=starts[1]["d"], H=scene.coupling["H"],
    )  # fmt: skip
    assert [row["scene"] for row in answer["schemes"]].count(True) == 1
    for row in answer["schemes"]:
        rho, _ = spectral_radius_float64(
            true.coefficients(),
            scene.method,
            scene.coupling["decomposition"],
            scene.coupling["k"],
            scheme=row["scheme"],
        )
        assert row["rho"] == pytest.approx(float(rho), rel=1e-9)
        assert row["verdict"] == ("stable" if rho < 1 else "unstable")


def test_predict_on_the_command_line(capsys):
    assert main(["cosim", str(SCENES / "two_mass_fd.yaml"), "--predict"]) == 0
    text = capsys.readouterr().out
    assert "body2 identified: m = 2 kg, c = 500 N/m, d = 1 N s/m" in text
    assert "* jacobi" in text and "gauss-seidel-12" in text and "unstable" in text
    assert main(["cosim", str(SCENES / "two_mass_fd.yaml"), "--predict", "--json"]) == 0
    answer = json.loads(capsys.readouterr().out)
    assert {row["scheme"] for row in answer["schemes"]} >= {"jacobi", "gauss-seidel-12", "gauss-seidel-21"}


def test_a_unit_that_is_not_linear_is_reported(capsys, tmp_path):
    """The Python unit with a cubic spring: the probes' linear model misfits, and the text says so."""
    data = yaml.safe_load((SCENES / "two_mass_python.yaml").read_text())
    for sub in data["subsystems"].values():
        sub["fmu"] = str((SCENES / sub["fmu"]).resolve())
    data["subsystems"]["body1"]["start"]["c3"] = 1.0e6
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["cosim", str(path), "--predict"]) == 0
    text = capsys.readouterr().out
    assert "body1 is not a linear oscillator" in text and "body2 is not" not in text
