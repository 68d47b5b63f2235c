"""SSP 1.0 and 2.0: an ``.ssp`` archive (unpacked into icosim's cache, keyed by its content) or an ``.ssd`` with its
resources beside it.

Read with pyssp-standard (``pip install pyssp-standard``: the SSP reference suite's reader, maintained, and the
one reader on PyPI that knows SSP 2.0; fmpy's ``read_ssd`` validates against SSP 1.0 only, reads only archives and
drops connector units and a connection's transformation).  pyssp-standard validates the file against the schema of
its version and gives the components, connectors (kind, type, unit), parameter bindings (inline, ``.ssv`` files,
``.ssm`` mappings with their transformations), units and the default experiment; a connection's
``LinearTransformation`` and ``suppressUnitConversion``, which it does not model, are read from the same lxml tree.

Parameter values land on the components: a binding on a component names its variables; one on the system names
``<component>.<variable>`` (after its ``prefix``); a mapping renames a value's source to a target, through its
``LinearTransformation`` if it has one.  A connection's value is ``factor * y + offset`` in the start connector's
unit, then converted into the end's unit by the units' base-unit factors and offsets (unless suppressed).

Refused, naming the element and the file: nested systems, signal dictionaries (and their references), a component
that is not an FMU, a parameter binding of a type other than an SSV, a mapping transformation other than
``LinearTransformation``, connections to or from the system's own connectors, an unknown unit, a conversion between
units of different base units.
"""

from __future__ import annotations

import hashlib
import zipfile
from pathlib import Path

from ..errors import SceneError
from .description import Component, Connection, Connector, System

__all__ = ["read_ssp", "unpack_ssp"]

_FMU = "application/x-fmu-sharedlibrary"
_SSV = "application/x-ssp-parameter-set"


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


def unpack_ssp(path) -> Path:
    """An ``.ssp`` archive unpacked into ``ssp/<sha256 of its bytes>`` in the units' cache
    (:func:`icosim.problems.fmu.build.cache_dir`), once: its ``SystemStructure.ssd``."""
    from ..build import cache_dir

    path = Path(path)
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    where = cache_dir() / "ssp" / digest
    ssd = where / "SystemStructure.ssd"
    if not ssd.exists():
        import shutil
        import tempfile

        where.parent.mkdir(parents=True, exist_ok=True)
        part = Path(tempfile.mkdtemp(prefix=f".{digest}.", dir=where.parent))  # whole or not at all
        try:
            with zipfile.ZipFile(path) as z:
                names = z.namelist()
                if "SystemStructure.ssd" not in names:
                    _fail(path, "archive", "holds no SystemStructure.ssd")
                for name in names:
                    target = (part / name).resolve()
                    if part.resolve() not in target.parents:
                        _fail(path, "archive", f"entry {name!r} lies outside the archive's folder")
                z.extractall(part)
            try:
                part.replace(where)
            except OSError:  # another process unpacked it meanwhile
                if not ssd.exists():
                    raise
        except zipfile.BadZipFile as exc:
            _fail(path, "archive", f"not a zip archive: {exc}")
        finally:
            shutil.rmtree(part, ignore_errors=True)
    return ssd


def _valid(path, shown, reader, kind):
    """A pyssp-standard file object of ``path``, validated against its version's schema (else refused naming it)."""
    from lxml import etree

    try:
        read = reader(path, mode="r")
        read.__check_compliance__()
    except (OSError, etree.XMLSyntaxError) as exc:
        _fail(shown, kind, f"{path.name}: cannot read: {exc}")
    except Exception as exc:  # xmlschema's validation errors
        first = " ".join(str(exc).split())[:400]
        _fail(shown, kind, f"{path.name} is not a valid SSP {kind}: {first}")
    return read


