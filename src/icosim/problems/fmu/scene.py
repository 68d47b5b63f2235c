"""Scene files: two FMU units and how they are coupled, checked against a JSON schema before anything is loaded.

A scene (YAML)::

    subsystems:
      body1: {fmu: ../../fmus/msd, start: {m: 1.0, c: 1000.0, d: 2.0, x0: 0.1},
              position: x, velocity: v, acceleration: a, force: lambda, force_sign: 1}
      body2: {fmu: ../../fmus/msd, start: {m: 2.0, c: 500.0, d: 1.0, x0: 0.1},
              position: x, velocity: v, acceleration: a, force: lambda, force_sign: -1}
    coupling: {method: projection, decomposition: ff, k: 1, scheme: jacobi, H: 1.0e-3}
    t_end: 0.5

``fmu`` is an ``.fmu`` file or a unit's source directory (``modelDescription.xml`` and ``sources/``, built on
first use: :mod:`icosim.problems.fmu.build`), relative to the scene file; two subsystems may name the same one (two
instances).  The first subsystem is the paper's subsystem 1.  A joint in the plane (the double pendulum,
``config/scenes/double_pendulum_ff.yaml``) names two components in every variable entry
(``position: [Px, Py]``).  Keys per subsystem: :data:`SUBSYSTEM_KEYS`;
coupling keys: :data:`COUPLING_KEYS` and the method's parameters (as :func:`icosim.engine.methods.make_method`
takes them, dimensional: ``mu`` and ``beta`` in s, ``gamma`` in s^2).  docs/fmi.md has the details.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from ...engine.bounds import MAX_K
from ...engine.decompositions import get_decomposition
from ...engine.graph import CouplingGraph, Joint
from ...engine.methods import engine_method, get_spec
from ...engine.schema import schema_defs
from ...errors import ParameterError
from .build import is_source_dir
from .errors import SceneError

__all__ = ["Scene", "load_scene", "scene_schema", "SUBSYSTEM_KEYS", "COUPLING_KEYS", "SCENE_KEYS"]

#: Keys of one subsystem and what they hold.
SUBSYSTEM_KEYS = {
    "fmu": "the unit: an .fmu file or a source directory, relative to the scene file",
    "start": "start values of the unit's parameters and inputs",
    "position": "name of the position output",
    "velocity": "name of the velocity output",
    "acceleration": "name of the acceleration output",
    "force": "name of the coupling-force input (a force-driven subsystem)",
    "acceleration_input": "name of the prescribed-acceleration input (a kinematically driven subsystem)",
    "reaction_force": "name of the output of the force the drive exerts (a kinematically driven subsystem)",
    "force_sign": "+1 or -1: the coupling force on this subsystem is force_sign * lambda",
    "mass": "the mass (a number, or the name of a unit variable holding it): the projection's weight",
    "set_position": "name of a tunable parameter or input that sets the position (projection)",
    "set_velocity": "name of a tunable parameter or input that sets the velocity (projection)",
    "rollback_tolerance": "relative difference accepted when a restored step is repeated (default 0: bit for bit)",
}

#: Top-level keys of a scene and what they hold.
SCENE_KEYS = {
    "subsystems": "the units by name (two)",
    "coupling": "the method, decomposition, k, scheme, H and their options",
    "t_start": "the start time (s; default 0)",
    "t_end": "the end time (s)",
    "initial_coupling": "the coupling variables at t_start, every component (default: computed from the units)",
    "initial": "check (default: refuse a joint whose positions or velocities differ at t_start), project (move "
    "the units onto the joint) or as-is (run, and report the gap)",
    "initial_tolerance": "the gap accepted at t_start, relative to max(1, the largest position or velocity)",
    "divergence_bound": "a state (SI) beyond this ends the run as diverged (default 1e10 (1 + |state at t_start|))",
    "limits": "call_seconds: the longest an FMI call of a unit may take; identify_seconds: the longest the "
    "identification of one unit may take (--predict)",
}

#: Coupling keys besides the method's parameters, and their defaults.
COUPLING_KEYS = {
    "method": None,
    "decomposition": None,
    "k": None,
    "scheme": "jacobi",
    "H": None,
    "iterations": 1,
    "inputs": "auto",
    "substeps": 16,
    "perturbation": 1.0e-3,
    "sensitivities": "each-step",
}


#: Subsystem keys that do not name unit variables.
_NOT_NAMES = ("fmu", "start", "force_sign", "mass", "rollback_tolerance")


def scene_schema() -> dict:
    """The JSON schema of a scene (the registries of methods, decompositions and schemes filled in)."""
    defs = schema_defs()
    name = {"type": "string", "minLength": 1}
    # one variable, or the components of a vector quantity (a joint in the plane: two)
    names = {"oneOf": [name, {"type": "array", "items": name, "minItems": 1, "maxItems": 3}]}
    sub = {
        "type": "object",
        "additionalProperties": False,
        "required": ["fmu", "position", "velocity", "acceleration", "force_sign"],
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
        },
    }
    params = defs["method_parameters"]["properties"]
    coupling = {
        "type": "object",
        "additionalProperties": False,
        "required": ["method", "decomposition", "k", "H"],
        "properties": {
            "method": defs["method"],
            "decomposition": defs["decomposition"],
            "k": {"type": "integer", "minimum": 0, "maximum": MAX_K},
            "scheme": defs["scheme"],
            "H": {"type": "number", "exclusiveMinimum": 0},
            "iterations": {"type": "integer", "minimum": 1, "maximum": 100},
            "inputs": {"enum": ["auto", "derivatives", "substeps"]},
            "substeps": {"type": "integer", "minimum": 1, "maximum": 100000},
            "perturbation": {"type": "number", "exclusiveMinimum": 0},
            "sensitivities": {"enum": ["each-step", "first-step"]},
            **params,
        },
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "type": "object",
        "additionalProperties": False,
        "required": ["subsystems", "coupling", "t_end"],
        "properties": {
            "subsystems": {
                "type": "object",
                "minProperties": 2,
                "maxProperties": 2,
                "additionalProperties": sub,
            },
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
    }


@dataclass
class Scene:
    """A checked scene: where it came from, its content, and what follows from it."""

    path: Path
    data: dict
    fmus: dict  # subsystem -> Path of its .fmu file or source directory
    method: object  # the CouplingMethod with the engine's (dimensionless) parameters
    n_steps: int

    @property
    def names(self) -> tuple:
        return tuple(self.data["subsystems"])

    @property
    def coupling(self) -> dict:
        return {**COUPLING_KEYS, **self.data["coupling"]}

    def graph(self, n_components: int = 1) -> CouplingGraph:
        """The units and joints (:mod:`icosim.engine.graph`): the two units joined by the coupling's
        decomposition."""
        return CouplingGraph(2, (Joint(0, 1, self.coupling["decomposition"]),), n_components, names=self.names)

    def graph_signs(self) -> list[int]:
        """Per unit, the sign with which the graph's coupling force reaches its input: the scene gives the sign
        of ``lambda`` on each unit, the graph acts with ``-lambda`` on the second."""
        return [
            int(sub["force_sign"]) * (1 if i == 0 else -1) for i, sub in enumerate(self.data["subsystems"].values())
        ]


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


def load_scene(path) -> Scene:
    """Read and check a scene file (no unit is loaded): :class:`~icosim.problems.fmu.errors.SceneError` names the file,
    the key and what is allowed."""
    import yaml

    from ...io.yamlio import load_yaml

    path = Path(path)
    try:
        data = load_yaml(path.read_text())
    except FileNotFoundError:
        raise SceneError(f"{path}: no such scene file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"{path}: cannot read the scene: {exc}") from None
    except yaml.YAMLError as exc:
        raise SceneError(f"{path}: not valid YAML: {' '.join(str(exc).split())}") from None
    _validate(path, data)
    c = {**COUPLING_KEYS, **data["coupling"]}
    decomposition = get_decomposition(c["decomposition"])
    spec = get_spec(c["method"])
    given = {k: c[k] for k in data["coupling"] if k not in COUPLING_KEYS}
    extra = sorted(set(given) - set(spec.arguments))
    if extra:
        _fail(
            path,
            f"coupling.{extra[0]}",
            f"not a parameter of method {spec.name} (its parameters: {', '.join(spec.arguments) or 'none'})",
        )
    try:
        method = spec.make(**given)
        method.check_decomposition(decomposition)
        method = engine_method(method, c["H"])
    except ParameterError as exc:
        _fail(path, "coupling", str(exc))
    t0, t_end, H = float(data.get("t_start", 0.0)), float(data["t_end"]), float(c["H"])
    steps = (t_end - t0) / H
    if not steps >= 1 or abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
        _fail(
            path,
            "t_end",
            f"t_end - t_start = {t_end - t0:g} s must be a whole number (>= 1) of macro steps H = {H:g} s",
        )
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
    if "initial_coupling" in data and len(data["initial_coupling"]) != decomposition.n_coupling * n_dim:
        _fail(
            path,
            "initial_coupling",
            f"needs {decomposition.n_coupling * n_dim} values ("
            f"{', '.join(decomposition.variables)}, {n_dim} component(s) each), got {len(data['initial_coupling'])}",
        )
    for (name, sub), kind in zip(data["subsystems"].items(), decomposition.kinds):
        need = ("force",) if kind == "force" else ("acceleration_input", "reaction_force")
        projects = method.projection or data.get("initial") == "project"
        if projects:
            need += ("mass", "set_position", "set_velocity")
        for key in need:
            if key not in sub:
                why = (
                    f"subsystem {name} is {kind}-driven in decomposition {decomposition.name}"
                    if key in ("force", "acceleration_input", "reaction_force")
                    else f"method {spec.name} projects"
                    if method.projection
                    else "initial: project moves the units onto the joint"
                )
                _fail(path, f"subsystems.{name}.{key}", f"required: {why} ({SUBSYSTEM_KEYS[key]})")
        if projects and isinstance(sub["position"], list) and len(sub["position"]) > 1:
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
    return Scene(path, data, fmus, method, int(round(steps)))


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
    where = ".".join(str(p) for p in err.absolute_path) or "top level"
    message = err.message
    if err.validator == "enum":
        message = f"{err.instance!r} is not allowed; allowed: {', '.join(map(str, err.validator_value))}"
    elif err.validator == "required":
        keys = err.schema.get("properties", {})
        message = f"{message}; its keys: {', '.join(keys)}"
    elif err.validator == "type" and isinstance(err.instance, str) and _is_number(err.instance):
        message = f"{message} (YAML reads {err.instance} as text: write the exponent with its sign, e.g. 1.0e+6)"
    elif err.validator == "additionalProperties":
        message = f"{message}; allowed keys: {', '.join(err.schema.get('properties', {}))}"
    raise SceneError(f"{path}: {where}: {message}")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_numbers(path, data):
    for key in ("t_start", "t_end"):
        if key in data and not math.isfinite(float(data[key])):
            _fail(path, key, f"must be a finite number, got {data[key]!r}")
