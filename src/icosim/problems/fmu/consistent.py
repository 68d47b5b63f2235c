"""The consistent initial coupling of an FMU problem: the coupling variables at ``T_0`` that meet the joints'
conditions on the acceleration level and the drives' force balances, from the units at their start.  A mixin of
:class:`~icosim.problems.fmu.problem.FmuCosimulation` (it uses the problem's units, inputs and residuals)."""

from __future__ import annotations

import numpy as np

from ...engine.residuals import Conditions

__all__ = ["ConsistentStart"]


class ConsistentStart:
    """:meth:`consistent_coupling`, for :class:`~icosim.problems.fmu.problem.FmuCosimulation`."""

    def consistent_coupling(self, *, iterations: int = 4) -> np.ndarray:
        """The coupling variables at ``T_0`` that meet the joints' conditions on the acceleration level and the
        balance of the drives' forces, from the units at their start (SI, ``(n_e,)``).

        Newton steps on those conditions as functions of ``e``, with difference quotients as the corrector
        takes them: a unit whose coupling output follows its input is read at once with the input set; one
        whose output follows only through a step is stepped with the input held over ``h`` and ``2 h`` from
        its start, and the two outputs are extrapolated to ``T_0`` (second order in ``h``).  Its outputs at
        ``T_0`` are the limit ``h -> 0`` of that extrapolation: ``h`` starts at ``H`` and is halved until two
        extrapolations agree (:meth:`_start_step`), since a unit may report outputs a step gives that are not
        smooth in the step's size (e.g. a force computed from the state at the start of its solver's last
        internal step: lagging by that step, whose size jumps where ``h`` passes the solver's step).  Linear
        units need one step.  The units are left at their start."""
        self._start_h = [None] * len(self.units)
        e = np.zeros(self.n_coupling)
        starts = [self._start_outputs(i) for i in range(len(self.units))]
        conditions = Conditions(self.graph, range(self.graph.n_joints), range(len(self.units)))
        for _ in range(iterations):
            r0 = self._start_conditions(e, starts, conditions)
            if not r0.size:
                break
            h = self.perturbation * np.maximum(1.0, np.abs(e))
            J = np.empty((r0.size, self.n_coupling))
            for j in range(self.n_coupling):
                ep = e.copy()
                ep[j] += h[j]
                J[:, j] = (self._start_conditions(ep, starts, conditions) - r0) / h[j]
            de = np.linalg.lstsq(J, -r0, rcond=None)[0]
            e = e + de
            if np.max(np.abs(de)) <= 1e-13 * max(1.0, np.max(np.abs(e))):
                break
        return e

    def coupling_rate(self, e0) -> np.ndarray:
        """The rate ``e'`` of the coupling variables at ``T_0`` (SI per s, ``(n_e,)``) on the start ``e0``: the
        time derivative of the conditions :meth:`consistent_coupling` meets, ``R_t + J e' = 0``, with ``J`` their
        Jacobian in ``e`` at ``e0`` and ``R_t`` their rate with ``e`` held (each unit's outputs along held steps of
        ``h``, ``2 h`` and ``3 h`` from its start, the slope of their quadratic at ``T_0``; ``h`` a sixteenth of
        the step of the start's extrapolation).  A history
        ``e0 - m H e'`` before ``T_0`` is then the solution's to first order (a held one only to zeroth order).
        The units are left at their start."""
        e0 = np.asarray(e0, dtype=float)
        if getattr(self, "_start_h", None) is None:
            self._start_h = [None] * len(self.units)
        starts = [self._start_outputs(i) for i in range(len(self.units))]
        conditions = Conditions(self.graph, range(self.graph.n_joints), range(len(self.units)))
        r0 = self._start_conditions(e0, starts, conditions)
        if not r0.size:
            return np.zeros(self.n_coupling)
        h = self.perturbation * np.maximum(1.0, np.abs(e0))
        J = np.empty((r0.size, self.n_coupling))
        for j in range(self.n_coupling):
            ep = e0.copy()
            ep[j] += h[j]
            J[:, j] = (self._start_conditions(ep, starts, conditions) - r0) / h[j]
        ys, slopes = [], []
        for i in range(len(self.units)):
            u = self.inputs(i, e0)
            step = (self._start_h[i] or self.H) / 16  # the slope's error falls as step^2, rounding's as 1/step
            y1, y2, y3 = (self._held_step(i, u, m * step) for m in (1, 2, 3))
            slope = (-2.5 * y1 + 4.0 * y2 - 1.5 * y3) / step
            y0 = 3 * y1 - 3 * y2 + y3
            slope[0, :2] = 0.0  # the state at T_0 as it is
            y0[0, :2] = starts[i]
            ys.append(y0)
            slopes.append(slope)
        self._to_start_all()
        at = self.stack(ys)
        r_at = self.residuals(at, e0, conditions)
        r_on = self.residuals(at + self.stack(slopes), e0, conditions)  # the conditions are affine in the outputs
        rate = np.concatenate([(r_on[key] - r_at[key]).ravel() for key in ("acc", "force")])
        return np.linalg.lstsq(J, -rate, rcond=None)[0]

    def _to_start_all(self):
        for i in range(len(self.units)):
            self._to_start(i)

    def _start_outputs(self, i):
        """Unit ``i``'s position and velocity at ``T_0``, ``(2, n_dim)``."""
        self._to_start(i)
        if self._drives[i] is not None:
            return np.asarray(self._committed[i], dtype=float).reshape(2, self.n_dim)
        return self.units[i].get(("position", "velocity"))

    def _start_conditions(self, e, starts, conditions):
        """The acceleration-level constraints and the force balances at ``T_0`` with the coupling variables ``e``."""
        ys = []
        for i, c in enumerate(self.couplings):
            u = self.inputs(i, e)
            if c.feedthrough and self._drives[i] is not None:
                y = self._drive_at_start(i, starts[i], u)
            elif c.feedthrough:
                self._to_start(i)
                self.units[i].set(c.input_key, self._scale[i] * u)
                y = self._outputs(i, np.asarray(u, dtype=float).tolist())[1]
            else:
                y = self._start_step(i, u)
            y[0, :2] = starts[i]  # the state at T_0 as it is
            ys.append(y)
        r = self.residuals(self.stack(ys), e, conditions)
        return np.concatenate([r["acc"].ravel(), r["force"].ravel()])

    def _start_step(self, i, u, *, rtol: float = 1e-9, halvings: int = 40):
        """Unit ``i``'s outputs at ``T_0`` with the input ``u``, extrapolated from held steps of ``h`` and ``2 h``
        (``2 y(h) - y(2 h)``); ``h`` is found at the first call: from ``H``, halved until the extrapolated
        acceleration and force agree with those of twice the step within ``rtol`` of the larger of 1 and their
        size (a smooth unit converges as ``h^2``), then kept for the Newton steps."""
        h = self._start_h[i]
        if h is not None:
            return 2 * self._held_step(i, u, h) - self._held_step(i, u, 2 * h)
        h = self.H
        wide = self._held_step(i, u, 2 * h)
        narrow = self._held_step(i, u, h)
        y = 2 * narrow - wide
        best = (h, y)  # the step and its extrapolation kept; without agreement, the smallest step's
        for _ in range(halvings):
            if h / 2 <= 1e-12 * max(1.0, abs(self.time)):  # a step the clock can no longer tell from none
                break
            h /= 2
            wide, narrow = narrow, self._held_step(i, u, h)
            y_half = 2 * narrow - wide
            scale = max(1.0, float(np.max(np.abs(y_half[0, 2:]))))
            if float(np.max(np.abs(y_half[0, 2:] - y[0, 2:]))) <= rtol * scale:
                # where the first halving already agrees, the step stays H: a smooth unit starts as it did
                best = (2 * h, y) if 2 * h == self.H else (h, y_half)
                break
            y = y_half
            best = (h, y)
        self._start_h[i] = best[0]
        return best[1]

    def _held_step(self, i, u, h):
        """Unit ``i``'s outputs after a step of ``h`` from its start with the input held at ``u``."""
        self._to_start(i)
        if self._drives[i] is not None:
            self._holds[i] = "scratch"
            return self._drive_step(i, [np.asarray(u, dtype=float).tolist()], h, 0)[1]
        self.units[i].step(self.couplings[i].input_key, [self._scale[i] * u], self.time, h, step_index=0)
        self._holds[i] = "scratch"
        return self._outputs(i, np.asarray(u, dtype=float).tolist())[1]
