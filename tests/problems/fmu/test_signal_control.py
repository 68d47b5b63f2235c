"""Controlled macro steps on scenes of signal connections (``coupling: {control: {tolerance, H_min, H_max}}``):
the joint scenes' controlled run (:func:`icosim.problems.fmu.controlled.controlled_steps`) with the signal problem's
checkpoint (:class:`icosim.problems.fmu.checkpoint.SignalCheckpoints`).

What the tests compare follows from the method, not from numbers of the code under test:

* **Tolerance proportionality** (OMSimulator's DualMassOscillator, ../shared/outside/omsimulator, its Model
  Exchange units integrated by icosim far below the coupling's error; the exact solution of DualMassOscillator.mo,
  test_drives.exact).  The estimate is the predictor's extrapolation error of the connections' values at
  ``T_N+1``, ``|e_c - e_p| ~ C H^(k+1) |e^(k+1)|``; the controller sizes each step so that it is about ``tol``
  (times ``1 + |e_c|``), so ``H ~ tol^(1/(k+1))``.  The inputs a unit follows over a step err by the same order,
  so the states err by ``H * tol`` per step, and over the ``T / H`` steps of the run by ``T tol``: the global error
  is proportional to ``tol`` (slope 1 of ``log(error)`` against ``log(tol)``, whatever ``k``), and the number of
  steps grows as ``tol^(-1/(k+1))``.
* **Fewer steps on a transient** (OMSimulator's QuarterCarModel, displacement/displacement, the road's step of
  road.csv at 0.1 s; the exact solution of its ``ReferenceSystem`` by scipy at rtol 1e-12): at rest until the step
  the estimate is zero and the controller takes its largest steps; after it, the steps follow the decaying ringing.
  The controlled run's macro steps, the rejected ones counted too, are fewer than the best fixed ``H`` needs for
  the controlled run's error: fixed steps on the road's breakpoint, whose error falls with ``H`` (checked), so the
  best is the largest ``H`` reaching it, found between the two fixed runs that bracket the error (the error a power
  of ``H`` between them: interpolated on the log-log line through them, no extrapolation).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from scipy.integrate import solve_ivp
from test_drives import exact
from test_implicit_signals import dmo_scene, positions
from test_quarter_car import OM as QC_OM
from test_quarter_car import ROAD_HEIGHT, ROAD_JUMP, reference

from icosim.cli import main
from icosim.engine.macrostep import macro_step
from icosim.io.netcdf import open_dataset
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_scene import open_signal_unit, run_signal_scene, signal_dataset, signal_wiring
from icosim.problems.fmu.signals import SignalCosimulation

pytestmark = pytest.mark.outside

TOLERANCES = (1e-3, 1e-4, 1e-5, 1e-6)  # three decades


def control(tol, **more):
    return {"tolerance": tol, "H_min": 1e-12, "H_max": 0.1, **more}


def slope(x, y):
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


@pytest.mark.parametrize("implicit", [False, True])
def test_the_error_is_proportional_to_the_tolerance_over_three_decades(tmp_path, implicit):
    """DualMassOscillator over 1 s (some 100 to 1000 steps), k = 2, Jacobi: slope 1 of the error (module
    docstring), the steps' -1/3."""
    k, errors, steps = 2, [], []
    for tol in TOLERANCES:
        run = run_signal_scene(load_scene(dmo_scene(tmp_path, 1e-3, 1.0, k=k, implicit=implicit,
                                                    control=control(tol))))  # fmt: skip
        assert run.steps.status == "stable", run.steps.reason
        errors.append(float(np.max(np.abs(positions(run) - exact(np.asarray(run.times))[:, :2]))))
        steps.append(len(run.steps.H))
    assert abs(slope(TOLERANCES, errors) - 1.0) <= 0.1, (errors, steps)
    assert abs(slope(TOLERANCES, steps) + 1.0 / (k + 1)) <= 0.1, (errors, steps)


