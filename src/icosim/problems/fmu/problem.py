"""FMU units joined by rigid joints as a co-simulation problem: what :func:`icosim.engine.macrostep.macro_step`
needs of them.

The problem holds no method-, order- or scheme-specific code: every method, ``k``, scheme and graph runs
through the one macro step unchanged.  Each subsystem is a :class:`~icosim.problems.fmu.units.Unit` with one
port (its joint point); its state at a communication point lives inside the FMU, saved with
``fmi2GetFMUstate`` and restored before every integration that starts there (docs/fmi.md).  The arrays the
macro step sees are the observable part of it:

* state ``s[i] = (x_i, v_i)`` (position and velocity of unit ``i``'s joint point, SI units; with ``n_d``
  components each -- one for a point on a line, two for a joint in the plane -- ``s[i]`` has ``2 n_d``
  entries, the positions first);
* coupling variables ``e``: those of the joints' decompositions in SI units (``lambda`` in N, ``a_tilde``
  in m/s^2), ``n_d`` components each (:mod:`icosim.engine.graph`);
* outputs ``y[i] = (x_i, v_i, a_i, f_i)`` at ``T_N+1``, shape ``(1, 4, n_d)``, with ``f_i`` the coupling
  force on unit ``i`` in the graph's sense: the sum of its joints' ``+-lambda`` for a force-driven unit,
  ``force_sign * reaction_force`` for a kinematically driven one.

A kinematically driven unit that takes its point's position or velocity, or has no outputs for them, is a drive
(:mod:`icosim.problems.fmu.drives`): the problem prescribes its point's motion.

Beside the joints a unit may take and give signal connections' values (a scene of joints and connections,
:mod:`icosim.problems.fmu.joint_signals`): ``signal_columns[i]`` are the entries of the coupling variables (the
graph's of joints and connections, whose joints' entries come first) its ``signal_input`` follows, handed over each
step with its coupling input (the unit's entry ``coupled``), and a unit that names a ``signal_output`` has it read
after each integration (:attr:`signal_values`).

A unit's input is ``force_sign`` times the force the graph gives it (:class:`Coupling`).  The constraint
residuals are those of the engine's dimensionless setting (``g``, ``H g'``, ``H^2 g''``), so the method
parameters mean what they mean for the built-in models (:func:`icosim.engine.methods.engine_method`).
"""

from __future__ import annotations

import numpy as np

from ...engine.graph import CouplingGraph
from ...engine.lagrange import monomial_coefficients
from ...engine.problem import CosimulationProblem
from ...engine.projection import joined_clusters, mass_weighted_projection
from ...errors import StepFailure
from .checkpoint import Checkpoints
from .consistent import ConsistentStart
from .drives import DrivenPoints
from .errors import UnitStepError

__all__ = ["FmuCosimulation", "Coupling"]

_FORCE_OUTPUTS = ("position", "velocity", "acceleration")
_KINEMATIC_OUTPUTS = ("position", "velocity", "acceleration", "reaction_force")


class Coupling:
    """How one unit is coupled: its kind (``"force"`` or ``"kinematic"``), the sign of its force input and
    reaction output relative to the coupling force the graph gives it (``+lambda_j`` on a joint's first
    subsystem, ``-lambda_j`` on its second), its mass for the projection (None: the scene does not project), whether its coupling output follows its
    input without a step, and how much (measured: :func:`icosim.problems.fmu.inspection.inspect_unit`)."""

    def __init__(self, kind, force_sign, mass=None, feedthrough=True, gain=float("nan")):
        self.kind, self.force_sign, self.mass = kind, float(force_sign), mass
        self.feedthrough = bool(feedthrough)
        #: the coupling output's response to the unit's input (measured), whose sign is the unit's convention
        self.gain = float(gain)

    @property
    def input_key(self):
        return "force" if self.kind == "force" else "acceleration_input"


