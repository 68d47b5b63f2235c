"""A system as a scene: its components as subsystems, its power bonds as joints, its defaults as the coupling.

A power bond (OSP: two ``VariableConnection``s of one ``powerBond``) between a unit that takes a force and returns
its point's velocity and a unit that takes a velocity and returns the force at that point is a joint ``fd``: the
first unit force driven (``force``: its bond input, ``velocity``: its bond output, ``position`` and
``acceleration``: its outputs of those names), the second a drive through its velocity (``velocity_input``,
``reaction_force``; without its own position outputs its point moves as prescribed).  The bond says that the
force side's input is the drive's output: ``force_sign`` +1 on the force side and -1 on the drive (the joint's
multiplier is the force side's input).  Which side is which the file does not say; icosim takes the force side to
be the unit whose bond output is a velocity (by its declared unit, or where the bond declares none by its name
``velocity``) beside outputs ``position`` and ``acceleration``, and the checks before the run measure that it moves
so (``moves``, ``direction``, ``role``).  A scene naming the system
(``system:``) may give the roles itself in ``subsystems``.

OSP's ``Algorithm`` ecco with its ``EccoConfiguration`` runs with controlled macro steps sized by ECCO's power
residual (``coupling.control: {estimate: power-residual, ...}``, :func:`ecco_control`) unless the scene gives its
own coupling.

Any other connection is a signal connection: a system of signal connections alone is a signal scene
(:func:`signal_system_data`, :mod:`icosim.problems.fmu.signal_scene`), coupled explicitly (implicitly where the
scene's coupling says ``implicit: true``).  A scene whose coupling names no ``method`` couples a power bond's two
connections as signals too (``{k: 0, scheme: jacobi, implicit: false}`` is the peers' fixed-step algorithm on
them); signals beside power bonds or joints coupled by a method are refused by name before any work, never
dropped.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import SceneError
from .description import System
from .read import find_system_file, is_system_file, read_system

__all__ = ["scene_data", "system_scene_data", "ecco_control", "DEFAULT_T_END", "ECCO_KEYS", "ROLE_KEYS"]

#: The interval a system runs where neither the file nor the scene gives an end time (s).
DEFAULT_T_END = 1.0
#: Subsystem keys that name a unit's role at a joint.
ROLE_KEYS = ("position", "velocity", "acceleration", "force", "acceleration_input", "reaction_force",
             "position_input", "velocity_input", "force_sign")  # fmt: skip

_INTERFACES = {"CoSimulation": "co-simulation", "ModelExchange": "model-exchange", "any": "auto"}


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


def default_coupling(H: float) -> dict:
    """The coupling a system runs with unless the scene gives one: the paper's Baumgarte index 1 with
    ``mu = H``, ``k = 1``, Jacobi, at the file's step."""
    return {"method": "baumgarte", "index": 1, "mu": H, "k": 1, "scheme": "jacobi", "H": H}


