"""OSP's ``OspSystemStructure.xml`` (libcosim's ``data/xsd/OspSystemStructure.xsd``, version 0.1), read with the
standard library's ElementTree: no maintained reader exists outside libcosim's own C++ parser.

Read as libcosim reads it: ``StartTime`` (default 0), ``EndTime``, ``BaseStepSize``, ``Algorithm`` (default
``fixedStep``), the simulators with their ``InitialValues`` (Real, Integer, Boolean, String), the
``VariableConnection``s (the direction of each from the units' model descriptions, as libcosim connects them: the
``causality`` attributes only label a power bond's ends) with their ``powerBond`` names, and the
``EccoConfiguration``.  Refused, naming the element and the file: ``Functions`` and ``SignalConnection`` /
``SignalGroupConnection`` (libcosim's function blocks), ``VariableGroupConnection`` (its groups live in each unit's
``OspModelDescription.xml``, which icosim does not read), a simulator's own ``stepSize`` (icosim steps every unit
at one macro step), a power bond of other than two connections, an unknown element.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from ..errors import SceneError
from .description import Component, Connection, Connector, System

__all__ = ["read_osp", "NAMESPACE"]

NAMESPACE = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"
_N = f"{{{NAMESPACE}}}"
_TOP = ("StartTime", "EndTime", "BaseStepSize", "Algorithm", "Simulators", "Functions", "Connections",
        "EccoConfiguration")  # fmt: skip
_ECCO = ("SafetyFactor", "StepSize", "MinimumStepSize", "MaximumStepSize", "MinimumChangeRate", "MaximumChangeRate",
         "ProportionalGain", "IntegralGain", "RelativeTolerance", "AbsoluteTolerance")  # fmt: skip
_NOT_SUPPORTED = {
    "Functions": "libcosim's function blocks (LinearTransformation, Sum, VectorSum) are not supported",
    "SignalConnection": "connections to function blocks are not supported",
    "SignalGroupConnection": "connections to function blocks are not supported",
    "VariableGroupConnection": "variable groups are defined in each unit's OspModelDescription.xml, which icosim "
    "does not read; connect the variables one by one (VariableConnection)",
}


def _local(tag: str) -> str:
    return tag.split("}", 1)[-1]


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


def _number(path, where, text):
    try:
        return float(text)
    except (TypeError, ValueError):
        _fail(path, where, f"not a number: {text!r}")


def read_osp(path) -> System:
    """Read an ``OspSystemStructure.xml`` (the units are not opened; the connections' directions are read from the
    units' model descriptions)."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        _fail(path, "XML", str(exc))
    except OSError as exc:
        _fail(path, "file", str(exc))
    if _local(root.tag) != "OspSystemStructure":
        _fail(path, root.tag, "not an OspSystemStructure")
    values = {}
    for child in root:
        name = _local(child.tag)
        if name in _NOT_SUPPORTED:
            _fail(path, name, _NOT_SUPPORTED[name])
        if name not in _TOP:
            _fail(path, name, f"unknown element; OspSystemStructure holds {', '.join(_TOP)}")
        values[name] = child
    text = {
        k: (values[k].text or "").strip() for k in ("StartTime", "EndTime", "BaseStepSize", "Algorithm") if k in values
    }
    components = _simulators(path, values.get("Simulators"))
    connections = _connections(path, values.get("Connections"), components)
    ecco = None
    if "EccoConfiguration" in values:
        ecco = {}
        for e in values["EccoConfiguration"]:
            ecco[_local(e.tag)] = _number(path, f"EccoConfiguration.{_local(e.tag)}", e.text)
        missing = [k for k in _ECCO if k not in ecco]
        if missing:
            _fail(path, "EccoConfiguration", f"lacks {', '.join(missing)} (libcosim needs every one)")
    system = System(
        path=path,
        format="OSP",
        name=path.parent.name,
        components=components,
        connections=connections,
        start_time=_number(path, "StartTime", text["StartTime"]) if "StartTime" in text else 0.0,
        stop_time=_number(path, "EndTime", text["EndTime"]) if "EndTime" in text else None,
        step_size=_number(path, "BaseStepSize", text["BaseStepSize"]) if "BaseStepSize" in text else None,
        algorithm=text.get("Algorithm", "fixedStep"),
        ecco=ecco,
    )
    _check_bonds(path, system)
    return system


def _simulators(path, element) -> dict:
    if element is None:
        _fail(path, "Simulators", "required")
    components = {}
    for sim in element:
        if _local(sim.tag) != "Simulator":
            _fail(path, f"Simulators.{_local(sim.tag)}", "unknown element; Simulators holds Simulator")
        name, source = sim.get("name"), sim.get("source")
        if not name or not source:
            _fail(path, "Simulator", "needs the attributes name and source")
        if name in components:
            _fail(path, f"Simulator {name}", "named twice")
        if sim.get("stepSize") is not None:
            _fail(path, f"Simulator {name}.stepSize", "a unit's own step size is not supported: icosim steps every "
                  "unit at one macro step (BaseStepSize)")  # fmt: skip
        start = {}
        for group in sim:
            if _local(group.tag) != "InitialValues":
                _fail(path, f"Simulator {name}.{_local(group.tag)}", "unknown element; Simulator holds InitialValues")
            for iv in group:
                variable = iv.get("variable")
                typed = list(iv)
                if not variable or len(typed) != 1:
                    _fail(path, f"Simulator {name}.InitialValue", "needs a variable and one typed value")
                start[variable] = _typed(path, f"Simulator {name}.InitialValue {variable}", typed[0])
        components[name] = Component(name=name, source=(path.parent / source).resolve(), start=start)
    return components


def _typed(path, where, element):
    kind, value = _local(element.tag), element.get("value")
    if value is None:
        _fail(path, where, "needs a value")
    if kind == "Real":
        return _number(path, where, value)
    if kind == "Integer":
        try:
            return int(value)
        except ValueError:
            _fail(path, where, f"not an integer: {value!r}")
    if kind == "Boolean":
        if value not in ("true", "false", "1", "0"):
            _fail(path, where, f"not a Boolean (true, false, 1, 0): {value!r}")
        return value in ("true", "1")
    if kind == "String":
        return value
    _fail(path, where, f"unknown type {kind}; allowed: Real, Integer, Boolean, String")


def _causalities(path, component) -> dict:
    """The unit's variables -> (causality, type, unit), from its model description."""
    from ..description import read_description
    from ..errors import FmuError

    try:
        md, _ = read_description(f"Simulator {component.name}", component.source)
    except FmuError as exc:
        _fail(path, f"Simulator {component.name}.source", str(exc))
    return {v.name: (v.causality, v.type, getattr(v, "unit", None)) for v in md.modelVariables}


def _connections(path, element, components) -> list:
    if element is None:
        return []
    found, described = [], {}
    for conn in element:
        kind = _local(conn.tag)
        if kind in _NOT_SUPPORTED:
            _fail(path, kind, _NOT_SUPPORTED[kind])
        if kind != "VariableConnection":
            _fail(path, kind, "unknown element; Connections holds VariableConnection")
        ends = [v for v in conn if _local(v.tag) == "Variable"]
        if len(ends) != 2:
            _fail(path, "VariableConnection", "needs two Variable elements")
        named = []
        for v in ends:
            sim, var = v.get("simulator"), v.get("name")
            if sim not in components:
                _fail(path, f"VariableConnection {sim}.{var}", f"no simulator {sim!r}; simulators: "
                      f"{', '.join(components)}")  # fmt: skip
            if sim not in described:
                described[sim] = _causalities(path, components[sim])
            if var not in described[sim]:
                _fail(path, f"VariableConnection {sim}.{var}", f"{components[sim].source.name} has no variable {var!r}")
            named.append((sim, var))
        causes = [described[s][v][0] for s, v in named]
        # libcosim: the end that is an output (or calculated parameter) feeds the other
        if causes[0] in ("output", "calculatedParameter"):
            start, end = named
        elif causes[1] in ("output", "calculatedParameter"):
            end, start = named
        else:
            _fail(path, f"VariableConnection {named[0][0]}.{named[0][1]} - {named[1][0]}.{named[1][1]}",
                  f"neither end is an output (causalities {causes[0]}, {causes[1]})")  # fmt: skip
        if described[end[0]][end[1]][0] != "input":
            _fail(path, f"VariableConnection {start[0]}.{start[1]} -> {end[0]}.{end[1]}",
                  f"{end[0]}.{end[1]} is not an input (causality {described[end[0]][end[1]][0]})")  # fmt: skip
        found.append(Connection(start=start, end=end, power_bond=conn.get("powerBond")))
    for sim, variables in described.items():
        used = {c.start[1] for c in found if c.start[0] == sim} | {c.end[1] for c in found if c.end[0] == sim}
        components[sim].connectors = tuple(
            Connector(n, variables[n][0], variables[n][1], variables[n][2]) for n in variables if n in used
        )
    return found


def _check_bonds(path, system):
    for bond, conns in system.power_bonds().items():
        if len(conns) != 2:
            _fail(path, f"powerBond {bond}", f"has {len(conns)} connection(s); a power bond is two (libcosim: "
                  "'does not have 2 connections')")  # fmt: skip
        a, b = conns
        if {a.start[0], a.end[0]} != {b.start[0], b.end[0]} or a.start[0] == a.end[0] or a.start[0] != b.end[0]:
            _fail(path, f"powerBond {bond}", f"its connections {a.label} and {b.label} must run between the same "
                  "two simulators, one each way")  # fmt: skip
