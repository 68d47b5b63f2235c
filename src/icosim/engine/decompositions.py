"""Decompositions (Sect. 2): which subsystem is force- or kinematically driven, and the registry of them.

A **decomposition** says which coupling variables exist and which coupling
conditions close the system:

========  ============================  ===========================================
name      coupling variables ``e``      conditions solved in step 2
========  ============================  ===========================================
``ff``    ``lambda``                    constraint (position/velocity/acc.)
``fd``    ``lambda``, ``a_tilde_1``     constraint and ``mu_2 - lambda = 0``
``df``    ``lambda``, ``a_tilde_2``     constraint and ``mu_1 - lambda = 0``
``dd``    ``a_tilde``                   ``mu_2 - mu_1 = 0``
========  ============================  ===========================================

``df`` is the mirror of ``fd``: subsystem 1 is kinematically driven by the
acceleration of subsystem 2, which is force driven.  The paper names it
(Sect. 3.2: force/displacement "may show a different stability behavior as a
displacement/force-decomposition approach due to the asymmetry") without
analysing it.  Everything the engine and the studies need of a decomposition
is here: which kind of input drives each subsystem and through which coupling
variable.  A new decomposition is a :class:`Decomposition` passed to
:func:`register`; a problem that cannot form its coupling conditions says so
(:meth:`icosim.engine.problem.CosimulationProblem.check_decomposition`).

>>> get_decomposition("fd").variables
('lambda_c', 'a_tilde_1')
>>> get_decomposition("df").kinds, get_decomposition("df").inputs
(('kinematic', 'force'), (1, 0))
>>> get_decomposition("dd").has_constraint_condition
False
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import ParameterError

__all__ = [
    "DECOMPOSITIONS",
    "Decomposition",
    "get_decomposition",
    "register",
    "with_constraint",
    "NEEDS_CONSTRAINT_CONDITION",
    "KINDS",
]

#: What drives a subsystem: a coupling force, or a prescribed acceleration.
KINDS = ("force", "kinematic")


@dataclass(frozen=True)
class Decomposition:
    """Which subsystem is force- or kinematically driven, and by which coupling variable.

    ``kinds[i]`` is ``"force"`` or ``"kinematic"`` for subsystem ``i``;
    ``inputs[i]`` the index into ``variables`` of the coupling variable
    driving it.  A force-driven subsystem is driven by a force (``lambda_c``),
    a kinematically driven one by an acceleration (``a_tilde...``).
    """

    name: str
    kinds: tuple[str, str]  # subsystem 1, subsystem 2
    inputs: tuple[int, int]  # index into e driving each subsystem
    variables: tuple[str, ...]  # names of the coupling variables e
    long_name: str

    def __post_init__(self) -> None:
        if len(self.kinds) != 2 or not set(self.kinds) <= set(KINDS):
            raise ValueError(f"decomposition {self.name}: kinds must be two of {KINDS}, got {self.kinds}")
        if len(self.inputs) != 2 or not all(0 <= j < len(self.variables) for j in self.inputs):
            raise ValueError(f"decomposition {self.name}: inputs must index the variables {self.variables}")
        if set(self.inputs) != set(range(len(self.variables))):
            raise ValueError(f"decomposition {self.name}: every coupling variable must drive a subsystem")
        for kind, j in zip(self.kinds, self.inputs):
            if self.variable_kind(j) != ("force" if kind == "force" else "acceleration"):
                raise ValueError(
                    f"decomposition {self.name}: a {kind}-driven subsystem cannot take {self.variables[j]}"
                )

    @property
    def n_coupling(self) -> int:
        return len(self.variables)

    @property
    def has_constraint_condition(self) -> bool:
        """Is the joint constraint itself one of the conditions (a force-driven subsystem: ff, fd, df)?"""
        return "force" in self.kinds

    @property
    def has_force_balance(self) -> bool:
        """Must multipliers of a kinematic subsystem balance (fd, df, dd)?"""
        return "kinematic" in self.kinds

    def variable_kind(self, j: int) -> str:
        """``"force"`` for ``lambda...``, ``"acceleration"`` for ``a_tilde...``."""
        return "force" if self.variables[j].startswith("lambda") else "acceleration"

    def mirrored(self) -> tuple[str, str]:
        """The kinds with the subsystems exchanged (``fd`` -> ``("kinematic", "force")``, the kinds of ``df``)."""
        return self.kinds[::-1]


#: name -> decomposition, in the order they are listed everywhere.
DECOMPOSITIONS: dict[str, Decomposition] = {}


def register(decomposition: Decomposition) -> Decomposition:
    """Add a decomposition to :data:`DECOMPOSITIONS` (configuration schemas, command line and studies read it)."""
    if decomposition.name in DECOMPOSITIONS:
        raise ValueError(f"decomposition {decomposition.name!r} is already registered")
    DECOMPOSITIONS[decomposition.name] = decomposition
    return decomposition


for _d in (
    Decomposition("ff", ("force", "force"), (0, 0), ("lambda_c",), "force/force"),
    Decomposition("fd", ("force", "kinematic"), (0, 1), ("lambda_c", "a_tilde_1"), "force/displacement"),
    Decomposition("df", ("kinematic", "force"), (1, 0), ("lambda_c", "a_tilde_2"), "displacement/force"),
    Decomposition("dd", ("kinematic", "kinematic"), (0, 0), ("a_tilde",), "displacement/displacement"),
):
    register(_d)


def with_constraint() -> tuple[str, ...]:
    """The decompositions whose conditions include the joint constraint (what Baumgarte and the
    weighted multiplier correct on)."""
    return tuple(name for name, d in DECOMPOSITIONS.items() if d.has_constraint_condition)


#: Why a method that corrects on the constraint's levels is refused where no subsystem is force driven
#: (decision: the paper leaves it out, Sect. 2.3).
NEEDS_CONSTRAINT_CONDITION = (
    "with both subsystems kinematically driven (displacement/displacement) the kinematics would have to be "
    "prescribed on position level, which needs at least quadratic approximation polynomials; the paper treats "
    "only projection there (Sect. 2.3). Use the method projection or a decomposition with a force-driven subsystem"
)


def get_decomposition(name: str | Decomposition) -> Decomposition:
    """The :class:`Decomposition` called ``name`` (a Decomposition is returned as it is)."""
    if isinstance(name, Decomposition):
        return name
    try:
        return DECOMPOSITIONS[name]
    except (KeyError, TypeError):
        raise ParameterError(f"decomposition must be one of {', '.join(DECOMPOSITIONS)}, got {name!r}") from None
