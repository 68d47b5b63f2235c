"""A scene of FMU units joined by joints beside units coupled by signal connections: checked, run by the one macro
step, written as one dataset
(:mod:`icosim.problems.fmu.joint_signal_run`).

::

    subsystems:
      body1: {fmu: ../../fmus/msd, start: {m: 1.0, c: 1000.0, d: 2.0, x0: 0.1},
              position: x, velocity: v, acceleration: a, force: lambda, force_sign: 1, mass: m, ...}
      body2: {fmu: ../../fmus/msd, start: {...}, position: x, ..., force_sign: 1}
      sensor: {fmu: ../../fmus/msd, start: {...}}
    joints:
      - {between: [body1, body2], decomposition: ff}
    connections:
      - {from: body1.x, to: sensor.lambda, factor: 200.0}
    coupling: {method: projection, k: 1, scheme: jacobi, H: 1.0e-3}
    t_end: 0.5

A unit in a joint has the keys of a scene of joints (:mod:`icosim.problems.fmu.scene`) and may give and take
connections' values through variables other than its joint's; a unit in no joint has those of a scene of connections
(:data:`~icosim.problems.fmu.signal_scene.SIGNAL_SUBSYSTEM_KEYS`) and takes part in a connection.  ``coupling``: the
keys of a scene of joints (the method closes the joints' conditions), ``scheme`` ``gauss-seidel`` with an ``order``
naming every unit (or ``gauss-seidel-<numbers>`` of every unit in file order), and ``implicit`` (default false: the
connections coupled explicitly, their inputs held or extrapolated with the joints' ``k``, :mod:`icosim.engine.macrostep`).
The part of the scene that the joints make is checked as a scene of joints (:attr:`JointSignalScene.joints`); the
run and its dataset: :mod:`icosim.problems.fmu.joint_signal_run`.  docs/signals.md, "Joints beside connections",
has the details.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ...engine.schemes import GaussSeidel, Scheme, get_scheme
from ...errors import ParameterError
from .errors import SceneError
from .joints import ORDERED_SCHEMES
from .scene_keys import COUPLING_KEYS, SCENE_KEYS, SUBSYSTEM_KEYS
from .signal_scene import IMPLICIT_DEFAULTS, check_signal_subsystem, scene_connections

__all__ = ["JointSignalScene", "joint_signal_scene"]

#: Coupling keys of the connections beside the joints' (:data:`~icosim.problems.fmu.scene.COUPLING_KEYS`).
SIGNAL_KEYS = {"implicit": False, "tol": None}
#: A joint unit's keys that name its joint's variables (a connection may not feed or read them instead).
_JOINT_VARIABLES = ("force", "acceleration_input", "position_input", "velocity_input", "set_position", "set_velocity")


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


@dataclass
class JointSignalScene:
    """A checked scene of joints and connections: ``joints`` the scene of the joint units alone (their
    :class:`~icosim.problems.fmu.scene.Scene`), ``connections`` as ``(source, output, target, input, factor, offset)``
    by name, ``coupling`` every coupling key with its default, ``scheme`` over every unit."""

    path: Path
    data: dict
    joints: object  # the joint units' icosim.problems.fmu.scene.Scene
    subsystems: dict
    connections: list
    coupling: dict
    scheme: Scheme
    t0: float
    t_end: float
    system: object = None

    @property
    def names(self) -> tuple:
        return tuple(self.subsystems)

    @property
    def n_steps(self) -> int:
        return self.joints.n_steps  # type: ignore[attr-defined]

    @property
    def method(self):
        return self.joints.method  # type: ignore[attr-defined]

    @property
    def signal_units(self) -> tuple:
        """The units in no joint."""
        return tuple(n for n in self.names if n not in self.joints.names)  # type: ignore[attr-defined]


def joint_signal_scene(path, data, system, joint_scene) -> JointSignalScene:
    """Check a scene of joints and connections (module docstring) before any unit is opened; ``joint_scene``
    checks the part the joints make as a scene of joints (:func:`icosim.problems.fmu.scene.joint_scene`)."""
    path = Path(path)
    allowed = (*SCENE_KEYS, "connections")
    for key in data:
        if key not in allowed:
            _fail(path, key, f"not a key of a scene of joints and connections; allowed: {', '.join(allowed)}")
    subs, joints = data.get("subsystems"), data.get("joints")
    if not isinstance(subs, dict) or len(subs) < 2:
        _fail(path, "subsystems", "must map at least two subsystem names to their settings")
    joined = (
        {n for j in joints if isinstance(j, dict) for n in j.get("between") or ()}
        if isinstance(joints, list)
        else set()
    )
    for name, sub in subs.items():
        if name not in joined:
            check_signal_subsystem(path, name, sub)
    coupling = data.get("coupling")
    if not isinstance(coupling, dict):
        _fail(path, "coupling", "must be a mapping with method, k and H")
    c = {**COUPLING_KEYS, **SIGNAL_KEYS, **coupling}
    if not isinstance(c["implicit"], bool):
        _fail(path, "coupling.implicit", f"must be true or false, got {c['implicit']!r}")
    if c["tol"] is not None and not c["implicit"]:
        _fail(path, "coupling.tol", "Newton's tolerance belongs to implicit: true")
    if c["implicit"]:  # Newton's iterations (at most) and tolerance
        c["iterations"] = coupling.get("iterations", IMPLICIT_DEFAULTS["iterations"])
        if c["tol"] is None:
            c["tol"] = IMPLICIT_DEFAULTS["tol"]
        elif isinstance(c["tol"], bool) or not isinstance(c["tol"], (int, float)) or not c["tol"] > 0:
            _fail(path, "coupling.tol", f"must be a number > 0, got {c['tol']!r}")
    if c["control"] is not None:
        _fail(path, "coupling.control", "controlled macro steps are for a scene of joints alone; beside connections "
              "the macro step is fixed (remove control)")  # fmt: skip
    names = list(subs)
    scheme, joint_scheme = _scheme(path, c, names, [n for n in names if n in joined])
    joint_data = {k: v for k, v in data.items() if k != "connections"}
    joint_data["subsystems"] = {n: s for n, s in subs.items() if n in joined}
    joint_data["coupling"] = {k: v for k, v in coupling.items() if k not in (*SIGNAL_KEYS, "scheme", "order")}
    joint_data["coupling"] |= joint_scheme
    scene = joint_scene(path, joint_data, system)
    specs, fed = scene_connections(path, data["connections"], subs)
    for n, (source, output, target, input_, _, _) in enumerate(specs):
        for who, var, end in ((source, output, "from"), (target, input_, "to")):
            sub = subs[who]
            taken = [k for k in (*_JOINT_VARIABLES, "position", "velocity", "acceleration", "reaction_force")
                     if who in joined and sub.get(k) == var]  # fmt: skip
            if end == "to" and taken:
                _fail(path, f"connections[{n}].to", f"{who}.{var} is {who}'s {taken[0]} ({SUBSYSTEM_KEYS[taken[0]]}): "
                      "its joint sets it; a connection feeds another input")  # fmt: skip
            if end == "to" and who in joined and ("position_input" in sub or "velocity_input" in sub):
                _fail(path, f"connections[{n}].to", f"{who} is a drive (its point's motion prescribed), which takes no "
                      "connection's input")  # fmt: skip
    used = {u for s in specs for u in (s[0], s[2])}
    alone = [n for n in names if n not in joined and n not in used]
    if alone:
        _fail(path, f"subsystems.{alone[0]}", "takes part in no joint or connection")
    t0 = float(data.get("t_start", 0.0))
    return JointSignalScene(path, data, scene, dict(subs), specs, c, scheme, t0, float(data["t_end"]), system)


def _scheme(path, c, names, joined) -> tuple[Scheme, dict]:
    """The scheme over every unit and the joint units' part of it (their order kept) for the scene of joints."""
    given = c["scheme"]
    if given in ORDERED_SCHEMES:
        order = c["order"]
        if not isinstance(order, list) or sorted(map(str, order)) != sorted(names):
            _fail(path, "coupling.order", f"{given} needs every subsystem once, those in joints and those in "
                  f"connections only, e.g. {names}; got {order!r}")  # fmt: skip
        leading = "as-integrated" if given.endswith("-as-integrated") else "reevaluated"
        scheme: Scheme = GaussSeidel([names.index(n) + 1 for n in order], leading)
    else:
        if c["order"] is not None:
            _fail(path, "coupling.order", f"only with scheme {' or '.join(ORDERED_SCHEMES)}")
        try:
            scheme = get_scheme(given)
        except ParameterError as exc:
            _fail(path, "coupling.scheme", f"{exc}; or gauss-seidel with order: {names}")
    numbers = getattr(scheme, "order", None)
    if numbers is None:
        return scheme, {"scheme": given}
    if len(numbers) != len(names):
        _fail(path, "coupling.scheme", f"{given} orders {len(numbers)} subsystems, the scene has {len(names)} "
              f"({', '.join(names)}, numbered in file order); or gauss-seidel with order: {names}")  # fmt: skip
    name = ORDERED_SCHEMES[1] if getattr(scheme, "leading_outputs", "") == "as-integrated" else ORDERED_SCHEMES[0]
    return scheme, {"scheme": name, "order": [names[i - 1] for i in numbers if names[i - 1] in joined]}
