"""Units checked before they are trusted (icosim.problems.fmu.inspection, icosim.problems.fmu.variables, icosim.problems.fmu.measures): typed
start values set with their own setters, a force input of the opposite sign, a unit without feedthrough, units of
measure, FMI 3.0 array elements, an inconsistent start, the initial coupling, and every refusal as one line
naming the unit, the key and the fix, exit status 2 and no dataset.

The units are fmus/ units in other tools' styles (fmus/README.md): body_rk45 (an embedded RK45 solver, typed
parameters sharing value reference 0, a force input of the opposite sign, no feedthrough), msd_mm (millimetres
and kilonewtons), statespace_fmi3 (FMI 3.0 arrays and structural parameters)."""

import json

import numpy as np
import pytest
import scipy.linalg
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.io.netcdf import open_dataset
from icosim.problems.fmu.predict import predict_scene
from icosim.problems.fmu.run import run_scene
from icosim.problems.fmu.scene import load_scene

pytestmark = pytest.mark.fmu

FMUS = ROOT / "fmus"
M_BODY, M_SPRING, C_SPRING, D_SPRING, G = 400.0, 100.0, 4.0e5, 200.0, 9.81


def body(**start):
    """body_rk45: a free body whose force input acts against the physical force, with gravity."""
    s = {"m": M_BODY, "inGravityField": True, "solverType": "RK45", "nSteps": 10, "x": 0.1, "gravityDirection": "down"}
    return {"fmu": str(FMUS / "body_rk45"), "start": s | start, "position": "x", "velocity": "v",
            "acceleration": "a", "force": "F", "force_sign": -1}  # fmt: skip


def spring(**start):
    s = {"m": M_SPRING, "c": C_SPRING, "d": D_SPRING, "x0": 0.1}
    return {"fmu": str(FMUS / "msd"), "start": s | start, "position": "x", "velocity": "v", "acceleration": "a",
            "force": "lambda", "force_sign": -1, "mass": "m", "set_position": "x_set", "set_velocity": "v_set"}  # fmt: skip


def write(tmp_path, first, second, name="scene.yaml", **top):
    coupling = {"method": "baumgarte", "index": 1, "mu": 1e-3, "decomposition": "ff", "k": 1, "scheme": "jacobi",
                "H": 1e-3}  # fmt: skip
    coupling = {k: v for k, v in (coupling | top.pop("coupling", {})).items() if v is not None}  # None: left out
    data = {"subsystems": {"body": first, "spring": second}, "coupling": coupling, "t_end": 0.2} | top
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def cosim(capsys, *argv):
    status = main(["cosim", *map(str, argv)])
    out = capsys.readouterr()
    return status, out.out, out.err.strip()


def refused(capsys, path, tmp_path, *needles):
    """The scene is refused: status 2, one line naming what is wrong, no dataset."""
    out = tmp_path / "run.nc"
    status, _, err = cosim(capsys, path, "--out", out)
    assert status == 2 and len(err.splitlines()) == 1 and err.startswith("icosim cosim: error: "), err
    for needle in needles:
        assert needle in err, err
    assert not out.exists() and not list(tmp_path.glob(".run.nc*"))
    return err


def joined_exact(t, x0=0.1, gravity=True):
    """The rigidly joined body and spring-mass: (m_b + m_s) x'' = -c x - d x' - m_b g (gravity on the body only),
    from rest at x0, by the matrix exponential of the system augmented by the constant force."""
    total = M_BODY + M_SPRING
    A = np.array([[0, 1, 0], [-C_SPRING / total, -D_SPRING / total, -M_BODY * G * gravity / total], [0, 0, 0]])
    return np.array([(scipy.linalg.expm(A * ti) @ [x0, 0.0, 1.0])[0] for ti in t])


# -- the unit of the "another tool" style: typed parameters, opposite sign, no feedthrough -------------------------


