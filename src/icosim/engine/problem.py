"""The co-simulation problem: what :func:`icosim.engine.macrostep.macro_step` needs of it.

A problem couples ``N`` subsystems by the joints of its coupling graph (:mod:`icosim.engine.graph`) through
the coupling variables ``e`` of the joints' decompositions.  :class:`CosimulationProblem` holds what every
problem shares -- the graph, the approximation order ``k``, the arithmetic, the extrapolation (Eq. 9/35/59)
and shift of the coupling history, the samples the corrector's interpolation polynomial runs through
(Eq. 11), the coupling conditions and their Jacobians assembled from each subsystem's sensitivities, and a
count of the work done -- and states the contract a subclass meets.  The linear models
(:mod:`icosim.problems.linear`), the double pendulum (:mod:`icosim.problems.pendulum`) and FMU units
(:mod:`icosim.problems.fmu`) are its subclasses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from . import layout, stages
from .backends import Backend, Float64
from .bounds import check_k
from .connection_conditions import ImplicitWork
from .decompositions import Decomposition
from .graph import CouplingGraph
from .lagrange import corrector_nodes, predictor_nodes, weights_at
from .methods.solve import KeptFactors
from .residuals import level_factors
from .schemes import get_scheme

if TYPE_CHECKING:
    from .methods.base import CouplingMethod
    from .residuals import Conditions
    from .schemes import Scheme
    from .stages import Plan, Stage

__all__ = ["CosimulationProblem", "Work"]


@dataclass
class Work:
    """Work done by a problem since the last :meth:`reset`.

    ``subsystem_integrations`` counts calls of a subsystem integrator (a
    batched call counts once), ``coupling_solves`` linear solves of coupling
    conditions, ``projections`` projection steps.  The problems count their
    integrations, :func:`icosim.engine.macrostep.macro_step` the solves and
    projections.
    """

    subsystem_integrations: int = 0
    coupling_solves: int = 0
    projections: int = 0

    def reset(self) -> None:
        self.subsystem_integrations = self.coupling_solves = self.projections = 0

    def as_dict(self) -> dict:
        return asdict(self)


class CosimulationProblem:
    """Base class of co-simulation problems (any number of subsystems and joints, any coupling scheme).

    Arrays: the state ``s`` is the subsystems' states at ``T_N`` (layout set by the subclass); the coupling
    history ``h[..., j, :] = e_N-j``, ``j = 0..k``; the outputs of subsystem ``i`` at ``T_N+1``,
    ``y_i[..., p, q, c]``, are port ``p``'s position, velocity, acceleration and force (``q``, as
    :data:`icosim.engine.graph.POSITION` ...), component ``c``.  Leading batch axes are allowed wherever the
    subclass allows them.

    The problem knows nothing of the order in which its subsystems advance:
    :func:`icosim.engine.macrostep.macro_step` drives each subsystem ``i`` separately, as the scheme's stages
    (:mod:`icosim.engine.stages`) say.  A subclass calls ``super().__init__(graph, k, backend)`` (a
    decomposition for ``graph``: the paper's pair) and implements, per subsystem ``i``:

    ``predict(i, state, history, *, final=False) -> (end_i, y_i)``
        subsystem ``i`` integrated over the macro step with the extrapolation polynomials through the
        history (Eq. 9/35/59): its state ``end_i`` at ``T_N+1`` and its outputs ``y_i``.  ``final=True``
        says ``end_i`` is final and no gradient through its integration will be asked for (a problem that
        computes gradients in the same pass may skip them).  A problem whose graph has connections also takes
        ``e_new``: the predictor of a subsystem fed by a connection's new sample, its inputs the interpolation
        polynomials through ``e_new`` (as :meth:`correct`, but its first integration of the macro step).
    ``correct(i, state, history, e) -> (end_i, y_i)``
        subsystem ``i`` integrated with the interpolation polynomials through :meth:`corrector_samples`
        (Eq. 11).
    ``reevaluate(i, end_i, y_i, e_old, e_new) -> y_i``
        the outputs of subsystem ``i`` at its fixed end state ``end_i``, re-evaluated with the coupling
        variables ``e_new`` at ``T_N+1`` instead of ``e_old`` (only the outputs its equations of motion tie
        algebraically to the input at ``T_N+1`` change: acceleration, coupling force, multiplier).
    ``sensitivity(i, state, history, e, end=None, y=None) -> dy_i/du_i``
        shape ``(..., n_inputs_i) + y_i.shape[-3:]``: how the outputs follow subsystem ``i``'s inputs
        (:meth:`inputs`) at ``T_N+1``.  ``end is None``: through its corrector integration (full gradients,
        Eq. 13/39/63); otherwise ``end`` is its final end state and it responds only algebraically (as
        :meth:`reevaluate`).  ``y``: its outputs at ``e`` as they stand (a difference quotient's base).

    and, for the whole,

    ``signal_output(i, y_i, output) -> value``
        output ``output`` of subsystem ``i`` in its outputs ``y_i``, where a connection reads it (a problem whose
        graph has connections).

    ``join(ends) -> state``
        the subsystems' end states as one state.
    ``project(state) -> state``
        the projection step (needed by methods that project).

    and counts each subsystem integration in :attr:`work`.

    **Checkpoint.**  The arrays are the state as the macro step sees it; a problem may hold more of it (an FMU
    problem's units hold their states inside the FMUs).  So a problem saves and restores what it holds between
    macro steps:

    ``checkpoint() -> checkpoint``
        an opaque object holding the problem's state at ``T_N`` beyond the arrays ``state`` and ``history``
        (which the caller keeps), taken between macro steps;
    ``restore(checkpoint)``
        the problem back at that ``T_N``: the next macro step from the state and history it was taken with
        gives what it gave then, bit for bit.

    A problem whose arrays are its whole state (the linear models, the pendulum) has the trivial checkpoint
    (None; :meth:`restore` does nothing): any state may be given to any step.  A stateful problem advances only
    from the state it last returned or whose checkpoint it last restored, and may keep only its latest
    checkpoint (the FMU problem's holds its units' saved FMU states: docs/engine.md).  The run loop
    (:func:`icosim.engine.run.simulate` with ``rollback``) and the adaptive driver
    (:func:`icosim.engine.control.driver.adaptive_macro_steps`: a rejected step is retried from the checkpoint)
    use it.  The base class provides :meth:`extrapolate`,
    :meth:`shift`, :meth:`corrector_samples`, :meth:`inputs`, :meth:`stack`, :meth:`residuals` (the engine's
    coupling conditions, :mod:`icosim.engine.residuals`, scaled by :attr:`condition_scale`) and
    :meth:`jacobians` (assembled from the sensitivities; kept when :attr:`constant_sensitivities`, with their
    factors: :meth:`kept_factors`); a problem with conditions of its own overrides the last two.  What a run
    forms once and reuses -- a scheme's stages on the graph (:meth:`plan`), the kept Jacobians and their factors
    -- is held by the problem, never shared with another.
    """

    #: the sensitivities do not change from step to step (a linear problem): the Jacobians are formed once
    constant_sensitivities: bool = False
    #: factors of the constraint's position, velocity and acceleration levels (None: the engine's time)
    condition_scale: Sequence[Any] | None = None
    #: the signal connections are closed by their conditions at ``T_N+1`` (:mod:`icosim.engine.connection_conditions`;
    #: the problem's :meth:`correct` steps a unit again from ``T_N`` each time it is called), not explicitly
    implicit_connections: bool = False
    #: the relative step of the implicit connections' difference quotients (times ``max(1, |e_c|)``)
    connection_perturbation: float = 1e-7

    def __init__(self, graph: CouplingGraph | str | Decomposition, k: int, backend: Backend | None = None) -> None:
        k = check_k(k)  # 0 .. icosim.engine.bounds.MAX_K
        self.backend = be = backend or Float64()
        self.graph = graph if isinstance(graph, CouplingGraph) else CouplingGraph.pair(graph)
        self.k = k
        self.pred_nodes = predictor_nodes(k)
        self.corr_nodes = corrector_nodes(k)
        #: Lagrange weights of the extrapolation (Eq. 9) at ``T_N+1``, in the backend's arithmetic
        self.w_pred = np.array([be.const(w) for w in weights_at(self.pred_nodes, 1)], dtype=be.dtype)
        self.work = Work()
        #: the implicit connections' Newton iterations and perturbed steps
        self.implicit_work = ImplicitWork()
        self._extrapolated: tuple = (None, None, None)  # (history, weights, e_p) of the last extrapolation
        self._plans: dict = {}  # scheme -> its stages on the graph (the kept Jacobians below are per stage)
        self._jacobians: dict = {}  # (stage, algebraic) -> (the kept Jacobians, their factors): constant ones
        self._level_factors: tuple = (None, None, None)  # (scale, dtype, its levels' factors) last formed
        self._assembly: dict = {}  # (stage, algebraic) -> what jacobians() needs of the stage every time

    @property
    def decomposition(self) -> Decomposition:
        """The decomposition of a problem with one joint (the paper's pair)."""
        if self.graph.n_joints != 1:
            raise AttributeError(f"a problem with {self.graph.n_joints} joints has a decomposition per joint")
        return self.graph.joints[0].decomposition

    @classmethod
    def check_decomposition(cls, decomposition: str | Decomposition) -> None:
        """Refuse (:class:`~icosim.errors.ParameterError`) a decomposition whose coupling conditions this
        problem cannot form; the engine's conditions exist for every registered one."""

    @property
    def n_coupling(self) -> int:
        """Number of coupling variables ``e`` (per time point)."""
        return self.graph.n_coupling

    def plan(self, scheme: str | Scheme, method: CouplingMethod | None = None) -> Plan:
        """The stages of ``scheme`` on this problem's graph (:func:`icosim.engine.stages.plan`), made once per scheme
        and held here: the Jacobians kept per stage stay kept from step to step.  With ``method``, refuses one
        whose solves the stages cannot serve."""
        p = self._plans.get(scheme)
        if p is None:
            p = self._plans[scheme] = stages.plan(get_scheme(scheme), self.graph, implicit=self.implicit_connections)
        if method is not None:
            p.check_method(method)
        return p

    def extrapolate(self, history: np.ndarray) -> np.ndarray:
        """Predicted coupling variables ``e_p`` at ``T_N+1`` (Eq. 9/35/59).  A macro step asks for it once and
        every predictor again: the last one is kept (for the same history and weights)."""
        last_history, last_weights, e_p = self._extrapolated
        if last_history is history and last_weights is self.w_pred:
            return e_p
        w = self.w_pred
        e_p = sum(w[j] * history[..., j, :] for j in range(self.k + 1))
        self._extrapolated = (history, self.w_pred, e_p)
        return e_p

    def corrector_samples(self, history: np.ndarray, e_new: np.ndarray) -> np.ndarray:
        """Samples of the interpolation polynomial (Eq. 11): ``e_new`` at ``T_N+1``, then ``e_N ... e_N-k+1``."""
        return _prepend(e_new, history[..., : self.k, :])

    def shift(self, history: np.ndarray, e_new: np.ndarray) -> np.ndarray:
        """The history one macro step later: ``e_new`` prepended, the oldest sample dropped."""
        return _prepend(e_new, history[..., :-1, :])

    def inputs(self, i: int, e: Any) -> Any:
        """Subsystem ``i``'s inputs from coupling variables on the last axis (:meth:`CouplingGraph.inputs`):
        samples ``(..., nodes, n_e)`` give ``(..., nodes, n_inputs_i)``."""
        return self.graph.inputs(i, e)

    def stack(self, ys: Sequence[Any]) -> Any:
        """Outputs of several subsystems, port after port: ``(..., ports, 4, n_c)``."""
        if len(ys) == 1:
            return ys[0]
        ys = [np.asarray(y) for y in ys]
        lead = _lead([y.shape[:-3] for y in ys])  # the ports' axis is not broadcast
        return layout.concatenate([_to_lead(y, lead, 3) for y in ys], axis=-3)

    def residuals(self, y: Any, e: Any, conditions: Conditions | None = None, e_held: Any = None) -> dict[str, Any]:
        """The coupling conditions at ``T_N+1`` (:class:`icosim.engine.residuals.Conditions`): ``pos``, ``vel``,
        ``acc`` (the constraint on each level) and ``force`` (the balance of forces), rows on the last axis,
        from the outputs ``y`` of ``conditions.units`` and their joints' coupling variables ``e`` (default:
        every joint, from every subsystem's outputs and all of ``e``); ``e_held``: the variables as the
        conditions' held subsystems saw them."""
        if conditions is None:
            conditions = self.every_condition
        scale = self.condition_scale
        if scale is None:
            return conditions(y, e, e_held=e_held)
        dtype = getattr(y, "dtype", None)
        last_scale, last_dtype, factors = self._level_factors
        if last_scale is not scale or last_dtype != dtype:  # formed once per scale (a problem's H)
            factors = level_factors(scale, dtype)
            self._level_factors = (scale, dtype, factors)
        return conditions(y, e, scale=scale, e_held=e_held, factors=factors)

    @property
    def every_condition(self) -> Conditions:
        """The conditions of every joint, from every subsystem's outputs (:meth:`stack` of all)."""
        from .residuals import Conditions

        graph = self.graph
        return Conditions(graph, range(graph.n_joints), range(graph.n_subsystems))

    def jacobians(
        self, state: Any, history: Any, e: Any, ys: Sequence[Any], ends: Sequence[Any], stage: Stage,
        algebraic: bool = True,
    ) -> dict[str, Any]:  # fmt: skip
        """``d residuals / d e`` of ``stage``'s closed joints by their coupling variables, ``(..., rows, cols)``.

        The subsystems the stage corrects respond through their corrector integration, the finished ones
        algebraically at their end states ``ends[i]`` (``algebraic=False``: not at all).  Each subsystem's
        :meth:`sensitivity` is carried to the coupling variables by the graph's input map and through the
        conditions, which are linear in outputs and coupling variables together."""
        key = (stage, algebraic)
        if self.constant_sensitivities and key in self._jacobians:
            return self._jacobians[key][0]
        how = self._assembly.get(key)
        if how is None:
            how = self._assembly[key] = self._assemble(stage)
        Bs, B_all, dE, held = how
        corrected = set(stage.corrected)
        Ss = []
        for i in stage.responders:
            if i in corrected:
                S = self.sensitivity(i, state, history, e, None, ys[i])
            elif algebraic:
                S = self.sensitivity(i, state, history, e, ends[i], ys[i])
            else:
                S = 0 * self.sensitivity(i, state, history, e, ends[i], ys[i])
            Ss.append(S)
        first = Ss[0]
        if B_all is not None and all(S.dtype == np.float64 and S.shape == first.shape for S in Ss):
            # every responder at once: (..., R, inputs, ports, 4, n_c) x (R, inputs, cols) -> (..., cols, R ports,
            # 4, n_c).  A column reaches one input of a responder (a joint attaches to one port of it), so each
            # entry is one product by 0 or +-1, as the tensor product of one responder at a time had it.
            dY = _output_derivatives(np.stack(Ss, axis=-5), B_all)
        else:
            blocks = []
            for S, B in zip(Ss, Bs):
                if S.dtype == object:
                    B = np.array([[self.backend.const(b) for b in row] for row in B], dtype=object)
                # (..., inputs, ports, 4, n_c) x (inputs, cols) -> (..., cols, ports, 4, n_c)
                blocks.append(np.moveaxis(np.tensordot(S, B, axes=([-4], [0])), -1, -4))
            dY = self.stack(blocks)
        joints = cast("Conditions", stage.conditions)  # a stage of joints (connections: their own Jacobian)
        res = self.residuals(dY, dE, joints, held)  # a held multiplier does not follow e
        jac = {key_: val.swapaxes(-1, -2) for key_, val in res.items()}
        if self.constant_sensitivities:
            self._jacobians[key] = (jac, KeptFactors())
        return jac

    def kept_factors(self, stage: Stage, algebraic: bool = True) -> KeptFactors | None:
        """The factors of ``stage``'s Jacobians where they are kept (:attr:`constant_sensitivities`: the same
        Jacobians every step, combined and factored once), for
        :meth:`~icosim.engine.methods.base.CouplingMethod.corrected_coupling`; else None."""
        kept = self._jacobians.get((stage, algebraic))
        return None if kept is None else kept[1]

    def _assemble(self, stage: Stage) -> tuple:
        """What :meth:`jacobians` of ``stage`` needs every time: the responders' input matrices (apart, and
        stacked where they have one shape), ``d e / d e`` and the held multipliers' (zero) derivative."""
        cols = stage.columns
        Bs = [self.graph.input_matrix(i, cols) for i in stage.responders]
        B_all = np.stack(Bs) if all(B.shape == Bs[0].shape for B in Bs) else None
        be = self.backend
        dE = np.full((len(cols), len(cols)), be.const(0), dtype=be.dtype)
        for c in range(len(cols)):
            dE[c, c] = be.const(1)
        return Bs, B_all, dE, 0 * dE

    def connect(
        self, e: Any, ys: Sequence[Any], units: Sequence[int], closed: Sequence[int] = ()
    ) -> tuple[Any, list[int]]:
        """``e`` with the variables of the connections out of ``units`` set to ``factor * y + offset`` of their
        outputs (:meth:`signal_output`) at ``T_N+1``, and the columns set; ``closed``: connections left as they
        are (closed implicitly by their conditions)."""
        graph, cols, values = self.graph, [], []
        for c, con in enumerate(graph.connections):
            if con.source in units and c not in closed:
                y = self.signal_output(con.source, ys[con.source], con.output)
                cols.append(graph.connection_column(c))
                values.append(con.factor * y + con.offset)
        if not cols:
            return e, cols
        out = np.array(np.broadcast_to(e, np.broadcast_shapes(e.shape, np.shape(values[0]) + e.shape[-1:])))
        for col, value in zip(cols, values):
            out[..., col] = value
        return out, cols

    def describe_connection(self, c: int) -> str:
        """Connection ``c`` in messages."""
        return self.graph.describe_connection(c)

    def checkpoint(self) -> Any:
        """The problem's state at ``T_N`` beyond the arrays (class docstring): None, the arrays are all of it."""
        return None

    def restore(self, checkpoint: Any) -> None:
        """Back to ``checkpoint`` (:meth:`checkpoint`): nothing to do where the arrays are the whole state."""

    # -- to be implemented by a subclass ------------------------------------------
    def predict(self, i: int, state: Any, history: Any, *, final: bool = False, e_new: Any = None) -> Any:
        raise NotImplementedError  # pragma: no cover - contract

    def correct(self, i: int, state: Any, history: Any, e: Any) -> Any:  # pragma: no cover - contract
        raise NotImplementedError

    def reevaluate(self, i: int, end: Any, y: Any, e_old: Any, e_new: Any) -> Any:  # pragma: no cover
        raise NotImplementedError

    def sensitivity(self, i: int, state: Any, history: Any, e: Any, end: Any = None, y: Any = None) -> Any:
        raise NotImplementedError  # pragma: no cover - contract

    def signal_output(self, i: int, y: Any, output: int) -> Any:  # pragma: no cover - contract
        raise NotImplementedError(f"{type(self).__name__} has no signal outputs")

    def join(self, ends: Sequence[Any]) -> Any:  # pragma: no cover - contract
        raise NotImplementedError

    def project(self, state: Any) -> Any:  # pragma: no cover - contract
        raise NotImplementedError(f"{type(self).__name__} has no projection step")


def _output_derivatives(S_all: np.ndarray, B_all: np.ndarray) -> np.ndarray:
    """The responders' output derivatives by the coupling variables: ``(..., R, inputs, ports, 4, n_c)`` x ``(R,
    inputs, cols)`` -> ``(..., cols, R ports, 4, n_c)``.  A column reaches one input of a responder (a joint
    attaches to one port of it), so each entry is one product by 0 or +-1."""
    dY = np.einsum("...rqpab,rqc->...crpab", S_all, B_all)
    return dY.reshape(dY.shape[:-5] + (dY.shape[-5], -1) + dY.shape[-2:])


def _prepend(e_new: np.ndarray, older: np.ndarray) -> np.ndarray:
    """Stack ``e_new`` in front of older samples (leading axes broadcast)."""
    lead = _lead([e_new.shape[:-1], older.shape[:-2]])
    return layout.concatenate([_to_lead(e_new, lead, 1)[..., None, :], _to_lead(older, lead, 2)], axis=-2)


def _lead(shapes: list[tuple]) -> tuple:
    """The leading axes the arrays of these leading shapes broadcast to."""
    first = shapes[0]
    return first if all(shape == first for shape in shapes) else np.broadcast_shapes(*shapes)


def _to_lead(a: np.ndarray, lead: tuple, trailing: int) -> np.ndarray:
    """``a`` broadcast to the leading axes ``lead`` before its last ``trailing`` axes (itself where it has them)."""
    return a if a.shape[:-trailing] == lead else np.broadcast_to(a, lead + a.shape[-trailing:])
