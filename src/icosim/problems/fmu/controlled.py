"""A scene's run with controlled macro steps: ``coupling.control`` (docs/fmi.md).

``coupling: {..., H: 1.0e-3, control: {tolerance: 1.0e-6, H_min: 1.0e-6, H_max: 1.0e-2}}`` runs the scene with the
engine's adaptive driver (:func:`icosim.engine.control.driver.adaptive_macro_steps`): ``H`` is the first step's
size, each next one is sized by the PI controller (:class:`icosim.engine.control.controller.StepController`, order
``k + 1``; ``safety``, ``fac_min``, ``fac_max``, ``beta1`` and ``beta2`` optional, as the pendulum study names
them) from the predictor-corrector estimate of the coupling variables (SI) scaled by ``tolerance``.  A rejected
step is retried from the problem's checkpoint (the units' saved FMU states at ``T_N``).  The starting history at
any spacing ``H`` is the start's coupling variables ``e_0`` moved back along their rate at ``t_start``,
``e_0 - m H e'_0`` (:func:`start_history`), so that the first step's estimate is of second order in ``H`` as the
next ones are (a held history makes it first order); a method whose parameters are given in seconds
(``mu``, ``beta``, ``gamma``) is rebuilt for each step's size.  The dataset's ``time`` is the accepted macro nodes,
``macro_step_size(time)`` the step that reached each (NaN at the start), ``control_error(time)`` its error norm,
and the attributes count the rejected steps.
``icosim cosim SCENE --tolerance TOL`` is the scene with ``coupling.control.tolerance: TOL`` (:func:`at_tolerance`:
the scene's other control keys, or ``H_min = 1e-6 H`` and ``H_max = t_end - t_start`` where it has none).

``estimate`` chooses the error estimate (:data:`icosim.engine.control.controller.ESTIMATES`): the
predictor-corrector difference above (``predictor-corrector``, the default) or ECCO's power residual
(``power-residual``: ``{estimate: power-residual, absolute_tolerance: 1.0e-6, H_min: 1.0e-5, H_max: 1.0e-2}``,
with ``relative_tolerance``, ``proportional_gain``, ``integral_gain``, ``safety``, ``fac_min`` and ``fac_max``
optional, defaults as libcosim's configuration of OSP's quarter truck gives them), where every joint is a power
bond: per joint ``r_j = f_a . v_a + f_b . v_b`` from the two sides' coupling forces and velocities at the step's
end, normed by :func:`~icosim.engine.control.controller.power_residual_estimate` and sized by ECCO's PI
controller (:func:`~icosim.engine.control.controller.ecco_controller`).  Such a run's dataset adds
``coupling_force(subsystem, time)`` and ``power_residual(joint, time)`` (docs/fmi.md, "Step control by the power
residual (ECCO)").
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...engine.control.controller import ESTIMATES, StepController, ecco_controller, power_residual_estimate
from ...engine.control.driver import adaptive_macro_steps
from ...engine.methods import engine_method, get_spec
from ...engine.run import Trajectory, simulate
from ...errors import ParameterError
from .errors import SceneError, UnitStepError

__all__ = [
    "CONTROL_KEYS",
    "ESTIMATE_KEYS",
    "control_schema",
    "check_control",
    "check_signal_control",
    "held_history",
    "control_settings",
    "power_residuals",
    "scene_steps",
    "controlled_steps",
    "controlled_entries",
    "start_history",
    "at_tolerance",
]

#: The estimate a control uses where it names none.
DEFAULT_ESTIMATE = "predictor-corrector"

#: Keys of ``coupling.control`` for every estimate, and what they hold (``H_min``, ``H_max`` required).
COMMON_KEYS = {
    "estimate": f"the error estimate: {', '.join(ESTIMATES)} (default {DEFAULT_ESTIMATE})",
    "H_min": "the smallest macro step (s): a step rejected there ends the run",
    "H_max": "the largest macro step (s)",
    "safety": "the controller's safety factor",
    "fac_min": "the smallest factor of one change of H",
    "fac_max": "the largest factor of one change of H",
}

#: Per estimate: its own keys and what they hold, and the defaults of the optional keys (a key without one is
#: required).
ESTIMATE_KEYS = {
    "predictor-corrector": (
        {
            "tolerance": "scales the predictor-corrector estimate: max |e_c - e_p| / (tolerance (1 + |e_c|)) <= 1",
            "beta1": "the PI controller's exponent of the error",
            "beta2": "the PI controller's exponent of the previous error",
        },
        {"safety": 0.9, "fac_min": 0.2, "fac_max": 2.0, "beta1": 0.7, "beta2": 0.4},
    ),
    "power-residual": (
        {
            "absolute_tolerance": "ECCO's absolute tolerance of each joint's energy residual |r_j| H (J)",
            "relative_tolerance": "ECCO's relative tolerance (of the largest energy residual)",
            "proportional_gain": "ECCO's proportional gain k_P (the exponent of the previous error)",
            "integral_gain": "ECCO's integral gain k_I (the error's exponent is k_I + k_P)",
        },
        # libcosim's configuration of the quarter truck (OspSystemStructure.xml and ecco_algorithm_test.cpp)
        {
            "safety": 0.99,
            "fac_min": 0.2,
            "fac_max": 1.5,
            "relative_tolerance": 1e-6,
            "proportional_gain": 0.2,
            "integral_gain": 0.15,
        },  # fmt: skip
    ),
}

#: Every key of ``coupling.control`` and what it holds.
CONTROL_KEYS = {**COMMON_KEYS, **{k: v for own, _ in ESTIMATE_KEYS.values() for k, v in own.items()}}


def control_schema() -> dict:
    """The JSON schema of ``coupling.control`` (which keys each estimate takes: :func:`check_control`)."""
    positive = {"type": "number", "exclusiveMinimum": 0}
    properties = {key: positive for key in CONTROL_KEYS}
    properties["estimate"] = {"enum": list(ESTIMATES)}
    properties["relative_tolerance"] = {"type": "number", "minimum": 0}
    return {"type": "object", "additionalProperties": False, "required": ["H_min", "H_max"], "properties": properties}


def control_settings(path, control) -> tuple[str, dict]:
    """The control's estimate and its settings with the defaults filled in; a :class:`SceneError` names a key the
    estimate does not take or lacks."""
    estimate = control.get("estimate", DEFAULT_ESTIMATE)
    own, defaults = ESTIMATE_KEYS[estimate]
    allowed = [k for k in CONTROL_KEYS if k in COMMON_KEYS or k in own]
    for key in control:
        if key not in allowed:
            raise SceneError(
                f"{path}: coupling.control.{key}: not a key of the {estimate} estimate; its keys: {', '.join(allowed)}"
            )
    missing = [k for k in own if k not in control and k not in defaults]
    if missing:
        raise SceneError(f"{path}: coupling.control: the {estimate} estimate needs {', '.join(missing)}")
    return estimate, {**defaults, **{k: v for k, v in control.items() if k != "estimate"}}


def controller(path, coupling) -> StepController:
    """The scene's controller; a :class:`SceneError` names ``coupling.control`` and what is wrong."""
    estimate, control = control_settings(path, coupling["control"])
    try:
        if estimate == "power-residual":
            ctl = ecco_controller(**{k: control[k] for k in ("safety", "fac_min", "fac_max", "proportional_gain",
                                                             "integral_gain", "H_min", "H_max")})  # fmt: skip
        else:
            control.pop("tolerance")
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