def test_body_with_typed_parameters_follows_the_joined_solution(tmp_path):
    """String, Boolean, Integer and Enumeration parameters (value reference 0 shared by Real m, Boolean
    inGravityField, Integer nSteps and String solverType), a force input of the opposite sign with force_sign -1,
    an acceleration updated only by doStep: the joint follows the exact joined solution, with gravity, within
    1e-3 of the amplitude (with m set to 1 by a Boolean written as a Real, or without gravity, it would not)."""
    run = run_scene(write(tmp_path, body(), spring()))
    assert run.status == "completed"
    exact = joined_exact(run.times)
    assert np.max(np.abs(run.positions[:, :, 0] - exact[:, None])) < 1e-3 * 0.1
    assert np.max(np.abs(exact - joined_exact(run.times, gravity=False))) > 1e-3  # gravity matters at this tolerance
    assert run.units["body"]["feedthrough"] == "through a step only"
    assert run.units["body"]["inputs"] == "substeps (16)"
    for solver in ("RK4", "RK45"):  # the String parameter reaches the unit: both solvers are exact for it
        other = run_scene(write(tmp_path, body(solverType=solver, nSteps=3), spring(), name=f"{solver}.yaml"))
        assert np.max(np.abs(other.positions[:, :, 0] - exact[:, None])) < 1e-3 * 0.1


def test_the_wrong_force_sign_is_refused_naming_the_unit_and_the_fix(capsys, tmp_path):
    path = write(tmp_path, body() | {"force_sign": 1}, spring())
    err = refused(capsys, path, tmp_path, "subsystems.body.force_sign", "push both units the same way")
    assert "-0.0025 m/s^2 per N" in err and "set subsystems.body.force_sign: -1" in err  # -1/400 kg, measured


