"""Scene files: FMU units and how they are joined, checked against a JSON schema before anything is loaded.

Two units (the paper's subsystems 1 and 2), the decomposition in the coupling::

    subsystems:
      body1: {fmu: ../../fmus/msd, start: {m: 1.0, c: 1000.0, d: 2.0, x0: 0.1},
              position: x, velocity: v, acceleration: a, force: lambda, force_sign: 1}
      body2: {fmu: ../../fmus/msd, start: {m: 2.0, c: 500.0, d: 1.0, x0: 0.1},
              position: x, velocity: v, acceleration: a, force: lambda, force_sign: -1}
    coupling: {method: projection, decomposition: ff, k: 1, scheme: jacobi, H: 1.0e-3}
    t_end: 0.5

Any number of units joined by ``joints``, each with its own decomposition (first side, second side)::

    subsystems: {a: {...}, b: {...}, c: {...}}
    joints:
      - {between: [a, b], decomposition: ff}
      - {between: [b, c], decomposition: fd}
    coupling: {method: baumgarte, index: 1, mu: 1.0e-3, k: 1, scheme: gauss-seidel, order: [c, b, a], H: 1.0e-3}

``force_sign`` means what its format says (:meth:`Scene.graph_signs`): without ``joints`` the coupling force
on the unit is ``force_sign * lambda`` (``+lambda`` on the first unit, ``-lambda`` on the second, so physical
inputs have ``1`` and ``-1``); with ``joints`` the unit's input is ``force_sign`` times the sum of its joints'
multipliers, ``+lambda_j`` where it is a joint's first side and ``-lambda_j`` where it is the second (physical
inputs have ``1`` everywhere).  Each unit has one joint point: all its joints attach there, a kinematically
driven unit is in one joint only, and the joints form a tree (a loop would repeat a condition).

``fmu`` is an ``.fmu`` file or a unit's source directory (``modelDescription.xml`` and ``sources/``, built on
first use: :mod:`icosim.problems.fmu.build`), relative to the scene file; subsystems may name the same one
(instances of it).  A joint in the plane (the double pendulum, ``config/scenes/double_pendulum_ff.yaml``) names
two components in every variable entry (``position: [Px, Py]``).  Keys per subsystem: :data:`SUBSYSTEM_KEYS`;
per joint :data:`JOINT_KEYS`; coupling keys: :data:`COUPLING_KEYS` and the method's parameters (as
:func:`icosim.engine.methods.make_method` takes them, dimensional: ``mu`` and ``beta`` in s, ``gamma`` in s^2).
A scene may name an SSP or OSP system file (``system:``, :mod:`icosim.problems.fmu.systems.scene`).
docs/fmi.md has the details.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from ...engine.bounds import MAX_K
from ...engine.graph import CouplingGraph, Joint
from ...engine.methods import engine_method, get_spec
from ...engine.schema import schema_defs
from ...engine.schemes import SCHEMES, GaussSeidel, Scheme, get_scheme
from ...errors import ParameterError
from .build import is_source_dir
from .controlled import check_control, control_schema
from .drives import role_keys
from .errors import SceneError
from .joints import NUMBERED, ORDERED_SCHEMES, check_order, driven_by, graph_message, joint_schema, scene_joints
from .scene_keys import COUPLING_KEYS, JOINT_KEYS, SCENE_KEYS, SUBSYSTEM_KEYS
from .variables import quoted_number_hint

__all__ = ["Scene", "load_scene", "joint_scene", "scene_schema", "SUBSYSTEM_KEYS", "JOINT_KEYS", "COUPLING_KEYS",
           "SCENE_KEYS"]  # fmt: skip

#: Subsystem keys that do not name unit variables.
_NOT_NAMES = ("fmu", "start", "force_sign", "mass", "rollback_tolerance", "interface", "tolerance", "record")


def scene_schema() -> dict:
    """The JSON schema of a scene (the registries of methods, decompositions and schemes filled in)."""
    defs = schema_defs()
    name = {"type": "string", "minLength": 1}
    # one variable, or the components of a vector quantity (a joint in the plane: two)
    names = {"oneOf": [name, {"type": "array", "items": name, "minItems": 1, "maxItems": 3}]}
    sub = {
        "type": "object",
        "additionalProperties": False,
        "required": ["fmu", "force_sign"],  # the variables each kind needs: load_scene
        "properties": {
            "fmu": name,
            "start": {
                "type": "object",
                # typed against the unit's model description when it is opened (icosim.problems.fmu.variables)
                "additionalProperties": {"type": ["number", "boolean", "string", "array", "object"]},
            },
            **{k: names for k in SUBSYSTEM_KEYS if k not in _NOT_NAMES},
            "force_sign": {"enum": [1, -1]},
            "mass": {"oneOf": [{"type": "number", "exclusiveMinimum": 0}, name]},
            "rollback_tolerance": {"type": "number", "minimum": 0},
            "interface": {"enum": ["auto", "co-simulation", "model-exchange"]},
            "tolerance": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1},
            "record": {"type": "array", "items": name, "uniqueItems": True},
        },
    }
    params = defs["method_parameters"]["properties"]
    coupling = {
        "type": "object",
        "additionalProperties": False,
        "required": ["method", "k", "H"],
        "properties": {
            "method": defs["method"],
            "decomposition": defs["decomposition"],
            "k": {"type": "integer", "minimum": 0, "maximum": MAX_K},
            "scheme": {
                "anyOf": [
                    {"enum": [*SCHEMES, *ORDERED_SCHEMES]},
                    {"type": "string", "pattern": NUMBERED},
                ]
            },
            "order": {"type": "array", "items": name, "minItems": 2, "uniqueItems": True},
            "H": {"type": "number", "exclusiveMinimum": 0},
            "iterations": {"type": "integer", "minimum": 1, "maximum": 100},
            "inputs": {"enum": ["auto", "derivatives", "substeps"]},
            "substeps": {"type": "integer", "minimum": 1, "maximum": 100000},
            "perturbation": {"type": "number", "exclusiveMinimum": 0},
            "sensitivities": {"enum": ["each-step", "first-step"]},
            "control": control_schema(),
            **params,
        },
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "type": "object",
        "additionalProperties": False,
        "required": ["subsystems", "coupling", "t_end"],
        "properties": {
            "subsystems": {"type": "object", "minProperties": 2, "additionalProperties": sub},
            "joints": {"type": "array", "minItems": 1, "items": joint_schema(name, defs["decomposition"])},
            "coupling": coupling,
            "t_start": {"type": "number"},
            "t_end": {"type": "number"},
            "initial_coupling": {"type": "array", "items": {"type": "number"}},
            "initial": {"enum": ["check", "project", "as-is"]},
            "initial_tolerance": {"type": "number", "exclusiveMinimum": 0},
            "divergence_bound": {"type": "number", "exclusiveMinimum": 0},
            "limits": {
                "type": "object",
                "additionalProperties": False,
                "properties": {
                    "call_seconds": {"type": "number", "exclusiveMinimum": 0},
                    "identify_seconds": {"type": "number", "exclusiveMinimum": 0},
                },
            },
        },
        # with joints each joint has its decomposition; without, two subsystems joined by the coupling's
        "if": {"required": ["joints"]},
        "then": {"properties": {"coupling": {"not": {"required": ["decomposition"]}}}},
        "else": {"properties": {"subsystems": {"maxProperties": 2}, "coupling": {"required": ["decomposition"]}}},
    }


@dataclass
class Scene:
    """A checked scene: where it came from, its content, and what follows from it."""

    path: Path
    data: dict
    fmus: dict  # subsystem -> Path of its .fmu file or source directory
    method: object  # the CouplingMethod with the engine's (dimensionless) parameters
    n_steps: int
    joints: tuple = ()  # the Joints (0-based subsystems); empty: the two subsystems of the coupling's decomposition
    n_dim: int = 1  # components of every position entry (1: a line, 2: the plane)
    system: object = None  # the system file it came from (icosim.problems.fmu.systems), or None

    @property
    def names(self) -> tuple:
        return tuple(self.data["subsystems"])

    @property
    def has_joints(self) -> bool:
        """Does the scene join its units by ``joints`` (else: two units, ``coupling.decomposition``)?"""
        return "joints" in self.data

    @property
    def scheme(self) -> Scheme:
        """The coupling scheme: a registered one, a numbered order, or ``gauss-seidel`` with ``coupling.order``
        (the names turned into the subsystems' numbers in file order)."""
        given = self.data["coupling"].get("scheme", COUPLING_KEYS["scheme"])
        if given in ORDERED_SCHEMES:
            numbers = [self.names.index(n) + 1 for n in self.data["coupling"]["order"]]
            leading = "as-integrated" if given.endswith("-as-integrated") else "reevaluated"
            return GaussSeidel(numbers, leading)
        return get_scheme(given)

    @property
    def coupling(self) -> dict:
        """The coupling keys with their defaults; ``scheme`` is the scheme's name (``gauss-seidel-312``), also
        where the scene gives ``gauss-seidel`` with an order."""
        return {**COUPLING_KEYS, **self.data["coupling"], "scheme": self.scheme.name}

    @property
    def decompositions(self) -> tuple:
        """Each joint's decomposition name, in the joints' order."""
        return tuple(j.decomposition.name for j in self.graph().joints)

    def graph(self, n_components: int | None = None) -> CouplingGraph:
        """The units and joints (:mod:`icosim.engine.graph`), one port per unit: the scene's ``joints``, or the
        two units joined by the coupling's decomposition."""
        n = self.n_dim if n_components is None else n_components
        joints = self.joints or (Joint(0, 1, self.data["coupling"]["decomposition"]),)
        return CouplingGraph(len(self.names), joints, n, names=self.names)

    def graph_signs(self) -> list[int]:
        """Per unit, the sign with which the graph's coupling force reaches its input.  With ``joints`` that is
        the scene's ``force_sign``; without, the scene gives the sign of ``lambda`` on each unit, and the graph
        acts with ``-lambda`` on the second."""
        subs = self.data["subsystems"].values()
        if self.has_joints:
            return [int(sub["force_sign"]) for sub in subs]
        return [int(sub["force_sign"]) * (1 if i == 0 else -1) for i, sub in enumerate(subs)]

    def joint_label(self, j: int) -> str:
        """``joints[j] (a–b, ff)``, or ``the joint`` of a scene without joints."""
        if not self.has_joints:
            return "the joint"
        jt = self.graph().joints[j]
        return f"joints[{j}] ({self.names[jt.first]}–{self.names[jt.second]}, {jt.decomposition.name})"

    def describe(self, *, scheme: bool = True) -> str:
        """The coupling in one line: method, decomposition or joints, ``k``, scheme (with the order by name;
        ``scheme=False``: without), H."""
        c = self.coupling
        if self.has_joints:
            joined = ", ".join(
                f"{self.names[jt.first]}–{self.names[jt.second]} {jt.decomposition.name}" for jt in self.graph().joints
            )
            how = f"{len(self.names)} units, joints {joined}"
        else:
            how = str(c["decomposition"])
        which = f", {self.scheme_text()}" if scheme else ""
        return f"{self.method.name}, {how}, k = {c['k']}{which}, H = {c['H']:g} s"

    def scheme_text(self, scheme: Scheme | None = None) -> str:
        """A scheme's name, with the order by the subsystems' names where the scene has joints
        (``gauss-seidel-321 (c → b → a)``)."""
        scheme = self.scheme if scheme is None else scheme
        order = getattr(scheme, "order", None)
        if not self.has_joints or order is None:
            return scheme.name
        return f"{scheme.name} ({' → '.join(self.names[i - 1] for i in order)})"


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


def load_scene(path) -> Scene:
    """Read and check a scene file, or an SSP or OSP system file as a scene (:mod:`icosim.problems.fmu.systems`; no
    unit is loaded): :class:`~icosim.problems.fmu.errors.SceneError` names the file, the key and what is allowed."""
    from .signal_scene import is_signal_scene, signal_scene
    from .systems.scene import scene_data

    path = Path(path)
    data, system = scene_data(path)
    if is_signal_scene(data) and "joints" in data:  # beside joints (.joint_signal_scene; its joints checked here)
        from .joint_signal_scene import joint_signal_scene

        return joint_signal_scene(path, data, system, joint_scene)
    if is_signal_scene(data):  # units coupled by connections (.signal_scene)
        return signal_scene(path, data, system)
    return joint_scene(path, data, system)


def joint_scene(path, data, system=None) -> Scene:
    """A scene of joints (or the paper's two units) from its ``data`` (read from ``path``), checked."""
    _validate(path, data)
    c = {**COUPLING_KEYS, **data["coupling"]}
    names = list(data["subsystems"])
    joints = scene_joints(path, data, names)
    spec = get_spec(c["method"])
    given = {k: c[k] for k in data["coupling"] if k not in COUPLING_KEYS}
    extra = sorted(set(given) - set(spec.arguments))
    if extra:
        its = ", ".join(spec.arguments) or "none"
        _fail(path, f"coupling.{extra[0]}", f"not a parameter of method {spec.name} (its parameters: {its})")
    try:
        method = spec.make(**given)
    except ParameterError as exc:
        _fail(path, "coupling", str(exc))
    for j, joint in enumerate(joints or (Joint(0, 1, c["decomposition"]),)):
        try:
            method.check_decomposition(joint.decomposition)
        except ParameterError as exc:
            _fail(path, f"joints[{j}].decomposition" if joints else "coupling", str(exc))
    try:
        method = engine_method(method, c["H"])
    except ParameterError as exc:
        _fail(path, "coupling", str(exc))
    check_control(path, c, joints or (Joint(0, 1, c["decomposition"]),), names)
    t0, t_end, H = float(data.get("t_start", 0.0)), float(data["t_end"]), float(c["H"])
    steps = (t_end - t0) / H
    if not steps >= 1 or abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
        whole = f"t_end - t_start = {t_end - t0:g} s must be a whole number (>= 1) of macro steps H = {H:g} s"
        _fail(path, "t_end", whole)
    fmus = {}
    entries = {
        f"{sname}.{key}": len(v) if isinstance(v, list) else 1
        for sname, sub in data["subsystems"].items()
        for key, v in sub.items()
        if key in SUBSYSTEM_KEYS and key not in _NOT_NAMES
    }
    if len(set(entries.values())) > 1:
        sizes = ", ".join(f"{key}: {n}" for key, n in entries.items())
        _fail(
            path,
            "subsystems",
            f"every variable entry must name as many components (one name, or lists of one length), got {sizes}",
        )
    n_dim = next(iter(entries.values()), 1)
    scene = Scene(path, data, fmus, method, int(round(steps)), joints, n_dim, system)
    graph = scene.graph()
    check_order(path, data["coupling"], scene, graph, method)
    if "initial_coupling" in data and len(data["initial_coupling"]) != graph.n_coupling:
        variables = graph.variable_names() if joints else graph.joints[0].decomposition.variables
        _fail(
            path,
            "initial_coupling",
            f"needs {graph.n_coupling} values ({', '.join(variables)}, {n_dim} component(s) each), got "
            f"{len(data['initial_coupling'])}",
        )
    for i, (name, sub) in enumerate(data["subsystems"].items()):
        kind = graph.port_kind(i, 0)
        projects = method.projection or data.get("initial") == "project"
        need = role_keys(path, data, graph, i, spec.name, projects, driven_by(scene, graph, i))
        for key in need:
            if key not in sub:
                why = (
                    f"subsystem {name} is {kind}-driven in {driven_by(scene, graph, i)}"
                    if key not in ("mass", "set_position", "set_velocity")
                    else f"method {spec.name} projects"
                    if method.projection
                    else "initial: project moves the units onto the joint"
                )
                _fail(path, f"subsystems.{name}.{key}", f"required: {why} ({SUBSYSTEM_KEYS[key]})")
        if projects and isinstance(sub.get("position"), list) and len(sub["position"]) > 1:
            _fail(
                path,
                f"subsystems.{name}.position",
                "projection moves one position per unit (the mass-weighted "
                "mean of Eq. 30); a joint with more components needs the method baumgarte or weighted",
            )
        fmu = (path.parent / sub["fmu"]).resolve()
        if not fmu.exists():
            _fail(path, f"subsystems.{name}.fmu", f"{sub['fmu']} does not exist (resolved to {fmu})")
        if fmu.is_dir() and not is_source_dir(fmu):
            _fail(
                path,
                f"subsystems.{name}.fmu",
                f"{sub['fmu']} is a directory but not a unit's source (it needs modelDescription.xml beside "
                "sources/); name the .fmu file or a unit's source directory",
            )
        fmus[name] = fmu
    return scene


def _validate(path, data):
    try:
        import jsonschema
    except ImportError:  # pragma: no cover - the fmi extra installs it
        raise SceneError(f"{path}: checking a scene needs jsonschema (pip install icosim[fmi])") from None
    validator = jsonschema.Draft202012Validator(scene_schema())
    errors = sorted(validator.iter_errors(data), key=lambda e: (len(e.absolute_path), list(map(str, e.absolute_path))))
    if not errors:
        _check_numbers(path, data)
        return
    err = errors[0]
    where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in err.absolute_path).lstrip(".") or "top level"
    message = err.message
    joined = graph_message(where, err, data)
    if joined is not None:
        message = joined
    elif err.validator == "enum":
        message = f"{err.instance!r} is not allowed; allowed: {', '.join(map(str, err.validator_value))}"
    elif err.validator == "required":
        keys = err.schema.get("properties", {})
        message = f"{message}; its keys: {', '.join(keys)}"
    elif err.validator == "type" and isinstance(err.instance, str) and quoted_number_hint(err.instance):
        message = f"{message}{quoted_number_hint(err.instance)}"
    elif err.validator == "additionalProperties":
        message = f"{message}; allowed keys: {', '.join(err.schema.get('properties', {}))}"
    raise SceneError(f"{path}: {where}: {message}")


def _check_numbers(path, data):
    for key in ("t_start", "t_end"):
        if key in data and not math.isfinite(float(data[key])):
            _fail(path, key, f"must be a finite number, got {data[key]!r}")
