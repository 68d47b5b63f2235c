"""Inputs fed by a time signal instead of a connection: a table (a CSV file or inline lists, interpolated piecewise
linearly, as OMSimulator's CSV components and SSP's signal tables are) or a constant.

A scene of signal connections names them under ``sources``::

    sources:
      - {to: wheel.z, table: road.csv}                    # CSV: a time column, then one value column (or name it)
      - {to: wheel.z, table: road.csv, column: road}
      - {to: wheel.z, table: {time: [0, 1, 1, 5], values: [0, 0, 0.1, 0.1]}}
      - {to: chassis.F, value: 0.0}

A table's times rise (two rows at one time: a jump, the first row the value before it, the last the value after);
before the first time the first value holds, after the last the last.  A table is known ahead of the run, so it is
not extrapolated as a connection's samples are: over each macro step ``[T_N, T_N+1]`` the unit is handed the chord
from the table's value just after ``T_N`` to its value just before ``T_N+1``.  That is the table itself where its
breakpoints lie on communication points, whatever ``k``; a breakpoint inside a step costs ``O(H)`` in that step
(a jump ``O(1)``).  A table time within :data:`SNAP` (relative) of a communication point counts as at it, so that
``t_0 + n H`` rounded in its last bit does not move a jump into the step before.

CSV files (a header row naming the columns, comma-separated) are read with the standard library's :mod:`csv`; a
file is relative to the scene.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import SceneError

__all__ = ["TableSource", "SOURCE_KEYS", "sources_of", "check_targets", "SNAP"]

#: Keys of one entry of ``sources``.
SOURCE_KEYS = ("to", "table", "column", "value")
#: Relative distance under which a table time and a communication point are one time.
SNAP = 1e-12


@dataclass(frozen=True)
class TableSource:
    """A piecewise-linear signal through ``(times[j], values[j])`` (a constant: one row)."""

    times: np.ndarray
    values: np.ndarray

    def _tol(self, t: float) -> float:
        return SNAP * max(1.0, abs(t), abs(float(self.times[-1])))

    def _between(self, j: int, t: float) -> float:
        """The value at ``t`` on the segment from row ``j - 1`` to row ``j``."""
        t0, t1 = self.times[j - 1], self.times[j]
        w = min(1.0, max(0.0, (t - t0) / (t1 - t0)))
        return float(self.values[j - 1] + w * (self.values[j] - self.values[j - 1]))

    def after(self, t: float) -> float:
        """The value just after ``t`` (a jump at ``t``: the value it jumps to)."""
        tol = self._tol(t)
        j = int(np.searchsorted(self.times, t + tol, side="right"))  # the first row after t
        if j == 0 or j == len(self.times):
            return float(self.values[min(j, len(self.values) - 1)])
        if self.times[j - 1] >= t - tol:
            return float(self.values[j - 1])
        return self._between(j, t)

    def before(self, t: float) -> float:
        """The value just before ``t`` (a jump at ``t``: the value it jumps from)."""
        tol = self._tol(t)
        j = int(np.searchsorted(self.times, t - tol, side="left"))  # the first row at or after t
        if j == 0 or j == len(self.times):
            return float(self.values[min(j, len(self.values) - 1)])
        if self.times[j] <= t + tol:
            return float(self.values[j])
        return self._between(j, t)

    def chord(self, t: float, H: float) -> tuple[float, float]:
        """The monomial coefficients ``(c0, c1)`` in ``tau = (s - t) / H`` of the chord over ``[t, t + H]``."""
        a = self.after(t)
        return a, self.before(t + H) - a


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


def _read_csv(path, where, file, column) -> tuple[list, list]:
    if not file.is_file():
        _fail(path, f"{where}.table", f"{str(file)!r} is not a file (a CSV table, relative to the scene)")
    with file.open(newline="") as handle:
        rows = [row for row in csv.reader(handle) if row and any(cell.strip() for cell in row)]
    if len(rows) < 2:
        _fail(path, f"{where}.table", f"{file.name}: needs a header row (time, then value columns) and one data row")
    header = [cell.strip() for cell in rows[0]]
    if len(header) < 2:
        _fail(path, f"{where}.table", f"{file.name}: needs a time column and a value column, got {header}")
    if column is None:
        if len(header) != 2:
            _fail(path, f"{where}.column", f"{file.name} has value columns {header[1:]}: name one")
        index = 1
    elif column not in header[1:]:
        _fail(path, f"{where}.column", f"{column!r} is not a column of {file.name}; allowed: {', '.join(header[1:])}")
    else:
        index = header.index(column)
    times, values = [], []
    for n, row in enumerate(rows[1:], start=2):
        try:
            times.append(float(row[0]))
            values.append(float(row[index]))
        except (ValueError, IndexError):
            _fail(path, f"{where}.table", f"{file.name} line {n}: {row!r} is not a row of numbers")
    return times, values


def _table(path, where, entry) -> TableSource:
    spec, column = entry["table"], entry.get("column")
    if isinstance(spec, str):
        times, values = _read_csv(path, where, (Path(path).parent / spec).resolve(), column)
    elif isinstance(spec, dict) and set(spec) == {"time", "values"}:
        if column is not None:
            _fail(path, f"{where}.column", "belongs to a table read from a CSV file")
        times, values = spec["time"], spec["values"]
        if not (isinstance(times, list) and isinstance(values, list) and len(times) == len(values) and times):
            _fail(path, f"{where}.table", "time and values must be lists of equal, non-zero length")
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in times + values):
            _fail(path, f"{where}.table", "time and values must hold numbers")
    else:
        _fail(path, f"{where}.table", f"{spec!r} must be a CSV file (relative to the scene) or {{time: [...], "
              "values: [...]}")  # fmt: skip
    t, v = np.asarray(times, dtype=float), np.asarray(values, dtype=float)
    if not (np.isfinite(t).all() and np.isfinite(v).all()):
        _fail(path, f"{where}.table", "times and values must be finite")
    if np.any(np.diff(t) < 0):
        _fail(path, f"{where}.table", "times must not fall (two rows at one time: a jump)")
    if np.any((t[2:] == t[1:-1]) & (t[1:-1] == t[:-2])):
        _fail(path, f"{where}.table", "three rows at one time: a jump takes two (the value before, the value after)")
    return TableSource(t, v)


def sources_of(path, entries, subsystems, fed) -> list[tuple[str, str, TableSource]]:
    """The scene's ``sources`` checked: ``(unit, input, source)`` each; ``subsystems``: the scene's subsystem
    names; ``fed``: ``(unit, input)`` -> the index of the connection that feeds it (an input takes one feed)."""
    if not isinstance(entries, list):
        _fail(path, "sources", "must be a list of {to: unit.input, table: FILE.csv} or {to: unit.input, value: x}")
    out, seen = [], {}
    for n, entry in enumerate(entries):
        where = f"sources[{n}]"
        if not isinstance(entry, dict) or "to" not in entry:
            _fail(path, where, "must be a mapping with to (unit.input) and table or value")
        for key in entry:
            if key not in SOURCE_KEYS:
                _fail(path, f"{where}.{key}", f"not a key of a source; allowed: {', '.join(SOURCE_KEYS)}")
        ref = entry["to"]
        unit, _, var = ref.partition(".") if isinstance(ref, str) else ("", "", "")
        if unit not in subsystems or not var:
            _fail(path, f"{where}.to", f"{ref!r} must be <subsystem>.<input> with a subsystem of "
                  f"{', '.join(subsystems)}")  # fmt: skip
        if (unit, var) in fed:
            _fail(path, f"{where}.to", f"{ref} is fed already by connections[{fed[unit, var]}]; an input takes one "
                  "connection or one source")  # fmt: skip
        if (unit, var) in seen:
            _fail(path, f"{where}.to", f"{ref} is fed already by sources[{seen[unit, var]}]")
        seen[unit, var] = n
        if ("table" in entry) == ("value" in entry):
            _fail(path, where, "takes one of table (a CSV file or {time, values}) and value (a constant)")
        if "value" in entry:
            value = entry["value"]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
                _fail(path, f"{where}.value", f"must be a finite number, got {value!r}")
            if "column" in entry:
                _fail(path, f"{where}.column", "belongs to a table read from a CSV file")
            source = TableSource(np.zeros(1), np.array([float(value)]))
        else:
            source = _table(path, where, entry)
        out.append((unit, var, source))
    return out


def check_targets(path, sources, fmus) -> None:
    """Refuse a source whose ``to`` is not a Real input of its unit, naming ``sources[n].to`` and the unit's inputs,
    before any unit is opened; ``fmus``: unit name -> its ``.fmu`` file."""
    from fmpy import read_model_description

    descriptions: dict = {}
    for n, (unit, var, _) in enumerate(sources):
        if unit not in descriptions:
            try:
                descriptions[unit] = read_model_description(str(fmus[unit]), validate=False)
            except Exception:  # no readable unit: opening it says why, naming the unit
                descriptions[unit] = None
        if descriptions[unit] is None:
            continue
        variables = descriptions[unit].modelVariables
        inputs = [v.name for v in variables if v.causality == "input" and v.type in ("Real", "Float64")]
        if var not in inputs:
            found = next((v for v in variables if v.name == var), None)
            what = "no variable of that name" if found is None else f"a {found.type} of causality {found.causality}"
            _fail(path, f"sources[{n}].to", f"{unit}.{var} is {what}; a source feeds a Real input, here one of "
                  f"{', '.join(inputs) or '(none)'}")  # fmt: skip