def system_scene_data(path, overlay: dict | None = None, *, where=None) -> tuple[dict, System]:
    """The scene data of the system at ``path`` (a file or a folder), with a scene's ``overlay`` (its keys other than
    ``system``) applied; ``where`` names the scene file in messages.  Returns the data (checked afterwards as
    every scene) and the system read."""
    overlay = dict(overlay or {})
    system = read_system(path)
    shown = where or system.path
    subs = overlay.get("subsystems", {}) or {}
    unknown = [n for n in subs if n not in system.components]
    if unknown:
        _fail(shown, f"subsystems.{unknown[0]}", f"the system has no component {unknown[0]!r}; its components: "
              f"{', '.join(system.components)}")  # fmt: skip
    bonds = system.power_bonds()
    signals = [c for c in system.connections if c.power_bond is None]
    # a coupling without a method is a coupling of signals: the power bonds' connections are then signals too
    bonds_as_signals = bool(bonds) and isinstance(overlay.get("coupling"), dict) and "method" not in overlay["coupling"]
    if signals and not bonds_as_signals and (bonds or "joints" in overlay):
        _fail(system.path, f"connection {signals[0].label}", "signal connections beside power bonds or joints are "
              "not yet supported: a system is coupled by signals alone or by joints alone (a scene coupling without "
              "a method couples the power bonds' connections as signals)")  # fmt: skip
    if signals or bonds_as_signals:
        if "joints" in overlay:
            _fail(shown, "joints", "a coupling without a method couples every connection as a signal; joints need "
                  "coupling.method")  # fmt: skip
        return signal_system_data(system, overlay, shown), system
    subsystems, joints, bonded = {}, [], {}
    for name, comp in system.components.items():
        subsystems[name] = {"fmu": str(comp.source), "start": dict(comp.start)}
        if comp.implementation in _INTERFACES:  # SSP: the interface the file asks of the unit
            subsystems[name]["interface"] = _INTERFACES[comp.implementation]
    for bond, (a, b) in bonds.items():
        for unit in {a.start[0], a.end[0]}:
            if unit in bonded:
                _fail(system.path, f"powerBond {bond}", f"{unit} is in power bonds {bonded[unit]} and {bond}: a unit "
                      "has one coupling point with one force input")  # fmt: skip
            bonded[unit] = bond
        given = [u for u in (a.start[0], a.end[0]) if any(k in subs.get(u, {}) for k in ROLE_KEYS)]
        if given:
            continue  # the scene names the roles, and joins the units by its joints or coupling.decomposition
        force_side, drive = _sides(system, bond, a, b)
        to_drive = a if a.start[0] == force_side else b
        to_force = b if to_drive is a else a
        for c in (to_drive, to_force):
            if (c.factor, c.offset, c.unit_factor, c.unit_offset) != (1.0, 0.0, 1.0, 0.0):
                _fail(system.path, f"connection {c.label}", "a power bond with a transformation is not supported")
        subsystems[force_side].update(
            {
                "position": "position",
                "velocity": to_drive.start[1],
                "acceleration": "acceleration",
                "force": to_force.end[1],
                "force_sign": 1,
            }  # fmt: skip
        )
        subsystems[drive].update(
            {"velocity_input": to_drive.end[1], "reaction_force": to_force.start[1], "force_sign": -1}
        )
        joints.append({"between": [force_side, drive], "decomposition": "fd"})
    for name, extra in subs.items():
        start = {**subsystems[name].get("start", {}), **(extra.get("start") or {})}
        subsystems[name].update(extra)
        subsystems[name]["start"] = start
    for name, sub in subsystems.items():
        if not sub["start"]:
            del sub["start"]
        sub.setdefault("record", [c.name for c in system.components[name].connectors if _recordable(c)])
    data = {k: v for k, v in overlay.items() if k != "subsystems"}
    data["subsystems"] = subsystems
    if "joints" not in data and joints:
        data["joints"] = joints
    if "coupling" not in data:
        if system.step_size is None:
            _fail(shown, "coupling", f"{system.format} gives no step size: a scene naming the system needs coupling "
                  "(method, k, H)")  # fmt: skip
        data["coupling"] = default_coupling(system.step_size)
        if system.algorithm == "ecco" and system.ecco is not None:
            data["coupling"]["H"] = system.ecco["StepSize"]
            data["coupling"]["control"] = ecco_control(system.ecco)
            given = ", ".join(f"{k}: {v if isinstance(v, str) else format(v, 'g')}"
                              for k, v in data["coupling"]["control"].items())  # fmt: skip
            system.notes.append(f"the file asks for libcosim's ECCO step control: run as coupling.control {{{given}}} "
                                f"from the first step H = {data['coupling']['H']:g} s (docs/fmi.md, 'Step control by "
                                "the power residual (ECCO)')")  # fmt: skip
    if "t_start" not in data and system.start_time:
        data["t_start"] = system.start_time
    if "t_end" not in data:
        t0 = float(data.get("t_start", 0.0))
        data["t_end"] = system.stop_time if system.stop_time is not None else t0 + DEFAULT_T_END
        if system.stop_time is None:
            system.notes.append(f"the file gives no end time: the run ends {DEFAULT_T_END:g} s after its start")
    if system.algorithm == "ecco" and "control" not in data["coupling"]:
        why = "without an EccoConfiguration" if system.ecco is None else "and the scene's coupling replaces it"
        system.notes.append(f"the file asks for libcosim's ECCO step control {why}: icosim couples at the fixed "
                            f"H = {data['coupling']['H']:g} s")  # fmt: skip
    return data, system


