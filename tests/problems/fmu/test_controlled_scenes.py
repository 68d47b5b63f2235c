"""The FMU problem's checkpoint and scenes with controlled macro steps (``coupling.control``).

* checkpoint, step on, restore, step again: the same step bit for bit (co-simulation units of fmus/, and a Model
  Exchange unit of another tool); the run loop's rollback leaves the units at the trajectory's last state;
* a controlled run of the two-unit scene (fmus/msd and fmus/msd_kinematic, fd) and of the three-unit chain rejects
  and accepts steps, and its error against the exact solution -- the rigidly joined masses,
  ``(sum m) x'' = -(sum c) x - (sum d) x'``, computed here with scipy -- follows its tolerance over three decades;
* every accepted step of a controlled run with rejections is the step a fresh problem takes from the same state
  at the same size (the retry starts from the checkpoint, not from where the rejected step left the units);
* the dataset's time is the accepted macro nodes, with the step sizes and the rejected steps' count;
* a control that cannot run is refused naming the key.
"""

import numpy as np
import pytest
import yaml
from helpers import ROOT
from scipy.linalg import expm
from toolchains import OUTSIDE

from icosim.engine.macrostep import macro_step
from icosim.engine.methods import engine_method, get_spec
from icosim.engine.run import simulate
from icosim.errors import StepFailure
from icosim.problems.fmu.controlled import start_history
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.problem import FmuCosimulation
from icosim.problems.fmu.run import consistent_start, open_units, run_dataset_data, run_scene
from icosim.problems.fmu.scene import load_scene

pytestmark = pytest.mark.fmu

TOLERANCES = (1e-3, 10**-4.5, 1e-6)


def scene_file(tmp_path, name, *, control=None, t_end=None, H=None):
    """``config/scenes/<name>`` with its units found in fmus/ and the changes given, written to ``tmp_path``."""
    data = yaml.safe_load((ROOT / "config" / "scenes" / name).read_text())
    for sub in data["subsystems"].values():
        sub["fmu"] = str(ROOT / "fmus" / sub["fmu"].rsplit("/", 1)[-1])
    if control is not None:
        data["coupling"]["control"] = control
    data["t_end"] = data["t_end"] if t_end is None else t_end
    data["coupling"]["H"] = data["coupling"]["H"] if H is None else H
    path = tmp_path / f"{name.removesuffix('.yaml')}_{len(list(tmp_path.iterdir()))}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def problem_of(scene, units, couplings):
    """The scene's problem, as run_scene makes it."""
    c = scene.coupling
    return FmuCosimulation(
        units, couplings, scene.graph(), c["k"], c["H"], t0=float(scene.data.get("t_start", 0.0)),
        perturbation=c["perturbation"], sensitivities=c["sensitivities"], iterations=c["iterations"],
    )  # fmt: skip


class Opened:
    """A scene's units and problem at its consistent start, closed on exit."""

    def __init__(self, path):
        self.scene = load_scene(path)
        self.units, couplings = open_units(self.scene)
        self.problem = problem_of(self.scene, self.units, couplings)
        self.start = consistent_start(self.scene, self.problem)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.problem.close()
        for unit in self.units:
            unit.close()


def exact(scene, times):
    """Positions and velocities of the rigidly joined masses from x0 at rest, ``(time, 2)``."""
    subs = [sub["start"] for sub in scene.data["subsystems"].values()]
    m, c, d = (sum(s[key] for s in subs) for key in ("m", "c", "d"))
    A = np.array([[0.0, 1.0], [-c / m, -d / m]])
    return np.array([expm(A * t) @ [subs[0]["x0"], 0.0] for t in times])


def error(run):
    """The largest error of any unit's position (relative to x0) and velocity (relative to its largest value)."""
    ref = exact(run.scene, run.times)
    dx = np.max(np.abs(run.positions[..., 0] - ref[:, None, 0])) / abs(ref[0, 0])
    dv = np.max(np.abs(run.velocities[..., 0] - ref[:, None, 1])) / np.max(np.abs(ref[:, 1]))
    return max(dx, dv)


