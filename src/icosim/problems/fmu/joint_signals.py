"""FMU units joined by rigid joints beside units coupled by signal connections: one co-simulation problem of both
kinds of condition (docs/signals.md, "Joints beside connections").

A unit in a joint (its port's position, velocity, acceleration and force:
:class:`~icosim.problems.fmu.problem.FmuCosimulation`) may also give and take connections' values; a unit in no
joint takes part in connections only (:class:`~icosim.problems.fmu.signals.SignalCosimulation`).  The graph holds
both, the joints' coupling variables first, then one per connection.  :class:`JointSignalCosimulation` is the signal
problem of every unit whose joint units are served by the FMU problem of the joints alone (the same joints, so the
same entries of ``e``), handed the whole ``e``: a joint unit's connected inputs follow their entries
(``signal_columns``) in the same step as its coupling input, and its connected outputs are read after each of its
integrations.

The arrays the macro step sees: a joint unit's outputs are :class:`JointOutputs` (its port's, ``(1, 4, n_d)``, and its
connected outputs), a signal unit's its connected outputs; :meth:`JointSignalCosimulation.stack` gives the joint
units' ports.  The state is the joint units' ``(x, v)`` (flattened, units in order) followed by the signal units'
outputs.

At ``t0`` the connections' values are those the units give as they open (handed from outputs to inputs until they
settle, before the joint units' states are first saved); the joints' coupling variables then follow from the joint
problem's consistent start, the units' connected inputs holding those values.  An algebraic loop of connections is
refused (its solver steps no joint).

Coupled implicitly, every joint unit is stepped again at the last stage with the joints' and the connections'
variables (:mod:`icosim.engine.joint_signal_conditions`), so none of its steps is final before the macro step's end,
and :meth:`JointSignalCosimulation.output_sensitivities` gives the corrector's Jacobian the joint units' connected
outputs by their coupling inputs from the same perturbed steps as their port outputs.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ...engine.graph import CouplingGraph, Joint
from ...engine.problem import CosimulationProblem
from ...errors import ParameterError, StepFailure
from .problem import FmuCosimulation
from .signals import SignalCosimulation

__all__ = ["JointOutputs", "JointSignalCosimulation"]

#: Corrector steps the joint problem counts before one is final, coupled implicitly: none is (Newton's iterations
#: and the Jacobian's perturbed steps may follow any of them).
NEVER_FINAL = 2**62


class JointOutputs(NamedTuple):
    """A joint unit's outputs: its port's ``(1, 4, n_d)`` and its connected outputs (None: it has none)."""

    ports: np.ndarray
    signals: np.ndarray | None


class JointSignalCosimulation(SignalCosimulation):
    """``units`` (every unit, in the scene's order, opened with their connected inputs and outputs) joined by
    ``joints`` (:class:`~icosim.engine.graph.Joint` s by the units' indices) and coupled by ``connections``.

    Parameters
    ----------
    couplings : the :class:`~icosim.problems.fmu.problem.Coupling` of each joint unit, in the units' order.
    n_dim : components of a joint.
    inputs, outputs, connections, k, H, t0, implicit : as :class:`~icosim.problems.fmu.signals.SignalCosimulation`.
    perturbation, sensitivities, iterations : as :class:`~icosim.problems.fmu.problem.FmuCosimulation`.
    """

    def __init__(self, units, couplings, joints, n_dim, inputs, outputs, connections, k, H, *, t0=0.0,
                 implicit=False, perturbation=1e-3, sensitivities="each-step", iterations=1):  # fmt: skip
        super().__init__(units, inputs, outputs, connections, k, H, t0=t0, implicit=implicit, joints=joints,
                         n_components=n_dim)  # fmt: skip
        if self.loops is not None:
            raise ParameterError(
                f"the connections {', '.join(self.label(c) for c in self.loops.loop)} form an algebraic loop, which "
                "a scene of joints and connections does not solve: break the loop (an output that depends on its "
                "input only through a step), or couple every unit by connections"
            )
        #: the units in a joint, in order, and each one's index in the joint problem
        self.joint_units = tuple(sorted({i for jt in joints for i in (jt.first, jt.second)}))
        self._where = {i: j for j, i in enumerate(self.joint_units)}
        self.signal_units = tuple(i for i in range(len(self.units)) if i not in self._where)
        #: the connections' values at t0, settled before the joint units' states are saved
        self.settled = SignalCosimulation.initial_history(self)[0]
        where = self._where
        graph = CouplingGraph(len(self.joint_units), [Joint(where[jt.first], where[jt.second], jt.decomposition)
                                                      for jt in joints], n_dim,
                              names=tuple(self.graph.names[i] for i in self.joint_units))  # fmt: skip
        columns = [[col for _, col in self.graph.signal_inputs(i)] for i in self.joint_units]
        #: the joint units' problem (:class:`~icosim.problems.fmu.problem.FmuCosimulation`), the same joints
        self.joints = FmuCosimulation([self.units[i] for i in self.joint_units], couplings, graph, k, H, t0=t0,
                                      perturbation=perturbation, sensitivities=sensitivities,
                                      iterations=NEVER_FINAL if implicit else iterations,
                                      signal_columns=columns)  # fmt: skip
        self.condition_scale = self.joints.condition_scale
        self.constant_sensitivities = self.joints.constant_sensitivities
        self._joint_state = None  # what the joint problem last returned: the state it advances from
        self._signal_ends: list = [self.outputs(i) for i in self.signal_units]

    # -- the start -------------------------------------------------------------------------------------
    def begin(self, state, history):
        """The state and coupling history at ``t0`` from the joint problem's start (its ``state`` and ``history``,
        :func:`~icosim.problems.fmu.run.consistent_start`) and the connections' settled values."""
        self._joint_state = state
        rows = np.tile(self.settled, (self.k + 1, 1))
        rows[:, : self.joints.n_coupling] = np.asarray(history, dtype=float)
        return self._state(), rows

    def _state(self):
        return np.concatenate([np.ravel(self._joint_state), *self._signal_ends])

    # -- the problem interface -----------------------------------------------------------------------
    def _joined(self, j, y):
        return JointOutputs(y, self.joints.signal_values[j])

    def predict(self, i, state, history, *, final=False, e_new=None):
        j = self._where.get(i)
        if j is None:
            return super().predict(i, state, history, final=final, e_new=e_new)
        final = final and not self.implicit_connections  # implicit: every joint unit is stepped again
        end, y = self.joints.predict(j, self._joint_state, history, final=final, e_new=e_new)
        return end, self._joined(j, y)

    def correct(self, i, state, history, e):
        j = self._where.get(i)
        if j is None:
            return super().correct(i, state, history, e)
        end, y = self.joints.correct(j, self._joint_state, history, e)
        return end, self._joined(j, y)

    def checkpoint(self):
        """Refused: the joint units' saved states live in :attr:`joints` (its own checkpoint), which the signal
        problem's checkpoint does not take; such a scene runs at fixed steps."""
        raise StepFailure("a scene of joints beside connections takes no checkpoint: it runs at fixed steps")

    def reevaluate(self, i, end, y, e_old, e_new):
        j = self._where[i]
        return self._joined(j, self.joints.reevaluate(j, end, y.ports, e_old, e_new))

    def sensitivity(self, i, state, history, e, end=None, y=None):
        return self.joints.sensitivity(
            self._where[i], self._joint_state, history, e, end, None if y is None else y.ports
        )

    def output_sensitivities(self, i, state, history, e, y):
        """A joint unit's :meth:`sensitivity` and its connected outputs' by its inputs, from the same perturbed steps
        (:meth:`~icosim.problems.fmu.problem.FmuCosimulation.output_sensitivities`), for one corrector of both kinds of
        condition (:mod:`icosim.engine.joint_signal_conditions`)."""
        return self.joints.output_sensitivities(self._where[i], self._joint_state, history, e, y.ports, y.signals)

    def signal_output(self, i, y, output):
        return y.signals[output] if isinstance(y, JointOutputs) else y[output]

    def stack(self, ys):
        """The joint units' port outputs, port after port (a signal unit's outputs, one axis, have no port)."""
        ports = [y.ports if isinstance(y, JointOutputs) else y for y in ys]
        return CosimulationProblem.stack(self, [y for y in ports if np.ndim(y) > 1])

    def join(self, ends):
        self._joint_state = self.joints.join([ends[i] for i in self.joint_units])
        self._signal_ends = [ends[i] for i in self.signal_units]
        self.step_index += 1
        return self._state()

    def project(self, state):
        """The joint problem's projection (Eq. 30) of the joint units; the signal units as they are."""
        self._joint_state = self.joints.project(self._joint_state)
        return self._state()

    def close(self):
        """Free the joint units' saved states (the units are closed by their owner)."""
        self.joints.close()