def at_tolerance(scene, tolerance):
    """The scene run with controlled macro steps at ``tolerance`` (the predictor-corrector estimate's): its
    ``coupling.control`` with ``tolerance`` set, or, where it has none, the defaults ``H_min`` a millionth of the
    first step ``H`` and ``H_max`` the run's span ``t_end - t_start``, so that the tolerance alone sizes the steps;
    checked as a scene file's control is.  A :class:`SceneError` says why not: a tolerance that is not a positive
    finite number, or a control of another estimate (which takes no tolerance)."""
    if not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance) and tolerance > 0):
        raise SceneError(f"{scene.path}: coupling.control.tolerance: must be a number > 0, got {tolerance!r}")
    coupling = scene.data["coupling"]
    span = float(scene.data["t_end"]) - float(scene.data.get("t_start", 0.0))
    control = dict(coupling.get("control") or {"H_min": 1e-6 * float(coupling["H"]), "H_max": span})
    estimate = control.get("estimate", DEFAULT_ESTIMATE)
    if estimate != DEFAULT_ESTIMATE:
        raise SceneError(
            f"{scene.path}: coupling.control.estimate: the scene's control uses the {estimate} estimate, which takes "
            f"no tolerance (its keys: {', '.join(ESTIMATE_KEYS[estimate][0])}); a tolerance applies to the "
            f"{DEFAULT_ESTIMATE} estimate"
        )
    control["tolerance"] = float(tolerance)
    data = {**scene.data, "coupling": {**coupling, "control": control}}
    if getattr(scene, "connections", None) is not None:  # a scene of signal connections keeps its checked coupling
        check_signal_control(scene.path, {**scene.coupling, "control": control})
        return dataclasses.replace(scene, data=data, coupling={**scene.coupling, "control": control})
    check_control(scene.path, {**scene.coupling, "control": control}, scene.graph().joints, scene.names)
    return dataclasses.replace(scene, data=data)


