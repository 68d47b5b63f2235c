"""A unit must move as it says, on units other tools ship (``../shared/outside``) and on our own.

* OSP's quarter-truck ``Chassis.fmu`` (libcosim's test data) reads doStep's ``noSetFMUStatePriorToCurrentPoint =
  false`` as "integrate the last step again from its start": the check finds it, and stepped with the flag it needs
  the chassis joined to a spring-mass (fmus/msd) follows the two bodies rigidly joined, with the chassis's gravity;
* the Reference-FMUs' ``StateSpace`` (FMI 3.0, explicit Euler at a fixed internal step of 1e-3 s) below that step
  does not move over a macro step while its acceleration says it should: refused by the movement check; at its own
  step it passes;
* our own ``statespace_fmi3`` with a constant position output (the first row of ``C`` zero) is refused by name.

The exact solutions are computed here with scipy's matrix exponential of the joined system augmented by its constant
force."""

import numpy as np
import pytest
import yaml
from helpers import ROOT
from scipy.linalg import expm
from toolchains import OUTSIDE

from icosim.problems.fmu.check import check_scene
from icosim.problems.fmu.errors import FmuError
from icosim.problems.fmu.run import run_dataset_data, run_scene
from icosim.problems.fmu.scene import load_scene

pytestmark = pytest.mark.fmu

G = -9.81  # the chassis's gravity (its parameter ``gravity``), m/s^2


def joined(times, mass, stiffness, damping, force):
    """Position of two bodies rigidly joined: ``mass x'' = -stiffness x - damping x' + force`` from rest at 0."""
    A = np.array([[0.0, 1.0, 0.0], [-stiffness / mass, -damping / mass, force / mass], [0.0, 0.0, 0.0]])
    return np.array([(expm(A * t) @ [0.0, 0.0, 1.0])[0] for t in times])


def write(tmp_path, subsystems, H, t_end, name="scene.yaml"):
    data = {
        "subsystems": subsystems,
        "coupling": {"method": "baumgarte", "index": 1, "mu": 1e-3, "decomposition": "ff", "k": 1,
                     "scheme": "jacobi", "H": H},
        "t_end": t_end,
    }  # fmt: skip
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def spring(m, c, d):
    return {"fmu": str(ROOT / "fmus" / "msd"), "start": {"m": m, "c": c, "d": d, "x0": 0.0},
            "position": "x", "velocity": "v", "acceleration": "a", "force": "lambda", "force_sign": 1}  # fmt: skip


def findings(report, name):
    row = next(r for r in report["units"] if r["name"] == name)
    return {f["check"]: f for f in row["findings"]}


# -- OSP's chassis ------------------------------------------------------------------------------------------------

M_CHASSIS, M_SPRING, C_SPRING, D_SPRING = 400.0, 100.0, 2.0e4, 50.0


def chassis_scene(tmp_path, force_sign):
    chassis = {"fmu": str(OUTSIDE / "osp-quarter-truck" / "Chassis.fmu"),
               "start": {"inGravityField": True, "mass": M_CHASSIS},
               "position": "position", "velocity": "velocity", "acceleration": "acceleration", "force": "force",
               "force_sign": force_sign}  # fmt: skip
    return write(tmp_path, {"spring": spring(M_SPRING, C_SPRING, D_SPRING), "chassis": chassis}, 1e-3, 1.0)


@pytest.mark.outside
def test_the_chassis_is_found_to_need_the_do_step_flag(tmp_path):
    report = check_scene(load_scene(chassis_scene(tmp_path, 1)))
    chassis, ours = findings(report, "chassis"), findings(report, "spring")
    assert not report["refused"]
    flag = chassis["doStep flag"]
    assert flag["verdict"] == "note" and "noSetFMUStatePriorToCurrentPoint" in flag["detail"]
    assert "with true on every step" in flag["detail"] or "true on every step" in flag["detail"]
    assert "noSetFMUStatePriorToCurrentPoint true" in chassis["rollback"]["detail"]
    assert chassis["moves"]["verdict"] == "pass" and chassis["responds"]["verdict"] == "pass"
    assert "doStep flag" not in ours  # fmus/msd ignores the flag, as the standard says it may


