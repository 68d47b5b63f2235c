"""FMU units coupled by signal connections as a co-simulation problem, coupled explicitly or implicitly by the one
macro step.

Each connection is a condition ``u_in = T(y_out)`` of the coupling graph (:class:`~icosim.engine.graph.Connection`,
``T`` the connection's linear transformation and unit conversion); its coupling variable is the input's value.
:func:`icosim.engine.macrostep.macro_step` with ``method=None`` steps each unit once per macro step with its inputs
held (``k = 0``) or extrapolated by the Lagrange polynomial through the last ``k + 1`` samples (Jacobi), or
interpolated through the sample a unit of an earlier stage has just given (Gauss-Seidel), and takes the units'
outputs at ``T_N+1`` as the connections' new samples.  No unit is stepped twice from one point, so units that
cannot save their state (``canGetAndSetFMUstate`` false) take part.  With ``implicit`` the corrector closes the
connections' conditions at ``T_N+1`` by Newton (:mod:`icosim.engine.connection_conditions`): each unit saves its
state when it is predicted and is restored to it before each corrector and perturbed step.

The arrays the macro step sees: a unit's outputs ``y_i`` are its connected outputs at ``T_N+1`` (in the unit's
own units of measure), its end state the same values; the state is their concatenation.  The units hold their
states.  The inputs a unit is handed over a step follow :meth:`icosim.problems.fmu.units.Unit.step`.

An algebraic loop (a cycle of connections each into an input its unit's output depends on directly, by the
units' ``ModelStructure`` or, where it gives no dependencies, measured: :func:`feedthrough_loop`) is solved at each
communication point, ``t0`` and every ``T_N+1``, by Newton's method without a step (:mod:`icosim.problems.fmu.loops`):
the connections' new samples are then the loop's values there, not the outputs as the step left them (the state
the macro step returns keeps those; the units hold the solved inputs).  Coupled implicitly, the loop's conditions
at ``T_N+1`` are among those the corrector closes (a unit's output after its step depends on the input's value
there); the loop solver gives the values at ``t0``.
"""

from __future__ import annotations

import numpy as np

from ...engine.graph import Connection, CouplingGraph
from ...engine.lagrange import monomial_coefficients
from ...engine.problem import CosimulationProblem
from .checkpoint import SignalCheckpoints
from .description import check_kind
from .loops import depends_directly, feedthrough_loop, loop_solver
from .units import Unit

__all__ = ["SignalCosimulation", "ForwardUnit", "feedthrough_loop", "depends_directly"]

#: The unit keys (:data:`icosim.problems.fmu.units.ROLES`) of a unit's connected inputs and outputs.
INPUTS, OUTPUTS = "signal_input", "signal_output"


class ForwardUnit(Unit):
    """A co-simulation unit stepped forward only, once per macro step (explicit coupling): it need not save and
    restore its state."""

    opened = "co-simulation, stepped forward only"

    def _check_kind(self, md):
        check_kind(self.label, self.path, md, saves_state=False)


