"""``record: [names]`` per subsystem: the named variables, read with the getter of their own type at ``t_start`` and
after each accepted macro step, in the dataset as ``<subsystem>.<variable>(time)``; a name the unit lacks, the
independent variable or a String is refused naming the unit and the variable.  On fmus/ and on units of other
tools: OSP's Chassis (value references shared between types), the Reference-FMUs' StateSpace (FMI 3.0 locals,
array elements, a structural parameter)."""

import json
import os

import numpy as np
import pytest
import yaml
from helpers import ROOT
from toolchains import OUTSIDE

from icosim.cli import main
from icosim.io.netcdf import open_dataset

FMUS = ROOT / "fmus"
pytestmark = [pytest.mark.fmu, pytest.mark.skipif(not hasattr(os, "fork"), reason="the supervised run needs os.fork")]


def msd(i, **over):
    return {"fmu": str(FMUS / "msd"), "start": {"m": float(i), "c": 1000.0 / i, "d": 2.0, "x0": 0.1},
            "position": "x", "velocity": "v", "acceleration": "a", "force": "lambda",
            "force_sign": 1 if i == 1 else -1, **over}  # fmt: skip


def scene(tmp_path, first, second, **coupling):
    data = {"subsystems": dict([first, second]),
            "coupling": {"method": "baumgarte", "index": 1, "mu": 1e-3, "decomposition": "ff", "k": 1, "H": 1e-3,
                         **coupling},
            "t_end": 0.02, "initial": "as-is"}  # fmt: skip
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def run(capsys, tmp_path, path):
    out = tmp_path / "run.nc"
    status = main(["cosim", str(path), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 0, err
    return open_dataset(out)


def refused(capsys, path):
    status = main(["cosim", str(path), "--out", str(path.parent / "run.nc")])
    err = capsys.readouterr().err.strip()
    assert status == 2 and len(err.splitlines()) == 1, err
    status = main(["cosim", str(path), "--check", "--json"])
    report = json.loads(capsys.readouterr().out)
    rows = [r for u in report["units"] for r in u["findings"] if r["check"] == "record"]
    assert status == 2 and rows and rows[0]["verdict"] == "refused"
    return err, rows[0]["detail"]


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-12"])
def test_recorded_variables_follow_the_run(capsys, tmp_path, scheme):
    path = scene(tmp_path, ("body1", msd(1, record=["lambda", "m", "a"])), ("body2", msd(2, record=["x"])),
                 scheme=scheme)  # fmt: skip
    ds = run(capsys, tmp_path, path)
    assert ds["body1.lambda"].dims == ("time",) and ds["body1.lambda"].attrs["units"] == "N"
    # the input as the unit holds it: force_sign 1 times the accepted coupling variable, from t_start on
    np.testing.assert_array_equal(ds["body1.lambda"].values, ds["coupling"].values[:, 0])
    np.testing.assert_array_equal(ds["body1.m"].values, 1.0)  # the start value
    np.testing.assert_array_equal(ds["body1.a"].values[1:], ds["acceleration"].values[0, 1:])
    np.testing.assert_array_equal(ds["body2.x"].values, ds["position"].values[1])
    # at t_start: Newton's law of msd with the computed coupling force, m a = -c x0 + lambda
    assert ds["body1.a"].values[0] == pytest.approx(-1000.0 * 0.1 + ds["coupling"].values[0, 0])
    # reading does not move the run: the same scene without record gives the same trajectory, bit for bit
    (tmp_path / "plain").mkdir()
    plain = run(
        capsys, tmp_path / "plain", scene(tmp_path / "plain", ("body1", msd(1)), ("body2", msd(2)), scheme=scheme)
    )
    np.testing.assert_array_equal(plain["position"].values, ds["position"].values)
    np.testing.assert_array_equal(plain["coupling"].values, ds["coupling"].values)


def test_a_name_the_unit_lacks_is_refused(capsys, tmp_path):
    path = scene(tmp_path, ("body1", msd(1, record=["x", "lamda"])), ("body2", msd(2)))
    err, detail = refused(capsys, path)
    assert "body1: record: the unit has no variable 'lamda'; close matches: lambda" in err
    assert "the unit has no variable 'lamda'" in detail


def test_record_must_be_a_list_of_names(capsys, tmp_path):
    path = scene(tmp_path, ("body1", msd(1, record="x")), ("body2", msd(2)))
    assert main(["cosim", str(path), "--check"]) == 2
    assert "subsystems.body1.record: 'x' is not of type 'array'" in capsys.readouterr().err


@pytest.mark.outside
def test_chassis_values_are_read_with_the_getter_of_their_type(capsys, tmp_path):
    """OSP's Chassis: its Boolean inGravityField shares value reference 1 with the Real acceleration (FMI 2.0 value
    references are per type); each is read with its own getter."""
    chassis = {"fmu": str(OUTSIDE / "osp-quarter-truck" / "Chassis.fmu"),
               "start": {"inGravityField": True, "mass": 400.0, "plotLength": 7},
               "position": "position", "velocity": "velocity", "acceleration": "acceleration", "force": "force",
               "force_sign": -1, "record": ["inGravityField", "plotLength", "mass", "force", "acceleration"]}  # fmt: skip
    spring = msd(1, force_sign=-1) | {"start": {"m": 1.0, "c": 1000.0, "d": 2.0, "x0": 0.0}}
    ds = run(capsys, tmp_path, scene(tmp_path, ("chassis", chassis), ("spring", spring)))
    np.testing.assert_array_equal(ds["chassis.inGravityField"].values, 1.0)
    np.testing.assert_array_equal(ds["chassis.plotLength"].values, 7.0)
    np.testing.assert_array_equal(ds["chassis.mass"].values, 400.0)
    # without joints the unit's input is force_sign * lambda
    np.testing.assert_array_equal(ds["chassis.force"].values, -ds["coupling"].values[:, 0])
    np.testing.assert_array_equal(ds["chassis.acceleration"].values[1:], ds["acceleration"].values[0, 1:])
    assert np.all(ds["chassis.acceleration"].values[1:] != 1.0)  # not the Boolean's value reference read as Real


@pytest.mark.outside
def test_chassis_string_is_refused(capsys, tmp_path):
    chassis = {"fmu": str(OUTSIDE / "osp-quarter-truck" / "Chassis.fmu"), "position": "position",
               "velocity": "velocity", "acceleration": "acceleration", "force": "force", "force_sign": -1,
               "record": ["solverType"]}  # fmt: skip
    err, _ = refused(capsys, scene(tmp_path, ("chassis", chassis), ("spring", msd(1, force_sign=-1))))
    assert "chassis: record: 'solverType' is String: only numbers are recorded" in err


STATESPACE = {
    "A": [[0.0, 1.0, 0.0], [-250.0, -0.5, 0.0], [0.0, 0.0, 0.0]],
    "B": [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, 0.0]],
    "C": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-250.0, -0.5, 0.0]],
    "D": [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.5, 0.0, 0.0]],
}


