"""Subsystems joined by rigid joints: the coupling graph every macro step works on.

``N`` subsystems, ``M`` joints.  A subsystem offers one or more **ports** (points where a joint can attach:
the joint point of a unit, the first or last mass of a chain segment).  A **joint** constrains a port of one
subsystem to a port of another -- positions equal, with ``n_c`` components (1 for points on a line, 2 for a
joint in the plane) -- and has its own decomposition (:mod:`icosim.engine.decompositions`), whose subsystem 1
and 2 are the joint's *first* and *second* side: ``ff``, ``fd``, ``df``, ``dd`` say which side is force driven
and which kinematically driven.  The paper's two subsystems joined by one joint are :meth:`CouplingGraph.pair`.

**Coupling variables.**  Each joint has its decomposition's variables, ``n_c`` components each; ``e`` is the
joints' variables one joint after another (:meth:`CouplingGraph.columns`).

**Inputs.**  A joint's multiplier acts with ``+lambda_j`` on its first side and ``-lambda_j`` on its second.
A force-driven port takes the sum over its joints (a chain's middle unit with one port takes
``-lambda_left + lambda_right``); a kinematically driven port takes its joint's ``a_tilde_j`` and takes part
in no other joint (its motion is that joint's alone).  A port in no joint takes no force.  Unit ``i``'s inputs
are its ports' inputs, port after port, ``n_c`` components each (:meth:`CouplingGraph.inputs`).

**Outputs.**  Every problem reports, per port, the position, velocity and acceleration of the port and the
force it sees (rows :data:`POSITION` ... :data:`FORCE`, ``n_c`` components): for a kinematically driven port
the force its drive exerts on it (the reaction), for a force-driven one its input.  The coupling conditions
(:mod:`icosim.engine.residuals`) are formed from them.

>>> g = CouplingGraph(3, [Joint(0, 1, "ff"), Joint(1, 2, "fd")])
>>> g.n_coupling, [g.columns(j) for j in range(2)]
(3, [(0,), (1, 2)])
>>> g.input_terms(1)  # subsystem 2, one port: -lambda of joint 1 plus lambda of joint 2
(((0, -1), (1, 1)),)
>>> g.input_terms(2)  # subsystem 3, kinematically driven: a_tilde of joint 2
(((2, 1),),)
>>> CouplingGraph(2, [Joint(0, 1, "ff", ports=(0, 1))]).ports  # unit 2 has a free port 0
(1, 2)

**Signal connections.**  A :class:`Connection` feeds output ``output`` of one subsystem, transformed
(``u = factor * y + offset``), into input ``input`` of another: the condition ``u_in = T(y_out)``.  Each is one
coupling variable after the joints' (the input's value, :meth:`CouplingGraph.connection_column`); the problem
says what its subsystems' signal outputs are (:meth:`~icosim.engine.problem.CosimulationProblem.signal_output`).
A graph may hold joints, connections or both; every subsystem takes part in one of them.

>>> s = CouplingGraph(2, (), connections=[Connection(1, 0, 0, 0), Connection(0, 0, 1, 0, factor=2.0)])
>>> s.n_coupling, s.connection_column(1), s.signal_inputs(1)
(2, 1, ((0, 1),))
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from ..errors import ParameterError
from .decompositions import Decomposition, get_decomposition

__all__ = ["Joint", "Connection", "CouplingGraph", "POSITION", "VELOCITY", "ACCELERATION", "FORCE", "OUTPUTS"]

#: The rows of a port's outputs.
POSITION, VELOCITY, ACCELERATION, FORCE = range(4)
OUTPUTS = ("position", "velocity", "acceleration", "force")


@dataclass(frozen=True)
class Joint:
    """A rigid joint between port ``ports[0]`` of subsystem ``first`` and port ``ports[1]`` of ``second``
    (0-based), with its decomposition (first side, second side)."""

    first: int
    second: int
    decomposition: Decomposition = field(default=None)  # type: ignore[assignment]
    ports: tuple[int, int] = (0, 0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "decomposition", get_decomposition(self.decomposition))
        object.__setattr__(self, "ports", tuple(int(p) for p in self.ports))
        for name, value in (("first", self.first), ("second", self.second)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
                raise ParameterError(f"joint {name} must be a subsystem index >= 0, got {value!r}")
        if self.first == self.second:
            raise ParameterError(f"a joint joins two different subsystems, got {self.first} twice")
        if len(self.ports) != 2 or min(self.ports) < 0:
            raise ParameterError(f"joint ports must be two port indices >= 0, got {self.ports!r}")

    @property
    def sides(self) -> tuple[tuple[int, int], tuple[int, int]]:
        """``((subsystem, port), (subsystem, port))`` of the first and the second side."""
        return (self.first, self.ports[0]), (self.second, self.ports[1])


@dataclass(frozen=True)
class Connection:
    """A signal connection: output ``output`` of subsystem ``source`` feeds input ``input`` of ``target``
    (0-based; the indices are the problem's, per subsystem), ``u = factor * y + offset``."""

    source: int
    output: int
    target: int
    input: int
    factor: float = 1.0
    offset: float = 0.0

    def __post_init__(self) -> None:
        for name in ("source", "output", "target", "input"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
                raise ParameterError(f"connection {name} must be an index >= 0, got {value!r}")
        if self.source == self.target:
            raise ParameterError(f"a connection joins two different subsystems, got {self.source} twice")
        for name in ("factor", "offset"):
            if not np.isfinite(getattr(self, name)):
                raise ParameterError(f"connection {name} must be finite, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class CouplingGraph:
    """``n_subsystems`` subsystems and their joints; ``n_components`` per joint (1: a line, 2: the plane).

    ``ports[i]``: the ports subsystem ``i`` has (default: as many as its joints name).  ``names``: the
    subsystems' names in messages (default ``1 ... N``).  The graph is checked when it is made: every
    joint names subsystems that exist, every subsystem is in a joint, the graph is connected, and a
    kinematically driven port is in no other joint.
    """

    n_subsystems: int
    joints: tuple[Joint, ...]
    n_components: int = 1
    ports: tuple[int, ...] = ()
    names: tuple[str, ...] = ()
    connections: tuple[Connection, ...] = ()

    def __post_init__(self) -> None:
        n = self.n_subsystems
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
            raise ParameterError(f"a coupling graph has at least 2 subsystems, got {n!r}")
        object.__setattr__(self, "joints", tuple(self.joints))
        object.__setattr__(self, "connections", tuple(self.connections))
        if not self.joints and not self.connections:
            raise ParameterError("a coupling graph has at least one joint or connection")
        if isinstance(self.n_components, bool) or self.n_components not in (1, 2, 3):
            raise ParameterError(f"n_components must be 1, 2 or 3, got {self.n_components!r}")
        names = tuple(self.names) or tuple(str(i + 1) for i in range(n))
        if len(names) != n:
            raise ParameterError(f"names: {len(names)} names for {n} subsystems")
        object.__setattr__(self, "names", names)
        for j, joint in enumerate(self.joints):
            for i in (joint.first, joint.second):
                if i >= n:
                    raise ParameterError(f"joint {j + 1} names subsystem {i + 1}, but there are {n}")
        fed: dict = {}
        for c, con in enumerate(self.connections):
            if max(con.source, con.target) >= n:
                raise ParameterError(f"connection {c + 1} names subsystem {max(con.source, con.target) + 1}, "
                                     f"but there are {n}")  # fmt: skip
            if fed.setdefault((con.target, con.input), c) != c:
                raise ParameterError(f"input {con.input + 1} of subsystem {names[con.target]} is fed by connections "
                                     f"{fed[(con.target, con.input)] + 1} and {c + 1}: an input takes one")  # fmt: skip
        used = [0] * n
        for joint in self.joints:
            for i, p in joint.sides:
                used[i] = max(used[i], p + 1)
        ports = tuple(self.ports) or tuple(used)
        if len(ports) != n or any(p < u for p, u in zip(ports, used)):
            raise ParameterError(f"ports {ports!r}: the joints use {tuple(used)} ports per subsystem")
        object.__setattr__(self, "ports", ports)
        signalled = {i for con in self.connections for i in (con.source, con.target)}
        alone = [names[i] for i in range(n) if used[i] == 0 and i not in signalled]
        if alone:
            raise ParameterError(f"subsystem(s) {', '.join(alone)} take part in no joint or connection")
        self._check_connected()
        self._check_kinematic_ports()

    # -- construction --------------------------------------------------------------------------
    @classmethod
    def pair(cls, decomposition: str | Decomposition, n_components: int = 1) -> CouplingGraph:
        """The paper's graph: subsystems 1 and 2 joined by one joint with ``decomposition``."""
        return cls(2, (Joint(0, 1, get_decomposition(decomposition)),), n_components)

    @classmethod
    def chain(
        cls, decompositions: Sequence[str | Decomposition], n_components: int = 1, *, ports: str = "ends"
    ) -> CouplingGraph:
        """``N = len(decompositions) + 1`` subsystems in a row, joint ``j`` between ``j`` and ``j + 1``.

        ``ports="ends"``: a subsystem between two neighbours has the joint to its left one at its port 0 and to
        its right one at its port 1 (a segment's first and last mass), the two end subsystems one port each;
        ``"one"``: every subsystem has one port, where its joints attach.
        """
        if ports not in ("ends", "one"):
            raise ParameterError(f"ports must be 'ends' or 'one', got {ports!r}")
        right = 1 if ports == "ends" else 0
        joints = tuple(
            Joint(j, j + 1, get_decomposition(d), ports=(0 if j == 0 else right, 0))
            for j, d in enumerate(decompositions)
        )
        return cls(len(joints) + 1, joints, n_components)

    def _check_connected(self) -> None:
        pairs = [(jt.first, jt.second) for jt in self.joints] + [(c.source, c.target) for c in self.connections]
        reached, frontier = {0}, [0]
        while frontier:
            i = frontier.pop()
            for a, b in pairs:
                if i in (a, b):
                    other = b if i == a else a
                    if other not in reached:
                        reached.add(other)
                        frontier.append(other)
        if len(reached) < self.n_subsystems:
            apart = [self.names[i] for i in range(self.n_subsystems) if i not in reached]
            raise ParameterError(
                f"the joints and connections do not connect every subsystem: {', '.join(apart)} not coupled to "
                f"{self.names[0]}"
            )

    def _check_kinematic_ports(self) -> None:
        for (i, p), joints in self._port_joints.items():
            kinematic = [j for j, side in joints if self.joints[j].decomposition.kinds[side] == "kinematic"]
            if kinematic and len(joints) > 1:
                j = kinematic[0]
                raise ParameterError(
                    f"subsystem {self.names[i]}'s port {p + 1} is kinematically driven by joint {j + 1} "
                    f"({self.joints[j].decomposition.name}) and takes part in {len(joints) - 1} more joint(s): "
                    "a kinematically driven port follows one joint only (give the subsystem another port, or "
                    "make it force driven there)"
                )

    # -- ports, variables, inputs --------------------------------------------------------------
    @cached_property
    def _port_joints(self) -> dict[tuple[int, int], list[tuple[int, int]]]:
        """``(subsystem, port) -> [(joint, side)]``."""
        out: dict[tuple[int, int], list[tuple[int, int]]] = {}
        for j, joint in enumerate(self.joints):
            for side, key in enumerate(joint.sides):
                out.setdefault(key, []).append((j, side))
        return out

    @cached_property
    def port_offsets(self) -> tuple[int, ...]:
        """Index of subsystem ``i``'s port 0 among all ports (ports numbered subsystem after subsystem)."""
        return tuple(int(v) for v in np.concatenate([[0], np.cumsum(self.ports)[:-1]]))

    @property
    def n_ports(self) -> int:
        return sum(self.ports)

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    def port_kind(self, i: int, p: int) -> str:
        """``"kinematic"`` if a joint drives port ``p`` of subsystem ``i`` kinematically, else ``"force"``."""
        for j, side in self._port_joints.get((i, p), ()):
            if self.joints[j].decomposition.kinds[side] == "kinematic":
                return "kinematic"
        return "force"

    def kinds(self, i: int) -> tuple[str, ...]:
        """The kind of each port of subsystem ``i``."""
        return tuple(self.port_kind(i, p) for p in range(self.ports[i]))

    @cached_property
    def _columns(self) -> tuple[tuple[int, ...], ...]:
        cols, start = [], 0
        for joint in self.joints:
            n = joint.decomposition.n_coupling * self.n_components
            cols.append(tuple(range(start, start + n)))
            start += n
        return tuple(cols)

    def columns(self, j: int) -> tuple[int, ...]:
        """The entries of ``e`` that are joint ``j``'s coupling variables (variable-major, then component)."""
        return self._columns[j]

    @property
    def n_coupling(self) -> int:
        """Number of coupling variables ``e`` (per time point): the joints', then one per connection."""
        return sum(len(c) for c in self._columns) + len(self.connections)

    def connection_column(self, c: int) -> int:
        """The entry of ``e`` that is connection ``c``'s input value."""
        return sum(len(col) for col in self._columns) + c

    def signal_inputs(self, i: int) -> tuple[tuple[int, int], ...]:
        """Subsystem ``i``'s inputs fed by connections: ``(input, column of e)`` pairs, by input."""
        return tuple(sorted((con.input, self.connection_column(c)) for c, con in enumerate(self.connections)
                            if con.target == i))  # fmt: skip

    def describe_connection(self, c: int) -> str:
        con = self.connections[c]
        return f"connection {c + 1} ({self.names[con.source]} -> {self.names[con.target]})"

    def variable_names(self) -> tuple[str, ...]:
        """Names of the entries of ``e``: the decomposition's (two subsystems, one component), else with the
        joint's number and the component (``lambda_c[2]``, ``a_tilde_1[1].y``)."""
        comps = ("x", "y", "z")[: self.n_components] if self.n_components > 1 else ("",)
        names = []
        for j, joint in enumerate(self.joints):
            tag = f"[{j + 1}]" if self.n_joints > 1 else ""
            for var in joint.decomposition.variables:
                names += [f"{var}{tag}" + (f".{c}" if c else "") for c in comps]
        return tuple(names) + tuple(f"u[{c + 1}]" for c in range(len(self.connections)))

    def _variable(self, j: int, kind: str) -> int:
        """Index of joint ``j``'s force (``lambda``) or acceleration (``a_tilde``) variable."""
        d = self.joints[j].decomposition
        return next(v for v in range(d.n_coupling) if d.variable_kind(v) == kind)

    def input_terms(self, i: int) -> tuple[tuple[tuple[int, int], ...], ...]:
        """Per input of subsystem ``i`` (port after port, ``n_c`` components each): the ``(column of e,
        sign)`` pairs it sums (a port in no joint: none, the input is zero)."""
        n_c = self.n_components
        terms = []
        for p in range(self.ports[i]):
            kind = self.port_kind(i, p)
            per_port = []
            for j, side in self._port_joints.get((i, p), ()):
                v = self._variable(j, "force" if kind == "force" else "acceleration")
                first_col = self._columns[j][v * n_c]
                sign = (1 if side == 0 else -1) if kind == "force" else 1
                per_port.append((first_col, sign))
            terms += [tuple((col + c, s) for col, s in per_port) for c in range(n_c)]
        return tuple(terms)

    def n_inputs(self, i: int) -> int:
        return self.ports[i] * self.n_components

    @cached_property
    def _gathers(self) -> tuple[Any, ...]:
        """Per subsystem: how :meth:`inputs` forms its inputs (index arrays and signs per term slot)."""
        out: list[tuple[str, Any, Any]] = []
        for i in range(self.n_subsystems):
            terms = self.input_terms(i)
            depth = max((len(t) for t in terms), default=0)
            if depth == 1 and all(len(t) == 1 for t in terms):
                first = [t[0][0] for t in terms]
                signs = [t[0][1] for t in terms]
                contiguous = first == list(range(first[0], first[0] + len(first)))
                index = slice(first[0], first[0] + len(first)) if contiguous else np.array(first)
                out.append(("one", index, None if all(s == 1 for s in signs) else np.array(signs, dtype=float)))
            elif depth == 0:  # ports in no joint: no force
                out.append(("zero", len(terms), None))
            else:
                slots = [
                    (
                        np.array([t[d][0] if d < len(t) else 0 for t in terms]),
                        np.array([t[d][1] if d < len(t) else 0 for t in terms], dtype=float),
                    )
                    for d in range(depth)
                ]
                out.append(("sum", slots, None))
        return tuple(out)

    def inputs(self, i: int, e: Any) -> Any:
        """Subsystem ``i``'s inputs from coupling variables ``e`` on the last axis: ``(..., n_inputs(i))``."""
        how, index, signs = self._gathers[i]
        if how == "zero":
            return 0 * e[..., :1] + np.zeros(index)
        if how == "one":
            u = e[..., index]
            return u if signs is None else u * signs
        total = None
        for cols, sgn in index:
            term = e[..., cols] * sgn
            total = term if total is None else total + term
        return total

    def input_matrix(self, i: int, columns: Sequence[int]) -> np.ndarray:
        """``d inputs(i) / d e[columns]`` (entries 0 and +-1), ``(n_inputs(i), len(columns))``."""
        where = {c: n for n, c in enumerate(columns)}
        B = np.zeros((self.n_inputs(i), len(columns)))
        for row, terms in enumerate(self.input_terms(i)):
            for col, sign in terms:
                if col in where:
                    B[row, where[col]] += sign
        return B

    def joints_of(self, i: int) -> tuple[int, ...]:
        """The joints subsystem ``i`` takes part in."""
        return tuple(j for j, joint in enumerate(self.joints) if i in (joint.first, joint.second))

    def neighbours(self, i: int) -> tuple[int, ...]:
        return tuple(
            joint.second if joint.first == i else joint.first
            for joint in self.joints
            if i in (joint.first, joint.second)
        )

    def is_pair(self) -> bool:
        return self.n_subsystems == 2 and self.n_joints == 1

    def describe_joint(self, j: int) -> str:
        joint = self.joints[j]
        return f"joint {j + 1} ({self.names[joint.first]}–{self.names[joint.second]}, {joint.decomposition.name})"
