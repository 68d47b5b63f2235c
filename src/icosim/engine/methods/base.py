"""What a coupling method is: a small rule, and the registry entry that describes it.

A **method** is a rule for forming the corrected coupling variables from the
predicted residuals ``r`` and their (constant, Eq. 13/39/63) sensitivities
``J = dr/de``: each of its *solves* picks a combination of the constraint
levels, stacks it with the force-balance rows and solves the linearised
conditions for ``delta e``; the corrected variables are
``e_p + sum_s w_s delta e_s`` (:class:`CouplingMethod`).

Its **registry entry** (:class:`MethodSpec`) is data about the rule that the
rest of the package reads: parameters (:class:`Parameter`: unit in the
dimensional setting of the convergence study and the pendulum, how it scales
with the macro step ``H``, symbols), labels, the indices it can be formulated
at and the parameters each index leaves unused, and the decompositions it is
defined for.  The entries live next to their rules (``baumgarte.py``,
``weighted.py``, ``projection.py``); :mod:`icosim.engine.methods` collects them in
:data:`~icosim.engine.methods.METHODS`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ParameterError
from .. import layout
from ..decompositions import DECOMPOSITIONS, Decomposition
from .solve import Factored, KeptFactors, solve_small

if TYPE_CHECKING:
    from ..backends import Backend

__all__ = ["CouplingMethod", "MethodSpec", "Parameter", "solve_small", "finite", "exact"]


@dataclass(frozen=True)
class CouplingMethod:
    """A rule for the corrected coupling variables (plus optional projection).

    ``solves`` is a tuple of ``(weight, (w_pos, w_vel, w_acc))``.
    ``params`` records the method parameters under their command-line names.
    ``requires_constraint``: the rule corrects on the constraint's levels, so
    it is defined only for decompositions whose conditions include the
    constraint (a force-driven subsystem); ``refusal`` says why.
    """

    name: str
    solves: tuple
    projection: bool = False
    params: dict = field(default_factory=dict)
    requires_constraint: bool = False
    refusal: str = ""

    @property
    def n_solves(self) -> int:
        """Linear solves of coupling conditions per corrector pass (the solves with a nonzero weight)."""
        return sum(1 for weight, _ in self.solves if weight != 0)

    @property
    def decompositions(self) -> tuple[str, ...]:
        """The registered decompositions the rule is defined for."""
        return supported_decompositions(self.requires_constraint)

    def check_decomposition(self, decomposition: Decomposition) -> None:
        if self.requires_constraint and not decomposition.has_constraint_condition:
            why = self.refusal or f"it is defined for {', '.join(self.decompositions)}"
            raise ParameterError(f"method {self.name!r} is not defined for decomposition {decomposition.name!r}: {why}")

    @cached_property
    def float_solves(self) -> tuple:
        """:attr:`solves` with the exact weights and levels as floats (what float64's ``const`` makes of them), made
        once: hashing their Fractions every macro step would cost more than the conversion."""
        return tuple((float(w), tuple(float(v) for v in lv)) for w, lv in self.solves)

    def corrected_coupling(
        self,
        e_pred: np.ndarray,
        residuals: Mapping[str, np.ndarray],
        jacobians: Mapping[str, np.ndarray],
        backend: Backend,
        factors: KeptFactors | None = None,
    ) -> np.ndarray:
        """``e_p + sum_s w_s delta_e_s`` from the linearised coupling conditions.

        ``residuals[level]`` has shape ``(..., n_level)`` and ``jacobians[level]``
        shape ``(..., n_level, n_e)``, levels ``pos``, ``vel``, ``acc``
        (constraint) and ``force`` (force balance, possibly empty).  ``factors``:
        the factored combinations of these Jacobians, where the problem keeps them
        (constant sensitivities: the same Jacobians every step); a float64 solve
        reads and fills it.
        """
        plain = getattr(backend, "dtype", None) is np.float64  # float64: the exact numbers converted once
        solves = self.float_solves if plain else self.solves
        const = _same if plain else backend.const
        kept = factors if plain else None
        total = None
        for weight, levels in solves:
            if weight == 0:
                continue  # an unused level may be singular (e.g. velocity at k = 0)
            r = _conditions(levels, residuals, axis=-1, const=const)
            if kept is not None and kept.used:  # the combination of these levels, factored once
                factor = kept.by_levels.get(levels)
                if factor is None:
                    factor = kept.by_levels[levels] = Factored(_conditions(levels, jacobians, axis=-2, const=const))
                de = factor.solve(-r)
            else:
                if kept is not None:
                    kept.used = True
                de = solve_small(_conditions(levels, jacobians, axis=-2, const=const), -r)
            term: np.ndarray = de if weight == 1 else const(weight) * de
            total = term if total is None else total + term
        return e_pred + total

    def condition_residuals(self, residuals: Mapping[str, np.ndarray]) -> np.ndarray:
        """The conditions of every solve of this method, concatenated.

        After a converged corrector they vanish for Baumgarte (``g + beta g' +
        gamma g''``) and projection (acceleration level); the weighted
        multiplier's result is a weighted mean of three solutions and satisfies
        none of its three conditions on its own.
        """
        rows = [_conditions(levels, residuals, axis=-1) for weight, levels in self.solves if weight != 0]
        return layout.concatenate(rows, axis=-1)


#: How a unit of the dimensional setting is written in running text.
UNIT_TEXT = {"s": "s", "s2": "s^2", "1": "dimensionless"}


@dataclass(frozen=True)
class Parameter:
    """One parameter of a method, under its command-line name.

    ``unit`` is the unit in the dimensional setting (convergence study,
    pendulum: ``"s"``, ``"s2"``, or ``"1"``); the engine works with the
    dimensionless value ``value / H**scaling`` (``beta_bar = beta / H``).  A
    ``shorthand`` parameter (Baumgarte's ``mu``) only sets others and is not a
    parameter of the rule itself.  ``symbol`` and ``tex`` name the
    dimensionless form (stability plots), ``tex_dimensional`` the dimensional
    one.  ``minimum`` (with ``exclusive_minimum``) is the smallest valid value.
    """

    name: str
    help: str
    unit: str = "1"
    scaling: int = 0
    symbol: str = ""
    tex: str = ""
    tex_dimensional: str = ""
    minimum: float = 0.0
    exclusive_minimum: bool = False
    shorthand: bool = False

    def __post_init__(self) -> None:
        if self.unit not in UNIT_TEXT:
            raise ValueError(f"parameter {self.name}: unit must be one of {list(UNIT_TEXT)}, got {self.unit!r}")
        if (self.unit == "1") != (self.scaling == 0):
            raise ValueError(f"parameter {self.name}: a dimensionless parameter has scaling 0, and only it")

    def engine_value(self, value: float, H: float) -> float:
        """The engine's dimensionless value of a dimensional ``value`` at macro step ``H``."""
        return value / H**self.scaling if self.scaling else value

    def schema(self) -> dict:
        """JSON schema of the parameter's value (configuration files)."""
        bound = "exclusiveMinimum" if self.exclusive_minimum else "minimum"
        out = {"type": "number", bound: self.minimum}
        if self.unit != "1":
            out["description"] = f"{self.help}; in {UNIT_TEXT[self.unit]} where the setting is dimensional"
        return out


@dataclass(frozen=True)
class MethodSpec:
    """Registry entry of a coupling method: its rule and the data about it.

    Parameters
    ----------
    name : the method's name in configurations and on the command line.
    label, short_label : plain-text names (figures and reports; scheme labels).
    build : the rule's factory, called with the parameters as keywords
        (``index`` included where the method takes one); returns a
        :class:`CouplingMethod` whose ``params`` hold the resolved parameters
        and the ``index`` that follows from them.
    parameters : the method's parameters other than ``index``.
    indices : the indices it can be formulated at; it takes an ``index``
        argument if there is more than one.
    unused_at_index : index -> parameters that index leaves out (Baumgarte at
        index 3 has no ``mu``).
    requires_constraint : the rule corrects on the constraint's levels (defined only where a
        decomposition's conditions include the constraint: :attr:`decompositions`).
    label_parameters : parameters named in curve and scheme labels.
    """

    name: str
    label: str
    short_label: str
    build: Callable[..., CouplingMethod]
    parameters: tuple[Parameter, ...] = ()
    indices: tuple[int, ...] = (1,)
    unused_at_index: Mapping[int, tuple[str, ...]] = field(default_factory=dict)
    requires_constraint: bool = False
    label_parameters: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        names = [p.name for p in self.parameters]
        if len(set(names)) != len(names) or "index" in names:
            raise ValueError(f"method {self.name}: parameter names must be distinct and not 'index', got {names}")
        if not self.indices or not set(self.indices) <= {1, 2, 3}:
            raise ValueError(f"method {self.name}: indices must be among 1, 2, 3, got {self.indices}")
        for index, unused in self.unused_at_index.items():
            if index not in self.indices or not set(unused) <= set(names):
                raise ValueError(f"method {self.name}: unused_at_index[{index}] = {unused} is not a subset of {names}")
        if not set(self.label_parameters) <= set(names):
            raise ValueError(f"method {self.name}: label_parameters {self.label_parameters} not among {names}")

    @property
    def decompositions(self) -> tuple[str, ...]:
        """The registered decompositions the method is defined for."""
        return supported_decompositions(self.requires_constraint)

    @property
    def takes_index(self) -> bool:
        return len(self.indices) > 1

    @property
    def arguments(self) -> tuple[str, ...]:
        """Keyword arguments of :meth:`make`: ``index`` (if taken) and the parameters."""
        return (("index",) if self.takes_index else ()) + tuple(p.name for p in self.parameters)

    @property
    def coordinates(self) -> tuple[str, ...]:
        """The rule's own parameters (no shorthand), as resolved for every curve."""
        return tuple(p.name for p in self.parameters if not p.shorthand)

    def parameter(self, name: str) -> Parameter:
        return next(p for p in self.parameters if p.name == name)

    def unused(self, index: int) -> tuple[str, ...]:
        return tuple(self.unused_at_index.get(index, ()))

    def make(self, **params: Any) -> CouplingMethod:
        """The method with these parameters (``None`` = not given); unknown ones are refused."""
        params = {k: v for k, v in params.items() if v is not None}
        allowed = set(self.arguments)
        extra = sorted(set(params) - allowed)
        if extra:
            raise ParameterError(
                f"parameter(s) {', '.join(extra)} not used by method {self.name!r}"
                + (f" (it takes {', '.join(sorted(allowed))})" if allowed else " (it takes none)")
            )
        return self.build(**params)

    def engine_params(self, params: dict, H: float) -> dict:
        """Dimensional parameters (``mu``, ``beta`` in s, ``gamma`` in s^2, ...) -> the engine's at step ``H``."""
        scale = {p.name: p for p in self.parameters}
        return {k: (scale[k].engine_value(v, H) if k in scale else v) for k, v in params.items() if v is not None}


def supported_decompositions(requires_constraint: bool) -> tuple[str, ...]:
    """Every registered decomposition, or those whose conditions include the constraint."""
    return tuple(name for name, d in DECOMPOSITIONS.items() if d.has_constraint_condition or not requires_constraint)


def finite(name: str, value: Any) -> float:
    """``value`` as a finite float; the error names the parameter."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(v):
        raise ParameterError(f"{name} must be a finite number, got {value!r}")
    return v


def exact(name: str, value: Any) -> Fraction:
    """``value`` as an exact rational: a float as the binary number it is, a decimal string or
    :class:`~fractions.Fraction` as the decimal number typed (so ``"0.1"`` is 1/10, not the double
    nearest to it).  The error names the parameter."""
    finite(name, value)  # checks it is a finite number
    try:
        return Fraction(value)
    except (TypeError, ValueError):
        return Fraction(float(value))


def _conditions(
    levels: Sequence[int | Fraction],
    parts: Mapping[str, np.ndarray],
    axis: int,
    const: Callable[[Any], Any] = float,
) -> np.ndarray:
    """Stack the constraint-level combination and the force-balance rows.

    ``parts`` maps ``pos``/``vel``/``acc``/``force`` to residuals (rows on the
    last axis) or Jacobians (rows on axis -2); ``levels`` are the weights of
    the three constraint levels, exact numbers turned into the parts'
    arithmetic by ``const`` (a backend's; a Fraction times a float array
    would make an object array).
    """
    rows = []
    if parts["pos"].shape[axis]:
        combined = None
        for w, key in zip(levels, ("pos", "vel", "acc")):
            if w == 0:
                continue
            term = parts[key] if w == 1 else const(w) * parts[key]
            combined = term if combined is None else combined + term
        rows.append(combined)
    if parts["force"].shape[axis]:
        rows.append(parts["force"])
    # levels all 0 would leave combined None (no registered method has them): mypy sees it, nothing checks it
    return rows[0] if len(rows) == 1 else layout.concatenate(rows, axis=axis)  # type: ignore[return-value]


def _same(value: Any) -> Any:
    return value
