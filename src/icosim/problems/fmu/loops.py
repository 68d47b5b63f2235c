"""Algebraic loops of signal connections, solved at each communication point by Newton's method without a step.

An algebraic loop is a cycle of connections each into an input that its unit's output feeding the next connection
depends on directly (:func:`feedthrough_loop`).  Whether an output depends directly on
an input is read from the unit's ``ModelStructure``; where the structure gives no dependencies for the output (FMI:
it may then depend on every input) it is measured (:func:`measured_depends`): the input is moved and the output read
again, without a step.  A cycle that is not one by measurement is no loop.

At a communication point (``t0``, and ``T_N+1`` once every unit stands there) the connections' values ``e`` solve

.. math:: F(e) = e - T(y(x, e)) = 0

with the units' states ``x`` fixed: ``e`` is handed to the inputs (FMI set, no ``doStep``: an FMI 2.0 co-simulation
unit's direct-feedthrough outputs follow its inputs between steps, a model-exchange unit recomputes them) and the
outputs are read.  Newton's method starts from the inputs as the units hold them (their start values at ``t0``,
after a step the extrapolation's value at its end) with the Jacobian ``I - dT(y)/de`` from the units' directional
derivatives where they provide them, else by forward differences, one input at a time (only its unit is set and
read again), kept from one point to the next while it serves
(:meth:`LoopSolver.solve`).  Every connection's value is an unknown, those on no cycle too: they follow in the same
Newton step.  The solve converges when every residual ``|F_j|`` is within
``coupling.loop_tolerance`` ``* max(1, |e_j|)``; it is refused (:class:`LoopError`, naming the loop's connections
and the time) where it has not converged within ``coupling.loop_iterations`` Newton steps, and where ``I - J`` is
singular (a loop gain of 1: the outputs do not fix the loop's values).

A loop whose Jacobian changes between the start and the root is nonlinear and may have other roots: the root found,
its start and the time are kept (:meth:`LoopSolver.info`) and said in the run's dataset.
"""

from __future__ import annotations

import json

import numpy as np

from ...errors import StepFailure
from .errors import SceneError

__all__ = ["LOOP_KEYS", "LoopError", "LoopSolver", "check_loop_keys", "depends_directly", "feedthrough_after",
           "feedthrough_loop", "measured_depends", "provides_directional", "directional_column", "loop_connections",
           "loop_solver", "SINGULAR", "SLOW"]  # fmt: skip

#: The coupling keys of the loop solve and their defaults.
LOOP_KEYS = {"loop_tolerance": 1e-10, "loop_iterations": 20}
#: ``I - J`` is singular where its smallest singular value is below this times its largest (the forward
#: differences are good to about 1e-8).
SINGULAR = 1e-6
#: A Newton step with a kept Jacobian that leaves more than this part of the residual takes a fresh one.
SLOW = 0.01


class LoopError(SceneError, StepFailure):
    """An algebraic loop that cannot be solved at a communication point: the message names the loop's connections,
    the time and why (not converged, or ``I - J`` singular).  A scene refused (at ``t0``) and a failed macro step
    (later: the run stops there, nothing written)."""


def check_loop_keys(fail, c: dict) -> None:
    """Refuse bad ``coupling.loop_tolerance`` and ``coupling.loop_iterations`` in ``c`` (``fail(where, message)``
    raises)."""
    tol, its = c["loop_tolerance"], c["loop_iterations"]
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 < tol < 1:
        fail("coupling.loop_tolerance", f"must be a number in (0, 1) (the relative residual), got {tol!r}")
    if isinstance(its, bool) or not isinstance(its, int) or its < 1:
        fail("coupling.loop_iterations", f"must be an integer >= 1 (Newton steps), got {its!r}")


def depends_directly(md, output: str, input_: str) -> bool:
    """Whether ``output`` depends on ``input_`` without a step, by the unit's ``ModelStructure`` (``md``, fmpy's
    model description): listed in its dependencies, or the dependencies not given (FMI: then it may depend on
    every input)."""
    for unknown in md.outputs:
        if unknown.variable.name == output:
            deps = unknown.dependencies
            return deps is None or any(v.name == input_ for v in deps)
    return True  # an output the structure does not list: it may depend on anything