def test_the_dataset_holds_the_steps_and_their_estimates(tmp_path):
    run = run_signal_scene(load_scene(dmo_scene(tmp_path, 1e-3, 0.5, k=1, control=control(1e-4))))
    ds = signal_dataset(run)
    H = ds["macro_step_size"].values
    assert math.isnan(H[0]) and np.allclose(np.cumsum(H[1:]), ds["time"].values[1:])
    assert ds.attrs["control_accepted_steps"] == len(H) - 1 and ds.attrs["control_status"] == "stable"
    assert np.all(ds["control_error"].values[1:] <= 1.0)
    assert ds["time"].values[-1] == pytest.approx(0.5, abs=1e-12)


QC_SCENE = {
    "subsystems": {
        "chassis": {"fmu": str(QC_OM / "QuarterCarModel.DisplacementDisplacement.Chassis.fmu"),
                    "interface": "model-exchange", "tolerance": 1e-10},
        "wheel": {"fmu": str(QC_OM / "QuarterCarModel.DisplacementDisplacement.Wheel.fmu"),
                  "interface": "model-exchange", "tolerance": 1e-10},
    },
    "connections": [{"from": f"chassis.{v}", "to": f"wheel.{v}"} for v in ("z_c", "der_z_c")]
    + [{"from": f"wheel.{v}", "to": f"chassis.{v}"} for v in ("z_w", "der_z_w")],
    "sources": [{"to": "wheel.z", "table": str(QC_OM / "road.csv"), "column": "road"}],
    "t_end": 1.0,
}  # fmt: skip
FIXED_N = (50, 100, 200, 400)  # H = 0.1 s / n: the road's step on every grid


def quarter_car(tmp_path, **coupling):
    """The run's largest error of the two positions against the exact solution, and the run."""
    path = tmp_path / f"qc_{len(list(tmp_path.iterdir()))}.yaml"
    path.write_text(yaml.safe_dump({**QC_SCENE, "coupling": {"k": 1, **coupling}}))
    run = run_signal_scene(load_scene(path))
    t = np.asarray(run.times)
    first = solve_ivp(reference, (0, ROAD_JUMP), np.zeros(4), args=(0.0,), rtol=1e-12, atol=1e-14, dense_output=True)
    second = solve_ivp(reference, (ROAD_JUMP, t[-1]), first.y[:, -1], args=(ROAD_HEIGHT,), rtol=1e-12, atol=1e-14,
                       dense_output=True)  # fmt: skip
    ref = np.where((t <= ROAD_JUMP)[:, None], first.sol(np.minimum(t, ROAD_JUMP)).T, second.sol(t).T)
    x = np.array([run.series["chassis.z_c"], run.series["wheel.z_w"]]).T
    return float(np.max(np.abs(x - ref[:, [0, 2]]))), run


@pytest.fixture(scope="module")
def fixed_runs(tmp_path_factory):
    """(steps, error) of each fixed H."""
    tmp = tmp_path_factory.mktemp("qc_fixed")
    return [(n * 10, quarter_car(tmp, H=ROAD_JUMP / n)[0]) for n in FIXED_N]


@pytest.mark.parametrize("tol", [1e-3, 1e-4])
def test_a_controlled_run_takes_fewer_steps_than_a_fixed_one_on_the_road_step(tmp_path, fixed_runs, tol):
    errors = [e for _, e in fixed_runs]
    assert all(a > b for a, b in zip(errors, errors[1:])), fixed_runs  # the error falls with H
    error, run = quarter_car(tmp_path, H=1e-3, control=control(tol))
    assert run.steps.status == "stable", run.steps.reason
    above = [j for j, e in enumerate(errors) if e > error]  # fixed steps that do not reach the controlled error
    assert above and len(above) < len(fixed_runs), (error, fixed_runs)  # a fixed H on either side
    (n1, e1), (n2, e2) = fixed_runs[above[-1]], fixed_runs[above[-1] + 1]
    needed = n1 * (n2 / n1) ** (math.log(e1 / error) / math.log(e1 / e2))  # log-log between the two
    taken = len(run.steps.H) + run.steps.n_rejected
    assert taken < needed, (taken, needed, error, fixed_runs)


