"""A scene's run with controlled macro steps: ``coupling.control`` (docs/fmi.md).

``coupling: {..., H: 1.0e-3, control: {tolerance: 1.0e-6, H_min: 1.0e-6, H_max: 1.0e-2}}`` runs the scene with the
engine's adaptive driver (:func:`icosim.engine.control.driver.adaptive_macro_steps`): ``H`` is the first step's
size, each next one is sized by the PI controller (:class:`icosim.engine.control.controller.StepController`, order
``k + 1``; ``safety``, ``fac_min``, ``fac_max``, ``beta1`` and ``beta2`` optional, as the pendulum study names
them) from the predictor-corrector estimate of the coupling variables (SI) scaled by ``tolerance``.  A rejected
step is retried from the problem's checkpoint (the units' saved FMU states at ``T_N``).  The starting history at
any spacing is the consistent start's coupling variables held; a method whose parameters are given in seconds
(``mu``, ``beta``, ``gamma``) is rebuilt for each step's size.  The dataset's ``time`` is the accepted macro nodes,
``macro_step_size(time)`` the step that reached each (NaN at the start), and the attributes count the rejected
steps.
"""

from __future__ import annotations

import math

import numpy as np

from ...engine.control.controller import StepController
from ...engine.control.driver import adaptive_macro_steps
from ...engine.methods import engine_method, get_spec
from ...engine.run import Trajectory, simulate
from ...errors import ParameterError
from .errors import SceneError, UnitStepError

__all__ = ["CONTROL_KEYS", "control_schema", "check_control", "scene_steps", "controlled_entries"]

#: Keys of ``coupling.control`` and what they hold (the first three required).
CONTROL_KEYS = {
    "tolerance": "scales the predictor-corrector estimate: max |e_c - e_p| / (tolerance (1 + |e_c|)) <= 1",
    "H_min": "the smallest macro step (s): a step rejected there ends the run",
    "H_max": "the largest macro step (s)",
    "safety": "the controller's safety factor (default 0.9)",
    "fac_min": "the smallest factor of one change of H (default 0.2)",
    "fac_max": "the largest factor of one change of H (default 2)",
    "beta1": "the PI controller's exponent of the error (default 0.7)",
    "beta2": "the PI controller's exponent of the previous error (default 0.4)",
}


def control_schema() -> dict:
    """The JSON schema of ``coupling.control``."""
    positive = {"type": "number", "exclusiveMinimum": 0}
    return {
        "type": "object",
        "additionalProperties": False,
        "required": ["tolerance", "H_min", "H_max"],
        "properties": {key: positive for key in CONTROL_KEYS},
    }


def controller(path, coupling) -> StepController:
    """The scene's controller; a :class:`SceneError` names ``coupling.control`` and what is wrong."""
    control = dict(coupling["control"])
    control.pop("tolerance")
    try:
        ctl = StepController(order=int(coupling["k"]) + 1, **control)
    except ParameterError as exc:
        raise SceneError(f"{path}: coupling.control: {exc}") from None
    H = float(coupling["H"])
    if not ctl.H_min <= H <= ctl.H_max:
        raise SceneError(
            f"{path}: coupling.control: the first step H = {H:g} s must lie in [H_min, H_max] = "
            f"[{ctl.H_min:g}, {ctl.H_max:g}] s"
        )
    return ctl


def check_control(path, coupling) -> None:
    """Refuse a ``coupling.control`` that cannot run (before any unit is opened)."""
    if coupling.get("control") is not None:
        controller(path, coupling)


def scene_steps(scene, problem, start, bound, accepted):
    """The scene's macro steps from its start: the run as a :class:`~icosim.engine.run.Trajectory`, its times and,
    for a controlled run, the driver's :class:`~icosim.engine.control.driver.AdaptiveSteps` (else None).  Fixed
    steps are the engine's run loop (:func:`icosim.engine.run.simulate`).  ``bound``: the divergence bound of the
    state; ``accepted(n, state, history, y)`` is called after each accepted step."""
    c = scene.coupling
    if c["control"] is None:
        traj = simulate(
            problem,
            scene.method,
            start.state,
            start.history,
            scene.n_steps,
            scheme=scene.scheme,
            iterations=c["iterations"],
            bound=bound,
            observe=accepted,
        )
        return traj, problem.t0 + c["H"] * np.arange(len(traj.states)), None
    ctl = controller(scene.path, c)
    given = {k: v for k, v in scene.data["coupling"].items() if k in get_spec(c["method"]).arguments}
    dimensional = get_spec(c["method"]).make(**given)
    states, coupling, outputs = [start.state], [start.history[0]], [None]

    def observe(n, state, history, y):
        worst = float(np.max(np.abs(state)))
        if not math.isfinite(worst):
            return "state not finite"
        return f"|state| > {bound:g}" if worst > bound else None

    def on_accept(state, history, y):
        states.append(state)
        coupling.append(history[0])
        outputs.append(y)
        accepted(len(states) - 1, state, history, y)

    steps = adaptive_macro_steps(
        problem,
        scene.method,
        start.state,
        start.history,
        t_end=float(scene.data["t_end"]) - problem.t0,
        H0=float(c["H"]),
        controller=ctl,
        tol=float(c["control"]["tolerance"]),
        restart=lambda H: start.history,  # the consistent start's coupling variables, held
        method_at=lambda H: engine_method(dimensional, H),
        observe=observe,
        on_accept=on_accept,
        scheme=scene.scheme,
        iterations=c["iterations"],
    )
    traj = Trajectory(states, coupling, outputs, steps=len(steps.H))
    if steps.status == "failed":  # a step that could not be computed even at H_min, or too many steps
        traj.failed_at, traj.reason = len(states), steps.reason
        at = f"t = {problem.t0 + steps.t[-1]:.12g} s"
        traj.error = (
            SceneError(f"{scene.path}: coupling.control: {steps.reason} (at {at}): raise H_min or the tolerance")
            if steps.reason.startswith("more than")
            else UnitStepError(f"no acceptable macro step at {at} down to H_min = {ctl.H_min:g} s: {steps.reason}")
        )
    elif steps.status == "diverged":
        traj.diverged_at, traj.reason = len(states), steps.reason
    return traj, problem.t0 + steps.t, steps


def controlled_entries(run) -> tuple[dict, dict]:
    """The dataset's entries and attributes of a controlled run (none for a run of fixed steps)."""
    steps = run.steps
    if steps is None:
        return {}, {}
    H = np.concatenate([[np.nan], steps.H])
    entry = {"macro_step_size": (("time",), H, {"units": "s", "comment": "the accepted step that reached each "
                                                 "time (NaN at the start)"})}  # fmt: skip
    attrs = {
        "control_accepted_steps": len(steps.H),
        "control_rejected_steps": int(steps.n_rejected),
        "control_status": steps.status,
    }
    return entry, attrs