def feedthrough_after(graph, inputs, outputs, depends) -> dict[int, list[int]]:
    """Connection -> the connections out of its target unit whose output depends directly on its input
    (``depends(unit, output name, input name)``)."""
    cons = graph.connections
    return {c: [d for d, nxt in enumerate(cons)
                if nxt.source == con.target and depends(con.target, outputs[con.target][nxt.output],
                                                        inputs[con.target][con.input])]
            for c, con in enumerate(cons)}  # fmt: skip


def feedthrough_loop(graph, inputs, outputs, descriptions, depends=None) -> list[int] | None:
    """A cycle of connections (their indices) each into an input that an output of its target unit fed by the next
    connection depends on directly, or None.  ``inputs[i]``, ``outputs[i]``: unit ``i``'s connected variables by
    index; ``descriptions[i]``: its model description; ``depends(unit, output, input)``: whether an output depends
    directly on an input (default :func:`depends_directly` by the descriptions)."""
    if depends is None:
        depends = lambda i, output, input_: depends_directly(descriptions[i], output, input_)  # noqa: E731
    cons, after = graph.connections, feedthrough_after(graph, inputs, outputs, depends)
    state: dict[int, int] = {}  # 1: on the path, 2: done

    def visit(c, path):
        state[c] = 1
        path.append(c)
        for d in after[c]:
            if state.get(d) == 1:
                return path[path.index(d) :]
            if d not in state:
                found = visit(d, path)
                if found:
                    return found
        path.pop()
        state[c] = 2
        return None

    for c in range(len(cons)):
        if c not in state:
            found = visit(c, [])
            if found:
                return found
    return None


def measured_depends(unit, keys: tuple[str, str], output: int, input_: int) -> bool:
    """Whether ``unit``'s output ``output`` (of those under ``keys[1]``) moves when its input ``input_`` (of those
    under ``keys[0]``) is moved, without a step; the input is set back.  The measurement holds at the unit's present
    state."""
    key, outputs = keys
    held = unit.get((key,)).ravel()
    before = unit.get((outputs,)).ravel()[output]
    moved = held.copy()
    moved[input_] += 1e-3 * max(1.0, abs(held[input_]))
    unit.set(key, moved)
    after = unit.get((outputs,)).ravel()[output]
    unit.set(key, held)
    return bool(after != before)


def provides_directional(unit) -> bool:
    """Whether ``unit`` gives its partial derivatives (``providesDirectionalDerivative``, FMI 2.0)."""
    return not unit.fmi3 and bool(getattr(unit._interface(unit.md), "providesDirectionalDerivative", False))


def directional_column(unit, keys: tuple[str, str], input_: int) -> np.ndarray:
    """The derivatives (SI) of ``unit``'s outputs under ``keys[1]`` by its input ``input_`` under ``keys[0]``, by
    ``fmi2GetDirectionalDerivative``."""
    key, outputs = keys
    seed = unit.fmi.directional(unit.fmi.refs(outputs), [unit.fmi.refs(key)[input_]], [1.0])
    return np.asarray(seed, dtype=float) * unit.factors[outputs] / unit.factors[key][input_]


def loop_connections(graph, after) -> list[int]:
    """The connections on a cycle of ``after`` (connection -> the connections it feeds directly), in order."""
    n = len(graph.connections)
    on = []
    for c in range(n):
        seen, todo = set(), list(after[c])
        while todo:
            d = todo.pop()
            if d == c:
                on.append(c)
                break
            if d not in seen:
                seen.add(d)
                todo.extend(after[d])
    return on


