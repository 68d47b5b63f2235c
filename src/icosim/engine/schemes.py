"""Coupling schemes: the order in which the subsystems advance within a macro step.

The paper analyses the **Jacobi** (parallel) scheme: every subsystem integrates with the extrapolated
coupling variables (predictor), the corrected coupling variables of every joint are formed from all
subsystems' outputs and gradients, and every subsystem integrates again with the interpolation polynomials
(corrector).  In a **Gauss-Seidel** (sequential) scheme the subsystems advance one after another in a
given order; each joint is closed when the later of its two subsystems advances: that subsystem is
predicted, the joint's coupling variables are corrected from its full gradients and from the finished
outputs of the earlier one (which responds only *algebraically*: its end state is final, only the outputs
its equations of motion tie to the input at ``T_N+1`` follow), and it is corrected with the interpolation
polynomials through them.  A subsystem that closes no joint (the first of the order, or one whose
neighbours all come later) advances once, with extrapolation, and is final.  For two subsystems the orders
1→2 and 2→1 are the schemes ``gauss-seidel-12`` and ``gauss-seidel-21``.  Derivation, equation by
equation: ``docs/gauss_seidel.md`` (two subsystems) and ``docs/chains.md`` (N subsystems).

A scheme is data: the *stages* of a macro step, the subsystems that advance together at each
(:meth:`Scheme.stages`); :mod:`icosim.engine.stages` turns them into what each stage integrates, closes
and solves on a coupling graph, and refuses what cannot be served (:func:`icosim.engine.stages.check`).
The coupling methods never see it.

A scheme is a registry entry (:data:`SCHEMES`, :func:`register`), spelled by its name everywhere: in the
library, the configuration, on the command line, in dataset attributes and in file names.  Any order of
any number of subsystems is spelled ``gauss-seidel-`` and the subsystems' numbers (``gauss-seidel-312``;
with ten or more subsystems separated by dots, ``gauss-seidel-10.9.8.7.6.5.4.3.2.1``).

>>> get_scheme("gauss-seidel-21").label
'Gauss–Seidel 2→1'
>>> get_scheme("gauss-seidel-312").order
(3, 1, 2)
>>> JACOBI.stages(3), GaussSeidel((2, 1, 3)).stages(3)
(((0, 1, 2),), ((1,), (0,), (2,)))

The earlier subsystems' outputs at ``T_N+1`` (acceleration, coupling force or multiplier) are
re-evaluated with the corrected coupling variables by default; ``leading_outputs="as-integrated"`` leaves
them as the subsystem integrated them with the extrapolated ones, the other reading of "sequential" (the
choice and what it changes: ``docs/gauss_seidel.md``):

>>> get_scheme("gauss-seidel-12-as-integrated").reevaluates_leading
False
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

from ..errors import ParameterError

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

#: What the earlier subsystems' outputs at ``T_N+1`` are in a Gauss-Seidel scheme.
LEADING_OUTPUTS = ("reevaluated", "as-integrated")


@dataclass(frozen=True)
class Scheme:
    """The stages of a macro step: the subsystems that advance together, one stage after another."""

    @property
    def name(self) -> str:  # pragma: no cover - defined by the subclasses
        raise NotImplementedError

    @property
    def label(self) -> str:  # pragma: no cover - defined by the subclasses
        raise NotImplementedError

    @property
    def variant(self) -> bool:
        """A variant kept for comparison (docs/gauss_seidel.md), not one of the schemes run by default."""
        return False

    @property
    def reevaluates_leading(self) -> bool:
        """Are the earlier subsystems' outputs at ``T_N+1`` re-evaluated with the corrected coupling
        variables (and do they respond to them algebraically), or left as integrated?"""
        return True

    def stages(self, n_subsystems: int) -> tuple[tuple[int, ...], ...]:  # pragma: no cover - subclasses
        """The subsystems (0-based) that advance at each stage, for ``n_subsystems`` subsystems."""
        raise NotImplementedError

    def __str__(self) -> str:
        return self.name


@dataclass(frozen=True, repr=False)
class Jacobi(Scheme):
    """Every subsystem predicted and corrected in parallel (the paper's scheme): one stage."""

    @property
    def name(self) -> str:
        return "jacobi"

    @property
    def label(self) -> str:
        return "Jacobi"

    def stages(self, n_subsystems: int) -> tuple[tuple[int, ...], ...]:
        return (tuple(range(n_subsystems)),)

    def __repr__(self) -> str:
        return "Jacobi()"


@dataclass(frozen=True, init=False, repr=False)
class GaussSeidel(Scheme):
    """The subsystems advance one after another in ``order`` (their 1-based numbers, each once).

    ``first=1`` or ``2`` is the order ``(1, 2)`` or ``(2, 1)`` of two subsystems.  ``leading_outputs``:
    ``"reevaluated"`` (default) -- an earlier subsystem's outputs at ``T_N+1`` follow the corrected
    coupling variables through its equation of motion, and it enters their solve with its algebraic
    gradients; ``"as-integrated"`` -- they stay as it integrated them, and it does not respond at all.
    """

    order: tuple[int, ...] = (1, 2)
    leading_outputs: str = "reevaluated"

    def __init__(
        self,
        order: Iterable[int | str] | None = None,
        leading_outputs: str = "reevaluated",
        *,
        first: int | None = None,
    ) -> None:
        if first is not None:
            if order is not None:
                raise ParameterError("give the order or the first subsystem, not both")
            if isinstance(first, bool) or first not in (1, 2):
                raise ParameterError(f"first must be 1 or 2 (the subsystem that advances first), got {first!r}")
            order = (first, 3 - first)
        given = (1, 2) if order is None else order
        try:
            numbers = tuple(int(i) for i in given)
        except (TypeError, ValueError):
            raise ParameterError(f"order must be the subsystems' numbers 1, 2, ..., got {given!r}") from None
        if sorted(numbers) != list(range(1, len(numbers) + 1)) or len(numbers) < 2:
            raise ParameterError(
                f"order must name each of the subsystems 1 ... N once (N >= 2), got {', '.join(map(str, numbers))}"
            )
        if leading_outputs not in LEADING_OUTPUTS:
            raise ParameterError(
                f"leading_outputs must be one of {', '.join(LEADING_OUTPUTS)}, got {leading_outputs!r}"
            )
        object.__setattr__(self, "order", numbers)
        object.__setattr__(self, "leading_outputs", leading_outputs)

    @property
    def reevaluates_leading(self) -> bool:
        return self.leading_outputs == "reevaluated"

    @property
    def variant(self) -> bool:
        return not self.reevaluates_leading

    @property
    def first(self) -> int:
        """The subsystem that advances first (1-based)."""
        return self.order[0]

    def stages(self, n_subsystems: int) -> tuple[tuple[int, ...], ...]:
        if len(self.order) != n_subsystems:
            raise ParameterError(
                f"scheme {self.name}: the order names {len(self.order)} subsystems, the problem has {n_subsystems}"
            )
        return tuple((i - 1,) for i in self.order)

    @property
    def name(self) -> str:
        sep = "" if len(self.order) < 10 else "."
        return "gauss-seidel-" + sep.join(map(str, self.order)) + ("" if self.reevaluates_leading else "-as-integrated")

    @property
    def label(self) -> str:
        return (
            "Gauss–Seidel "
            + "→".join(map(str, self.order))
            + ("" if self.reevaluates_leading else " (outputs as integrated)")
        )

    def __repr__(self) -> str:
        extra = "" if self.reevaluates_leading else f", leading_outputs={self.leading_outputs!r}"
        return f"GaussSeidel({self.order!r}{extra})"


JACOBI = Jacobi()
GS12 = GaussSeidel(first=1)
GS21 = GaussSeidel(first=2)

#: The registered schemes by their names (the dataset attribute ``scheme``), in the order listed everywhere:
#: Jacobi and the two orders of two subsystems (with their variants).  Any other order is spelled by its name.
SCHEMES: dict[str, Scheme] = {}


def register(scheme: Scheme) -> Scheme:
    """Add a scheme to :data:`SCHEMES` (configuration schemas, command line and studies read it)."""
    if scheme.name in SCHEMES:
        raise ValueError(f"scheme {scheme.name!r} is already registered")
    SCHEMES[scheme.name] = scheme
    return scheme


for _s in (JACOBI, GS12, GS21, GaussSeidel(first=1, leading_outputs="as-integrated"),
           GaussSeidel(first=2, leading_outputs="as-integrated")):  # fmt: skip
    register(_s)


def standard_schemes() -> tuple[str, ...]:
    """The registered schemes that are not variants (what ``icosim advise`` ranks by default)."""
    return tuple(name for name, s in SCHEMES.items() if not s.variant)


_ORDER = re.compile(r"gauss-seidel-(\d+(?:\.\d+)*)(-as-integrated)?")


def get_scheme(scheme: str | Scheme | None = None) -> Scheme:
    """The scheme named ``scheme`` (``None``: Jacobi; a :class:`Scheme` is returned as it is): a registered
    one, or a Gauss-Seidel order ``gauss-seidel-<numbers>``."""
    if isinstance(scheme, Scheme):
        return scheme
    name = "jacobi" if scheme is None else scheme
    if isinstance(name, str) and name in SCHEMES:
        return SCHEMES[name]
    match = _ORDER.fullmatch(name) if isinstance(name, str) else None
    if match:
        digits = match.group(1)
        order = digits.split(".") if "." in digits else list(digits)
        try:
            scheme_ = GaussSeidel(order, "as-integrated" if match.group(2) else "reevaluated")
        except ParameterError as exc:
            raise ParameterError(f"scheme {name!r}: {exc}") from None
        if scheme_.name == name:  # one spelling per order
            return scheme_
    raise ParameterError(
        f"scheme must be one of {', '.join(SCHEMES)} or gauss-seidel-<order> (e.g. gauss-seidel-312), got {scheme!r}"
    )