def signal_system_data(system: System, overlay: dict, shown) -> dict:
    """The signal scene (:mod:`icosim.problems.fmu.signal_scene`) of a system whose connections are all signals:
    each connection's transformation and unit conversion as one ``factor`` and ``offset``; explicit Jacobi coupling
    with held inputs at the file's step (the peers' fixed-step algorithm) unless the scene gives its coupling."""
    subs = overlay.get("subsystems", {}) or {}
    subsystems = {}
    for name, comp in system.components.items():
        sub = {"fmu": str(comp.source), "start": dict(comp.start)}
        if comp.implementation in _INTERFACES and comp.implementation != "any":
            sub["interface"] = _INTERFACES[comp.implementation]
        connected = {c.start[1] for c in system.connections if c.start[0] == name}
        connected |= {c.end[1] for c in system.connections if c.end[0] == name}
        # the other Real connectors the file declares, read as the connected ones are
        sub["record"] = [c.name for c in comp.connectors if c.type == "Real" and c.kind in ("input", "output")
                         and c.name not in connected]  # fmt: skip
        if not sub["record"]:
            del sub["record"]
        extra = dict(subs.get(name, {}))
        sub["start"] = {**sub["start"], **(extra.pop("start", None) or {})}
        sub.update(extra)
        if not sub["start"]:
            del sub["start"]
        subsystems[name] = sub
    connections = [
        {
            "from": ".".join(c.start),
            "to": ".".join(c.end),
            "factor": c.unit_factor * c.factor,
            "offset": c.unit_factor * c.offset + c.unit_offset,
        }  # fmt: skip
        for c in system.connections
    ]
    data = {k: v for k, v in overlay.items() if k != "subsystems"} | {"subsystems": subsystems}
    data["connections"] = connections
    if "coupling" not in data:
        if system.step_size is None:
            _fail(shown, "coupling", f"{system.format} gives no step size: a scene naming the system needs coupling "
                  "(H, and k, scheme)")  # fmt: skip
        data["coupling"] = {"k": 0, "scheme": "jacobi", "H": system.step_size}
    if "t_start" not in data and system.start_time:
        data["t_start"] = system.start_time
    if "t_end" not in data:
        t0 = float(data.get("t_start", 0.0))
        data["t_end"] = system.stop_time if system.stop_time is not None else t0 + DEFAULT_T_END
    if system.algorithm == "ecco":
        system.notes.append("the file asks for libcosim's ECCO step control, which signal connections do not yet "
                            f"have: icosim couples at the fixed H = {data['coupling']['H']:g} s")  # fmt: skip
    return data


#: OSP's EccoConfiguration elements -> the keys of ``coupling.control`` they set (StepSize: ``coupling.H``).
ECCO_KEYS = {"MinimumStepSize": "H_min", "MaximumStepSize": "H_max", "SafetyFactor": "safety",
             "MinimumChangeRate": "fac_min", "MaximumChangeRate": "fac_max", "ProportionalGain": "proportional_gain",
             "IntegralGain": "integral_gain", "RelativeTolerance": "relative_tolerance",
             "AbsoluteTolerance": "absolute_tolerance"}  # fmt: skip


def ecco_control(ecco: dict) -> dict:
    """``coupling.control`` for an OSP ``EccoConfiguration`` (element -> value): ECCO's power residual.

    >>> ecco_control({"MinimumStepSize": 1e-5, "MaximumStepSize": 0.01, "SafetyFactor": 0.99, "StepSize": 1e-4,
    ...               "MinimumChangeRate": 0.2, "MaximumChangeRate": 1.5, "ProportionalGain": 0.2,
    ...               "IntegralGain": 0.15, "RelativeTolerance": 1e-6, "AbsoluteTolerance": 1e-6})["estimate"]
    'power-residual'
    """
    return {"estimate": "power-residual", **{key: float(ecco[element]) for element, key in ECCO_KEYS.items()}}