def test_predict_identifies_the_body_through_steps_and_its_radius_is_measured(capsys, tmp_path):
    """--predict on a unit without feedthrough: probing steps (finite inputs), the mass within 1 %, gravity as a
    constant force, the free mass (c = 0); Gauss-Seidel 1->2 would re-evaluate the body without a step: not
    defined.  Gauss-Seidel 2->1 is predicted unstable and a run grows by that rho within 5 %."""
    path = write(tmp_path, body(), spring())
    answer = predict_scene(load_scene(path))
    b, s = answer["units"]["body"], answer["units"]["spring"]
    assert b["m"] == pytest.approx(M_BODY, rel=1e-2) and not b["feedthrough"]
    assert b["F0"] == pytest.approx(-M_BODY * G, rel=1e-6) and abs(b["c"]) < 1e-3 * C_SPRING
    assert (s["m"], s["c"], s["d"]) == pytest.approx((M_SPRING, C_SPRING, D_SPRING), rel=1e-9)
    rows = {r["scheme"]: r for r in answer["schemes"]}
    assert rows["gauss-seidel-12"]["verdict"] == "not defined" and "feedthrough" in rows["gauss-seidel-12"]["reason"]
    rho = rows["gauss-seidel-21"]["rho"]
    assert rows["gauss-seidel-21"]["verdict"] == "unstable" and rho > 1.5
    run = run_scene(write(tmp_path, body(), spring(), name="gs.yaml", coupling={"scheme": "gauss-seidel-21"}))
    assert run.status == "diverged"
    amp = np.max(np.abs(run.positions[:, :, 0]), axis=1)
    n = len(amp) - 1
    growth = (amp[n] / amp[n // 2]) ** (1 / (n - n // 2))
    assert growth == pytest.approx(rho, rel=0.05)
    status, _, err = cosim(capsys, write(tmp_path, body(), spring(), name="gs12.yaml",
                                         coupling={"scheme": "gauss-seidel-12"}), "--out", tmp_path / "x.nc")  # fmt: skip
    assert status == 2 and "coupling.scheme: gauss-seidel-12" in err and "no direct feedthrough" in err


@pytest.mark.parametrize(
    "name, value, needles",
    [
        ("inGravityField", 1, ["'inGravityField' is declared Boolean", "true or false; got 1"]),
        ("solverType", 4, ["'solverType' is declared String", "got 4"]),
        ("nSteps", 2.5, ["'nSteps' is declared Integer", "got 2.5"]),
        ("nSteps", 2**40, ["out of the range of Integer"]),
        ("gravityDirection", "sideways", ["declared Enumeration", "down (1), up (2)"]),
        ("a", 1.0, ["'a' is an output with initial = calculated", "initial = exact or approx"]),
        ("m", True, ["'m' is declared Real", "got True"]),
        ("nstep", 1, ["no variable 'nstep'", "close matches: nSteps"]),
    ],
)
def test_a_start_value_of_the_wrong_type_or_state_is_refused(capsys, tmp_path, name, value, needles):
    path = write(tmp_path, body(**{name: value}), spring())
    refused(capsys, path, tmp_path, "body: start: ", *needles)


def test_a_unit_that_refuses_its_start_values_is_named_with_its_own_message(capsys, tmp_path):
    path = write(tmp_path, body(solverType="Euler"), spring())
    refused(capsys, path, tmp_path, "body:", "could not be initialised", "the unit said:", "RK4", "RK45")


# -- units of measure ---------------------------------------------------------------------------------------------


def mm_unit(**start):
    s = {"m": 1.0, "c": 1.0, "d": 0.002, "x0": 100.0}  # N/mm and N s/mm: 1000 N/m, 2 N s/m; 100 mm
    return {"fmu": str(FMUS / "msd_mm"), "start": s | start, "position": "x", "velocity": "v", "acceleration": "a",
            "force": "lambda", "force_sign": 1}  # fmt: skip


def msd_unit(**start):
    s = {"m": 1.0, "c": 1000.0, "d": 2.0, "x0": 0.1}
    return {"fmu": str(FMUS / "msd"), "start": s | start, "position": "x", "velocity": "v", "acceleration": "a",
            "force": "lambda", "force_sign": 1, "mass": "m", "set_position": "x_set", "set_velocity": "v_set"}  # fmt: skip


def test_declared_units_are_converted_to_si(tmp_path):
    """The same physical system once in SI (msd) and once in millimetres and kilonewtons (msd_mm): the joint's
    trajectory and multiplier are the same to rounding."""
    other = msd_unit(m=2.0, c=500.0, d=1.0) | {"force_sign": -1}
    si = run_scene(write(tmp_path, msd_unit(), other, name="si.yaml"))
    mm = run_scene(write(tmp_path, mm_unit(), other, name="mm.yaml"))
    assert np.max(np.abs(mm.states - si.states)) < 1e-12 * np.max(np.abs(si.states))
    assert np.max(np.abs(mm.coupling - si.coupling)) < 1e-9 * np.max(np.abs(si.coupling))


def test_a_start_value_may_carry_a_declared_unit(tmp_path):
    """x0 given as 0.1 m where the unit works in mm (its display unit m): the same run as 100 mm."""
    other = msd_unit(m=2.0, c=500.0, d=1.0) | {"force_sign": -1}
    a = run_scene(write(tmp_path, mm_unit(), other, name="a.yaml"))
    b = run_scene(write(tmp_path, mm_unit(x0={"value": 0.1, "unit": "m"}), other, name="b.yaml"))
    np.testing.assert_array_equal(a.states, b.states)


def test_a_coupling_variable_in_the_wrong_unit_is_refused(capsys, tmp_path):
    """msd_mm's velocity named as its position: mm/s is not a length."""
    refused(capsys, write(tmp_path, mm_unit() | {"position": "v"}, msd_unit()), tmp_path,
            "body: position: 'v' is in mm/s", "position must be a length")  # fmt: skip


def test_a_start_value_in_an_undeclared_unit_is_refused(capsys, tmp_path):
    refused(capsys, write(tmp_path, mm_unit(x0={"value": 0.1, "unit": "km"}), msd_unit()), tmp_path,
            "unit 'km' is not one the unit declares for x0", "allowed: mm, m")  # fmt: skip


# -- FMI 3.0 arrays -----------------------------------------------------------------------------------------------

A_MSD = [[0.0, 1.0], [-250.0, -0.5]]  # m = 2 kg, c = 500 N/m, d = 1 N s/m


def statespace(**start):
    s = {"A": A_MSD, "B": [[0.0], [0.5]], "C": [[1.0, 0.0], [0.0, 1.0], A_MSD[1]], "D": [[0.0], [0.0], [0.5]],
         "x0": [0.1, 0.0]}  # fmt: skip
    return {"fmu": str(FMUS / "statespace_fmi3"), "start": s | start, "position": "y[1]", "velocity": "y[2]",
            "acceleration": "y[3]", "force": "u[1]", "force_sign": -1}  # fmt: skip


def test_array_elements_couple_an_fmi3_state_space_unit(tmp_path):
    """The mass-spring-damper as an FMI 3.0 state-space unit (array starts as nested lists, coupling variables
    y[1], y[2], y[3], u[1]) against the same mass as msd_fmi3: both integrate exactly with the input held over a
    sub-step, so the runs agree to rounding."""
    twin = msd_unit(m=2.0, c=500.0, d=1.0) | {"fmu": str(FMUS / "msd_fmi3"), "force_sign": -1}
    a = run_scene(write(tmp_path, msd_unit(), twin, name="twin.yaml"))
    b = run_scene(write(tmp_path, msd_unit(), statespace(), name="ss.yaml"))
    assert b.status == "completed"
    assert np.max(np.abs(a.states - b.states)) < 1e-12 * np.max(np.abs(a.states))


def test_structural_parameters_resize_the_arrays(tmp_path):
    """r = 4 outputs (structural parameter, set in configuration mode): y[4] repeats the position."""
    s = statespace(r=4, C=[[1.0, 0.0], [0.0, 1.0], A_MSD[1], [1.0, 0.0]], D=[[0.0], [0.0], [0.5], [0.0]])
    run = run_scene(write(tmp_path, msd_unit(), s | {"position": "y[4]"}))
    base = run_scene(write(tmp_path, msd_unit(), statespace(), name="base.yaml"))
    np.testing.assert_array_equal(run.states, base.states)


@pytest.mark.parametrize(
    "change, needles",
    [
        ({"position": "y"}, ["'y' is an array of shape 3", "y[1]"]),
        ({"position": "y[4]"}, ["'y[4]' is not an element of y (shape 3"]),
        ({"position": "y[1,1]"}, ["not an element of y"]),
        ({"start": {"x0": [0.1, 0.0, 0.0]}}, ["x0 is a Float64 array of shape 2", "give a list of 2 values"]),
        ({"start": {"n": 9}}, ["A is a Float64 array of shape 9 x 9", "give a list of 81 values"]),
        ({"start": {"r": 6, "C": [[1.0, 0.0]] * 6, "D": [[0.0]] * 6}}, ["fmi3SetUInt64 refused 6", "the unit said:"]),
    ],
)
def test_array_names_and_starts_are_checked(capsys, tmp_path, change, needles):
    unit = statespace()
    if "start" in change:
        unit["start"] = unit["start"] | change.pop("start")
    refused(capsys, write(tmp_path, msd_unit(), unit | change), tmp_path, *needles)


def test_an_input_that_does_not_drive_the_unit_is_refused(capsys, tmp_path):
    """B = 0 and D = 0: the state-space unit's outputs ignore u[1], at once and through a step."""
    unit = statespace(B=[[0.0], [0.0]], D=[[0.0], [0.0], [0.0]])
    refused(capsys, write(tmp_path, msd_unit(), unit), tmp_path, "spring: feedthrough", "do not respond")


# -- the start ----------------------------------------------------------------------------------------------------


def test_an_inconsistent_start_is_refused_projected_or_accepted(capsys, tmp_path):
    """Positions 0.1 and 0.12 at t_start: refused naming both; initial: project moves both units to the
    mass-weighted mean; initial: as-is runs and reports the gap."""
    first, second = msd_unit(), spring(x0=0.12) | {"force_sign": -1}
    refused(capsys, write(tmp_path, first, second), tmp_path, "initial: the joint's positions differ", "body 0.1",
            "spring 0.12", "initial: project")  # fmt: skip
    first = first | {"mass": "m", "set_position": "x_set", "set_velocity": "v_set"}
    projected = run_scene(write(tmp_path, first, second, name="p.yaml", initial="project"))
    assert projected.states[0, 0, 0] == projected.states[0, 1, 0] == pytest.approx((0.1 * 1 + 0.12 * 100) / 101)
    assert projected.start.position_gap == pytest.approx(0.02)
    out = tmp_path / "as_is.nc"
    status, text, _ = cosim(capsys, write(tmp_path, first, second, name="a.yaml", initial="as-is"), "--out", out)
    assert status == 0 and "joint gap at start 0.02 m, 0 m/s (as-is)" in text
    attrs = open_dataset(out).attrs
    assert attrs["initial"] == "as-is" and attrs["initial_position_gap"] == pytest.approx(0.02)


def test_the_initial_coupling_is_the_one_the_joint_needs(tmp_path):
    """Two undamped msd units at rest at x0: the computed multiplier is the exact one (lambda = m1 a + c1 x0 with
    a = -(c1 + c2) x0 / (m1 + m2)).  From it, Baumgarte index 1 (mu = H) at k = 1 converges in position by at
    least one and a half orders more than from zero coupling, whose inconsistent start dominates the error."""
    m1, c1, m2, c2 = 1.0, 1000.0, 2.0, 500.0
    first, second = msd_unit(d=0.0), msd_unit(m=m2, c=c2, d=0.0) | {"force_sign": -1}
    a = -(c1 + c2) * 0.1 / (m1 + m2)
    run = run_scene(write(tmp_path, first, second))
    assert run.coupling[0, 0] == pytest.approx(m1 * a + c1 * 0.1, rel=1e-12)
    assert run.start.coupling_source == "computed"
    omega = np.sqrt((c1 + c2) / (m1 + m2))
    errors = {}
    for zero in (False, True):
        for H in (2e-3, 1e-3):
            extra = {"initial_coupling": [0.0]} if zero else {}
            path = write(tmp_path, first, second, name=f"e{zero}{H}.yaml", coupling={"H": H, "mu": H}, **extra)
            r = run_scene(path)
            errors[zero, H] = np.max(np.abs(r.positions[:, 0, 0] - 0.1 * np.cos(omega * r.times)))
    consistent, zero = (np.log2(errors[z, 2e-3] / errors[z, 1e-3]) for z in (False, True))
    assert consistent > zero + 1.5
    assert errors[True, 1e-3] > 100 * errors[False, 1e-3]


def test_check_prints_a_table_per_unit(capsys, tmp_path):
    status, text, _ = cosim(capsys, write(tmp_path, body(), spring()), "--check")
    assert status == 0 and "every check passed" in text
    for row in ("rollback      pass", "feedthrough   note", "direction     pass", "start values  pass",
                "inGravityField = true (Boolean, fmi2SetBoolean, instantiated)", "solverType = RK45 (String"):  # fmt: skip
        assert row in text, text
    status, text, _ = cosim(capsys, write(tmp_path, body() | {"force_sign": 1}, spring(), name="w.yaml"), "--check",
                            "--json")  # fmt: skip
    report = json.loads(text)
    assert status == 2 and report["refused"]
    assert any(f["check"] == "direction" and f["verdict"] == "refused" for f in report["scene_findings"])
