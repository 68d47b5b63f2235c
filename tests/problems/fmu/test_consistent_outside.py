"""The consistent start on OSP's quarter truck (../shared/outside/osp-quarter-truck), whose units compute their
outputs in ``doStep`` only, from the state at the start of their solver's last internal step:

* the Wheel, stepped by fmpy alone: its ``out_spring_damper_f`` after a step is the force at the start of its last
  internal Euler step (``-dc`` times its velocity one internal step earlier), so a step's output lags by that step,
  whose size jumps where the step passes the solver's 1e-5 s;
* the start force the problem computes is the wheel's spring force at ``t = 0`` as the wheel gives it after a step
  much shorter than its solver's (the bond's force balance at ``t_start``), not the value extrapolated from steps
  of ``H`` and ``2 H`` (``-dc a_w dt``: 3.75 N off);
* a controlled run with the predictor-corrector estimate accepts its first step and then ends at ``H_min`` saying
  that its estimate does not shrink with H: after an accepted step of ``H_1`` the wheel's force lags by ``H_1 / 16``
  (its sub-step), which no smaller retry removes: the estimate stays at ``|f'| H_1 / 16 / (tol (1 + |f|))``, with
  ``f' = -dc a_w`` the rate of the wheel's force (``a_w``: the wheel's acceleration, from its velocity stepped by
  fmpy).
"""

import numpy as np
import pytest
import yaml
from toolchains import OUTSIDE

from icosim.problems.fmu.run import run_dataset_data, run_scene

pytestmark = pytest.mark.outside

OSP = OUTSIDE / "osp-quarter-truck"
#: the Wheel's damper (its modelDescription's start value of ``dc``, N s/m) and the file's solver step (s)
DC, DT = 1000.0, 1e-5


def wheel_after(steps):
    """The Wheel as the OSP file sets it up (mass 40, Euler at 1e-5 s, ``in_vel`` 0), stepped by fmpy through
    ``steps`` (s) from 0: its ``out_spring_damper_f`` and ``velocity`` after the last."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(OSP / "Wheel.fmu")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(OSP / "Wheel.fmu"),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="wheel")  # fmt: skip
    fmu.instantiate()
    fmu.setReal([vr["mass"], vr["timeStep"]], [40.0, DT])
    fmu.setString([vr["solverType"]], ["Euler"])
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.setReal([vr["in_vel"]], [0.0])
    t = 0.0
    for h in steps:
        fmu.doStep(t, h, True)
        t += h
    force, velocity = fmu.getReal([vr["out_spring_damper_f"], vr["velocity"]])
    fmu.terminate()
    fmu.freeInstance()
    return force, velocity


def overlay(tmp_path, name, **keys):
    path = tmp_path / name
    path.write_text(yaml.safe_dump({"system": str(OSP / "OspSystemStructure.xml"), **keys}))
    return path


def test_the_wheel_reports_the_force_of_one_internal_step_before():
    _, v_one = wheel_after([DT])
    force, _ = wheel_after([2 * DT])
    assert v_one > 1e-3  # the tire pushes the wheel up from the start
    assert force == pytest.approx(-DC * v_one, rel=1e-12)  # in_vel 0: the damper on the velocity at DT, not 2 DT
    tiny, _ = wheel_after([1e-9])
    assert tiny == 0.0  # the force at t = 0: the spring and damper start unstretched


def test_the_start_force_is_the_wheel_s_spring_force_at_t_start(tmp_path):
    at_start, _ = wheel_after([1e-9])
    coupling = {"method": "baumgarte", "index": 1, "mu": 1e-4, "k": 1, "scheme": "jacobi", "H": 1e-4}
    data = run_dataset_data(run_scene(overlay(tmp_path, "start.yaml", t_end=2e-4, coupling=coupling)))
    force = data.array("chassis.force")
    # the force balance at t_start to the extrapolation's convergence (far below the lag's -dc a_w dt = 3.75 N)
    assert abs(force[0] - at_start) < 1e-6, force[:2]


def test_a_controlled_run_says_its_estimate_does_not_shrink_with_h(tmp_path):
    control = {"tolerance": 1e-3, "H_min": 1e-10, "H_max": 1e-2}
    coupling = {"method": "baumgarte", "index": 1, "mu": 1e-4, "k": 1, "scheme": "jacobi", "H": 1e-4,
                "control": control}  # fmt: skip
    run = run_scene(overlay(tmp_path, "controlled.yaml", t_end=0.01, coupling=coupling))
    assert run.status == "diverged" and len(run.times) == 2  # the start is consistent: the first step is accepted
    assert "> 1 at H_min = 1e-10 s" in run.reason and "the estimate does not shrink with H" in run.reason
    data = run_dataset_data(run)
    (H1,) = run.steps.H
    f = float(np.ravel(data.array("chassis.force"))[1])
    a_w = wheel_after([H1])[1] / H1  # the wheel's mean acceleration over the step (the chassis stands nearly still)
    floor = DC * abs(a_w) * H1 / 16 / (1e-3 * (1 + abs(f)))
    err = float(run.reason.split("error norm ")[1].split(" ")[0])
    assert err == pytest.approx(floor, rel=0.1), (err, floor)
