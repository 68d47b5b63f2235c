"""Two FMU units as a co-simulation problem: what :func:`icosim.engine.macrostep.macro_step` needs of them.

The problem holds no method-, order- or scheme-specific code: every method, ``k`` and scheme runs through the
one macro step unchanged.  Each subsystem is a :class:`~icosim.problems.fmu.units.Unit`; its state at a communication
point lives inside the FMU, saved with ``fmi2GetFMUstate`` and restored before every integration that starts
there (docs/fmi.md).  The arrays the macro step sees are the observable part of it:

* state ``s[i] = (x_i, v_i)`` (position and velocity of unit ``i``'s joint point, SI units; with ``n_d``
  components each -- one for a point on a line, two for a joint in the plane -- ``s[i]`` has ``2 n_d``
  entries, the positions first);
* coupling variables ``e``: those of the decomposition in SI units (``lambda_c`` in N, ``a_tilde`` in m/s^2),
  ``n_d`` components each;
* outputs ``y[i] = (x_i, v_i, a_i, f_i)`` at ``T_N+1``, shape ``(4, n_d)``, with ``f_i`` the coupling force as
  seen by unit ``i`` in the units of ``lambda_c``: the input for a force-driven unit,
  ``force_sign * reaction_force`` for a kinematically driven one.

The constraint residuals are those of the engine's dimensionless setting (``g``, ``H g'``, ``H^2 g''``), so the
method parameters mean what they mean for the built-in models (:func:`icosim.engine.methods.engine_method`).
"""

from __future__ import annotations

import numpy as np

from ...engine.lagrange import monomial_coefficients
from ...engine.problem import CosimulationProblem
from ...engine.residuals import coupling_conditions
from ...errors import StepFailure
from .errors import UnitStepError

__all__ = ["FmuCosimulation", "Coupling"]

_FORCE_OUTPUTS = ("position", "velocity", "acceleration")
_KINEMATIC_OUTPUTS = ("position", "velocity", "acceleration", "reaction_force")


class Coupling:
    """How one unit is coupled: its kind (``"force"`` or ``"kinematic"``), the sign of the coupling force on it,
    its mass for the projection (None: the scene does not project), whether its coupling output follows its
    input without a step, and how much (measured: :func:`icosim.problems.fmu.inspection.inspect_unit`)."""

    def __init__(self, kind, force_sign, mass=None, feedthrough=True, gain=float("nan")):
        self.kind, self.force_sign, self.mass = kind, float(force_sign), mass
        self.feedthrough = bool(feedthrough)
        #: the coupling output's response to the unit's input (measured), whose sign is the unit's convention
        self.gain = float(gain)

    @property
    def input_key(self):
        return "force" if self.kind == "force" else "acceleration_input"