class FmuCosimulation(Checkpoints, ConsistentStart, DrivenPoints, CosimulationProblem):
    """FMU units joined by rigid joints (decompositions ff, fd, df, dd per joint).

    Parameters
    ----------
    units : the :class:`~icosim.problems.fmu.units.Unit` s, opened at ``t0``.
    couplings : a :class:`Coupling` per unit, the kinds matching the graph's.
    graph : the :class:`~icosim.engine.graph.CouplingGraph` (one port per unit), or a decomposition: the
        paper's two units joined by one joint.
    k : as for every problem.
    H : macro-step size in s.
    t0 : start time.
    perturbation : the sensitivities are difference quotients with the step ``perturbation * max(1, |u|)``
        (exact up to rounding for linear units).
    sensitivities : ``"each-step"`` (recomputed every macro step) or ``"first-step"`` (computed once and kept:
        exact for linear units, whose sensitivities are constant).
    iterations : the macro step's corrector steps: the last one's integration is final (doStep's
        ``noSetFMUStatePriorToCurrentPoint``), as is a prediction that is not corrected.
    signal_columns : per unit, the entries of ``e`` its connected inputs follow (module docstring); none by default.
    """

    def __init__(
        self,
        units,
        couplings,
        graph,
        k,
        H,
        *,
        t0=0.0,
        perturbation=1e-3,
        sensitivities="each-step",
        iterations=1,
        signal_columns=None,
    ):
        self.units, self.couplings = tuple(units), tuple(couplings)
        dims = {len(u.elements.get("position") or u.elements["reaction_force"]) for u in self.units}
        if len(dims) != 1:
            raise ValueError("every unit must name as many position components")
        #: components of the joint's position (1: a point on a line; 2: a joint in the plane)
        self.n_dim = dims.pop()
        if not isinstance(graph, CouplingGraph):
            graph = CouplingGraph.pair(graph, self.n_dim)
        if graph.n_subsystems != len(self.units) or graph.n_components != self.n_dim or set(graph.ports) != {1}:
            raise ValueError(f"the graph must join {len(self.units)} units of one port, {self.n_dim} components")
        super().__init__(graph, k)
        for i, c in enumerate(self.couplings):
            if c.kind != graph.port_kind(i, 0):
                raise ValueError(
                    f"unit {self.units[i].label} is {c.kind}-driven, the graph needs {graph.port_kind(i, 0)}"
                )
        n = len(self.units)
        self.H, self.t0 = float(H), float(t0)
        self.condition_scale = (1.0, self.H, self.H**2)
        self.perturbation, self.sensitivities = float(perturbation), sensitivities
        self.constant_sensitivities = sensitivities == "first-step"
        self.step_index = 0  # macro steps completed
        self.iterations = int(iterations)
        self._corrections = [0] * len(self.units)  # corrector integrations of each unit in this macro step
        self.C_pred = np.array(monomial_coefficients(self.pred_nodes), dtype=float)
        self.C_corr = np.array(monomial_coefficients(self.corr_nodes), dtype=float)
        self._scale = [c.force_sign if c.kind == "force" else 1.0 for c in self.couplings]
        self._start = [u.save() for u in self.units]  # the FMU states at T_N
        self._holds = ["start"] * n  # what each unit holds now: "start", id of an end array, or "scratch"
        self._ends = [{} for _ in range(n)]  # id(end) -> (end, FMU state) of this macro step's integrations
        self._committed = None
        self._clock, self._steps, self._kept = (self.t0, 0), None, None  # Checkpoints: T_N's origin, sizes, latest
        self._clusters = joined_clusters(graph, range(n))  # each unit is one body
        # the units' masses for the projection (a drive without its own position has no inertia there: its point
        # follows the joint)
        self._masses = np.array([0.0 if c.mass is None else float(c.mass) for c in self.couplings])
        self._corrector_rows: tuple = (None, None, None)  # (history, e_new, their corrector samples), the last
        self._drives = self._drive_entries()
        self.signal_columns = tuple(tuple(c) for c in signal_columns) if signal_columns else ((),) * n
        #: per unit, its connected outputs after its latest integration or re-evaluation (None: it has none)
        self.signal_values: list = [None] * n

    # -- time and the initial point -----------------------------------------------------------------
    @property
    def time(self) -> float:
        """``T_N``: the communication point the units stand at."""
        return self._clock[0] + (self.step_index - self._clock[1]) * self.H  # T_0 + N H while H is fixed

    def initial_state(self):
        """The units' positions and velocities after initialisation, ``(2, 2 n_dim)`` (a drive's point:
        :meth:`~icosim.problems.fmu.drives.DrivenPoints._start_points`)."""
        self._committed = np.stack(self._start_points())
        return self._committed

    def initial_history(self, e0=None):
        """The coupling history at ``T_0``: ``e0`` (zeros by default) at every past node, ``(k + 1, n_e)``."""
        e0 = np.zeros(self.n_coupling) if e0 is None else np.asarray(e0, dtype=float)
        return np.tile(e0, (self.k + 1, 1))

    def stand(self, i, e):
        """Unit ``i`` at the communication point ``T_N`` (its saved state restored where it holds another) with its
        input from the coupling variables ``e`` there (``(n_e,)``), as the outputs at ``T_N`` are read."""
        self._to_start(i)
        u = self._scale[i] * np.asarray(self.inputs(i, np.asarray(e, dtype=float)))
        if self._drives[i] is None:
            self.units[i].set(self.couplings[i].input_key, u)
        else:  # a drive's inputs: its point at T_N with the acceleration u
            self.units[i].set("drive", self._drive_values(i, *self._point(i), u.tolist()))

    # -- one unit integrated --------------------------------------------------------------------------
    def _to_start(self, i):
        if self._holds[i] != "start":
            self.units[i].restore(self._start[i])
            self._holds[i] = "start"

    def _check_state(self, state):
        if self._committed is not None and state is not self._committed:
            raise StepFailure(
                "an FMU problem advances only from the state it last returned or restored (its units' states live "
                "in the FMUs: restore a checkpoint to go back)"
            )

    def _integrate(self, i, U, C, final=False):
        """Unit ``i`` over ``[T_N, T_N+1]`` from its start, its input through the samples ``U`` (``(k+1, n_dim)``)
        with the monomial coefficients ``C``; returns its end ``(x, v)`` and outputs ``(1, 4, n_dim)``.  ``final``:
        the macro step will not integrate the unit again from ``T_N`` (the unit is told so)."""
        restore = None if self._holds[i] == "start" else self._start[i]
        coef = C @ U  # the input polynomial's monomial coefficients, rows m (connected inputs after the joints')
        self._holds[i] = "scratch"  # from here on: a refused call leaves the unit in no known state
        self.work.subsystem_integrations += 1
        if self._drives[i] is not None:
            return self._drive_step(i, coef.tolist(), self.H, self.step_index + 1, restore)
        n = self.n_dim
        key, u = self.couplings[i].input_key, self._scale[i] * coef
        if self.signal_columns[i]:
            key, u = "coupled", np.hstack([u[:, :n], coef[:, n:]])
        values = self.units[i].advance(
            key, u, self.time, self.H, step_index=self.step_index + 1, restore=restore, read=self._output_keys(i),
            final=final and self._kept is None,
        )  # fmt: skip
        self._read_signals(i)
        return self._outputs(i, np.add.reduce(coef[:, :n]), values)  # the input at T_N+1: u(1)

    def _read_signals(self, i):
        if "signal_output" in self.units[i].elements:
            self.signal_values[i] = self.units[i].get(("signal_output",)).ravel()

    def _output_keys(self, i):
        if self._drives[i] is not None:
            return self._drives[i][1] + ("reaction_force",)
        return _FORCE_OUTPUTS if self.couplings[i].kind == "force" else _KINEMATIC_OUTPUTS

    def _outputs(self, i, u1, values=None):
        """Unit ``i``'s end ``(x, v)`` and outputs ``(1, 4, n_dim)`` as it stands (``values``: as just read), its
        input ``u1`` at ``T_N+1``.  A unit that returns a value that is not finite for finite inputs is at fault
        (:class:`UnitStepError`)."""
        c, n = self.couplings[i], self.n_dim
        values = self.units[i].get(self._output_keys(i)) if values is None else np.asarray(values, dtype=float)
        values = values.ravel()
        y = np.empty(4 * n)
        if c.kind == "force":
            y[: 3 * n], y[3 * n :] = values, u1
        else:
            y[: 3 * n], y[3 * n :] = values[: 3 * n], c.force_sign * values[3 * n :]
        if not np.isfinite(y).all() and np.isfinite(u1).all() and not np.isfinite(values).all():
            self._not_finite(i, values.reshape(-1, n))
        end, y.shape = y[: 2 * n], (1, 4, n)  # the end: a view of the outputs' first two rows
        return end, y

    def _not_finite(self, i, values):
        unit = self.units[i]
        keys = _FORCE_OUTPUTS if self.couplings[i].kind == "force" else _KINEMATIC_OUTPUTS
        row, col = (int(j) for j in np.argwhere(~np.isfinite(values))[0])
        name = unit.elements[keys[row]][col].name if keys[row] in unit.elements else f"(prescribed) {keys[row]}"
        raise UnitStepError(
            f"unit {unit.label} returned {keys[row]} {name} = {float(values[row, col])!r} in macro step {self.step_index + 1} "
            f"(t = {self.time:.12g} s) although its input was finite{unit.said()}"
        )

    def _keep(self, i, end):
        """Save unit ``i``'s state as the one belonging to ``end`` (the macro step may finish with it)."""
        self._ends[i][id(end)] = (end, self.units[i].save())
        self._holds[i] = id(end)

    def _at_end(self, i, end, u1):
        """Unit ``i``'s outputs at its end state ``end`` with the input ``u1`` at ``T_N+1`` (no step)."""
        if self._holds[i] != id(end):
            self.units[i].restore(self._ends[i][id(end)][1])
            self._holds[i] = id(end)
        if self._drives[i] is not None:  # the point stands where the end state has it; its acceleration is u1
            return self._drive_outputs(i, list(end[: self.n_dim]), list(end[self.n_dim :]), list(u1))[1]
        self.units[i].set(self.couplings[i].input_key, self._scale[i] * np.asarray(u1))
        self._read_signals(i)
        return self._outputs(i, u1)[1]

    # -- the problem interface -------------------------------------------------------------------------
    def _samples(self, i, e_new, history):
        """Unit ``i``'s input samples: :meth:`inputs` of ``history`` (``e_new`` None) or of
        :meth:`corrector_samples`, ``(k + 1, n_dim)``, and the entries its connected inputs follow after them."""
        if e_new is None:
            rows = history[..., : self.k + 1, :]  # (a longer history's older samples take no part)
        else:  # the same for every unit of the macro step: formed once
            last_history, last_e, rows = self._corrector_rows
            if last_history is not history or last_e is not e_new:
                rows = self.corrector_samples(history, np.asarray(e_new, dtype=float))
                self._corrector_rows = (history, e_new, rows)
        U = np.asarray(self.inputs(i, rows), dtype=float)
        cols = self.signal_columns[i]
        return np.concatenate([U, np.asarray(rows, dtype=float)[..., cols]], axis=-1) if cols else U

    def predict(self, i, state, history, *, final=False, e_new=None):
        """Unit ``i`` with the extrapolation polynomials (``e_new`` given: the interpolation polynomials through it, a
        unit fed by a connection's new sample); its FMU state is saved only where the end is ``final`` (a unit that
        is corrected in the same stage ends at its corrector's state)."""
        self._check_state(state)
        C = self.C_pred if e_new is None else self.C_corr
        end, y = self._integrate(i, self._samples(i, e_new, history), C, final)
        if final:
            self._keep(i, end)
        return end, y

    def correct(self, i, state, history, e_new):
        """Unit ``i`` with the interpolation polynomials; the last corrector step's integration is final."""
        self._check_state(state)
        self._corrections[i] += 1
        final = self._corrections[i] >= self.iterations
        end, y = self._integrate(i, self._samples(i, e_new, history), self.C_corr, final)
        self._keep(i, end)
        return end, y

    def reevaluate(self, i, end, y, e_old, e_new):
        """Outputs at the fixed end state with the input at ``T_N+1`` set from ``e_new`` (``fmi2SetReal``, no step)."""
        return self._at_end(i, end, np.asarray(self.inputs(i, np.asarray(e_new, dtype=float)), dtype=float))

    def join(self, ends):
        """The macro step's end: each unit's FMU state of ``ends[i]`` becomes the next start; the rest are freed."""
        for i, end in enumerate(ends):
            kept = self._ends[i].pop(id(end))[1]
            for _, other in self._ends[i].values():
                self.units[i].free(other)
            self._ends[i].clear()
            self._free_start(i)
            self._start[i] = kept
            self._holds[i] = "start" if self._holds[i] == id(end) else "scratch"
        self.step_index += 1
        self._corrections = [0] * len(self.units)
        self._committed = np.array(ends)  # (units, 2 n_dim): np.stack's array
        return self._committed

    def sensitivity(self, i, state, history, e, end=None, y=None):
        """``dy_i/du_i`` by difference quotients from the outputs ``y`` at ``e``, ``(n_dim, 1, 4, n_dim)``: unit
        ``i`` repeats its corrector step with each input component perturbed at ``T_N+1`` (restored start state,
        one ``doStep`` each) or, at its fixed end state, is re-evaluated with it (no step)."""
        return self._sensitivity(i, history, e, end, y)[0]

    def output_sensitivities(self, i, state, history, e, y, signals):
        """:meth:`sensitivity` through the corrector step and, from the same steps, the derivatives of unit ``i``'s
        connected outputs by its inputs, ``(n_dim, n_outputs)`` from their values ``signals`` at ``e`` (None: it
        has none, and so is the second)."""
        return self._sensitivity(i, history, e, None, y, signals)

    def _sensitivity(self, i, history, e, end, y, signals=None):
        rows = self._samples(i, e, history)  # (k + 1, n_dim) and the connected inputs; row 0 at T_N+1
        u1 = rows[0, : self.n_dim]  # re-evaluated at the end state only where ``end`` is given
        h = self.perturbation * np.maximum(1.0, np.abs(u1))
        if y is not None:
            base = y
        else:
            base = self._at_end(i, end, u1) if end is not None else self._integrate(i, rows, self.C_corr)[1]
        out = np.empty((self.n_dim,) + base.shape)
        ds = None if signals is None else np.empty((self.n_dim, len(signals)))
        for c in range(self.n_dim):
            if end is not None:
                up = u1.copy()
                up[c] += h[c]
                yp = self._at_end(i, end, up)
            else:
                Up = rows.copy()  # the rows after the first are not changed
                Up[0, c] += h[c]
                yp = self._integrate(i, Up, self.C_corr)[1]
            out[c] = (yp - base) / h[c]
            if ds is not None:
                ds[c] = (self.signal_values[i] - signals) / h[c]
        return out, ds

    def project(self, state):
        """Mass-weighted projection of positions and velocities (Eq. 30), written into the units."""
        rows = mass_weighted_projection(self._clusters, self._masses, np.asarray(state, dtype=float))
        n = self.n_dim
        for i, unit in enumerate(self.units):
            self._to_start(i)
            if unit.projected_keys:  # one call; a drive's point without its outputs is the committed state
                parts = {"set_position": rows[i][:n], "set_velocity": rows[i][n:]}
                unit.set("projected", np.concatenate([parts[k] for k in unit.projected_keys]))
            self._free_start(i)
            self._start[i] = unit.save()
        self._committed = np.array(rows)
        return self._committed

    def close(self):
        """Free the saved states (the units themselves are closed by their owner)."""
        for i, unit in enumerate(self.units):
            for _, s in self._ends[i].values():
                unit.free(s)
            self._ends[i].clear()
            if self._start[i] is not None:
                self._free_start(i)
                self._start[i] = None
        self._release()
