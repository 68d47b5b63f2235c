"""Roles that fit the unit: a compliant unit (velocity in, force out; OSP's Wheel) named in a kinematic role is refused
from its measured response, and in any role from a velocity its model description declares (a unit of measure or
a quantity); a force-driven unit named kinematic is refused; the kinematically driven test units pass."""

import json
import os
import re
import zipfile

import pytest
import yaml
from helpers import ROOT
from toolchains import OUTSIDE

from icosim.cli import main
from icosim.problems.fmu.build import build_unit

FMUS = ROOT / "fmus"
pytestmark = [pytest.mark.fmu, pytest.mark.skipif(not hasattr(os, "fork"), reason="the supervised run needs os.fork")]

# OSP's Wheel (its sources/OSP/Wheel/src/system.cpp): m a = kc (x_in - x) + dc (v_in - v) - kw (x - groundPos)
WHEEL_M, WHEEL_DC = 40.0, 1000.0
MSD = {"fmu": str(FMUS / "msd"), "start": {"m": 1.0, "c": 1000.0, "d": 2.0, "x0": 0.0}, "position": "x",
       "velocity": "v", "acceleration": "a", "force": "lambda", "force_sign": 1}  # fmt: skip


def scene(tmp_path, other, decomposition):
    data = {"subsystems": {"body": MSD, "other": other}, "t_end": 0.01, "initial": "as-is",
            "coupling": {"method": "baumgarte", "index": 1, "mu": 1e-3, "decomposition": decomposition, "k": 1,
                         "H": 1e-3}}  # fmt: skip
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def check(capsys, path):
    status = main(["cosim", str(path), "--check", "--json"])
    report = json.loads(capsys.readouterr().out)
    return status, {r["check"]: r for r in report["units"][1]["findings"]}


def edited(source, tmp_path, edit):
    """``source`` (an .fmu) with its modelDescription.xml passed through ``edit``."""
    target = tmp_path / f"edited-{source.name}"
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            zout.writestr(item, edit(data.decode()).encode() if item.filename == "modelDescription.xml" else data)
    return target


def wheel(fmu=None, kinematic=True):
    roles = ({"acceleration_input": "in_vel", "reaction_force": "out_spring_damper_f"} if kinematic
             else {"force": "in_vel"})  # fmt: skip
    return {"fmu": str(fmu or OUTSIDE / "osp-quarter-truck" / "Wheel.fmu"), "position": "position",
            "velocity": "velocity", "acceleration": "acceleration", "force_sign": -1, **roles}  # fmt: skip


@pytest.mark.outside
def test_the_wheel_in_a_kinematic_role_is_refused_as_compliant(capsys, tmp_path):
    status, found = check(capsys, scene(tmp_path, wheel(), "fd"))
    role = found["role"]
    assert status == 2 and role["verdict"] == "refused", role
    assert "the input does not prescribe the motion of the point it outputs" in role["detail"]
    assert "a compliant unit (velocity in, force out): join it as a drive through its velocity" in role["detail"]
    numbers = re.search(
        r"moves by ([-+.\d]+) m/s\^2 .* its drive force moves by ([-+.\d]+) N, ([-+.\d]+) kg", role["detail"]
    )
    accel, force, mass = (float(v) for v in numbers.groups())
    # a velocity held at 1 m/s on the damper: the force dc, the wheel's acceleration dc / m, to the step's decay of
    # the damper's relative velocity (dc H / m = 2.5 % at H = 1e-3 s)
    assert accel == pytest.approx(WHEEL_DC / WHEEL_M, rel=3e-2)
    assert force == pytest.approx(WHEEL_DC, rel=3e-2)
    assert mass == pytest.approx(WHEEL_M, rel=1e-2)
    # and a run is refused the same way, one line
    status = main(["cosim", str(scene(tmp_path, wheel(), "fd")), "--out", str(tmp_path / "run.nc")])
    err = capsys.readouterr().err.strip()
    assert status == 2 and "icosim cosim: error: other: role: " in err and "compliant unit" in err


@pytest.mark.outside
@pytest.mark.parametrize("kinematic", [False, True])
def test_a_wheel_declaring_its_input_a_velocity_is_refused_in_every_role(capsys, tmp_path, kinematic):
    fmu = edited(
        OUTSIDE / "osp-quarter-truck" / "Wheel.fmu",
        tmp_path,
        lambda xml: xml.replace('name="in_vel" valueReference="7" variability="discrete" causality="input">\n'
                                '\t\t\t<Real start="0.000000"/>', 'name="in_vel" valueReference="7" '
                                'variability="discrete" causality="input">\n\t\t\t<Real unit="m/s" start="0.0"/>'),
    )  # fmt: skip
    status, found = check(capsys, scene(tmp_path, wheel(fmu, kinematic), "fd" if kinematic else "ff"))
    key = "acceleration_input" if kinematic else "force"
    assert status == 2 and found["open"]["verdict"] == "refused"
    assert f"{key}: 'in_vel' is in m/s (m s^-1)" in found["open"]["detail"]
    assert "the unit takes a velocity, a compliant unit (velocity in, force out)" in found["open"]["detail"]


def test_a_force_input_declared_a_velocity_quantity_is_refused(capsys, tmp_path):
    fmu = edited(
        build_unit(FMUS / "msd"),
        tmp_path,
        lambda xml: xml.replace('<Real start="0.0" unit="N"/>', '<Real start="0.0" quantity="Velocity"/>'),
    )
    status, found = check(capsys, scene(tmp_path, MSD | {"fmu": str(fmu), "force_sign": -1}, "ff"))
    assert status == 2
    assert "force: 'lambda' is declared a Velocity (quantity)" in found["open"]["detail"]
    assert "compliant unit" in found["open"]["detail"]


def test_a_force_driven_unit_named_kinematic_is_refused(capsys, tmp_path):
    # without its units of measure (which alone would refuse a force as an acceleration): the measured check
    fmu = edited(build_unit(FMUS / "msd"), tmp_path, lambda xml: re.sub(r' unit="[^"]*"', "", xml))
    other = MSD | {"fmu": str(fmu), "start": {"m": 2.0, "c": 500.0, "d": 1.0, "x0": 0.0}, "force_sign": -1}
    other = {k: v for k, v in other.items() if k != "force"} | {"acceleration_input": "lambda", "reaction_force": "a"}
    status, found = check(capsys, scene(tmp_path, other, "fd"))
    role = found["role"]
    assert status == 2 and role["verdict"] == "refused"
    # a force of 1 N on 2 kg (read as 1 m/s^2): the acceleration moves by 1/m, the velocity by H/m
    accel, vel = (
        float(v) for v in re.search(r"moves by ([-+.\d]+) m/s\^2 .* by ([-+.\de]+) m/s", role["detail"]).groups()
    )
    assert accel == pytest.approx(0.5, rel=1e-3) and vel == pytest.approx(0.5e-3, rel=1e-3)


@pytest.mark.parametrize("name", ["two_mass_fd", "two_mass_dd", "double_pendulum_fd"])
def test_kinematically_driven_units_fit_their_role(capsys, name):
    status = main(["cosim", str(ROOT / "config" / "scenes" / f"{name}.yaml"), "--check", "--json"])
    report = json.loads(capsys.readouterr().out)
    roles = [r for u in report["units"] for r in u["findings"] if r["check"] == "role"]
    assert status == 0 and roles and all(r["verdict"] == "pass" for r in roles), roles