def statespace(record):
    """The Reference-FMUs' StateSpace (FMI 3.0, three states by its structural parameters, which cannot be set) as
    msd's second mass: x = (position, velocity, unused), y = (x1, x2, x2'), u[1] the force."""
    return {"fmu": str(OUTSIDE / "reference-fmus" / "fmus3" / "StateSpace.fmu"), "start": STATESPACE,
            "position": "y[1]", "velocity": "y[2]", "acceleration": "y[3]", "force": "u[1]", "force_sign": -1,
            "record": record}  # fmt: skip


@pytest.mark.outside
def test_statespace_locals_and_array_elements(capsys, tmp_path):
    path = scene(tmp_path, ("body1", msd(1)), ("body2", statespace(["x[1]", "der(x)[2]", "n", "u[1]"])), H=2e-3)
    ds = run(capsys, tmp_path, path)
    # its equations: y[1] = x[1] (C's first row), y[3] = der(x)[2] (C's and D's third rows are A's and B's second)
    np.testing.assert_array_equal(ds["body2.x[1]"].values, ds["position"].values[1])
    np.testing.assert_allclose(ds["body2.der(x)[2]"].values[1:], ds["acceleration"].values[1, 1:], rtol=1e-9)
    np.testing.assert_array_equal(ds["body2.n"].values, 3.0)  # the structural parameter's default
    np.testing.assert_array_equal(ds["body2.u[1]"].values, -ds["coupling"].values[:, 0])
    assert np.ptp(ds["body2.x[1]"].values) > 1e-3  # it moved


@pytest.mark.outside
def test_statespace_independent_variable_is_refused(capsys, tmp_path):
    err, _ = refused(capsys, scene(tmp_path, ("body1", msd(1)), ("body2", statespace(["time"]))))
    assert "body2: record: 'time' has causality independent" in err and "the dataset's time" in err
