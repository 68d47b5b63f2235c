"""Coupling schemes: the order in which the two subsystems advance within a macro step.

The paper analyses the **Jacobi** (parallel) scheme: both subsystems integrate
with the extrapolated coupling variables (predictor), the corrected coupling
variables are formed from both subsystems' outputs and gradients, and both
integrate again with the interpolation polynomials (corrector).  In the
**Gauss-Seidel** (sequential) scheme the *first* subsystem advances once, with
the extrapolation polynomials, and its state at ``T_N+1`` is final; the
corrected coupling variables are formed from its finished outputs (it
contributes only its *algebraic* gradients: its end state is fixed, only the
outputs that depend on the coupling variables at ``T_N+1`` through its
equations of motion follow them), and only the *second* subsystem is corrected,
with the interpolation polynomials through the corrected values.  Derivation,
equation by equation: ``docs/gauss_seidel.md``.

A scheme is data: which subsystems lead (advance once, algebraic gradients
only) and which are corrected.  :func:`icosim.engine.macrostep.macro_step` reads it;
the coupling methods never see it.

A scheme is a registry entry (:data:`SCHEMES`, :func:`register`), spelled
by its name everywhere: in the library, the configuration, on the command
line, in dataset attributes and in file names.

>>> get_scheme("gauss-seidel-21").label
'Gauss–Seidel 2→1'
>>> GaussSeidel(first=1).leading, GaussSeidel(first=1).corrected
((0,), (1,))
>>> JACOBI.leading, JACOBI.integrations_per_step
((), 4)

The leading subsystem's outputs at ``T_N+1`` (acceleration, coupling force or
multiplier) are re-evaluated with the corrected coupling variables by default;
``leading_outputs="as-integrated"`` leaves them as the subsystem integrated them
with the extrapolated ones, the other reading of "sequential" (the choice and
what it changes: ``docs/gauss_seidel.md``):

>>> get_scheme("gauss-seidel-12-as-integrated").reevaluates_leading
False
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ..errors import ParameterError
from .decompositions import DECOMPOSITIONS, Decomposition, get_decomposition

__all__ = [
    "Scheme",
    "Jacobi",
    "GaussSeidel",
    "JACOBI",
    "GS12",
    "GS21",
    "SCHEMES",
    "LEADING_OUTPUTS",
    "get_scheme",
    "register",
    "standard_schemes",
]

#: Number of subsystems of every problem in this package.
N_SUBSYSTEMS = 2


@dataclass(frozen=True)
class Scheme:
    """Which subsystems lead (advance once, with extrapolation) and which are corrected.

    Subsystem indices are 0-based (subsystem 1 of the paper is 0).  A leading
    subsystem's state at ``T_N+1`` is final after its one integration; in the
    corrected coupling variables it contributes its algebraic gradients only.
    A corrected subsystem is predicted (extrapolation, Eq. 9/35/59) and
    corrected (interpolation through the corrected values, Eq. 11) and
    contributes its full gradients (Eq. 13/39/63).
    """

    leading: tuple = ()

    @property
    def name(self) -> str:  # pragma: no cover - defined by the subclasses
        raise NotImplementedError

    @property
    def variant(self) -> bool:
        """A variant kept for comparison (docs/gauss_seidel.md), not one of the schemes run by default."""
        return False

    @property
    def reevaluates_leading(self) -> bool:
        """Are the leading subsystems' outputs at ``T_N+1`` re-evaluated with the corrected coupling
        variables (and do they respond to them algebraically), or left as integrated?"""
        return True

    @property
    def corrected(self) -> tuple:
        return tuple(i for i in range(N_SUBSYSTEMS) if i not in self.leading)

    def fixed(self, ends: Sequence[Any]) -> tuple:
        """Per subsystem: its final end state if it leads, else ``None`` (what the problems' Jacobians take)."""
        return tuple(ends[i] if i in self.leading else None for i in range(N_SUBSYSTEMS))

    @property
    def integrations_per_step(self) -> int:
        """Subsystem integrations per macro step with one corrector pass."""
        return len(self.leading) + 2 * len(self.corrected)

    @property
    def label(self) -> str:  # pragma: no cover - defined by the subclasses
        raise NotImplementedError

    def check_decomposition(self, decomposition: str | Decomposition) -> None:
        """Refuse (:class:`~icosim.errors.ParameterError`) a decomposition the scheme cannot couple.

        A leading subsystem whose outputs stay as integrated does not respond to
        the corrected coupling variables; a coupling variable that drives only
        that subsystem then enters no coupling condition, and the corrector's
        linear system is singular at every point (fd and df: ``lambda_c`` drives
        only the force-driven subsystem, ``a_tilde`` only the kinematic one).
        """
        decomposition = get_decomposition(decomposition)
        lone = self._lone_input(decomposition)
        if lone is None:
            return
        i, j = lone
        allowed = [name for name in DECOMPOSITIONS if self.couples(name)]
        variable = decomposition.variables[j]
        raise ParameterError(
            f"scheme {self.name} cannot couple decomposition {decomposition.name}: subsystem {i + 1} leads and is "
            f"the only one driven by {variable}, so with its outputs left as integrated no coupling condition "
            f"depends on {variable} (the corrector's linear system is singular). "
            f"Allowed decompositions: {', '.join(allowed)}"
        )

    def couples(self, decomposition: str | Decomposition) -> bool:
        """Can the scheme couple ``decomposition`` (see :meth:`check_decomposition`)?"""
        return self._lone_input(get_decomposition(decomposition)) is None

    def _lone_input(self, decomposition: Decomposition) -> tuple[int, int] | None:
        """``(i, j)``: a leading subsystem ``i`` that does not respond and is the only one driven by ``e_j``."""
        if self.reevaluates_leading:
            return None
        for i in self.leading:
            j = decomposition.inputs[i]
            if not any(decomposition.inputs[c] == j for c in self.corrected):
                return i, j
        return None

    def __str__(self) -> str:
        return self.name


@dataclass(frozen=True, repr=False)
class Jacobi(Scheme):
    """Both subsystems predicted and corrected in parallel (the paper's scheme)."""

    leading: tuple = ()

    @property
    def name(self) -> str:
        return "jacobi"

    @property
    def label(self) -> str:
        return "Jacobi"

    def __repr__(self) -> str:
        return "Jacobi()"


#: What the leading subsystem's outputs at ``T_N+1`` are in a Gauss-Seidel scheme.
LEADING_OUTPUTS = ("reevaluated", "as-integrated")


@dataclass(frozen=True, init=False, repr=False)
class GaussSeidel(Scheme):
    """Subsystem ``first`` (1 or 2) advances once with extrapolation; the other is corrected.

    ``leading_outputs``: ``"reevaluated"`` (default) -- the first subsystem's
    outputs at ``T_N+1`` follow the corrected coupling variables through its
    equation of motion, and it enters their solve with its algebraic gradients;
    ``"as-integrated"`` -- they stay as it integrated them, and it does not
    respond at all.
    """

    first: int = 1
    leading_outputs: str = "reevaluated"

    def __init__(self, first: int = 1, leading_outputs: str = "reevaluated") -> None:
        if isinstance(first, bool) or first not in (1, 2):
            raise ParameterError(f"first must be 1 or 2 (the subsystem that advances first), got {first!r}")
        if leading_outputs not in LEADING_OUTPUTS:
            raise ParameterError(
                f"leading_outputs must be one of {', '.join(LEADING_OUTPUTS)}, got {leading_outputs!r}"
            )
        object.__setattr__(self, "first", int(first))
        object.__setattr__(self, "leading", (int(first) - 1,))
        object.__setattr__(self, "leading_outputs", leading_outputs)

    @property
    def reevaluates_leading(self) -> bool:
        return self.leading_outputs == "reevaluated"

    @property
    def variant(self) -> bool:
        return not self.reevaluates_leading

    @property
    def second(self) -> int:
        return 3 - self.first

    @property
    def name(self) -> str:
        return f"gauss-seidel-{self.first}{self.second}" + ("" if self.reevaluates_leading else "-as-integrated")

    @property
    def label(self) -> str:
        return f"Gauss–Seidel {self.first}→{self.second}" + (
            "" if self.reevaluates_leading else " (outputs as integrated)"
        )

    def __repr__(self) -> str:
        extra = "" if self.reevaluates_leading else f", leading_outputs={self.leading_outputs!r}"
        return f"GaussSeidel(first={self.first}{extra})"


JACOBI = Jacobi()
GS12 = GaussSeidel(first=1)
GS21 = GaussSeidel(first=2)

#: Every registered scheme by its name (the dataset attribute ``scheme``), in the order listed everywhere.
SCHEMES: dict[str, Scheme] = {}


def register(scheme: Scheme) -> Scheme:
    """Add a scheme to :data:`SCHEMES` (configuration schemas, command line and studies read it)."""
    if scheme.name in SCHEMES:
        raise ValueError(f"scheme {scheme.name!r} is already registered")
    SCHEMES[scheme.name] = scheme
    return scheme


for _s in (JACOBI, GS12, GS21, GaussSeidel(1, "as-integrated"), GaussSeidel(2, "as-integrated")):
    register(_s)


def standard_schemes() -> tuple[str, ...]:
    """The registered schemes that are not variants (what ``icosim advise`` ranks by default)."""
    return tuple(name for name, s in SCHEMES.items() if not s.variant)


def get_scheme(scheme: str | Scheme | None = None) -> Scheme:
    """The registered scheme named ``scheme`` (``None``: Jacobi; a :class:`Scheme` is returned as it is)."""
    if isinstance(scheme, Scheme):
        return scheme
    name = "jacobi" if scheme is None else scheme
    try:
        return SCHEMES[name]
    except (KeyError, TypeError):
        raise ParameterError(f"scheme must be one of {', '.join(SCHEMES)}, got {scheme!r}") from None