@pytest.mark.outside
def test_the_chassis_joined_to_a_spring_mass_follows_the_joined_masses(tmp_path):
    """The chassis's ``force`` acts against the physical force (+400 N gives -1 m/s^2), so it takes the same
    ``force_sign`` as the spring-mass: the direction check refuses the other sign."""
    run = run_scene(chassis_scene(tmp_path, 1))
    assert run.status == "completed"
    exact = joined(run.times, M_CHASSIS + M_SPRING, C_SPRING, D_SPRING, M_CHASSIS * G)
    amplitude = abs(M_CHASSIS * G / C_SPRING)  # the static deflection: the oscillation about it from rest
    assert np.min(exact) < -1.9 * amplitude  # it falls through twice the deflection: it moves
    for body in (0, 1):
        assert np.max(np.abs(run.positions[:, body, 0] - exact)) < 1e-3 * amplitude
    attrs = run_dataset_data(run).attrs
    assert attrs["chassis_do_step_flag"].startswith("true on every step")
    assert attrs["spring_do_step_flag"] == "true on final steps"
    assert attrs["chassis_rollback_difference"] <= 1e-12 and attrs["spring_rollback_difference"] == 0.0
    with pytest.raises(FmuError, match="force_sign"):
        run_scene(chassis_scene(tmp_path, -1))


# -- the Reference-FMUs' StateSpace --------------------------------------------------------------------------------

M2, C2, D2, F2 = 2.0, 500.0, 1.0, 10.0  # the second body, and a constant force on it through u[2]


def statespace_scene(tmp_path, H):
    """The Reference StateSpace has n = 3 states (its structural parameters cannot be set) and ignores ``x0``: a
    mass-spring-damper in the first two, the third idle; ``u[1]`` the coupling force, ``u[2]`` a constant force."""
    a, b = [-C2 / M2, -D2 / M2, 0.0], [1 / M2, 1 / M2, 0.0]
    unit = {
        "fmu": str(OUTSIDE / "reference-fmus" / "fmus3" / "StateSpace.fmu"),
        "start": {"A": [[0.0, 1.0, 0.0], a, [0.0] * 3], "B": [[0.0] * 3, b, [0.0] * 3],
                  "C": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], a], "D": [[0.0] * 3, [0.0] * 3, b], "u": [0.0, F2, 0.0]},
        "position": "y[1]", "velocity": "y[2]", "acceleration": "y[3]", "force": "u[1]", "force_sign": -1,
    }  # fmt: skip
    return write(tmp_path, {"body1": spring(1.0, 1000.0, 2.0), "body2": unit}, H, 0.2, f"ss_{H:g}.yaml")


@pytest.mark.outside
def test_the_reference_statespace_below_its_internal_step_is_refused(tmp_path):
    with pytest.raises(FmuError) as refused:
        run_scene(statespace_scene(tmp_path, 5e-4))
    text = str(refused.value)
    assert text.startswith("body2: moves: ") and "velocity y[2] changes by 0 " in text
    assert "trapezoid integral of its acceleration y[3]" in text and "0.0025" in text  # 5 m/s^2 over 5e-4 s


@pytest.mark.outside
def test_the_reference_statespace_at_multiples_of_its_internal_step_is_accepted(tmp_path):
    """At H = 1e-3 and 2e-3 it takes one and two explicit Euler steps of 1e-3 s per macro step: accepted, and
    its error is its own Euler's (about 1.3 % of the static deflection here), the same at both H."""
    report = check_scene(load_scene(statespace_scene(tmp_path, 1e-3)))
    assert not report["refused"]
    errors = []
    for H in (1e-3, 2e-3):
        run = run_scene(statespace_scene(tmp_path, H))
        exact = joined(run.times, 1.0 + M2, 1000.0 + C2, 2.0 + D2, F2)
        errors.append(np.max(np.abs(run.positions[:, 0, 0] - exact)) / (F2 / (1000.0 + C2)))
    assert errors[0] < 0.05 and abs(errors[1] / errors[0] - 1) < 0.1


# -- a constant position ------------------------------------------------------------------------------------------