@pytest.mark.parametrize("control_, where, says", [
    ({"estimate": "power-residual", "absolute_tolerance": 1e-6, "H_min": 1e-6, "H_max": 1e-2},
     "coupling.control.estimate", "power residual needs joints"),
    ({"H_min": 1e-6, "H_max": 1e-2}, "coupling.control.tolerance", "required"),
    ({"tolerance": 1e-6, "H_min": 1e-2, "H_max": 1e-1}, "coupling.control", "must lie in [H_min, H_max]"),
    ({"tolerance": 1e-6, "H_min": 1e-6, "H_max": 1e-2, "gain": 1}, "coupling.control", "gain"),
])  # fmt: skip
def test_a_bad_control_is_refused_naming_the_key(tmp_path, control_, where, says):
    with pytest.raises(SceneError) as refused:
        load_scene(dmo_scene(tmp_path, 1e-3, 1.0, control=control_))
    assert f": {where}" in str(refused.value) and says in str(refused.value), str(refused.value)


def test_a_unit_that_cannot_save_its_state_is_refused_naming_the_control(tmp_path):
    """OMSimulator's Co-Simulation units declare canGetAndSetFMUstate false: a rejected step could not be retried."""
    with pytest.raises(SceneError) as refused:
        run_signal_scene(load_scene(dmo_scene(tmp_path, 1e-3, 1.0, interface=None, control=control(1e-6))))
    for says in ("subsystems.system1", "canGetAndSetFMUstate=false", "coupling.control", "fixed steps"):
        assert says in str(refused.value), str(refused.value)


def test_the_tolerance_option_runs_a_signal_scene_controlled(tmp_path, capsys):
    """``icosim cosim SCENE --tolerance TOL`` on a scene without a control: the defaults (``H_min = 1e-6 H``,
    ``H_max = t_end - t_start``), every accepted step's error norm at most 1, the steps counted in the summary."""
    path, out = dmo_scene(tmp_path, 1e-3, 0.5, k=1), tmp_path / "run.nc"
    assert main(["cosim", str(path), "--tolerance", "1e-5", "--out", str(out)]) == 0
    assert "accepted_steps" in capsys.readouterr().out
    ds = open_dataset(out)
    assert ds.attrs["control_status"] == "stable" and np.all(ds["control_error"].values[1:] <= 1.0)
    assert ds["time"].values[-1] == pytest.approx(0.5, abs=1e-12)


@pytest.mark.parametrize("implicit", [False, True])
def test_a_restored_checkpoint_repeats_the_step_bit_for_bit(tmp_path, implicit):
    """The problem contract (docs/engine.md): from a restored checkpoint the next macro step, of another size first,
    gives what it gave (every unit's state at T_N set again, the step's size and the time with it)."""
    scene = load_scene(dmo_scene(tmp_path, 1e-3, 1.0, k=1, implicit=implicit, control=control(1e-4)))
    cons, inputs, outputs, _ = signal_wiring(scene)
    units = [open_signal_unit(scene, name, inputs[i], outputs[i]) for i, name in enumerate(scene.names)]
    try:
        problem = SignalCosimulation(units, inputs, outputs, cons, 1, 1e-3, implicit=implicit)
        newton = {"iterations": 10, "tol": 1e-10} if implicit else {}
        state, history, _ = macro_step(problem, None, problem.initial_state(), problem.initial_history(), **newton)
        kept = problem.checkpoint()
        first = macro_step(problem, None, state, history, **newton)
        problem.restore(kept)
        problem.set_macro_step(2e-3, [1e-3])
        other = macro_step(problem, None, state, history, **newton)
        assert problem.time == pytest.approx(3e-3, abs=1e-15)
        problem.restore(kept)
        assert problem.time == pytest.approx(1e-3, abs=1e-15) and problem.H == 1e-3
        again = macro_step(problem, None, state, history, **newton)
    finally:
        for unit in units:
            unit.close()
    assert all(np.array_equal(a, b) for a, b in zip(first, again))
    assert not np.array_equal(first[1], other[1])
