"""The double pendulum split into link 1 and link 2, as the macro step sees it (docs/pendulum.md).

Each link is integrated over a macro step by Radau IIA, compiled with numba
(:mod:`icosim.problems.pendulum.integrator.compiled`, one call per link integration through
:mod:`icosim.problems.pendulum.integrator.compiled_step`); the sensitivities of the coupling conditions are
forward differences, integrated in one batch with the predictor.
"""

from __future__ import annotations

import math

import numpy as np

from ...engine.backends import Float64
from ...engine.bounds import check_k
from ...engine.decompositions import get_decomposition
from ...engine.lagrange import monomial_coefficients, variable_step_polynomials
from ...engine.problem import CosimulationProblem
from ...errors import ParameterError
from .conditions import CONDITIONS, check_decomposition
from .integrator.compiled_step import STATS, _link_outputs, _link_step
from .integrator.systems import CompiledLink, link_failure
from .links import Link1, Link2
from .manifold import project_state
from .model import PendulumParameters, joint_constraint
from .names import coupling_variables

__all__ = ["PendulumCosimulation"]


# -- the co-simulation problem (protocol of icosim.engine.macrostep) ----------------------
class PendulumCosimulation(CosimulationProblem):
    """The double pendulum split into link 1 and link 2 (decomposition ff, fd or dd).

    State: ``s = (phi1, omega1, x_S2, y_S2, phi2, vx2, vy2, omega2)`` at ``T_N``.
    History: ``h[j, :] = e_N-j``, ``j = 0..k`` (names :func:`~icosim.problems.pendulum.names.coupling_variables`).
    Outputs at ``T_N+1``: ``y[i, :, :] = (P_i, P_i', P_i'', f_i)`` per link
    (joint point position, velocity, acceleration, joint force on link 2 as
    seen by link ``i``: the input ``lambda_c`` for a force-driven link, the
    multiplier for a kinematically driven one).
    """

    def __init__(
        self,
        params: PendulumParameters,
        decomposition: str,
        k: int,
        H: float,
        *,
        rtol: float = 1e-6,
        atol: float = 1e-6,
        fd_step: float = 1e-3,
        newton_tol: float = 1e-8,
    ):
        dec = get_decomposition(decomposition)
        self.check_decomposition(dec)
        k = check_k(k)  # 0 .. icosim.engine.bounds.MAX_K
        for name, v in (("H", H), ("rtol", rtol), ("atol", atol), ("fd_step", fd_step), ("newton_tol", newton_tol)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
        super().__init__(dec, k, Float64())
        self.params, self.H = params, float(H)
        self.rtol, self.atol, self.fd_step, self.newton_tol = rtol, atol, fd_step, newton_tol
        self.links = (Link1(params, dec.kinds[0]), Link2(params, dec.kinds[1]))
        self.compiled_links = tuple(CompiledLink(link) for link in self.links)
        # the two components of the coupling variable driving each link
        self.inputs = tuple(slice(2 * j, 2 * j + 2) for j in dec.inputs)
        self._cols = tuple(2 * j for j in dec.inputs)  # their first column in e
        self._n_coupling = len(coupling_variables(dec))
        # monomial coefficients of the interpolation polynomial (Eq. 11) in tau = (t - T_N)/H
        self.C_corr = np.array(monomial_coefficients(self.corr_nodes), dtype=float)
        self._cache = None
        # the Newton matrix of the first Radau step, per link: the state it belongs to and the matrix
        self._jac0 = [None, None]
        self._jac0_matrix = tuple(np.zeros((link.n, link.n)) for link in self.links)
        self._tolerances = np.array([rtol, atol, newton_tol], dtype=float)
        # the counters of stats and jacobian_stats (integrator.compiled_step.STATS), which the kernel adds to
        self._counts = np.zeros(len(STATS), dtype=np.int64)

    @classmethod
    def check_decomposition(cls, decomposition):
        """Refuse a decomposition for which the pendulum has no coupling conditions (:mod:`.conditions`)."""
        check_decomposition(decomposition)

    @property
    def stats(self) -> dict:
        """Link integrations, their accepted and rejected Radau steps, right-hand side evaluations, and
        ``split``: integrations that took more than one step or rejected one (docs/pendulum.md)."""
        c = self._counts.tolist()
        return {"integrations": c[0], "steps": c[1], "rejected": c[2], "fev": c[3], "split": c[4]}

    @property
    def jacobian_stats(self) -> dict:
        """Jacobians of the links' right-hand sides (Radau's own and the shared first-step one) and the
        right-hand side evaluations spent on the shared ones (not in ``stats["fev"]``)."""
        c = self._counts.tolist()
        return {"jev": c[5], "fev": c[6]}

    @property
    def n_coupling(self) -> int:
        """Coupling variables per time point: two per joint quantity (:func:`~icosim.problems.pendulum.names.coupling_variables`)."""
        return self._n_coupling

    # -- helpers --------------------------------------------------------------
    def _split(self, state):
        return state[:2], state[2:]

    def _step_link(self, i, state, e, history, perturb):
        """Link ``i`` over one macro step from ``state`` in one compiled call (:func:`~.integrator.compiled_step._link_step`):
        the samples ``e``, ``history[0..k-1]`` of its input (:meth:`corrector_samples`; with ``perturb``, two
        more members whose ``e`` is moved by the forward-difference steps ``fd_step * max(1, |e|)``).
        Returns end states (B, n) and outputs (B, 4, 2)."""
        if history.shape[0] < self.k:
            raise ValueError(f"need {self.k} past samples of the coupling variables, got {history.shape[0]}")
        link = self.compiled_links[i]
        fresh = self._jac0[i] is not state
        if fresh:
            self._jac0[i] = state
        start = state[:2] if i == 0 else state[2:]
        y, out, status, t, h_abs = _link_step(
            link.link_id,
            link.kind_id,
            link.par,
            self.H,
            self.C_corr,
            _floats(e),
            _floats(history),
            self._cols[i],
            perturb,
            self.fd_step,
            _floats(start),
            self._jac0_matrix[i],
            fresh,
            self._tolerances,
            100000,
            self._counts,
        )
        if status:
            raise link_failure(status, t, h_abs, 100000)
        self.work.subsystem_integrations += 1
        return y, out

    def _respond(self, i, state, history, e, fixed=None):
        """Outputs of link ``i`` at ``e`` and, per coupling variable ``j`` driving it, at ``e + h_j``.

        ``fixed is None``: through link ``i``'s corrector integration, one batch
        of the base and the perturbed inputs (full gradients); otherwise
        ``fixed`` is the link's final end state and its outputs are re-evaluated
        there (algebraic gradients of a leading link, no integration).
        Returns ``(end_i, y_i, {j: y_i(e + h_j)})`` (``end_i`` the end state of the base member).
        """
        col = self._cols[i]
        if fixed is None:
            ends, y = self._step_link(i, state, e, history, True)
            end = ends[0]
        else:
            end, y = fixed, self._end_outputs(i, fixed, e, True)
        return end, y[0], {col: y[1], col + 1: y[2]}

    def _end_outputs(self, i, end, e, perturb):
        """Outputs (B, 4, 2) of link ``i`` at its end state ``end`` for its input ``e`` held at ``T_N+1``
        (:func:`~.integrator.compiled_step._link_outputs`; with ``perturb`` also for the two perturbed inputs)."""
        link = self.compiled_links[i]
        return _link_outputs(
            link.link_id, link.kind_id, link.par, self.H, _floats(end), _floats(e), self._cols[i], perturb, self.fd_step
        )

    def _linearise(self, state, history, e, fixed=(None, None), responses=None):
        """Outputs at ``e`` and ``d residuals / d e`` by forward differences.

        ``responses[i]`` (optional) is link ``i``'s :meth:`_respond` at ``e``
        already computed (the predictor's batch).  The residuals of the base
        outputs and of every perturbed ``e_j`` are formed in one batch: the
        same elementwise arithmetic as one call per member.
        """
        n_e = self.n_coupling
        h = self.fd_step * np.maximum(1.0, np.abs(e))
        ys, perturbed = [], []
        for i in range(2):
            got = responses[i] if responses is not None else None
            _, y_i, pert_i = got if got is not None else self._respond(i, state, history, e, fixed[i])
            ys.append(y_i)
            perturbed.append(pert_i)
        # member 0: the base outputs; member 1 + j: every link driven by e_j responds (in ff and dd both are)
        Y = np.empty((1 + n_e, 2) + ys[0].shape)
        for i in range(2):
            Y[:, i] = ys[i]
            for j, y_ij in perturbed[i].items():
                Y[1 + j, i] = y_ij
        r = self.residuals(Y)
        jac = {key: ((val[1:] - val[0]) / h[:, None]).T for key, val in r.items()}
        return Y[0], jac

    # -- the problem interface ------------------------------------------------
    def predict(self, i, state, history, *, final=False):
        """Link ``i`` with the extrapolation polynomial, i.e. the interpolation polynomial through ``e_p``.

        A link to be corrected is integrated in one batch with its forward-difference
        perturbations (kept for :meth:`jacobians`); a leading (``final``) link alone.
        """
        e_p = self.extrapolate(history)
        if final:
            end, y = self._step_link(i, state, e_p, history, False)
            return end[0], y[:1]
        if self._cache is None or self._cache[0] is not state or self._cache[1] is not history:
            self._cache = (state, history, e_p, [None, None])
        end, y_i, _ = self._cache[3][i] = self._respond(i, state, history, e_p)
        return end, y_i[None]

    def jacobians(self, state, history, e, ys, ends, stage, algebraic=True):
        """``d residuals / d e`` by forward differences of the links' outputs through its own conditions
        (:meth:`_linearise`); the links the stage corrects respond through their integration, a finished
        one at its end state."""
        fixed = tuple(ends[i] if i in stage.finished else None for i in range(2))
        y = self.stack(ys)
        c = self._cache
        responses = [None, None]
        if c is not None and c[0] is state and c[1] is history and np.array_equal(c[2], e):
            responses = [c[3][i] if fixed[i] is None else None for i in range(2)]
        if not algebraic:  # a finished link's outputs stay as integrated: it does not respond
            responses = [(f, y[i], {}) if f is not None else r for i, (f, r) in enumerate(zip(fixed, responses))]
        return self._linearise(state, history, e, fixed, responses)[1]

    def correct(self, i, state, history, e_new):
        end, y = self._step_link(i, state, e_new, history, False)
        return end[0], y[:1]

    def reevaluate(self, i, end, y, e_old, e_new):
        """Link ``i``'s outputs at its fixed end state with the input ``e_new`` at ``T_N+1`` (exact)."""
        return self._end_outputs(i, end, e_new, False)[:1]

    def join(self, ends):
        return np.concatenate(ends)

    def stack(self, ys):
        return np.concatenate(ys) if len(ys) > 1 else ys[0]

    def residuals(self, y, e=None, conditions=None, e_held=None):
        """Joint constraint on each level (2 rows; both links kinematic: its normal component) and force balance,
        link 1 minus link 2 (:data:`~icosim.problems.pendulum.conditions.CONDITIONS`, by the kinds of the links;
        the pendulum's own, in its sense of ``lambda_c``)."""
        return CONDITIONS[self.decomposition.kinds](y)

    def project(self, state):
        return project_state(self.params, state)

    # -- quantities of a state ----------------------------------------------------
    def constraint(self, state):
        return joint_constraint(self.params, state)

    # -- variable macro steps (icosim.engine.control.driver) ------------------------------------
    def set_macro_step(self, H: float, past_steps=None):
        """Size ``H`` of the next macro step and the sizes ``H_N-1, ..., H_N-k`` of the past ones.

        The extrapolation (Eq. 9) and interpolation (Eq. 11) polynomials then
        run through the non-equidistant nodes of :mod:`icosim.engine.lagrange`
        (:func:`~icosim.engine.lagrange.variable_predictor_nodes`), their weights
        computed exactly from the float step sizes and rounded once;
        ``past_steps=None`` means equal steps (the nodes of a fixed ``H``).
        """
        self.H, _, self.w_pred, _, self.C_corr = variable_step_polynomials(H, past_steps, self.k)
        self._cache = None  # the predictor's responses (kept for the Jacobians) belong to the old nodes


def _floats(a):
    """``a`` as a C-contiguous float64 array (itself when it is one): one specialisation of the kernels."""
    return np.ascontiguousarray(a, dtype=np.float64)
