"""Decompositions (Sect. 2): which subsystem is force- or kinematically driven.

A **decomposition** says which coupling variables exist and which coupling
conditions close the system:

========  ==========================  =====================================
name      coupling variables ``e``    conditions solved in step 2
========  ==========================  =====================================
``ff``    ``lambda``                  constraint (position/velocity/acc.)
``fd``    ``lambda``, ``a_tilde_1``   constraint and ``mu_2 - lambda = 0``
``dd``    ``a_tilde``                 ``mu_2 - mu_1 = 0``
========  ==========================  =====================================

>>> get_decomposition("fd").variables
('lambda_c', 'a_tilde_1')
>>> get_decomposition("dd").has_constraint_condition
False
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import ParameterError

__all__ = ["DECOMPOSITIONS", "Decomposition", "get_decomposition", "DD_NEEDS_POSITION_LEVEL"]


@dataclass(frozen=True)
class Decomposition:
    """Which subsystem is force- or kinematically driven, and by which variable."""

    name: str
    kinds: tuple[str, str]  # subsystem 1, subsystem 2
    inputs: tuple[int, int]  # index into e driving each subsystem
    variables: tuple[str, ...]  # names of the coupling variables e
    long_name: str

    @property
    def n_coupling(self) -> int:
        return len(self.variables)

    @property
    def has_constraint_condition(self) -> bool:
        """Is the joint constraint itself one of the conditions (ff, fd)?"""
        return "force" in self.kinds

    @property
    def has_force_balance(self) -> bool:
        """Must multipliers of a kinematic subsystem balance (fd, dd)?"""
        return "kinematic" in self.kinds


DECOMPOSITIONS = {
    "ff": Decomposition("ff", ("force", "force"), (0, 0), ("lambda_c",), "force/force"),
    "fd": Decomposition("fd", ("force", "kinematic"), (0, 1), ("lambda_c", "a_tilde_1"), "force/displacement"),
    "dd": Decomposition("dd", ("kinematic", "kinematic"), (0, 0), ("a_tilde",), "displacement/displacement"),
}

#: Why a method that corrects on the constraint's levels is refused with ``dd``
#: (decision: the paper leaves it out, Sect. 2.3).
DD_NEEDS_POSITION_LEVEL = (
    "with displacement/displacement coupling the kinematics "
    "would have to be prescribed on position level, which needs at least quadratic "
    "approximation polynomials; the paper treats only projection there (Sect. 2.3). "
    "Use the method projection or the decomposition ff or fd."
)


def get_decomposition(name) -> Decomposition:
    """The :class:`Decomposition` called ``name`` (a Decomposition is returned as it is)."""
    if isinstance(name, Decomposition):
        return name
    try:
        return DECOMPOSITIONS[name]
    except KeyError:
        raise ParameterError(f"decomposition must be one of {', '.join(DECOMPOSITIONS)}, got {name!r}") from None
