"""A scheme's stages on a coupling graph: what each stage of a macro step integrates, closes and solves.

A scheme (:mod:`icosim.engine.schemes`) says which subsystems advance together, stage after stage.  On a
graph (:mod:`icosim.engine.graph`) that makes, per stage:

* ``units``: the subsystems that advance (each is predicted with the extrapolation polynomials);
* ``joints``: the joints it closes -- those whose later subsystem advances here; their coupling variables
  are corrected at this stage, and only at this one;
* ``corrected``: the subsystems of this stage in a closed joint -- they respond to the corrected variables
  through their corrector integration (full gradients) and are corrected; a subsystem of this stage in no
  closed joint advances once and is final;
* ``finished``: the subsystems of earlier stages in a closed joint -- their end states are final; they
  respond algebraically (re-evaluated outputs) or, with ``leading_outputs="as-integrated"``, not at all.

Jacobi is one stage: every subsystem, every joint.  The plan also refuses what cannot be served, before any
work (:func:`plan`):

* a coupling variable that drives only finished subsystems which do not respond (``as-integrated``): no
  condition depends on it;
* a stage subsystem that two or more closed joints reach through one force input from finished subsystems
  (a chain's middle unit advancing after both its neighbours), with a method solve that has no
  acceleration-level condition (Baumgarte at index 2 or 3, the weighted multiplier): the finished neighbours
  do not respond on the position and velocity levels, so those conditions depend on one input -- two
  conditions, one unknown.  Neighbours corrected at the same stage (Jacobi) respond through their own inputs.

Signal connections are coupled explicitly (a connection's new sample is its source's output), or, with
``implicit``, closed by their conditions at ``T_N+1`` (:mod:`icosim.engine.connection_conditions`; ``connections``
the ones closed): all of them at the last stage, every unit a connection feeds in ``corrected`` (those of earlier
stages too: they are stepped again from ``T_N``).  Joints beside implicit connections are closed with them, at the
last stage, every joint unit corrected: one corrector of both kinds of condition
(:mod:`icosim.engine.joint_signal_conditions`).  The conditions hold at ``T_N+1`` with every unit's inputs the
interpolation polynomial through the new values, a system in the new values alone: its solution is the same in
any order of the units, which Gauss-Seidel's earlier stages change only in the predictor, Newton's start (a later
unit fed by an earlier one's new output, docs/signals.md).

>>> from icosim.engine.graph import CouplingGraph
>>> from icosim.engine.schemes import get_scheme
>>> p = plan(get_scheme("gauss-seidel-132"), CouplingGraph.chain(["ff", "ff"], ports="one"))
>>> [(s.units, s.joints, s.corrected, s.finished) for s in p.stages]
[((0,), (), (), ()), ((2,), (), (), ()), ((1,), (0, 1), (1,), (0, 2))]
>>> p.integrations
4
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError
from .connection_conditions import SignalConditions
from .decompositions import DECOMPOSITIONS
from .graph import CouplingGraph
from .joint_signal_conditions import JointSignalConditions
from .residuals import Conditions

if TYPE_CHECKING:
    from .decompositions import Decomposition
    from .methods.base import CouplingMethod
    from .schemes import Scheme

__all__ = ["Stage", "Plan", "plan", "check", "couples"]


@dataclass(frozen=True, eq=False)
class Stage:
    """One stage of a macro step (module docstring); ``conditions`` forms the closed joints' conditions from
    the outputs of :attr:`responders` (stacked in that order)."""

    index: int
    units: tuple[int, ...]
    joints: tuple[int, ...]
    corrected: tuple[int, ...]
    finished: tuple[int, ...]
    conditions: Conditions | SignalConditions | JointSignalConditions | None
    connections: tuple[int, ...] = ()  # the signal connections closed implicitly here

    @cached_property
    def responders(self) -> tuple[int, ...]:
        """The subsystems in a closed joint, in their order (whose outputs :attr:`conditions` reads)."""
        return tuple(sorted(self.corrected + self.finished))

    @property
    def columns(self) -> tuple[int, ...]:
        """The entries of ``e`` corrected at this stage."""
        return self.conditions.columns if self.conditions is not None else ()

    @cached_property
    def column_index(self) -> slice | np.ndarray:
        """:attr:`columns` as an index of ``e``'s last axis: a slice where they are consecutive (a view, no
        copy; a chain's stage closes neighbouring joints), else an integer array."""
        cols = self.columns
        if cols and list(cols) == list(range(cols[0], cols[-1] + 1)):
            return slice(cols[0], cols[-1] + 1)
        return np.array(cols, dtype=np.intp)


