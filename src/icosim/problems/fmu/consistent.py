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
        whose output follows only through a step is stepped with the input held over ``H`` and ``2 H`` from
        its start, and the two outputs are extrapolated to ``T_0`` (second order in ``H``).  Linear units need
        one step.  The units are left at their start."""
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
                y = 2 * self._held_step(i, u, self.H) - self._held_step(i, u, 2 * self.H)
            y[0, :2] = starts[i]  # the state at T_0 as it is
            ys.append(y)
        r = self.residuals(self.stack(ys), e, conditions)
        return np.concatenate([r["acc"].ravel(), r["force"].ravel()])

    def _held_step(self, i, u, h):
        """Unit ``i``'s outputs after a step of ``h`` from its start with the input held at ``u``."""
        self._to_start(i)
        if self._drives[i] is not None:
            self._holds[i] = "scratch"
            return self._drive_step(i, [np.asarray(u, dtype=float).tolist()], h, 0)[1]
        self.units[i].step(self.couplings[i].input_key, [self._scale[i] * u], self.time, h, step_index=0)
        self._holds[i] = "scratch"
        return self._outputs(i, np.asarray(u, dtype=float).tolist())[1]
