"""Variables a scene asks to record: ``record: [names]`` per subsystem, read from the unit at ``t_start`` and after
each accepted macro step, written to the dataset as ``<subsystem>.<variable>(time)``.

Which variables may be read follows the standard: FMI 2.0 lets ``fmi2GetReal``/``Integer``/``Boolean`` determine
the value of every variable of the model description at the current time (section 2.1.7), in the step-complete
state of Co-Simulation too (section 4.2.4), and FMI 3.0's ``fmi3Get{VariableType}`` so; a ``local`` must not be
*connected* to another unit (FMI 2.0 section 2.2.7), but reading it for the record is what its visibility is for.
So any numeric variable (Real, Integer, Boolean, Enumeration; FMI 3.0 Float, Int, UInt, Boolean, Enumeration, an
array element as ``y[2]``) of causality output, local, parameter, calculated parameter, structural parameter or
input is recorded (an input or parameter: the value the unit holds).  The independent variable is refused (its
value is the dataset's ``time``), and so are String, Binary and Clock variables, naming the variable and the unit.
A value is recorded as the unit holds it, in its declared unit (the dataset's ``units`` attribute says which), not
converted to SI.
"""

from __future__ import annotations

import numpy as np

from . import guard
from .errors import FmuError

__all__ = ["Recorder", "Recording", "READABLE", "recorded_entries"]

#: Causalities whose variables the get functions may read in step mode.
READABLE = ("output", "local", "parameter", "calculatedParameter", "structuralParameter", "input")

# FMI type -> the fmpy getter (FMI 2.0 keeps one per family, FMI 3.0 one per type)
_FMI2_GETTERS = {"Real": "getReal", "Integer": "getInteger", "Enumeration": "getInteger", "Boolean": "getBoolean"}
_FMI3_GETTERS = {
    "Float64": "getFloat64",
    "Float32": "getFloat32",
    **{f"{s}Int{n}": f"get{s}Int{n}" for s in ("", "U") for n in (8, 16, 32, 64)},
    "Boolean": "getBoolean",
    "Enumeration": "getInt64",
}


class Recorder:
    """The variables ``names`` of ``unit`` (a :class:`~icosim.problems.fmu.units.Unit`), checked when it is made
    (:class:`FmuError` naming the unit and the variable), read with the getter of each one's type."""

    def __init__(self, unit, names):
        self.unit, self.names = unit, list(names)
        getters = _FMI3_GETTERS if unit.fmi3 else _FMI2_GETTERS
        self.elements, self.units = [], []
        for name in self.names:
            el = unit.table.element("record", name)
            var = el.variable
            if var.causality not in READABLE:
                raise FmuError(
                    f"{unit.label}: record: {name!r} has causality {var.causality}: the independent variable is "
                    "the dataset's time; record an output, local, parameter or input"
                )
            if var.type not in getters:
                raise FmuError(
                    f"{unit.label}: record: {name!r} is {var.type}: only numbers are recorded "
                    f"({', '.join(dict.fromkeys(getters))})"
                )
            self.elements.append((el, getters[var.type]))
            declared = var.unit or (var.declaredType.unit if var.declaredType is not None else None)
            self.units.append(declared or "")

    def read(self) -> list:
        """The variables' values as the unit holds them now (floats; a Boolean as 0 or 1)."""
        unit = self.unit
        out = []
        with guard.call(unit, "fmi3GetFloat64" if unit.fmi3 else "fmi2GetReal", unit.t):
            for el, getter in self.elements:
                get = getattr(unit.fmu, getter)
                ref = [el.value_reference]
                values = get(ref, el.size) if unit.fmi3 else get(ref)
                out.append(float(values[el.index]))
        return out


class Recording:
    """The recorded variables of a run's units, read at ``t_start`` with the coupling variables ``e0`` there, then
    by :meth:`read` after each accepted macro step; :meth:`result` at the end."""

    def __init__(self, problem, units, scene, e0):
        self.problem = problem
        subs = scene.data["subsystems"].values()
        self.recorders = {
            i: Recorder(u, sub["record"]) for i, (u, sub) in enumerate(zip(units, subs)) if sub.get("record")
        }
        self.rows = {i: [] for i in self.recorders}
        self.read(e0)

    def read(self, e):
        """Read every recorded variable at the communication point with the accepted coupling variables ``e``."""
        for i, rec in self.recorders.items():
            self.problem.stand(i, e)  # the accepted state and input, wherever the step left the unit
            self.rows[i].append(rec.read())

    def result(self, n_rows) -> dict:
        """Subsystem -> (names, units, values ``(n_rows, names)``) of the first ``n_rows`` communication points."""
        return {
            rec.unit.label: (rec.names, rec.units, np.array(self.rows[i][:n_rows], dtype=float).reshape(n_rows, -1))
            for i, rec in self.recorders.items()
        }


def recorded_entries(recorded: dict) -> dict:
    """Dataset entries ``<subsystem>.<variable>`` (time) of ``recorded``: subsystem -> (names, units, values
    ``(time, names)``)."""
    entries = {}
    for label, (names, units, values) in recorded.items():
        for j, (name, unit) in enumerate(zip(names, units)):
            attrs = {"long_name": f"{name} of subsystem {label}", "comment": "as the unit holds it at t_start and "
                     "after each accepted macro step, in its declared unit"}  # fmt: skip
            entries[f"{label}.{name}"] = (
                ("time",),
                np.asarray(values, dtype=float)[:, j],
                attrs | ({"units": unit} if unit else {}),
            )
    return entries