@dataclass(frozen=True, eq=False)
class Plan:
    """The stages of a scheme on a graph."""

    scheme: Scheme
    graph: CouplingGraph
    stages: tuple[Stage, ...]

    @property
    def integrations(self) -> int:
        """Subsystem integrations per macro step with one corrector pass."""
        return sum(len(s.units) + len(s.corrected) for s in self.stages)

    @property
    def reevaluated(self) -> tuple[int, ...]:
        """The subsystems whose outputs are re-evaluated at their end states without a step (finished ones that
        respond algebraically), in the order they first are."""
        if not self.scheme.reevaluates_leading:
            return ()
        return tuple(dict.fromkeys(i for s in self.stages for i in s.finished))

    @property
    def closes_all_at_once(self) -> bool:
        """One stage closes every joint from every subsystem's outputs (Jacobi)."""
        return len(self.stages) == 1

    def check_method(self, method: CouplingMethod) -> None:
        """Refuse (:class:`~icosim.errors.ParameterError`) a method the joints' decompositions or the stages
        cannot serve, naming why and what would."""
        for joint in self.graph.joints:
            method.check_decomposition(joint.decomposition)
        _check_method(self, method)


def plan(scheme: Scheme, graph: CouplingGraph, method: CouplingMethod | None = None, *, implicit: bool = False) -> Plan:
    """The stages of ``scheme`` on ``graph``; refuses (:class:`~icosim.errors.ParameterError`) what they cannot
    serve -- with ``method``, also a method whose solves they cannot serve -- naming why and what would.  Made
    anew on each call: a problem holds the plans it steps with
    (:meth:`~icosim.engine.problem.CosimulationProblem.plan`).  ``implicit``: the signal connections are closed
    by their conditions (module docstring)."""
    p = _plan(scheme, graph, implicit)
    if not scheme.reevaluates_leading:
        _check_lone_variables(p)
    if method is not None:
        p.check_method(method)
    return p


def check(scheme: Scheme, graph: CouplingGraph | str | Decomposition, method: CouplingMethod | None = None) -> Plan:
    """:func:`plan` on ``graph``, or on the paper's two subsystems joined by a decomposition."""
    if not isinstance(graph, CouplingGraph):
        graph = CouplingGraph.pair(graph)
    return plan(scheme, graph, method)


def couples(scheme: Scheme, graph: CouplingGraph | str | Decomposition, method: CouplingMethod | None = None) -> bool:
    """Can ``scheme`` couple ``graph`` (or the pair joined by a decomposition), with ``method``?"""
    try:
        check(scheme, graph, method)
    except ParameterError:
        return False
    return True


def _plan(scheme: Scheme, graph: CouplingGraph, implicit: bool = False) -> Plan:
    if implicit and graph.connections:
        return _implicit_plan(scheme, graph)
    done: list[int] = []
    closed: set[int] = set()
    stages = []
    for index, units in enumerate(scheme.stages(graph.n_subsystems)):
        advanced = set(done) | set(units)
        joints = tuple(
            j for j, jt in enumerate(graph.joints) if j not in closed and jt.first in advanced and jt.second in advanced
        )
        in_joints = {i for j in joints for i in (graph.joints[j].first, graph.joints[j].second)}
        corrected = tuple(i for i in units if i in in_joints)
        finished = tuple(i for i in done if i in in_joints)
        held = () if scheme.reevaluates_leading else finished  # they saw the multipliers as they integrated
        conditions = Conditions(graph, joints, sorted(corrected + finished), held) if joints else None
        stages.append(Stage(index, tuple(units), joints, corrected, finished, conditions))
        closed |= set(joints)
        done += list(units)
    return Plan(scheme, graph, tuple(stages))


def _implicit_plan(scheme: Scheme, graph: CouplingGraph) -> Plan:
    """Every connection (and every joint beside them) closed at the last stage, every unit a connection feeds (and
    every joint unit) stepped again with it (the order of the stages makes the predictor only: module docstring)."""
    units = scheme.stages(graph.n_subsystems)
    cons = tuple(range(len(graph.connections)))
    conditions: SignalConditions | JointSignalConditions = SignalConditions(graph, cons)
    if graph.joints:  # one corrector of both kinds of condition
        conditions = JointSignalConditions(
            graph, tuple(sorted({i for jt in graph.joints for i in (jt.first, jt.second)}))
        )
    joints = tuple(range(graph.n_joints))
    stages = [Stage(index, tuple(u), (), (), (), None) for index, u in enumerate(units[:-1])]
    stages.append(Stage(len(units) - 1, tuple(units[-1]), joints, conditions.targets, (), conditions, cons))
    return Plan(scheme, graph, tuple(stages))