def read_ssp(path) -> System:
    """Read an ``.ssp`` archive or an ``.ssd`` file (the units are not opened)."""
    from lxml import etree
    from pyssp_standard.ssd import SSD

    path = Path(path)
    shown = path
    ssd_path = unpack_ssp(path) if path.suffix == ".ssp" else path
    base = ssd_path.parent
    try:
        ssd = SSD(ssd_path, mode="r")
    except (OSError, etree.XMLSyntaxError) as exc:
        _fail(shown, "SystemStructure", f"cannot read: {exc}")
    try:
        ssd.__check_compliance__()
    except Exception as exc:  # xmlschema's validation errors
        first = " ".join(str(exc).split())[:400]
        _fail(shown, "schema", f"not a valid SSP {ssd.version} system structure: {first}")
    ns = ssd.namespaces
    root = ssd.root
    system_el = root.find("ssd:System", ns)
    if system_el is None:
        _fail(shown, "System", "the file has no system")
    system_bound = [
        _bound(shown, base, b, f"System {ssd.system.name}") for b in ssd.system.parameter_bindings or []
    ]  # read (and validated) first: a broken parameter file is named before the structure's refusals
    for tag, why in (("ssd:Elements/ssd:System", "nested systems are not supported: flatten the system"),
                     ("ssd:Elements/ssd:SignalDictionaryReference", "signal dictionaries are not supported"),
                     ("ssd:SignalDictionaries", "signal dictionaries are not supported")):  # fmt: skip
        hit = system_el.find(tag, ns)
        if hit is not None:
            _fail(shown, f"{tag.split(':')[-1]} {hit.get('name', '')}".strip(), why)
    units = _units(ssd.units)
    components = {}
    for comp in _components(ssd.system):
        if comp.component_type not in (None, _FMU):
            _fail(shown, f"Component {comp.name}", f"of type {comp.component_type}; only FMUs ({_FMU}) are supported")
        connectors = tuple(_connector(c) for c in comp.connectors)
        components[comp.name] = Component(
            name=comp.name,
            source=(base / comp.source).resolve(),
            connectors=connectors,
            implementation=comp.implementation,
        )
        for binding in comp.parameter_bindings or []:
            for name, value in _bound(shown, base, binding, f"Component {comp.name}").items():
                components[comp.name].start[name] = value
    for bound in system_bound:
        for name, value in bound.items():
            owner, _, variable = name.partition(".")
            if owner not in components or not variable:
                _fail(shown, f"System {ssd.system.name} ParameterBinding", f"{name!r} names no component's variable "
                      f"(<component>.<variable>; components: {', '.join(components)})")  # fmt: skip
            components[owner].start[variable] = value
    connections = [
        _connection(shown, el, components, units, ns) for el in system_el.findall("ssd:Connections/ssd:Connection", ns)
    ]
    experiment = ssd.default_experiment
    return System(
        path=shown,
        format=f"SSP {ssd.version}",
        name=ssd.name or ssd.system.name,
        components=components,
        connections=connections,
        units=units,
        start_time=experiment.start_time if experiment is not None else None,
        stop_time=experiment.stop_time if experiment is not None else None,
    )


def _components(system):
    return [e for e in system.elements if type(e).__name__ == "Component"]


def _connector(c) -> Connector:
    kind = type(c.type_).__name__.removeprefix("Type") if c.type_ is not None else None
    return Connector(c.name, c.kind, kind, getattr(c.type_, "unit", None))


