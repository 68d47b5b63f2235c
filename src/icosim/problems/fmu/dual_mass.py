"""The exact solution of OMSimulator's DualMassOscillator (``DualMassOscillator.mo``, ``ReferenceSystemEq``): two
masses, each on a spring-damper to the ground, joined by a third,

    m1 x1'' + (c1 + c2) x1' - c2 x2' + (k1 + k2) x1 - k2 x2 = 0,
    m2 x2'' - c2 x1' + (c2 + c3) x2' - k2 x1 + (k2 + k3) x2 = 0,

from rest at ``x1_start``, ``x2_start``; solved by the matrix exponential.  Split into its units (System1: mass 1
on its spring-damper, input ``F`` the force on it, outputs ``x1``, ``v1``, ``a1``; System2: the point driven by
``x1``, ``v1``, ``a1``, output ``F = k2 (x2 - x1) + c2 (v2 - v1)`` the force sensed there), the connections carry
:meth:`DualMass.outputs`.

The parameters are read from the units themselves (:meth:`DualMass.from_units`: the start values their model
descriptions declare, those a run overrides given), or from the Modelica source (:meth:`DualMass.from_modelica`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
from scipy.linalg import expm

__all__ = ["DualMass", "UNIT_PARAMETERS"]

#: The parameters each unit declares (DualMassOscillator.mo: System1, System2).
UNIT_PARAMETERS = {"system1": ("m1", "k1", "c1", "x1_start"), "system2": ("m2", "k2", "c2", "k3", "c3", "x2_start")}


@dataclass(frozen=True)
class DualMass:
    """The monolithic oscillator; ``k`` are the springs, ``c`` the dampers (the Modelica names)."""

    m1: float = 1.0
    k1: float = 10.0
    c1: float = 0.2
    m2: float = 1.0
    k2: float = 10.0
    c2: float = 0.5
    k3: float = 20.0
    c3: float = 0.3
    x1_start: float = 0.0
    x2_start: float = 0.5

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if not np.isfinite(value) or (f.name[0] == "m" and not value > 0):
                raise ValueError(f"DualMass: {f.name} = {value!r}: a finite number (a mass > 0)")

    @classmethod
    def from_units(cls, system1, system2, starts=None) -> DualMass:
        """The parameters the units' model descriptions declare (start values), with ``starts`` (unit -> {name:
        value}, a scene's ``start``) over them."""
        from fmpy import read_model_description

        values = {}
        for unit, path in (("system1", system1), ("system2", system2)):
            declared = {v.name: v.start for v in read_model_description(str(path)).modelVariables}
            given = dict((starts or {}).get(unit, {}))
            for name in UNIT_PARAMETERS[unit]:
                if name not in given and declared.get(name) is None:
                    raise ValueError(f"{path}: declares no start value of the parameter {name}")
                values[name] = float(given.get(name, declared.get(name)))
        return cls(**values)

    @classmethod
    def from_modelica(cls, path, model: str = "ReferenceSystemEq") -> DualMass:
        """The parameters of ``model`` in the Modelica source ``path`` (``parameter Real name = value``)."""
        text = Path(path).read_text()
        found = re.search(rf"\bmodel\s+{model}\b(.*?)\bend\s+{model}\s*;", text, re.S)
        if found is None:
            raise ValueError(f"{path}: no model {model}")
        pairs = re.findall(r"parameter\s+Real\s+(\w+)\s*=\s*([-+0-9.eE]+)", found.group(1))
        values = {name: float(value) for name, value in pairs}
        missing = [f.name for f in fields(cls) if f.name not in values]
        if missing:
            raise ValueError(f"{path}: {model} has no parameter {', '.join(missing)}")
        return cls(**{f.name: values[f.name] for f in fields(cls)})

    @property
    def amplitude(self) -> float:
        """The largest start displacement: the scale of the free oscillation (m)."""
        return max(abs(self.x1_start), abs(self.x2_start))

    @property
    def matrix(self) -> np.ndarray:
        """``A`` of ``z' = A z``, ``z = (x1, x2, v1, v2)``."""
        K = np.array([[self.k1 + self.k2, -self.k2], [-self.k2, self.k2 + self.k3]])
        C = np.array([[self.c1 + self.c2, -self.c2], [-self.c2, self.c2 + self.c3]])
        Minv = np.diag([1 / self.m1, 1 / self.m2])
        return np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ K, -Minv @ C]])

    @property
    def start(self) -> np.ndarray:
        return np.array([self.x1_start, self.x2_start, 0.0, 0.0])

    def exact(self, t) -> np.ndarray:
        """``x1, x2, v1, v2`` at the times ``t`` (any sign), ``(len(t), 4)``."""
        A, z0 = self.matrix, self.start
        return np.array([expm(A * float(s)) @ z0 for s in np.atleast_1d(t)])

    def outputs(self, t) -> dict:
        """The units' connected outputs at the time ``t``: ``system1.{x1, v1, a1}``, ``system2.F``, and
        ``system2.mass2.s`` (x2)."""
        z = self.exact([t])[0]
        x1, x2, v1, v2 = z
        force = self.k2 * (x2 - x1) + self.c2 * (v2 - v1)
        a1 = (self.matrix @ z)[2]
        return {"system1.x1": x1, "system1.v1": v1, "system1.a1": a1, "system2.F": force, "system2.mass2.s": x2}
