"""One description of a system, whatever file it came from: components, connectors, connections, bound parameters,
units, the default experiment and, for OSP, the power bonds and the master's algorithm."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Connector", "Component", "Connection", "System"]


@dataclass(frozen=True)
class Connector:
    """A component's connector: ``kind`` input, output, parameter, calculatedParameter, inout or ``None`` (OSP
    names none: the unit's model description says), ``type`` Real, Integer, Boolean, String, Enumeration or
    ``None``, ``unit`` as the file names it."""

    name: str
    kind: str | None = None
    type: str | None = None
    unit: str | None = None


@dataclass
class Component:
    """A unit of the system: its name, its FMU (resolved against the file), connectors and the start values the
    file binds (``start``: variable -> value, typed as the file types them)."""

    name: str
    source: Path
    connectors: tuple = ()
    start: dict = field(default_factory=dict)
    implementation: str | None = None  # SSP: CoSimulation, ModelExchange or any

    def connector(self, name: str) -> Connector | None:
        return next((c for c in self.connectors if c.name == name), None)


@dataclass(frozen=True)
class Connection:
    """``start`` feeds ``end`` (component, connector), ``end = factor * start + offset`` in the connectors' own
    units (the file's ``LinearTransformation``), then converted from the start's unit to the end's (``unit_factor``,
    ``unit_offset``: 1 and 0 where the units agree or the file suppresses the conversion).  ``power_bond``: the
    OSP power bond it belongs to."""

    start: tuple
    end: tuple
    factor: float = 1.0
    offset: float = 0.0
    unit_factor: float = 1.0
    unit_offset: float = 0.0
    power_bond: str | None = None

    @property
    def label(self) -> str:
        return f"{self.start[0]}.{self.start[1]} -> {self.end[0]}.{self.end[1]}"

    def apply(self, value: float) -> float:
        """The end's value for the start's ``value``."""
        return self.unit_factor * (self.factor * value + self.offset) + self.unit_offset


@dataclass
class System:
    """A system file read: ``format`` (``SSP 1.0``, ``SSP 2.0``, ``OSP``), components by name, connections, the
    units the file defines (name -> (factor, offset, exponents)), the default experiment (``start_time``,
    ``stop_time``, ``step_size``: ``None`` where the file gives none) and OSP's ``algorithm`` with its ``ecco``
    configuration (kept, reported; icosim couples with its own methods at a fixed or controlled step)."""

    path: Path
    format: str
    name: str
    components: dict
    connections: list
    units: dict = field(default_factory=dict)
    start_time: float | None = None
    stop_time: float | None = None
    step_size: float | None = None
    algorithm: str | None = None
    ecco: dict | None = None
    notes: list = field(default_factory=list)  # what a run from it takes that the file did not say

    def power_bonds(self) -> dict:
        """Bond name -> its connections, in file order."""
        bonds: dict = {}
        for c in self.connections:
            if c.power_bond is not None:
                bonds.setdefault(c.power_bond, []).append(c)
        return bonds

    def summary(self) -> dict:
        """What was read, as plain data (the dataset keeps it as JSON)."""
        return {
            "file": str(self.path),
            "format": self.format,
            "name": self.name,
            "components": {
                n: {"source": str(c.source), "start": c.start, "connectors": [vars(k) for k in c.connectors]}
                for n, c in self.components.items()
            },
            "connections": [
                {
                    "connection": c.label,
                    "factor": c.factor,
                    "offset": c.offset,
                    "unit_factor": c.unit_factor,
                    "unit_offset": c.unit_offset,
                    "power_bond": c.power_bond,
                }
                for c in self.connections
            ],  # fmt: skip
            "start_time": self.start_time,
            "stop_time": self.stop_time,
            "step_size": self.step_size,
            "algorithm": self.algorithm,
            "ecco": self.ecco,
            "notes": self.notes,
        }