def power_bonds(path, joints, names) -> list:
    """The joints as power bonds: ``(first, second)`` unit per joint; a :class:`SceneError` where a unit is in
    more than one joint (its coupling force is then the sum of several joints', and no joint's own)."""
    seen = {}
    for j, joint in enumerate(joints):
        for i in (joint.first, joint.second):
            if i in seen:
                raise SceneError(
                    f"{path}: coupling.control.estimate: power-residual needs each unit in one joint; "
                    f"{names[i]} is in joints {seen[i] + 1} and {j + 1}"
                )
            seen[i] = j
    return [(jt.first, jt.second) for jt in joints]


def power_residuals(bonds, y) -> np.ndarray:
    """Each joint's power residual ``f_a . v_a + f_b . v_b`` (W) from the outputs ``y`` at a step's end
    (``y[i] = (x_i, v_i, a_i, f_i)``, the coupling force ``f_i`` in the graph's sense)."""
    y = np.asarray(y, float)
    return np.array([float(y[a, 3] @ y[a, 1] + y[b, 3] @ y[b, 1]) for a, b in bonds])


def check_control(path, coupling, joints=None, names=()) -> None:
    """Refuse a ``coupling.control`` that cannot run (before any unit is opened); ``joints``: the scene's
    (:class:`~icosim.engine.graph.Joint` s), checked for the power residual."""
    if coupling.get("control") is not None:
        controller(path, coupling)
        if joints is not None and control_settings(path, coupling["control"])[0] == "power-residual":
            power_bonds(path, joints, names)


def check_signal_control(path, coupling) -> None:
    """A scene of signal connections' ``coupling.control``: the predictor-corrector estimate only (the power residual
    needs joints, whose two sides exchange a force and a velocity)."""
    control = coupling.get("control")
    if control is None:
        return
    if not isinstance(control, dict):
        raise SceneError(f"{path}: coupling.control: must be a mapping with tolerance, H_min and H_max")
    if control.get("estimate", DEFAULT_ESTIMATE) != DEFAULT_ESTIMATE:
        raise SceneError(f"{path}: coupling.control.estimate: {control['estimate']!r} is not allowed for signal "
                         f"connections; allowed: {DEFAULT_ESTIMATE} (the power residual needs joints)")  # fmt: skip
    if "tolerance" not in control:
        raise SceneError(f"{path}: coupling.control.tolerance: required (it scales the {DEFAULT_ESTIMATE} estimate)")
    check_control(path, coupling)


def held_history(history):
    """The starting history of a signal scene's controlled run at a spacing ``H``, as a function of ``H``: the
    connections' values at ``t_start`` (``history``'s first row) at every node.  The
    first step's estimate is then of first order in ``H`` whatever ``k`` (the extrapolation of a constant): the
    controller starts with a small step and grows it by ``fac_max`` per step."""
    rows = np.asarray(history, dtype=float)
    return lambda H: np.tile(rows[0], (len(rows), 1))