def _recordable(connector) -> bool:
    """Connectors read at communication points: inputs and outputs of a numeric type."""
    return connector.kind in ("input", "output", "inout", None) and connector.type in (
        None, "Real", "Integer", "Boolean", "Enumeration")  # fmt: skip


def _variables(label, path) -> dict:
    from ..description import read_description

    return {v.name: v for v in read_description(label, path)[0].modelVariables}


def _quantity(variable) -> str | None:
    """``velocity`` or ``force`` where the variable's declared unit says so, else None."""
    from ..measures import ROLE_QUANTITIES, parse

    unit = variable.unit or (variable.declaredType.unit if variable.declaredType is not None else None)
    dims = parse(unit)[0] if unit and parse(unit) else None
    for key in ("velocity", "force"):
        if dims is not None and dims == ROLE_QUANTITIES[key][1]:
            return key
    return None


def _sides(system, bond, a, b) -> tuple[str, str]:
    """(force-driven unit, velocity drive) of a bond: by the declared units of the bond's variables where they
    declare a velocity or a force, else the unit whose bond output is its output ``velocity``; the force side must
    have outputs ``position`` and ``acceleration``."""
    variables = {c.start[0]: _variables(c.start[0], system.components[c.start[0]].source) for c in (a, b)}
    said = {}
    for c in (a, b):
        for unit, name in (c.start, c.end):
            q = _quantity(variables[unit][name])
            if q is not None:
                said.setdefault(c.label, set()).add(q)
    fits = []
    for c in (a, b):
        unit = c.start[0]
        outputs = {n for n, v in variables[unit].items() if v.causality == "output"}
        by_units = said.get(c.label) == {"velocity"} and said.get((b if c is a else a).label, {"force"}) == {"force"}
        by_name = not said and c.start[1] == "velocity"
        if (by_units or by_name) and {"position", "acceleration"} <= outputs:
            fits.append((unit, c.end[0]))
    if len(fits) != 1:
        _fail(system.path, f"powerBond {bond} ({a.label}, {b.label})", "cannot tell which side is force driven "
              "(the unit whose bond output is a velocity, by its declared unit or else its name 'velocity', beside "
              "outputs 'position' and 'acceleration'); name the roles in a scene: system: FILE, subsystems: "
              "{<unit>: {force, position, velocity, acceleration, force_sign}, <drive>: {velocity_input, "
              "reaction_force, force_sign}}, with joints or coupling.decomposition")  # fmt: skip
    return fits[0]


def scene_data(path) -> tuple[dict, System | None]:
    """The data of a scene file (YAML) or of a system file (or its folder), and the system read (``None`` for a
    scene without ``system``): a scene naming a system has it applied (:func:`system_scene_data`)."""
    import yaml

    from ....io.yamlio import load_yaml

    path = Path(path)
    if is_system_file(path):
        return system_scene_data(path)
    try:
        data = load_yaml(path.read_text())
    except FileNotFoundError:
        raise SceneError(f"{path}: no such scene file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"{path}: cannot read the scene: {exc}") from None
    except yaml.YAMLError as exc:
        raise SceneError(f"{path}: not valid YAML: {' '.join(str(exc).split())}") from None
    if not isinstance(data, dict) or "system" not in data:
        return data, None
    if not isinstance(data["system"], str) or not data["system"]:
        _fail(path, "system", f"must name a system file (or its folder), got {data['system']!r}")
    overlay = {k: v for k, v in data.items() if k != "system"}
    target = (path.parent / data["system"]).resolve()
    if not target.exists():
        _fail(path, "system", f"{data['system']} does not exist (resolved to {target})")
    return system_scene_data(find_system_file(target), overlay, where=path)