# -- the checkpoint -------------------------------------------------------------------------------------------
def steps_repeat(opened, n_before=2):
    """Checkpoint after ``n_before`` steps, two steps on, restore, the step again: bit for bit the same."""
    scene, problem = opened.scene, opened.problem
    state, history = opened.start.state, opened.start.history
    for _ in range(n_before):
        state, history, _ = macro_step(problem, scene.method, state, history, scheme=scene.scheme)
    checkpoint = problem.checkpoint()
    first = macro_step(problem, scene.method, state, history, scheme=scene.scheme)
    on = macro_step(problem, scene.method, first[0], first[1], scheme=scene.scheme)
    assert not np.array_equal(on[0], first[0])
    with pytest.raises(StepFailure, match="only from the state it last returned or restored"):
        macro_step(problem, scene.method, state, history, scheme=scene.scheme)  # the units stand elsewhere
    problem.restore(checkpoint)
    again = macro_step(problem, scene.method, state, history, scheme=scene.scheme)
    for a, b in zip(first, again):
        assert np.array_equal(a, b)
    assert problem.step_index == n_before + 1


@pytest.mark.parametrize("name", ["two_mass_fd.yaml", "chain3.yaml"])
def test_restored_fmu_problem_repeats_its_step_bit_for_bit(tmp_path, name):
    with Opened(scene_file(tmp_path, name)) as opened:
        steps_repeat(opened)


@pytest.mark.outside
def test_restored_model_exchange_unit_repeats_its_step_bit_for_bit(tmp_path):
    """OMSimulator's System1 as Model Exchange (integrated by icosim) against fmus/msd_kinematic."""
    body1 = {"fmu": str(OUTSIDE / "omsimulator" / "DualMassOscillator.System1.fmu"), "start": {"x1_start": 0.1},
             "position": "x1", "velocity": "v1", "acceleration": "a1", "force": "F", "force_sign": 1}  # fmt: skip
    body2 = {"fmu": str(ROOT / "fmus" / "msd_kinematic"), "start": {"m": 2.0, "c": 20.0, "d": 0.5, "x0": 0.1},
             "position": "x", "velocity": "v", "acceleration": "a", "acceleration_input": "a_in",
             "reaction_force": "F", "force_sign": -1}  # fmt: skip
    data = {"subsystems": {"body1": body1, "body2": body2}, "t_end": 0.01,
            "coupling": {"method": "baumgarte", "index": 1, "mu": 5e-3, "decomposition": "fd", "k": 1, "H": 1e-3}}  # fmt: skip
    path = tmp_path / "me.yaml"
    path.write_text(yaml.safe_dump(data))
    with Opened(path) as opened:
        assert opened.units[0].interface == "model-exchange"
        steps_repeat(opened)


def test_restore_takes_only_the_latest_checkpoint(tmp_path):
    with Opened(scene_file(tmp_path, "two_mass_fd.yaml")) as opened:
        scene, problem = opened.scene, opened.problem
        old = problem.checkpoint()
        state, history, _ = macro_step(problem, scene.method, opened.start.state, opened.start.history)
        problem.checkpoint()
        with pytest.raises(StepFailure, match="only its latest checkpoint"):
            problem.restore(old)


def test_rollback_leaves_the_units_at_the_last_kept_step(tmp_path):
    """A run its observer stops at step 3: with rollback, the step from its last state is the full run's third."""
    with Opened(scene_file(tmp_path, "chain3.yaml")) as opened:
        scene, problem, start = opened.scene, opened.problem, opened.start
        stopped = simulate(
            problem, scene.method, start.state, start.history, 5, scheme=scene.scheme, rollback=True,
            observe=lambda n, *_: "stop" if n == 3 else None,
        )  # fmt: skip
        assert stopped.diverged_at == 3 and len(stopped.states) == 3
        history = np.stack(stopped.coupling[::-1])  # k = 1: e_2, e_1
        third = macro_step(problem, scene.method, stopped.states[-1], history, scheme=scene.scheme)
    with Opened(scene_file(tmp_path, "chain3.yaml")) as opened:
        scene, problem, start = opened.scene, opened.problem, opened.start
        full = simulate(problem, scene.method, start.state, start.history, 3, scheme=scene.scheme)
    assert np.array_equal(third[0], full.states[3])


# -- controlled macro steps -----------------------------------------------------------------------------------
def controlled(tmp_path, name, tolerance, t_end=0.05):
    control = {"tolerance": tolerance, "H_min": 1e-10, "H_max": 1e-2}
    return run_scene(scene_file(tmp_path, name, control=control, t_end=t_end, H=1e-4))


