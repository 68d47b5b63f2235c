"""Coupling methods (Sect. 2) and their registry.

Each method is a small rule plus a registry entry (:class:`MethodSpec`) in its
own module; :data:`METHODS` collects the entries, as scipy's ``solve_ivp``
keeps its ``METHODS`` table.  Everything that needs to know about methods --
:func:`make_method`, the command line, the convergence study, the pendulum, the
figures and the configuration schemas -- reads this table, so a new method is
a new module with its rule and its entry, and one line below.

========================  =============================================  ==========
module                    rule                                           parameters
========================  =============================================  ==========
:mod:`.baumgarte`         one solve on ``g + beta g' + gamma g''``        mu, beta, gamma, index
:mod:`.weighted`          mean of the three level solutions, (1, a, b)   a, b, index
:mod:`.projection`        acceleration level, then projection (Eq. 30)   --
========================  =============================================  ==========

Newton's rule (:mod:`.newton`: ``e - J^-1 r``) closes implicitly coupled signal connections, not joints: it is
no entry of the table.

>>> sorted(METHODS)
['baumgarte', 'projection', 'weighted']
>>> make_method("baumgarte", index=2, mu=1.0).params
{'beta': 2.0, 'gamma': 0.0, 'mu': 1.0, 'index': 2}
>>> engine_method(make_method("baumgarte", index=1, mu=1e-3), H=1e-3).params["gamma"]
1.0
"""

from __future__ import annotations

from typing import Any

from ...errors import ParameterError
from . import baumgarte, projection, weighted
from .base import UNIT_TEXT, CouplingMethod, MethodSpec, Parameter, solve_small

__all__ = [
    "METHODS",
    "MethodSpec",
    "Parameter",
    "CouplingMethod",
    "solve_small",
    "register",
    "get_spec",
    "make_method",
    "engine_method",
    "parameters",
    "argument_names",
    "parameter_units",
    "indices",
    "UNIT_TEXT",
]

#: name -> registry entry, in the order the methods are listed everywhere.
METHODS: dict[str, MethodSpec] = {spec.name: spec for spec in (baumgarte.SPEC, weighted.SPEC, projection.SPEC)}


def register(spec: MethodSpec) -> MethodSpec:
    """Add a method to :data:`METHODS` (its parameters must agree with same-named ones of other methods)."""
    if spec.name in METHODS:
        raise ValueError(f"method {spec.name!r} is already registered")
    known = parameters()
    for p in spec.parameters:
        other = known.get(p.name)
        if other is not None and (other.unit, other.scaling) != (p.unit, p.scaling):
            raise ValueError(f"parameter {p.name!r} of {spec.name!r} has another unit or H scaling than before")
    METHODS[spec.name] = spec
    return spec


def get_spec(name: str) -> MethodSpec:
    try:
        return METHODS[name]
    except KeyError:
        raise ParameterError(f"method must be one of {', '.join(METHODS)}, got {name!r}") from None


def make_method(name: str, **params: Any) -> CouplingMethod:
    """Build a method by name; ``params`` as its factory takes them (None = not given)."""
    return get_spec(name).make(**params)


def engine_method(method: CouplingMethod, H: float) -> CouplingMethod:
    """The method with dimensional parameters (``beta`` in s, ``gamma`` in s^2, ...) at macro step ``H``
    rebuilt with the engine's dimensionless ones (``beta_bar = beta/H``, ``gamma_bar = gamma/H^2``)."""
    spec = get_spec(method.name)
    own = {p.name: p.engine_value(method.params[p.name], H) for p in spec.parameters if not p.shorthand}
    return spec.make(**{k: v for k, v in own.items()})


def parameters() -> dict[str, Parameter]:
    """Every registered parameter by name (first definition wins), in registry order."""
    out: dict[str, Parameter] = {}
    for spec in METHODS.values():
        for p in spec.parameters:
            out.setdefault(p.name, p)
    return out


def argument_names() -> tuple[str, ...]:
    """``index`` and every parameter name: what a configuration or the command line may give."""
    return ("index",) + tuple(parameters())


def indices() -> tuple[int, ...]:
    """Every index some registered method takes as an argument."""
    return tuple(sorted({i for spec in METHODS.values() if spec.takes_index for i in spec.indices}))


def parameter_units(*, index: bool = False) -> dict[str, str]:
    """Unit of every parameter in the dimensional setting (``"s"``, ``"s2"``, ``"1"``); ``index`` adds it."""
    out = {name: p.unit for name, p in parameters().items()}
    return {**out, "index": "1"} if index else out