def _lone_variable(p: Plan) -> tuple[int, int, list[int]] | None:
    """``(joint, column, subsystems it drives)``: a coupling variable that drives only finished subsystems."""
    graph = p.graph
    for stage in p.stages:
        for j in stage.joints:
            for col in graph.columns(j):
                driven = [i for i in range(graph.n_subsystems) if any(
                    c == col for terms in graph.input_terms(i) for c, _ in terms)]  # fmt: skip
                if not any(i in stage.corrected for i in driven):
                    return j, col, driven
    return None


def _check_lone_variables(p: Plan) -> None:
    """A finished subsystem whose outputs stay as integrated does not respond; a coupling variable that drives
    only such subsystems enters no condition (fd and df of two subsystems: ``lambda_c`` drives only the
    force-driven subsystem, ``a_tilde`` only the kinematic one)."""
    lone = _lone_variable(p)
    if lone is None:
        return
    graph = p.graph
    j, col, driven = lone
    variable = graph.variable_names()[col]
    who = ", ".join(graph.names[i] for i in driven)
    if graph.is_pair():
        allowed = [name for name in DECOMPOSITIONS if _lone_variable(_plan(p.scheme, CouplingGraph.pair(name))) is None]
        raise ParameterError(
            f"scheme {p.scheme.name} cannot couple decomposition {graph.joints[j].decomposition.name}: subsystem "
            f"{who} advances first and is the only one driven by {variable}, so with its outputs left as "
            f"integrated no coupling condition depends on {variable} (the corrector's linear system is singular). "
            f"Allowed decompositions: {', '.join(allowed)}"
        )
    raise ParameterError(
        f"scheme {p.scheme.name} cannot couple {graph.describe_joint(j)}: only subsystem(s) {who}, finished "
        f"before the joint closes, are driven by {variable}, so with their outputs left as integrated no coupling "
        "condition depends on it (the corrector's linear system is singular). Use the re-evaluated outputs (the "
        "scheme without -as-integrated) or Jacobi"
    )


def _check_method(p: Plan, method: CouplingMethod) -> None:
    """Two closed joints reaching a stage subsystem through one force input from finished subsystems, with a
    solve that has no acceleration-level condition: the position and velocity conditions depend on that one
    input only.  (A neighbour corrected at the same stage, as in Jacobi, responds through its own input.)"""
    levels = [lv for weight, lv in method.solves if weight != 0 and lv[2] == 0]
    if not levels:
        return
    graph = p.graph
    for stage in p.stages:
        for i in stage.corrected:
            for port in range(graph.ports[i]):
                other = {j: graph.joints[j].second if graph.joints[j].first == i else graph.joints[j].first
                         for j in stage.joints if (i, port) in graph.joints[j].sides}  # fmt: skip
                through = [j for j, o in other.items() if o in stage.finished]
                if len(through) < 2:
                    continue
                others = sorted({other[j] for j in through})
                joints = " and ".join(graph.describe_joint(j) for j in through)
                index = method.params.get("index")
                what = f"method {method.name}" + (f" (index {index})" if index is not None else "")
                raise ParameterError(
                    f"scheme {p.scheme.name} cannot serve {what}: subsystem {graph.names[i]} advances after "
                    f"{', '.join(graph.names[o] for o in others)}, and {joints} reach it through one force "
                    f"input (its port {port + 1}); a solve of the method has no acceleration-level condition, on "
                    "which alone the finished subsystems respond, so two conditions depend on one input (the "
                    f"corrector's linear system is singular). Use an order in which {graph.names[i]} does not "
                    f"come after all of them (e.g. {_tree_order(graph)}), Jacobi, or a method with an "
                    "acceleration-level condition (baumgarte at index 1, projection)"
                )


def _tree_order(graph: CouplingGraph) -> str:
    """A Gauss-Seidel order in which every subsystem after the first has one earlier neighbour, where the
    graph allows it (a tree, visited breadth first from subsystem 1)."""
    order, seen = [0], {0}
    for i in order:
        for other in graph.neighbours(i):
            if other not in seen:
                seen.add(other)
                order.append(other)
    sep = "" if graph.n_subsystems < 10 else "."
    return "gauss-seidel-" + sep.join(str(i + 1) for i in order)