class FmuCosimulation(CosimulationProblem):
    """Two FMU units coupled by a rigid joint (decompositions ff, fd, df, dd).

    Parameters
    ----------
    units : two :class:`~icosim.problems.fmu.units.Unit`, opened at ``t0``.
    couplings : two :class:`Coupling`, the kinds matching the decomposition's.
    decomposition, k : as for every problem.
    H : macro-step size in s.
    t0 : start time.
    perturbation : the sensitivities are difference quotients with the step ``perturbation * max(1, |e_j|)``
        (exact up to rounding for linear units).
    sensitivities : ``"each-step"`` (recomputed every macro step) or ``"first-step"`` (computed once and kept:
        exact for linear units, whose sensitivities are constant).
    """

    def __init__(
        self,
        units,
        couplings,
        decomposition,
        k,
        H,
        *,
        t0=0.0,
        perturbation=1e-3,
        sensitivities="each-step",
    ):
        super().__init__(decomposition, k)
        self.units, self.couplings = tuple(units), tuple(couplings)
        dims = {len(u.elements["position"]) for u in self.units}
        if len(dims) != 1:
            raise ValueError("both units must name as many position components")
        #: components of the joint's position (1: a point on a line; 2: a joint in the plane)
        self.n_dim = dims.pop()
        for i, (c, kind) in enumerate(zip(self.couplings, self.decomposition.kinds)):
            if c.kind != kind:
                raise ValueError(f"unit {self.units[i].label} is {c.kind}-driven, decomposition needs {kind}")
        self.H, self.t0 = float(H), float(t0)
        self.perturbation, self.sensitivities = float(perturbation), sensitivities
        self.step_index = 0  # macro steps completed
        self.C_pred = np.array(monomial_coefficients(self.pred_nodes), dtype=float)
        self.C_corr = np.array(monomial_coefficients(self.corr_nodes), dtype=float)
        self._start = [u.save() for u in self.units]  # the FMU states at T_N
        self._holds = ["start", "start"]  # what each unit holds now: "start", id of an end array, or "scratch"
        self._ends = [{}, {}]  # id(end) -> (end, FMU state) of this macro step's integrations
        self._jac = {}
        self._committed = None

    @property
    def n_coupling(self) -> int:
        """Coupling variables per time point: the decomposition's, ``n_dim`` components each."""
        return self.decomposition.n_coupling * self.n_dim

    def _inputs(self, i):
        """The components of ``e`` that drive unit ``i``."""
        j = self.decomposition.inputs[i]
        return slice(j * self.n_dim, (j + 1) * self.n_dim)

    # -- time and the initial point -----------------------------------------------------------------
    @property
    def time(self) -> float:
        """``T_N``: the communication point the units stand at."""
        return self.t0 + self.step_index * self.H

    def initial_state(self):
        """The units' positions and velocities after initialisation, ``(2, 2 n_dim)``."""
        self._committed = np.stack([u.get(("position", "velocity")).ravel() for u in self.units])
        return self._committed

    def initial_history(self, e0=None):
        """The coupling history at ``T_0``: ``e0`` (zeros by default) at every past node, ``(k + 1, n_e)``."""
        e0 = np.zeros(self.n_coupling) if e0 is None else np.asarray(e0, dtype=float)
        return np.tile(e0, (self.k + 1, 1))

    def consistent_coupling(self, *, iterations: int = 4) -> np.ndarray:
        """The coupling variables at ``T_0`` that meet the joint's condition on the acceleration level and the
        balance of the drives' forces, from the units at their start (SI, ``(n_e,)``).

        Newton steps on those conditions as functions of ``e``, with difference quotients as the corrector
        takes them: a unit whose coupling output follows its input is read at once with the input set; one
        whose output follows only through a step is stepped with the input held over ``H`` and ``2 H`` from
        its start, and the two outputs are extrapolated to ``T_0`` (second order in ``H``).  Linear units need
        one step.  The units are left at their start."""
        e = np.zeros(self.n_coupling)
        starts = [self._start_outputs(i) for i in range(2)]
        for _ in range(iterations):
            r0 = self._start_conditions(e, starts)
            if not r0.size:
                break
            h = self.perturbation * np.maximum(1.0, np.abs(e))
            J = np.empty((r0.size, self.n_coupling))
            for j in range(self.n_coupling):
                ep = e.copy()
                ep[j] += h[j]
                J[:, j] = (self._start_conditions(ep, starts) - r0) / h[j]
            de = np.linalg.lstsq(J, -r0, rcond=None)[0]
            e = e + de
            if np.max(np.abs(de)) <= 1e-13 * max(1.0, np.max(np.abs(e))):
                break
        return e

    def _start_outputs(self, i):
        """Unit ``i``'s position and velocity at ``T_0``, ``(2, n_dim)``."""
        self._to_start(i)
        return self.units[i].get(("position", "velocity"))

    def _start_conditions(self, e, starts):
        """The acceleration-level constraint and the force balance at ``T_0`` with the coupling variables ``e``."""
        ys = []
        for i in range(2):
            c, u = self.couplings[i], e[self._inputs(i)]
            xv = starts[i]
            if c.feedthrough:
                self._to_start(i)
                self.units[i].set(c.input_key, (c.force_sign if c.kind == "force" else 1.0) * u)
                y = self._outputs(i, u)[1]
            else:
                y = 2 * self._held_step(i, u, self.H) - self._held_step(i, u, 2 * self.H)
            y[:2] = xv  # the state at T_0 as it is
            ys.append(y)
        r = self.residuals(np.stack(ys))
        return np.concatenate([r["acc"].ravel(), r["force"].ravel()])

    def _held_step(self, i, u, h):
        """Unit ``i``'s outputs after a step of ``h`` from its start with the input held at ``u``."""
        self._to_start(i)
        c = self.couplings[i]
        self.units[i].step(c.input_key, [(c.force_sign if c.kind == "force" else 1.0) * u], self.time, h, step_index=0)
        self._holds[i] = "scratch"
        return self._outputs(i, u)[1]

    # -- one unit integrated --------------------------------------------------------------------------
    def _to_start(self, i):
        if self._holds[i] != "start":
            self.units[i].restore(self._start[i])
            self._holds[i] = "start"

    def _check_state(self, state):
        if self._committed is not None and state is not self._committed:
            raise StepFailure(
                "an FMU problem advances only from the state it last returned (its units' states live in the FMUs)"
            )

    def _integrate(self, i, samples, C):
        """Unit ``i`` over ``[T_N, T_N+1]`` from its start, the input through ``samples`` (``(k+1, n_e)``) with
        the monomial coefficients ``C``; returns its end ``(x, v)`` and outputs ``(x, v, a, f)``."""
        self._to_start(i)
        unit, c = self.units[i], self.couplings[i]
        coef = C @ samples[:, self._inputs(i)]  # (k + 1, n_dim)
        scale = c.force_sign if c.kind == "force" else 1.0
        unit.step(c.input_key, scale * coef, self.time, self.H, step_index=self.step_index + 1)
        self.work.subsystem_integrations += 1
        self._holds[i] = "scratch"
        return self._outputs(i, coef.sum(axis=0))

    def _outputs(self, i, u1):
        """Unit ``i``'s end ``(x, v)`` and outputs ``(x, v, a, f)`` as it stands, its input ``u1`` at ``T_N+1``.
        A unit that returns a value that is not finite for finite inputs is at fault (:class:`UnitStepError`)."""
        c = self.couplings[i]
        if c.kind == "force":
            x, v, a = values = self.units[i].get(_FORCE_OUTPUTS)
            f = np.broadcast_to(np.asarray(u1, dtype=float), x.shape)
        else:
            x, v, a, r = values = self.units[i].get(_KINEMATIC_OUTPUTS)
            f = c.force_sign * r
        if not np.isfinite(values).all() and np.isfinite(u1).all():
            self._not_finite(i, values)
        return np.concatenate([x, v]), np.stack([x, v, a, f])

    def _not_finite(self, i, values):
        unit = self.units[i]
        keys = _FORCE_OUTPUTS if self.couplings[i].kind == "force" else _KINEMATIC_OUTPUTS
        row, col = (int(j) for j in np.argwhere(~np.isfinite(values))[0])
        name = unit.elements[keys[row]][col].name
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
        c = self.couplings[i]
        self.units[i].set(c.input_key, (c.force_sign if c.kind == "force" else 1.0) * u1)
        return self._outputs(i, u1)[1]

    # -- the problem interface -------------------------------------------------------------------------
    def predict(self, i, state, history, *, final=False):
        self._check_state(state)
        end, y = self._integrate(i, history, self.C_pred)
        self._keep(i, end)
        return end, y

    def correct(self, i, state, history, e_new):
        self._check_state(state)
        end, y = self._integrate(i, self.corrector_samples(history, e_new), self.C_corr)
        self._keep(i, end)
        return end, y

    def reevaluate(self, i, end, y, e_old, e_new):
        """Outputs at the fixed end state with the input at ``T_N+1`` set to ``e_new`` (``fmi2SetReal``, no step)."""
        return self._at_end(i, end, np.asarray(e_new, dtype=float)[self._inputs(i)])

    def join(self, ends):
        """The macro step's end: each unit's FMU state of ``ends[i]`` becomes the next start; the rest are freed."""
        for i, end in enumerate(ends):
            kept = self._ends[i].pop(id(end))[1]
            for _, other in self._ends[i].values():
                self.units[i].free(other)
            self._ends[i].clear()
            self.units[i].free(self._start[i])
            self._start[i] = kept
            self._holds[i] = "start" if self._holds[i] == id(end) else "scratch"
        self.step_index += 1
        self._committed = np.stack(ends)
        return self._committed

    def stack(self, ys):
        return np.stack(ys)

    def residuals(self, y):
        """Joint constraint on three levels (``g``, ``H g'``, ``H^2 g''``) and force balance, unit 1 minus unit 2
        (:func:`icosim.engine.residuals.coupling_conditions`)."""
        return coupling_conditions(y, self.decomposition, scale=(1.0, self.H, self.H**2))

    def jacobians(self, state, history, e, y, fixed=(None, None), algebraic=True):
        """``d residuals / d e_N+1`` by difference quotients: a unit that is corrected repeats its corrector step
        with the perturbed input (restored start state, one ``doStep`` per coupling variable driving it); a
        finished (leading) unit is re-evaluated at its end state with the perturbed input (no step)."""
        key = tuple("full" if f is None else "algebraic" if algebraic else "none" for f in fixed)
        if self.sensitivities == "first-step" and key in self._jac:
            return self._jac[key]
        e = np.asarray(e, dtype=float)
        h = self.perturbation * np.maximum(1.0, np.abs(e))
        r0 = self.residuals(y)
        jac = {name: np.zeros(val.shape + (self.n_coupling,)) for name, val in r0.items()}
        for j in range(self.n_coupling):
            yj = np.array(y, dtype=float, copy=True)
            for i in range(2):
                if j not in range(self.n_coupling)[self._inputs(i)] or key[i] == "none":
                    continue
                ep = e.copy()
                ep[j] += h[j]
                if key[i] == "full":
                    yj[i] = self._integrate(i, self.corrector_samples(history, ep), self.C_corr)[1]
                else:
                    yj[i] = self._at_end(i, fixed[i], ep[self._inputs(i)])
            for name, val in self.residuals(yj).items():
                jac[name][..., j] = (val - r0[name]) / h[j]
        self._jac[key] = jac
        return jac

    def project(self, state):
        """Mass-weighted projection of positions and velocities (Eq. 30), written into the units."""
        m = np.array([c.mass for c in self.couplings], dtype=float)
        xv = (m[0] * state[0] + m[1] * state[1]) / m.sum()
        n = self.n_dim
        for i, unit in enumerate(self.units):
            self._to_start(i)
            unit.set("set_position", xv[:n])
            unit.set("set_velocity", xv[n:])
            unit.free(self._start[i])
            self._start[i] = unit.save()
        self._committed = np.stack([xv, xv])
        return self._committed

    def close(self):
        """Free the saved states (the units themselves are closed by their owner)."""
        for i, unit in enumerate(self.units):
            for _, s in self._ends[i].values():
                unit.free(s)
            self._ends[i].clear()
            if self._start[i] is not None:
                unit.free(self._start[i])
                self._start[i] = None
