"""A unit's variables as the FMI standard defines them: typed, with value references per type, arrays whose
elements a scene names as ``y[2]`` or ``A[1,2]``, and start values checked before any call.

FMI 2.0 value references are unique only within a type (a Boolean and a Real may share one), so a variable is
always set with the setter of its own type (:data:`SETTERS`).  Which variables may take a start value, and in
which state, follows the standard's tables (FMI 2.0 section 4.2.4, FMI 3.0 section 2.3):

* state *instantiated*: variables with ``variability != constant`` and ``initial = exact`` or ``approx``
  (parameters, and outputs, states and locals whose start the unit declares as exact or approximate);
* *initialization mode*: besides, inputs and ``initial = exact`` variables (fmpy's ``settable_in_*``);
* FMI 3.0 *configuration mode*: structural parameters (array sizes), set first.

Anything else (a constant, the independent variable, an output or local with ``initial = calculated``, a
calculated parameter) is refused naming the rule.  A scene value must be a YAML scalar of the variable's type
(a number for Real/Float, an integer in range for Integer/IntN/UIntN, true/false for Boolean, text for String,
an item's name or value for Enumeration), a list (nested for a matrix, row-major) for an FMI 3.0 array, or
``{value: 3.5, unit: mm}`` where the variable declares a unit with that display unit (fmpy converts it).

Array elements are numbered from 1, as in Modelica and the FMI 3.0 terminal example (the standard leaves the
base to the tool), in row-major order: ``A[1,2]`` is the first row's second element.

>>> integer_range("UInt8")
(0, 255)
>>> parse_element("A[1, 2]")
('A', (1, 2))
"""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass

from .errors import FmuError

__all__ = [
    "Element",
    "StartValue",
    "VariableTable",
    "family",
    "integer_range",
    "parse_element",
    "declared_start",
    "setter",
]