class SignalCosimulation(SignalCheckpoints, CosimulationProblem):
    """Units (:class:`~icosim.problems.fmu.units.Unit`, opened with their connected inputs under
    :data:`INPUTS` and outputs under :data:`OUTPUTS`) coupled by ``connections``.

    Parameters
    ----------
    units : the opened units, at ``t0``.
    inputs, outputs : per unit, its connected input and output names (the connections' ``input`` and ``output``
        index them).
    connections : the :class:`~icosim.engine.graph.Connection` s.
    k : the order of the inputs' extrapolation (0: held).
    H : macro-step size in s.
    sources : per unit, the :class:`~icosim.problems.fmu.signal_sources.TableSource` s of its inputs after the
        connected ones (``inputs[i]`` lists those last), each handed its chord over a step.
    implicit : the connections closed by their conditions at ``T_N+1`` (Newton,
        :mod:`icosim.engine.connection_conditions`): each unit saves its state at ``T_N`` when it is predicted and
        is restored to it before every further step of the macro step (units that save and restore state).  An
        algebraic loop is then closed with every other connection at ``T_N+1``; its solver serves ``t0`` only.
    loop_tolerance, loop_iterations : the algebraic loops' Newton solve (:class:`~icosim.problems.fmu.loops.LoopSolver`).
    joints, n_components : joints of the graph beside the connections, whose units a subclass serves
        (:class:`~icosim.problems.fmu.joint_signals.JointSignalCosimulation`).
    """

    def __init__(self, units, inputs, outputs, connections, k, H, *, t0=0.0, sources=None, implicit=False,
                 loop_tolerance=1e-10, loop_iterations=20, joints=(), n_components=1):  # fmt: skip
        self.units = tuple(units)
        self.sources = tuple(map(tuple, sources)) if sources is not None else tuple(() for _ in self.units)
        self.input_names, self.output_names = tuple(map(tuple, inputs)), tuple(map(tuple, outputs))
        graph = CouplingGraph(len(self.units), joints, n_components, names=tuple(u.label for u in self.units),
                              connections=connections)  # fmt: skip
        super().__init__(graph, k)
        self.implicit_connections = bool(implicit)
        self._saved = [None] * len(self.units)  # implicit: each unit's state at T_N
        self._saved_at = [None] * len(self.units)  # the macro step it was saved in
        #: the algebraic loops' solver (:mod:`icosim.problems.fmu.loops`), None without a loop
        self.loops = loop_solver(self, INPUTS, OUTPUTS, loop_tolerance, loop_iterations)
        self._standing: set[int] = set()  # the units standing at T_N+1 in this macro step (:meth:`connect`)
        self.H, self.t0 = float(H), float(t0)
        self.step_index = 0
        self._clock, self._steps, self._kept = (self.t0, 0), None, None  # SignalCheckpoints: T_N's origin, sizes
        self.C_pred = np.array(monomial_coefficients(self.pred_nodes), dtype=float)
        self.C_corr = np.array(monomial_coefficients(self.corr_nodes), dtype=float)

    def label(self, c: int) -> str:
        """Connection ``c`` as ``unit.output -> unit.input``."""
        con, names = self.graph.connections[c], self.graph.names
        return (f"{names[con.source]}.{self.output_names[con.source][con.output]} -> "
                f"{names[con.target]}.{self.input_names[con.target][con.input]}")  # fmt: skip

    describe_connection = label

    @property
    def time(self) -> float:
        return self._clock[0] + (self.step_index - self._clock[1]) * self.H  # T_0 + N H while H is fixed

    def outputs(self, i: int) -> np.ndarray:
        """Unit ``i``'s connected outputs as it stands."""
        if not self.output_names[i]:
            return np.zeros(0)
        return self.units[i].get((OUTPUTS,)).ravel()

    def _set_inputs(self, i: int, e: np.ndarray) -> None:
        cols = [col for _, col in self.graph.signal_inputs(i)]
        if cols or self.sources[i]:
            fed = [s.after(self.time) for s in self.sources[i]]
            self.units[i].set(INPUTS, np.concatenate([np.asarray(e, dtype=float)[cols], fed]))

    def initial_history(self, rows=None) -> np.ndarray:
        """The coupling history at ``t0``: ``rows`` (``(k + 1, n_e)``, from ``T_0`` back) where given, else the
        connections' values at ``t0`` at every node.  Those are found by handing the outputs to the inputs until
        they settle (without an algebraic loop, within as many passes as there are connections), or with a loop by
        its Newton solve (:meth:`~icosim.problems.fmu.loops.LoopSolver.solve`)."""
        if rows is not None:
            rows = np.asarray(rows, dtype=float)
            for i in range(self.graph.n_subsystems):
                self._set_inputs(i, rows[0])
            return rows
        if self.loops is not None:  # the inputs a table feeds set first: the loop is solved with them
            start = self.loops.start()
            for i in range(self.graph.n_subsystems):
                self._set_inputs(i, start)
            return np.tile(self.loops.solve(self.t0), (self.k + 1, 1))
        e = np.zeros(self.n_coupling)
        for _ in range(len(self.graph.connections) + 1):
            e_new, _ = self.connect(
                e, [self.outputs(i) for i in range(self.graph.n_subsystems)], range(len(self.units))
            )
            for i in range(self.graph.n_subsystems):
                self._set_inputs(i, e_new)
            if np.array_equal(e_new, e):
                break
            e = e_new
        return np.tile(e, (self.k + 1, 1))

    def connect(self, e, ys, units, closed=()):
        """The connections' new samples (:meth:`~icosim.engine.problem.CosimulationProblem.connect`); with an
        algebraic loop coupled explicitly, once every unit stands at ``T_N+1``, every connection's value solved there
        (:mod:`icosim.problems.fmu.loops`).  Coupled implicitly, the corrector closes the loop."""
        e, cols = super().connect(e, ys, units, closed)
        if self.loops is not None and not self.implicit_connections:
            self._standing.update(units)
            if len(self._standing) == self.graph.n_subsystems:
                self._standing.clear()
                e, cols = self.loops.solve(self.time + self.H), list(self.loops.cols)
        return e, cols

    def initial_state(self) -> np.ndarray:
        return np.concatenate([self.outputs(i) for i in range(self.graph.n_subsystems)])

    def _step(self, i, rows, C):
        """Unit ``i`` over ``[T_N, T_N+1]``, its inputs the polynomial through the samples ``rows`` (``(k + 1,
        n_e)``) with the monomial coefficients ``C``."""
        unit = self.units[i]
        cols = [col for _, col in self.graph.signal_inputs(i)]
        self.work.subsystem_integrations += 1
        if cols or self.sources[i]:
            coefficients = C @ rows[:, cols]
            if self.sources[i]:  # a table's chord: linear over the step, whatever k
                chords = np.array([s.chord(self.time, self.H) for s in self.sources[i]]).T
                n = max(len(coefficients), 2)
                coefficients = np.hstack([np.pad(coefficients, ((0, n - len(coefficients)), (0, 0))),
                                          np.pad(chords, ((0, n - 2), (0, 0)))])  # fmt: skip
            unit.step(INPUTS, coefficients, self.time, self.H, step_index=self.step_index + 1, final=self._final)
        else:  # a unit fed by no connection: nothing to hand it
            unit._do_step(self.time, self.H, self.step_index + 1, self._final)
            unit.t = self.time + self.H
        y = self.outputs(i)
        if not np.isfinite(y).all():
            from .errors import UnitStepError

            bad = int(np.argwhere(~np.isfinite(y))[0, 0])
            raise UnitStepError(f"unit {unit.label} returned {self.output_names[i][bad]} = {y[bad]!r} in macro step "
                                f"{self.step_index + 1} (t = {self.time:.12g} s){unit.said()}")  # fmt: skip
        return y, y

    @property
    def _final(self) -> bool:
        """No state before the step's end will be restored: coupled explicitly and no checkpoint kept."""
        return not self.implicit_connections and self._kept is None

    def _save(self, i):
        """The state at ``T_N`` of unit ``i`` (implicit), for the corrector's and the Jacobian's steps."""
        if self._saved[i] is not None:
            self.units[i].free(self._saved[i])
        self._saved[i], self._saved_at[i] = self.units[i].save(), self.step_index

    def predict(self, i, state, history, *, final=False, e_new=None):
        """Unit ``i`` with the extrapolation polynomials, or, ``e_new`` given (fed by a connection's new sample), the
        interpolation polynomials through it; implicit: its state at ``T_N`` saved first."""
        if self.implicit_connections:
            self._save(i)
        if e_new is not None:
            return self._step(i, self.corrector_samples(history, np.asarray(e_new, dtype=float)), self.C_corr)
        return self._step(i, history[: self.k + 1], self.C_pred)

    def correct(self, i, state, history, e):
        if self.implicit_connections:  # restored to its state at T_N, which its predictor saved
            self.units[i].restore(self._saved[i])
        return self._step(i, self.corrector_samples(history, np.asarray(e, dtype=float)), self.C_corr)

    def signal_output(self, i, y, output):
        return y[output]

    def stack(self, ys):
        return np.concatenate(ys)

    def join(self, ends):
        self.step_index += 1  # the macro step's last call: every unit stands at T_N+1
        return np.concatenate(ends)


def connections_of(specs, names) -> tuple[list, list, list]:
    """The engine's connections and each unit's connected inputs and outputs from ``specs``: ``(source unit, output,
    target unit, input, factor, offset)`` by name; ``names``: the units in order."""
    index = {n: i for i, n in enumerate(names)}
    inputs = [[] for _ in names]
    outputs = [[] for _ in names]
    cons = []
    for source, output, target, input_, factor, offset in specs:
        s, t = index[source], index[target]
        if output not in outputs[s]:
            outputs[s].append(output)
        if input_ not in inputs[t]:
            inputs[t].append(input_)
        cons.append(Connection(s, outputs[s].index(output), t, inputs[t].index(input_), factor, offset))
    return cons, inputs, outputs