def _units(units) -> dict:
    """name -> (factor, offset, base-unit exponents) of the units the file defines."""
    out = {}
    for name, unit in getattr(units, "units", {}).items():
        b = unit.base_unit
        exps = tuple(int(getattr(b, k) or 0) for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad")) if b else (0,) * 8
        factor = float(b.factor) if b is not None and b.factor is not None else 1.0
        offset = float(b.offset) if b is not None and b.offset is not None else 0.0
        out[name] = (factor, offset, exps)
    return out


def _value(parameter):
    kind, attrs = parameter["type_name"], parameter["type_value"].parameter
    value = attrs.get("value")
    if kind == "Real":
        return float(value)
    if kind == "Integer":
        return int(value)
    if kind == "Boolean":
        return value in ("true", "1", True)
    return value


def _bound(path, base, binding, owner) -> dict:
    """A parameter binding's values by the names they bind (prefix applied, mapping applied)."""
    from pyssp_standard.ssm import SSM
    from pyssp_standard.ssv import SSV

    where = f"{owner} ParameterBinding"
    if binding.type != _SSV:
        _fail(path, where, f"of type {binding.type}; only parameter sets ({_SSV}) are supported")
    if binding.source is not None:
        source = (base / binding.source).resolve()
        if not source.exists():
            _fail(path, f"{where} source", f"{binding.source} does not exist (resolved to {source})")
        parameters = _valid(source, path, SSV, "parameter set").ssv_elem.parameters
    elif binding.ssv is not None:
        parameters = binding.ssv.parameters
    else:
        parameters = []
    values = {p["name"]: _value(p) for p in parameters}
    if binding.parameter_mapping is not None:
        mapping = binding.parameter_mapping
        if mapping.source is not None:
            source = (base / mapping.source).resolve()
            if not source.exists():
                _fail(path, f"{where} ParameterMapping", f"{mapping.source} does not exist (resolved to {source})")
            entries = _valid(source, path, SSM, "parameter mapping").ssm_elem.entries
        else:
            entries = mapping.ssm.entries if mapping.ssm is not None else []
        mapped = {}
        for entry in entries:
            if entry.source not in values:
                continue
            value = values[entry.source]
            t = entry.transformation
            if t is not None and t.transformation_type is not None:
                if t.transformation_type != "LinearTransformation":
                    _fail(path, f"{where} ParameterMapping {entry.source} -> {entry.target}",
                          f"{t.transformation_type} is not supported (LinearTransformation is)")  # fmt: skip
                factor = float(t.transformation.get("factor") or 1.0)
                offset = float(t.transformation.get("offset") or 0.0)
                value = factor * value + offset
            mapped[entry.target] = value
        # an unmapped source binds by its own name (SSP: the mapping renames only what it names)
        named = {s for s in values if any(e.source == s for e in entries)}
        values = {**{k: v for k, v in values.items() if k not in named}, **mapped}
    prefix = binding.prefix or ""
    return {f"{prefix}{k}": v for k, v in values.items()}


def _connection(path, el, components, units, ns) -> Connection:
    start = (el.get("startElement"), el.get("startConnector"))
    end = (el.get("endElement"), el.get("endConnector"))
    label = f"{start[0] or '(system)'}.{start[1]} -> {end[0] or '(system)'}.{end[1]}"
    if start[0] is None or end[0] is None:
        _fail(path, f"Connection {label}", "connections to or from the system's own connectors are not supported")
    for comp, conn in (start, end):
        if comp not in components:
            _fail(path, f"Connection {label}", f"no component {comp!r}; components: {', '.join(components)}")
        if components[comp].connector(conn) is None:
            _fail(path, f"Connection {label}", f"component {comp} has no connector {conn!r}")
    factor, offset = 1.0, 0.0
    for tag in ("ssc:LinearTransformation", "ssd:LinearTransformation"):
        lt = el.find(tag, ns)
        if lt is not None:
            factor, offset = float(lt.get("factor", 1.0)), float(lt.get("offset", 0.0))
    for tag in ("BooleanMappingTransformation", "IntegerMappingTransformation", "EnumerationMappingTransformation"):
        if el.find(f"ssc:{tag}", ns) is not None:
            _fail(path, f"Connection {label}", f"{tag} is not supported (LinearTransformation is)")
    unit_factor, unit_offset = 1.0, 0.0
    a, b = components[start[0]].connector(start[1]).unit, components[end[0]].connector(end[1]).unit
    if el.get("suppressUnitConversion", "false") not in ("true", "1") and a and b and a != b:
        for u in (a, b):
            if u not in units:
                _fail(path, f"Connection {label}", f"unit {u!r} is not defined in the file's Units")
        (fa, oa, ea), (fb, ob, eb) = units[a], units[b]
        if ea != eb:
            _fail(path, f"Connection {label}", f"connects {a} to {b}, which are of different base units")
        # SI value = factor * value + offset on each side
        unit_factor, unit_offset = fa / fb, (oa - ob) / fb
    return Connection(start, end, factor, offset, unit_factor, unit_offset)