#: The FMI types by family.
_FAMILIES = {
    "real": ("Real", "Float32", "Float64"),
    "integer": ("Integer", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64"),
    "boolean": ("Boolean",),
    "string": ("String",),
    "enumeration": ("Enumeration",),
    "binary": ("Binary",),
    "clock": ("Clock",),
}
_FAMILY = {t: f for f, types in _FAMILIES.items() for t in types}

#: What a scene writes for each family (in messages).
_SPELLING = {
    "real": "a number",
    "integer": "an integer",
    "boolean": "true or false",
    "string": "text",
    "enumeration": "an item's name or value",
}


def family(fmi_type: str) -> str:
    """``real``, ``integer``, ``boolean``, ``string``, ``enumeration``, ``binary`` or ``clock``."""
    return _FAMILY[fmi_type]


def integer_range(fmi_type: str) -> tuple[int, int]:
    """The values an integer type holds (FMI 2.0 ``Integer`` is 32 bits)."""
    if fmi_type == "Integer":
        return -(2**31), 2**31 - 1
    bits = int(re.sub(r"\D", "", fmi_type))
    return (0, 2**bits - 1) if fmi_type.startswith("U") else (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1)


def setter(md, variable) -> str:
    """The name of the FMI function that sets ``variable`` (its own type's)."""
    if md.fmiVersion.startswith("3."):
        return "fmi3SetInt64" if variable.type == "Enumeration" else f"fmi3Set{variable.type}"
    return "fmi2SetInteger" if variable.type == "Enumeration" else f"fmi2Set{variable.type}"


_ELEMENT = re.compile(r"^(?P<base>.+?)\[(?P<idx>\s*\d+\s*(?:,\s*\d+\s*)*)\]$")


def parse_element(name: str):
    """``("y", (2,))`` for ``"y[2]"``, ``(name, None)`` for a name without indices."""
    m = _ELEMENT.match(name)
    if not m:
        return name, None
    return m["base"], tuple(int(i) for i in m["idx"].split(","))


@dataclass(frozen=True)
class Element:
    """One scalar a scene names: a whole scalar variable, or one element of an FMI 3.0 array.

    ``index`` is the element's position in the variable's values (row-major, 0-based); ``size`` the number of
    values the variable holds (1 for a scalar)."""

    name: str
    variable: object  # fmpy's ModelVariable
    index: int = 0
    size: int = 1

    @property
    def value_reference(self) -> int:
        return self.variable.valueReference


@dataclass(frozen=True)
class StartValue:
    """A start value checked against the unit: the variable, the value as its setter takes it (a list for an
    array; ``(value, unit)`` for a value with a display unit), and the state it is set in."""

    name: str
    variable: object
    value: object
    state: str  # "configuration", "instantiated" or "initialization"
    setter: str
    text: str  # the value as the scene gave it, for messages and the check table


class VariableTable:
    """A unit's variables by name, with the array sizes its structural parameters give (the scene's start values
    of them, else their declared starts)."""

    def __init__(self, label: str, md, start: dict | None = None):
        self.label, self.md = label, md
        self.fmi3 = md.fmiVersion.startswith("3.")
        self.by_name = {v.name: v for v in md.modelVariables}
        start = dict(start or {})
        self.shapes = {}
        for v in md.modelVariables:
            shape = []
            for dim in v.dimensions:
                if dim.start is not None:
                    shape.append(int(dim.start))
                else:
                    sized_by = dim.variable
                    given = start.get(sized_by.name, sized_by.start)
                    try:
                        shape.append(int(given))
                    except (TypeError, ValueError):
                        raise FmuError(
                            f"{label}: start: {sized_by.name}: the size of {v.name} must be an integer, got {given!r}"
                        ) from None
            self.shapes[v.name] = tuple(shape)

    # -- names ----------------------------------------------------------------------------------------------------
    def variable(self, key: str, name: str):
        """The variable called ``name`` (the scene key ``key`` for the message), or :class:`FmuError` with close
        matches."""
        if name in self.by_name:
            return self.by_name[name]
        close = difflib.get_close_matches(name, list(self.by_name), n=3, cutoff=0.5)
        hint = f"; close matches: {', '.join(close)}" if close else f"; it has {', '.join(sorted(self.by_name)[:12])}"
        raise FmuError(f"{self.label}: {key}: the unit has no variable {name!r}{hint}")

    def size(self, variable) -> int:
        return math.prod(self.shapes.get(variable.name, ()))

    def element(self, key: str, name: str) -> Element:
        """The scalar that ``name`` names: a scalar variable (FMI 2.0 structured names such as ``k[0]`` included),
        or an element ``y[2]``/``A[1,2]`` of an FMI 3.0 array (indices from 1)."""
        if name in self.by_name:
            var = self.by_name[name]
            shape = self.shapes[name]
            if shape:
                example = f"{name}[{','.join('1' * len(shape))}]"
                raise FmuError(
                    f"{self.label}: {key}: {name!r} is an array of shape {_shape_text(shape)}: name one element, "
                    f"e.g. {example} (indices from 1, row-major)"
                )
            return Element(name, var)
        base, indices = parse_element(name)
        if indices is None or base not in self.by_name:
            self.variable(key, name)  # raises with close matches
        var, shape = self.by_name[base], self.shapes[base]
        if not shape:
            raise FmuError(f"{self.label}: {key}: {base!r} is a scalar; name it without indices")
        if len(indices) != len(shape) or any(not 1 <= i <= n for i, n in zip(indices, shape)):
            raise FmuError(
                f"{self.label}: {key}: {name!r} is not an element of {base} (shape {_shape_text(shape)}; "
                f"indices from 1, {len(shape)} of them)"
            )
        flat = 0
        for i, n in zip(indices, shape):
            flat = flat * n + (i - 1)
        return Element(name, var, flat, math.prod(shape))

    # -- start values ---------------------------------------------------------------------------------------------
    def start_values(self, start: dict) -> list[StartValue]:
        """The scene's start values checked (name, settability, type, shape, unit), in the order they are set."""
        checked = [self._start_value(name, value) for name, value in start.items()]
        order = {"configuration": 0, "instantiated": 1, "initialization": 2}
        return sorted(checked, key=lambda s: order[s.state])

    def _start_value(self, name: str, given) -> StartValue:
        var = self.variable("start", name)
        where = f"{self.label}: start: {name}"
        state = self._settable_state(where, var)
        fam = family(var.type)
        if fam in ("binary", "clock"):
            raise FmuError(f"{where}: a {var.type} variable cannot take a start value from a scene")
        value, unit = given, None
        if isinstance(given, dict):
            if set(given) != {"value", "unit"}:
                raise FmuError(f"{where}: a value with a unit is written {{value: 1.5, unit: mm}}, got {given!r}")
            value, unit = given["value"], given["unit"]
            self._check_unit(where, var, unit)
        shape = self.shapes[var.name]
        if shape:
            flat = _flatten(value)
            if flat is None or len(flat) != math.prod(shape):
                raise FmuError(
                    f"{where}: {var.name} is a {var.type} array of shape {_shape_text(shape)}: give a list of "
                    f"{math.prod(shape)} values (nested lists for a matrix, row-major), got {value!r}"
                )
            converted = [self._typed(where, var, v) for v in flat]
        else:
            if isinstance(value, (list, tuple)):
                raise FmuError(f"{where}: {var.name} is a scalar {var.type}, got a list {value!r}")
            converted = self._typed(where, var, value)
        out = converted if unit is None else (converted, unit)
        return StartValue(name, var, out, state, setter(self.md, var), _text(given))

    def _settable_state(self, where: str, var) -> str:
        """The state the standard lets ``var`` be set in before the first step, or :class:`FmuError` naming the
        rule."""
        version = "FMI 3.0" if self.fmi3 else "FMI 2.0"
        if var.causality == "structuralParameter":
            return "configuration"
        if var.variability == "constant":
            raise FmuError(f"{where}: {var.name!r} is a constant; {version} allows no value to be set for it")
        if var.causality == "independent":
            raise FmuError(f"{where}: {var.name!r} is the independent variable (time); set t_start instead")
        if var.causality == "calculatedParameter":
            raise FmuError(
                f"{where}: {var.name!r} is a calculated parameter (the unit computes it from other parameters); "
                f"{version} allows setting only parameters, inputs and variables with initial = exact or approx"
            )
        if var.initial in ("exact", "approx"):
            return "instantiated"
        if var.causality == "input":
            return "initialization"
        raise FmuError(
            f"{where}: {var.name!r} is {_article(var.causality)} {var.causality} with initial = {var.initial}; "
            f"{version} allows start values only for inputs and for variables with initial = exact or approx "
            "(the unit computes this one)"
        )

    def _typed(self, where: str, var, value):
        fam = family(var.type)
        bad = f"{where}: {var.name!r} is declared {var.type}, which takes {_SPELLING[fam]}; got {value!r}"
        if fam == "real":
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise FmuError(bad + (quoted_number_hint(value) if isinstance(value, str) else ""))
            if not math.isfinite(value):
                raise FmuError(f"{where}: must be a finite number, got {value!r}")
            return float(value)
        if fam == "integer":
            if isinstance(value, bool) or not isinstance(value, int):
                raise FmuError(bad)
            lo, hi = integer_range(var.type)
            if not lo <= value <= hi:
                raise FmuError(f"{where}: {value} is out of the range of {var.type} ({lo} .. {hi})")
            return int(value)
        if fam == "boolean":
            if not isinstance(value, bool):
                raise FmuError(bad)
            return value
        if fam == "string":
            if not isinstance(value, str):
                raise FmuError(bad + " (quote it in the scene to give it as text)")
            return value
        items = var.declaredType.items if var.declaredType is not None else []
        by_name = {item.name: int(item.value) for item in items}
        if isinstance(value, str) and value in by_name:
            return by_name[value]
        if isinstance(value, int) and not isinstance(value, bool) and value in by_name.values():
            return value
        allowed = ", ".join(f"{n} ({v})" for n, v in by_name.items())
        raise FmuError(f"{bad}; its items: {allowed}")

    def _check_unit(self, where: str, var, unit):
        if family(var.type) != "real":
            raise FmuError(f"{where}: only a Real/Float variable takes a value with a unit ({var.name} is {var.type})")
        base = var.unit or (var.declaredType.unit if var.declaredType is not None else None)
        if base is None:
            raise FmuError(f"{where}: {var.name} declares no unit; give the value alone")
        definitions = {u.name: u for u in self.md.unitDefinitions}
        display = [d.name for d in definitions[base].displayUnits] if base in definitions else []
        if unit != base and unit not in display:
            allowed = ", ".join([base, *display])
            raise FmuError(f"{where}: unit {unit!r} is not one the unit declares for {var.name}; allowed: {allowed}")


def declared_start(variable, size: int):
    """An FMI 3.0 Float64 array's declared start values (zeros where it declares none), as a float array."""
    import numpy as np

    text = variable.start
    values = [float(v) for v in str(text).split()] if text not in (None, "") else []
    return np.array(values if len(values) == size else [0.0] * size, dtype=float)


def _flatten(value):
    """A (nested) list of values in row-major order, or None if ``value`` is not a list."""
    if not isinstance(value, (list, tuple)):
        return None
    out = []
    for v in value:
        out.extend(_flatten(v) if isinstance(v, (list, tuple)) else [v])
    return out


def _shape_text(shape) -> str:
    return " x ".join(str(n) for n in shape)


def _article(word: str) -> str:
    return "an" if word[:1] in "aeiou" else "a"


def _text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def quoted_number_hint(text: str) -> str:
    """Why YAML read ``text`` as text where a number was wanted: an exponent without its sign (YAML 1.1 reads
    ``1.0e6`` as a string) or quotes around the number; ``""`` if ``text`` is no number."""
    try:
        float(text)
    except ValueError:
        return ""
    if re.search(r"[eE]\d", text.strip()):
        return f" (YAML reads {text} as text: write the exponent with its sign, e.g. 1.0e+6)"
    return f" ({text!r} is quoted text: write the number without quotes)"