class LoopSolver:
    """Newton's method on ``e = T(y(x, e))`` for a :class:`~icosim.problems.fmu.signals.SignalCosimulation`
    ``problem`` whose connections ``loop`` (their indices) lie on algebraic loops."""

    def __init__(self, problem, keys: tuple[str, str], loop, tolerance: float = LOOP_KEYS["loop_tolerance"],
                 iterations: int = LOOP_KEYS["loop_iterations"]):  # fmt: skip
        self.problem, self.keys, self.key, self.loop = problem, keys, keys[0], list(loop)
        #: the units whose Jacobian columns come from their directional derivatives
        self.directional = {i for i, u in enumerate(problem.units) if provides_directional(u)}
        self.tolerance, self.iterations = float(tolerance), int(iterations)
        graph = problem.graph
        self.cols = np.array([graph.connection_column(c) for c in range(len(graph.connections))])
        self.solves = self.newton_steps = self.evaluations = self.jacobians = 0
        self._A: np.ndarray | None = None  # I - J as the last solve ended with it
        self.most_steps, self.largest_residual = 0, 0.0
        self.first: dict = {}  # the solve at the first point: time, start, root, steps, nonlinear

    def names(self) -> str:
        return ", ".join(self.problem.label(c) for c in self.loop)

    # -- the loop's function --------------------------------------------------------------------------------
    def _hand(self, i: int, e: np.ndarray) -> None:
        """Unit ``i``'s connected inputs set to their columns of ``e`` (its other inputs as they are)."""
        unit, fed = self.problem.units[i], self.problem.graph.signal_inputs(i)
        values = unit.get((self.key,)).ravel()
        for input_, col in fed:
            values[input_] = e[col]
        unit.set(self.key, values)

    def _given(self, i: int, g: np.ndarray) -> None:
        """The entries of ``g`` that connections out of unit ``i`` give (``factor * y + offset``), read."""
        y = self.problem.outputs(i)
        for c, con in enumerate(self.problem.graph.connections):
            if con.source == i:
                g[self.problem.graph.connection_column(c)] = con.factor * y[con.output] + con.offset

    def _fed_units(self) -> list[int]:
        return sorted({con.target for con in self.problem.graph.connections})

    def values(self, e: np.ndarray) -> np.ndarray:
        """``T(y(x, e))``: ``e`` handed to every connected input, every connected output read."""
        self.evaluations += 1
        for i in self._fed_units():
            self._hand(i, e)
        g = np.array(e, dtype=float, copy=True)
        for i in range(self.problem.graph.n_subsystems):
            self._given(i, g)
        return g

    def jacobian(self, e: np.ndarray, g: np.ndarray) -> np.ndarray:
        """``dT(y)/de`` at ``e`` (``g = T(y(x, e))``, the inputs standing at ``e``), a connection's value at a time:
        by the unit's directional derivatives where it provides them (FMI 2.0), else by forward differences (its
        value moved, only its unit set and read, the unit set back)."""
        graph, n = self.problem.graph, len(e)
        J = np.zeros((n, n))
        for c, con in enumerate(graph.connections):
            col = graph.connection_column(c)
            if con.target in self.directional:
                dy = directional_column(self.problem.units[con.target], self.keys, con.input)
                for d, nxt in enumerate(graph.connections):
                    if nxt.source == con.target:
                        J[graph.connection_column(d), col] = nxt.factor * dy[nxt.output]
                continue
            moved = e.copy()
            moved[col] += np.sqrt(np.finfo(float).eps) * max(1.0, abs(e[col]))
            h = moved[col] - e[col]  # the step as represented
            self._hand(con.target, moved)
            g_moved = g.copy()
            self._given(con.target, g_moved)
            J[:, col] = (g_moved - g) / h
            self._hand(con.target, e)
        self.evaluations += sum(con.target not in self.directional for con in graph.connections)
        return J

    # -- the solve ------------------------------------------------------------------------------------------
    def start(self) -> np.ndarray:
        """The connections' values as the units' inputs hold them."""
        e = np.zeros(self.problem.n_coupling)
        for i in self._fed_units():
            held = self.problem.units[i].get((self.key,)).ravel()
            for input_, col in self.problem.graph.signal_inputs(i):
                e[col] = held[input_]
        return e

    def solve(self, t: float) -> np.ndarray:
        """The connections' values at time ``t`` solving the loop, handed to the units' inputs; Newton from
        :meth:`start`.  The first solve takes the Jacobian at its start whatever the residual there, so a loop of
        gain 1 is refused even where its start happens to satisfy it.  A later solve steps with the Jacobian the
        solve before ended with while each step cuts the residual a hundredfold (:data:`SLOW`); from the first step that
        does not, it takes a fresh Jacobian at every step (Newton's method, for a loop whose Jacobian moves)."""
        e0 = e = self.start()
        A, J0, before, fresh = self._A, None, np.inf, False
        for step in range(self.iterations + 1):
            g = self.values(e)
            r = e - g
            size = float(np.max(np.abs(r) / np.maximum(1.0, np.abs(e)), initial=0.0))
            if not np.isfinite(size):
                raise LoopError(f"connections: the algebraic loop {self.names()} at t = {t:.12g} s: an output is not "
                                f"finite at the loop's values {e.tolist()}")  # fmt: skip
            if size <= self.tolerance and (self.first or step > 0):
                break
            if step == self.iterations:
                raise LoopError(
                    f"connections: the algebraic loop {self.names()} at t = {t:.12g} s: Newton's method has not "
                    f"converged in coupling.loop_iterations = {self.iterations} steps (relative residual {size:.3g} > "
                    f"coupling.loop_tolerance = {self.tolerance:g}); raise loop_iterations or loosen loop_tolerance"
                )
            if A is None or fresh or size > SLOW * before:  # once fresh, fresh at every step: Newton's method
                A, fresh = self._newton_matrix(e, g, t), True
                J0 = A if J0 is None else J0
            if size <= self.tolerance:
                break
            e, before = e - np.linalg.solve(A, r), size
            self.newton_steps += 1
        self._A = A
        self.solves += 1
        self.most_steps = max(self.most_steps, step)
        self.largest_residual = max(self.largest_residual, size)
        if not self.first:
            nonlinear = step > 0 and not np.allclose(self._newton_matrix(e, g, t), J0, rtol=1e-5, atol=1e-6)
            self.first = {"time": t, "start": e0[self.cols[self.loop]].tolist(),
                          "root": e[self.cols[self.loop]].tolist(), "steps": step, "nonlinear": nonlinear}  # fmt: skip
        return e

    def _newton_matrix(self, e: np.ndarray, g: np.ndarray, t: float) -> np.ndarray:
        """``I - J`` at ``e`` (:meth:`jacobian`), refused where singular."""
        A = np.eye(len(e)) - self.jacobian(e, g)
        self.jacobians += 1
        s = np.linalg.svd(A, compute_uv=False)
        if not s[-1] > SINGULAR * max(s[0], 1.0):
            raise LoopError(
                f"connections: the algebraic loop {self.names()} is ill-posed at t = {t:.12g} s: I - J (J the "
                f"derivative of the connections' values by the loop's inputs) is singular (smallest singular "
                f"value {s[-1]:.3g}, a loop gain of 1), so the outputs do not determine the loop's values"
            )
        return A

    def message(self) -> str:
        """What the first solve found, said for a nonlinear loop (which may have other roots)."""
        f = self.first
        if not f:
            return ""
        found = f"the loop's values {f['root']} from the start {f['start']} at t = {f['time']:.12g} s"
        if f["nonlinear"]:
            return (f"the algebraic loop {self.names()} is nonlinear and may have several roots: Newton's method "
                    f"found {found}; each later point starts from the inputs the step before left")  # fmt: skip
        return f"the algebraic loop {self.names()} is linear: {found}"

    def info(self) -> dict:
        """The loop's connections, the first solve's start and root, and the solves' counts, for a dataset."""
        return {
            "loop_connections": self.names(),
            "loop_start_t0": json.dumps(self.first.get("start")),
            "loop_root_t0": json.dumps(self.first.get("root")),
            "loop_nonlinear": int(bool(self.first.get("nonlinear"))),
            "loop_message": self.message(),
            "loop_solves": self.solves,
            "loop_newton_steps": self.newton_steps,
            "loop_most_steps": self.most_steps,
            "loop_largest_residual": self.largest_residual,
            "loop_evaluations": self.evaluations,
            "loop_directional": ", ".join(self.problem.units[i].label for i in sorted(self.directional)),
            "loop_jacobians": self.jacobians,
            "loop_tolerance": self.tolerance,
            "loop_iterations": self.iterations,
        }


def loop_solver(problem, inputs_key: str, outputs_key: str, tolerance, iterations) -> LoopSolver | None:
    """The loop solver of ``problem`` (a :class:`~icosim.problems.fmu.signals.SignalCosimulation`, units open, their
    connected inputs and outputs under the unit keys ``inputs_key`` and ``outputs_key``), None where its connections
    form no algebraic loop; a dependency the ``ModelStructure`` does not give is measured."""
    units, ins, outs = problem.units, problem.input_names, problem.output_names

    def depends(i, output, input_):
        md = units[i].md
        listed = next((u for u in md.outputs if u.variable.name == output), None)
        if listed is not None and listed.dependencies is None:
            return measured_depends(units[i], (inputs_key, outputs_key), outs[i].index(output), ins[i].index(input_))
        return depends_directly(md, output, input_)

    loop = loop_connections(problem.graph, feedthrough_after(problem.graph, ins, outs, depends))
    return LoopSolver(problem, (inputs_key, outputs_key), loop, tolerance, iterations) if loop else None