def start_history(problem, start):
    """The controlled run's starting history at a spacing ``H``, as a function of ``H``: the rows
    ``e_0 - m H e'_0`` (``m = 0 .. k``) from the start's coupling variables and their rate
    (:meth:`~icosim.problems.fmu.problem.FmuCosimulation.coupling_rate`; the units are left at their start)."""
    e0 = np.asarray(start.history[0], dtype=float)
    rate = problem.coupling_rate(e0)
    back = np.arange(problem.k + 1, dtype=float)[:, None]
    return lambda H: e0 - back * float(H) * rate


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
    given = {k: v for k, v in scene.data["coupling"].items() if k in get_spec(c["method"]).arguments}
    dimensional = get_spec(c["method"]).make(**given)
    return controlled_steps(scene, problem, start.state, start.history, bound, accepted,
                            restart=start_history(problem, start), method=scene.method,
                            method_at=lambda H: engine_method(dimensional, H), iterations=c["iterations"])  # fmt: skip


def controlled_steps(scene, problem, state, history, bound, accepted, *, restart, method=None, method_at=None,
                     iterations=1, corrector_tol=None):  # fmt: skip
    """The scene's controlled macro steps from ``state`` and ``history`` at its start (:func:`scene_steps`; a
    scene of joints or of signal connections): ``restart(H)`` the starting history at spacing ``H``, ``method``
    the coupling rule (None: connections only) or ``method_at(H)`` one per step size, ``iterations`` and
    ``corrector_tol`` the macro step's corrector."""
    c = scene.coupling
    ctl = controller(scene.path, c)
    name, settings = control_settings(scene.path, c["control"])
    estimate, tol = None, settings.get("tolerance", math.nan)
    if name == "power-residual":
        bonds = power_bonds(scene.path, problem.graph.joints, scene.names)
        atol, rtol = float(settings["absolute_tolerance"]), float(settings["relative_tolerance"])

        def estimate(H, history, e_p, y):
            return power_residual_estimate(power_residuals(bonds, y), H, atol, rtol)

    states, coupling, outputs = [state], [history[0]], [None]

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
        method,
        state,
        restart(float(c["H"])),
        t_end=float(scene.data["t_end"]) - problem.t0,
        H0=float(c["H"]),
        controller=ctl,
        tol=float(tol),
        estimate=estimate,
        restart=restart,
        method_at=method_at,
        observe=observe,
        on_accept=on_accept,
        scheme=scene.scheme,
        iterations=iterations,
        corrector_tol=corrector_tol,
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
    name, settings = control_settings(run.scene.path, run.scene.coupling["control"])
    attrs = {
        "control_estimate": name,
        "control_accepted_steps": len(steps.H),
        "control_rejected_steps": int(steps.n_rejected),
        "control_status": steps.status,
    }
    entry["control_error"] = (("time",), np.concatenate([[np.nan], steps.estimate]), {
        "units": "1", "comment": f"the {name} estimate's norm of each accepted step (<= 1; NaN at the start)"})  # fmt: skip
    if name == "power-residual":
        bonds = power_bonds(run.scene.path, run.scene.graph().joints, run.scene.names)
        nan = np.full(len(bonds), np.nan)
        residual = np.array([nan] + [power_residuals(bonds, y) for y in run.outputs[1:]])
        squeeze = (lambda a: a[..., 0]) if run.outputs.shape[-1] == 1 else (lambda a: a)
        entry["coupling_force"] = (
            ("subsystem", "time") + (() if run.outputs.shape[-1] == 1 else ("component",)),
            squeeze(np.moveaxis(run.outputs[:, :, 3, :], 0, 1)),
            {"units": "N", "comment": "the coupling force on each unit at the end of each macro step, in the "
             "joints' sense (+lambda on a joint's first side, force_sign times its reaction force on a drive); "
             "NaN at the start"},
        )  # fmt: skip
        entry["power_residual"] = (("joint", "time"), residual.T, {"units": "W", "comment": "f_a . v_a + f_b . v_b "
                                   "of each joint's two sides at the end of each macro step (NaN at the start)"})  # fmt: skip
        attrs |= {f"control_{k}": float(settings[k]) for k in ESTIMATE_KEYS[name][0]}
    return entry, attrs
