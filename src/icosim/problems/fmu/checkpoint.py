"""The FMU problem's checkpoint and its macro step of varying size (the problem contract: docs/engine.md).

:class:`~icosim.problems.fmu.problem.FmuCosimulation` keeps each unit's state at ``T_N`` inside its FMU, saved
(``_start``: ``fmi2GetFMUstate``, or a Model Exchange unit's continuous states, time and inputs), with what each
unit holds now (``_holds``) and the states saved within the macro step (``_ends``).  A checkpoint holds the saved
states at ``T_N`` themselves -- no FMI call, no copy -- with the step count, the time's origin, the step sizes set
and the state returned at ``T_N``; :meth:`~Checkpoints.restore` makes them the start again.  The problem keeps
only its latest checkpoint: taking one frees the states of the one before, and the macro step's end does not free
a start that the kept checkpoint holds.  While one is kept no unit is told that its step is final (doStep's
``noSetFMUStatePriorToCurrentPoint``): a restore may follow.  The units of
:class:`~icosim.problems.fmu.signals.SignalCosimulation` stand at ``T_N`` between macro steps: its checkpoint
(:class:`SignalCheckpoints`) saves their states there when it is taken.  Both change their step's size by
:class:`MacroStepSizes`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...engine.lagrange import variable_step_polynomials
from ...errors import StepFailure

__all__ = ["Checkpoints", "FmuCheckpoint", "MacroStepSizes", "SignalCheckpoints"]


@dataclass(frozen=True)
class FmuCheckpoint:
    """:meth:`Checkpoints.checkpoint`: the step count ``N``, the time's origin ``(T, N')`` (``T_N = T + (N - N')
    H``), the step sizes set (None: those of the problem's start), ``H``, the state returned at ``T_N`` and each
    unit's saved state there."""

    step_index: int
    clock: tuple
    steps: tuple | None
    H: float
    state: object
    starts: tuple


class MacroStepSizes:
    """:meth:`set_macro_step` of the FMU problems, on their ``step_index``, ``_clock`` (``T_N = T + (N - N') H``),
    ``_steps`` and ``H``; the conditions' scale follows ``H`` where the problem scales its conditions."""

    def set_macro_step(self, H, past_steps=None):
        """Size ``H`` of the next macro step and the sizes ``H_N-1, ..., H_N-k`` of the past ones (newest first;
        None: equal steps), as the pendulum's
        (:meth:`icosim.problems.pendulum.problem.PendulumCosimulation.set_macro_step`): the extrapolation and
        interpolation polynomials through the actual nodes (:func:`icosim.engine.lagrange.variable_step_polynomials`),
        the conditions' scale ``(1, H, H^2)``; the kept Jacobians belong to the old step and are formed again."""
        H, past, w_pred, C_pred, C_corr = variable_step_polynomials(H, past_steps, self.k)
        steps = (H, tuple(past))
        if steps == self._steps:
            return
        self._clock = (self.time, self.step_index)  # the time from here on: T_N + (N' - N) H
        self._steps, self.H = steps, H
        self.w_pred, self.C_pred, self.C_corr = w_pred, np.asarray(C_pred, dtype=float), np.asarray(C_corr, dtype=float)
        if self.condition_scale is not None:
            self.condition_scale = (1.0, H, H**2)
        self._jacobians.clear()


class Checkpoints(MacroStepSizes):
    """The checkpoint of :class:`~icosim.problems.fmu.problem.FmuCosimulation` (module docstring), on its ``units``,
    ``_start``, ``_holds``, ``_ends``, ``_committed``, ``step_index``, ``_clock``, ``_steps`` and ``_kept``."""

    def checkpoint(self):
        """The problem at ``T_N``, between macro steps (module docstring)."""
        if any(self._ends):
            raise StepFailure("an FMU problem takes a checkpoint between macro steps, not within one")
        kept = FmuCheckpoint(self.step_index, self._clock, self._steps, self.H, self._committed, tuple(self._start))
        self._release()
        self._kept = kept
        return kept

    def restore(self, checkpoint):
        """Back to ``checkpoint``, the latest one taken (an older one's states are freed): the units' saved states
        at its ``T_N`` become their start again; the states saved since are freed."""
        if checkpoint is not self._kept:
            raise StepFailure(
                "an FMU problem restores only its latest checkpoint (the saved states of an older one are freed)"
            )
        for i, unit in enumerate(self.units):
            for _, other in self._ends[i].values():
                unit.free(other)
            self._ends[i].clear()
            if self._start[i] is not checkpoint.starts[i]:
                unit.free(self._start[i])
                self._start[i] = checkpoint.starts[i]
                self._holds[i] = "scratch"  # the unit stands wherever the steps since left it
            elif self._holds[i] != "start":
                self._holds[i] = "scratch"
        steps = checkpoint.steps or (checkpoint.H, (checkpoint.H,) * self.k)
        if self._steps is not None and steps != self._steps:
            self.set_macro_step(*steps)
        self.step_index, self._clock, self._committed = checkpoint.step_index, checkpoint.clock, checkpoint.state
        self._corrections = [0] * len(self.units)

    def _free_start(self, i):
        """Free unit ``i``'s saved start unless the kept checkpoint holds it."""
        if self._kept is None or self._kept.starts[i] is not self._start[i]:
            self.units[i].free(self._start[i])

    def _release(self):
        """Free the kept checkpoint's saved states that are not the units' start."""
        kept, self._kept = self._kept, None
        if kept is not None:
            for i, unit in enumerate(self.units):
                if kept.starts[i] is not None and kept.starts[i] is not self._start[i]:
                    unit.free(kept.starts[i])


class SignalCheckpoints(MacroStepSizes):
    """The checkpoint of :class:`~icosim.problems.fmu.signals.SignalCosimulation`, whose units stand at ``T_N``
    between macro steps and hold their states there: a checkpoint saves each unit's state at ``T_N``
    (``fmi2GetFMUstate``, or a Model Exchange unit's states), :meth:`restore` sets them again.  As the joint
    problem's, only the latest is kept, and while one is kept no unit is told that its step is final (on its
    ``units``, ``step_index``, ``_clock``, ``_steps``, ``H`` and ``_kept``)."""

    def checkpoint(self):
        """The problem at ``T_N``, between macro steps: every unit's state saved."""
        self._release()
        self._kept = FmuCheckpoint(self.step_index, self._clock, self._steps, self.H, None,
                                   tuple(unit.save() for unit in self.units))  # fmt: skip
        return self._kept

    def restore(self, checkpoint):
        """Back to ``checkpoint``, the latest one taken: each unit's state at its ``T_N`` set again."""
        if checkpoint is not self._kept:
            raise StepFailure("an FMU problem restores only its latest checkpoint (the saved states of an older one "
                              "are freed)")  # fmt: skip
        for unit, saved in zip(self.units, checkpoint.starts):
            unit.restore(saved)
        steps = checkpoint.steps or (checkpoint.H, (checkpoint.H,) * self.k)
        if self._steps is not None and steps != self._steps:
            self.set_macro_step(*steps)
        self.step_index, self._clock = checkpoint.step_index, checkpoint.clock

    def _release(self):
        """Free the kept checkpoint's saved states."""
        kept, self._kept = self._kept, None
        if kept is not None:
            for unit, saved in zip(self.units, kept.starts):
                unit.free(saved)