def test_a_constant_position_output_is_refused_by_name(tmp_path):
    """``statespace_fmi3`` with the first row of ``C`` zero: ``y[1]`` is 0 whatever the force, while its velocity
    and acceleration move (so the feedthrough and direction checks pass)."""
    unit = {"fmu": str(ROOT / "fmus" / "statespace_fmi3"),
            "start": {"A": [[0.0, 1.0], [-250.0, -0.5]], "B": [[0.0], [0.5]],
                      "C": [[0.0, 0.0], [0.0, 1.0], [-250.0, -0.5]], "D": [[0.0], [0.0], [0.5]], "x0": [0.0, 0.0]},
            "position": "y[1]", "velocity": "y[2]", "acceleration": "y[3]", "force": "u[1]", "force_sign": -1}  # fmt: skip
    path = write(tmp_path, {"body1": spring(1.0, 1000.0, 2.0), "body2": unit}, 1e-3, 0.01)
    report = check_scene(load_scene(path))
    found = findings(report, "body2")
    assert found["feedthrough"]["verdict"] == "pass" and found["direction"]["verdict"] == "pass"
    assert found["responds"]["verdict"] == "refused"
    with pytest.raises(FmuError, match=r"^body2: responds: its position y\[1\] does not respond to its force \(0\.0 m"):
        run_scene(path)


# -- a unit of our own that depends on the flag (fmus/faulty, faults 11 and 12) --------------------------------------


def flag_scene(tmp_path, fault):
    """``faulty`` with fault 11 (false read as "the last step again from its start") or 12 (and no restore after a
    step with true), or ``msd`` itself (fault None), joined to ``msd``."""
    body1 = {"fmu": str(ROOT / "fmus" / ("msd" if fault is None else "faulty")),
             "start": {"m": 1.0, "c": 1000.0, "d": 2.0, "x0": 0.1} | ({} if fault is None else {"fault": fault}),
             "position": "x", "velocity": "v", "acceleration": "a", "force": "lambda", "force_sign": 1}  # fmt: skip
    body2 = spring(2.0, 500.0, 1.0) | {"force_sign": -1}
    body2["start"] = body2["start"] | {"x0": 0.1}
    return write(tmp_path, {"body1": body1, "body2": body2}, 1e-3, 0.05, f"flag_{fault}.yaml")


def test_a_unit_that_needs_the_flag_is_stepped_with_it_and_moves_as_msd(tmp_path):
    """Fault 11 stepped with noSetFMUStatePriorToCurrentPoint true on every step is ``msd``: the run is ``msd``'s
    bit for bit (which does not read the flag), and the check table and the dataset say how it was stepped."""
    found = findings(check_scene(load_scene(flag_scene(tmp_path, 11))), "body1")
    assert found["doStep flag"]["verdict"] == "note" and "x is " in found["doStep flag"]["detail"]
    assert found["rollback"]["verdict"] == "pass"
    run, reference = run_scene(flag_scene(tmp_path, 11)), run_scene(flag_scene(tmp_path, None))
    np.testing.assert_array_equal(run.states, reference.states)
    assert np.ptp(run.states[:, 0, 0]) > 0.01  # it moves
    attrs = run_dataset_data(run).attrs
    assert attrs["body1_do_step_flag"] == "true on every step (the unit needs it)"
    assert run_dataset_data(reference).attrs["body1_do_step_flag"] == "true on final steps"


def test_a_unit_that_needs_the_flag_and_then_cannot_roll_back_is_refused_naming_it(tmp_path):
    with pytest.raises(FmuError) as refused:
        run_scene(flag_scene(tmp_path, 12))
    text = str(refused.value)
    assert text.startswith("body1: doStep flag: its step depends on doStep's noSetFMUStatePriorToCurrentPoint")
    assert "with the flag it needs (true on every step) its restored steps do not repeat" in text


def test_the_flag_is_true_on_the_final_integration_of_each_macro_step(monkeypatch):
    """Jacobi with one corrector step: per macro step and unit, the prediction and the sensitivity's step are
    rolled back (false), the corrector's integration is final (true).  The calls are counted on each unit's fmpy
    instance (its ``fmi2DoStep``, which fmpy's ``doStep`` calls)."""
    import collections

    from icosim.problems.fmu import run as run_module

    flags, opened = collections.Counter(), run_module.open_units

    def counted(*args, **kwargs):
        units, couplings = opened(*args, **kwargs)
        for unit in units:
            fmu, step = unit.fmu, unit.fmu.fmi2DoStep

            def recorded(c, t, h, flag, step=step, name=unit.label):
                flags[name, bool(flag)] += 1
                return step(c, t, h, flag)

            fmu.fmi2DoStep = recorded
        return units, couplings

    monkeypatch.setattr(run_module, "open_units", counted)
    run = run_module.run_scene(ROOT / "config" / "scenes" / "two_mass_ff.yaml")
    steps = len(run.times) - 1
    for name in ("body1", "body2"):
        assert flags[name, True] == steps and flags[name, False] == 2 * steps
