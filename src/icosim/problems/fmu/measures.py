"""Units of measure of a unit's coupling variables: what they must be (a length, a velocity, an acceleration, a
force), and the factor to SI of what the unit declares.

A variable's unit is its ``unit`` attribute or its declared type's.  The unit is read from its
``<BaseUnit>`` (exponents of kg, m, s, A, K, mol, cd, rad, a factor and an offset) where the model description
defines one, else from its name as a Modelica unit expression (``m``, ``mm``, ``m/s2``, ``m.s-2``, ``kN``,
``kg.m/s2``, ``N.s/m``; prefixes ``k``, ``m``, ``u``, ...).  A coupling variable whose unit does not fit its role
is refused naming both; one without a unit is taken to be in SI; one whose unit cannot be read is taken as it is
and reported (``icosim cosim --check``).

>>> parse("kN")
({'kg': 1, 'm': 1, 's': -2}, 1000.0)
>>> parse("m.s-2") == parse("m/s2")
True
>>> parse("mm/s")
({'m': 1, 's': -1}, 0.001)
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import FmuError
from .roles import COMPLIANT, velocity_input

__all__ = ["ROLE_QUANTITIES", "Measure", "measure", "parse"]

_LENGTH = {"m": 1}
_VELOCITY = {"m": 1, "s": -1}
_ACCELERATION = {"m": 1, "s": -2}
_FORCE = {"kg": 1, "m": 1, "s": -2}

#: Scene key -> (the quantity it must carry, its SI dimensions).
ROLE_QUANTITIES = {
    "position": ("a length", _LENGTH),
    "velocity": ("a velocity", _VELOCITY),
    "acceleration": ("an acceleration", _ACCELERATION),
    "acceleration_input": ("an acceleration", _ACCELERATION),
    "position_input": ("a length", _LENGTH),
    "velocity_input": ("a velocity", _VELOCITY),
    "force": ("a force", _FORCE),
    "reaction_force": ("a force", _FORCE),
    "set_position": ("a length", _LENGTH),
    "set_velocity": ("a velocity", _VELOCITY),
}

_SYMBOLS = {
    "m": (_LENGTH, 1.0),
    "s": ({"s": 1}, 1.0),
    "g": ({"kg": 1}, 1e-3),
    "N": (_FORCE, 1.0),
    "J": ({"kg": 1, "m": 2, "s": -2}, 1.0),
    "W": ({"kg": 1, "m": 2, "s": -3}, 1.0),
    "Pa": ({"kg": 1, "m": -1, "s": -2}, 1.0),
    "Hz": ({"s": -1}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "deg": ({"rad": 1}, 3.141592653589793 / 180),
    "min": ({"s": 1}, 60.0),
    "h": ({"s": 1}, 3600.0),
    "A": ({"A": 1}, 1.0),
    "K": ({"K": 1}, 1.0),
    "mol": ({"mol": 1}, 1.0),
    "cd": ({"cd": 1}, 1.0),
}
_PREFIXES = {
    "G": 1e9,
    "M": 1e6,
    "k": 1e3,
    "h": 1e2,
    "d": 1e-1,
    "c": 1e-2,
    "m": 1e-3,
    "u": 1e-6,
    "µ": 1e-6,
    "n": 1e-9,
    "p": 1e-12,
}
_FACTOR = re.compile(r"^(?P<sym>[A-Za-zµ]+)(?P<exp>[+-]?\d+)?$")
_BASE_EXPONENTS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def _symbol(text: str):
    if text in _SYMBOLS:
        return _SYMBOLS[text]
    for n in (2, 1):  # "da" is the only two-letter prefix; not used for these quantities
        prefix, rest = text[:n], text[n:]
        if prefix in _PREFIXES and rest in _SYMBOLS:
            dims, factor = _SYMBOLS[rest]
            return dims, _PREFIXES[prefix] * factor
    return None


def parse(text: str):
    """``(dimensions, factor to SI)`` of a Modelica unit expression, or None if it cannot be read."""
    text = text.strip()
    if text in ("", "1"):
        return {}, 1.0
    parts = text.split("/")
    if len(parts) > 2:
        return None
    dims, factor = {}, 1.0
    for sign, part in zip((1, -1), parts):
        for token in part.split("."):
            if sign == 1 and token == "1" and len(parts) == 2:
                continue  # "1/s"
            m = _FACTOR.match(token)
            found = _symbol(m["sym"]) if m else None
            if found is None:
                return None
            exp = sign * int(m["exp"] or 1)
            d, f = found
            for base, e in d.items():
                dims[base] = dims.get(base, 0) + e * exp
            factor *= f**exp
    return {k: v for k, v in dims.items() if v}, factor


@dataclass(frozen=True)
class Measure:
    """A coupling variable's unit: its name (None: not declared), the factor that takes its values to SI, and how
    it was read (``"BaseUnit"``, ``"name"``, ``"not declared"``, ``"not understood"``)."""

    unit: str | None
    factor: float
    read_from: str

    @property
    def checked(self) -> bool:
        return self.read_from in ("BaseUnit", "name")


def _declared(variable) -> str | None:
    if variable.unit:
        return variable.unit
    return variable.declaredType.unit if variable.declaredType is not None else None


def measure(label: str, md, key: str, variable) -> Measure:
    """The unit of ``variable`` in the role ``key`` (:data:`ROLE_QUANTITIES`): :class:`FmuError` naming both where
    it is not the role's quantity (a velocity as a force or acceleration input: a compliant unit's, refused)."""
    velocity_input(label, key, variable)
    unit = _declared(variable)
    if key not in ROLE_QUANTITIES:  # a connection's variable: in its own unit (the connection converts)
        return Measure(unit, 1.0, "the connection's")
    if unit is None:
        return Measure(None, 1.0, "not declared")
    definitions = {u.name: u for u in md.unitDefinitions}
    base = definitions[unit].baseUnit if unit in definitions else None
    if base is not None:
        dims = {e: getattr(base, e) for e in _BASE_EXPONENTS if getattr(base, e)}
        factor, offset, read_from = float(base.factor), float(base.offset), "BaseUnit"
    else:
        parsed = parse(unit)
        if parsed is None:
            return Measure(unit, 1.0, "not understood")
        (dims, factor), offset, read_from = parsed, 0.0, "name"
    quantity, wanted = ROLE_QUANTITIES[key]
    if dims != wanted:
        why = ""
        if key in ("force", "acceleration_input") and dims == _VELOCITY:
            why = f": the unit takes a velocity, {COMPLIANT}"
        raise FmuError(
            f"{label}: {key}: {variable.name!r} is in {unit} ({_dims_text(dims)}), but {key} must be "
            f"{quantity} ({_dims_text(wanted)}){why}"
        )
    if offset != 0.0:
        raise FmuError(f"{label}: {key}: {variable.name!r} is in {unit}, a unit with an offset; {key} needs none")
    return Measure(unit, factor, read_from)


def _dims_text(dims: dict) -> str:
    if not dims:
        return "dimensionless"
    return " ".join(f"{b}^{e}" if e != 1 else b for b, e in sorted(dims.items(), key=lambda i: -i[1]))