@pytest.mark.parametrize("name", ["two_mass_fd.yaml", "chain3.yaml"])
def test_error_follows_the_tolerance(tmp_path, name):
    """Tolerance proportionality: over three decades each tenfold tighter tolerance gives an error smaller by
    between 1 and 100 times ten (the ratio follows the tolerance's within a factor of 10); steps are rejected."""
    runs = [controlled(tmp_path, name, tol) for tol in TOLERANCES]
    for run in runs:
        assert run.status == "completed" and run.times[-1] == pytest.approx(0.05, abs=1e-12)
    assert sum(run.steps.n_rejected for run in runs) > 0
    errors = [error(run) for run in runs]
    for (t1, e1), (t2, e2) in zip(zip(TOLERANCES, errors), zip(TOLERANCES[1:], errors[1:])):
        assert 0.1 < (e1 / e2) / (t1 / t2) < 10
    assert 0.1 < (errors[0] / errors[-1]) / (TOLERANCES[0] / TOLERANCES[-1]) < 10
    assert errors[-1] < 1e-3  # and the tightest is close to the exact solution
    assert len(runs[-1].times) > 3 * len(runs[0].times)  # by taking more steps


def test_a_retry_starts_from_the_checkpoint(tmp_path):
    """Every accepted step of a run with rejections equals, bit for bit, the step of a fresh problem that takes
    the accepted sizes only (each from the state before it, a checkpoint held as the driver holds one)."""
    run = controlled(tmp_path, "chain3.yaml", 1e-5, t_end=0.02)
    assert run.steps.n_rejected > 0 and run.status == "completed"
    with Opened(run.scene.path) as opened:
        scene, problem = opened.scene, opened.problem
        c = scene.coupling
        given = {k: v for k, v in scene.data["coupling"].items() if k in get_spec(c["method"]).arguments}
        dimensional = get_spec(c["method"]).make(**given)
        state, past = opened.start.state, [float(c["H"])] * c["k"]
        history = start_history(problem, opened.start)(float(run.steps.H[0]))  # as the driver restarts it
        states = [state]
        for H in run.steps.H:
            problem.set_macro_step(float(H), past)
            problem.checkpoint()
            state, history, _ = macro_step(problem, engine_method(dimensional, H), state, history, scheme=scene.scheme)
            states.append(state)
            past = ([float(H)] + past)[: c["k"]]
    assert np.array_equal(np.array(states), run.states)


def test_the_dataset_holds_the_accepted_steps(tmp_path):
    """A first step of H_max, too large for the tolerance: rejected, then smaller steps that grow."""
    control = {"tolerance": 1e-5, "H_min": 1e-10, "H_max": 1e-2}
    run = run_scene(scene_file(tmp_path, "two_mass_fd.yaml", control=control, t_end=0.01, H=1e-2))
    ds = run_dataset_data(run)
    H = np.asarray(ds["data_vars"]["macro_step_size"]["data"])
    times = np.asarray(ds["coords"]["time"]["data"])
    assert np.isnan(H[0]) and np.allclose(np.cumsum(H[1:]), times[1:] - times[0], rtol=0, atol=1e-15)
    assert len(np.unique(np.round(H[1:], 15))) > 1  # the steps changed size
    assert ds.attrs["control_rejected_steps"] == run.steps.n_rejected > 0
    assert ds.attrs["control_accepted_steps"] == len(times) - 1


@pytest.mark.parametrize(
    "control, match",
    [
        ({"tolerance": 1e-6, "H_min": 1e-3, "H_max": 1e-2}, r"coupling.control: the first step H = 0.0001 s must lie"),
        ({"tolerance": 1e-6, "H_min": 1e-2, "H_max": 1e-3}, r"coupling.control: controller needs 0 < H_min < H_max"),
        ({"tolerance": 1e-6, "H_min": 1e-6, "H_max": 1e-2, "safety": 2.0}, r"coupling.control: controller needs"),
        ({"tolerance": 1e-6, "H_max": 1e-2}, r"coupling.control"),
        ({"tolerance": 1e-6, "H_min": 1e-6, "H_max": 1e-2, "order": 3}, r"coupling.control"),
    ],
)
def test_a_control_that_cannot_run_is_refused(tmp_path, control, match):
    with pytest.raises(SceneError, match=match):
        load_scene(scene_file(tmp_path, "two_mass_fd.yaml", control=control, H=1e-4))


def test_a_step_rejected_at_h_min_ends_the_run(tmp_path):
    """At a tolerance of 1e-9 the chain's first step needs H below 1e-5 s, so H_min = 1e-5 ends the run at the first
    step, saying why: the error norm at H_min and how it fell over the retries (as H^2, k = 1)."""
    control = {"tolerance": 1e-9, "H_min": 1e-5, "H_max": 1e-2}
    run = run_scene(scene_file(tmp_path, "chain3.yaml", control=control, t_end=0.01, H=1e-4))
    assert run.status == "diverged" and len(run.times) == 1
    assert "> 1 at H_min = 1e-05 s" in run.reason and run.steps.n_rejected > 0
    order = float(run.reason.split("it falls as H^")[1].split(")")[0].split(",")[0])
    assert 1.5 < order < 2.5, run.reason


def first_estimates(opened, history_at, sizes):
    """The predictor-corrector difference of the first macro step (max over the coupling variables, SI) at each
    size, from the start with the history ``history_at(H)``."""
    scene, problem, start = opened.scene, opened.problem, opened.start
    c = scene.coupling
    given = {k: v for k, v in scene.data["coupling"].items() if k in get_spec(c["method"]).arguments}
    dimensional = get_spec(c["method"]).make(**given)
    out = []
    for H in sizes:
        problem.set_macro_step(H, [H] * c["k"])
        history = history_at(H)
        e_p = problem.extrapolate(history)
        checkpoint = problem.checkpoint()
        _, hist, _ = macro_step(problem, engine_method(dimensional, H), start.state, history, scheme=scene.scheme)
        problem.restore(checkpoint)
        out.append(float(np.max(np.abs(hist[0] - e_p))))
    return np.array(out)


def test_the_first_step_s_estimate_is_of_second_order_from_the_start_s_rate(tmp_path):
    """k = 1: the predictor extrapolates the history linearly, so with the history ``e_0 - m H e'_0`` the first
    step's estimate is ``H^2 e''/2`` to leading order (a quarter per halving of H); with ``e_0`` held it is
    ``H e'_0`` (a half per halving), the first-order start a tight tolerance pays for in tiny first steps."""
    sizes = [4e-4, 2e-4, 1e-4, 5e-5]
    with Opened(scene_file(tmp_path, "chain3.yaml")) as opened:
        moved = first_estimates(opened, start_history(opened.problem, opened.start), sizes)
        held = first_estimates(opened, lambda H: opened.start.history, sizes)
    np.testing.assert_allclose(moved[1:] / moved[:-1], 0.25, rtol=0.1)
    np.testing.assert_allclose(held[1:] / held[:-1], 0.5, rtol=0.1)
    assert moved[-1] < 0.05 * held[-1]


# -- ECCO's power residual as the estimate (tests/problems/fmu/test_ecco_steps.py: on OSP's quarter truck) ----------
def power_control(atol, H_min=1e-7):
    return {"estimate": "power-residual", "absolute_tolerance": atol, "H_min": H_min, "H_max": 1e-2}


def test_the_error_falls_as_the_power_tolerance_tightens_on_the_exact_two_unit_system(tmp_path):
    """The two-unit scene's units integrate their linear equations, so the joint's power residual
    ``f_a v_a + f_b v_b`` is the coupling's own (the drive's velocity against the force side's): each tighter decade
    of ``absolute_tolerance`` takes more steps and gives a smaller error against the exact solution."""
    errors, steps = [], []
    for atol in (1e-3, 1e-5, 1e-7, 1e-9):
        run = run_scene(scene_file(tmp_path, "two_mass_fd.yaml", control=power_control(atol), t_end=0.1, H=1e-4))
        assert run.status == "completed"
        errors.append(error(run))
        steps.append(len(run.steps.H))
    assert np.all(np.diff(errors) < 0) and np.all(np.diff(steps) > 0), (errors, steps)


def test_the_power_residual_needs_each_unit_in_one_joint(tmp_path):
    with pytest.raises(SceneError, match=r"coupling.control.estimate: power-residual needs each unit in one joint; "
                                         r"b is in joints 1 and 2"):  # fmt: skip
        load_scene(scene_file(tmp_path, "chain3.yaml", control=power_control(1e-6)))
