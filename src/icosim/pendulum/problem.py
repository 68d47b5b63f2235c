"""The double pendulum split into link 1 and link 2, as the macro step sees it (docs/pendulum.md).

Each link is integrated over a macro step by Radau IIA (:mod:`icosim.pendulum.integrator.radau`,
compiled for the links in :mod:`icosim.pendulum.integrator.compiled`); the sensitivities
of the coupling conditions are forward differences, integrated in one batch
with the predictor.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from ..engine.backends import Float64
from ..engine.bounds import check_k
from ..engine.decompositions import get_decomposition
from ..engine.lagrange import (
    lagrange_coefficients,
    lagrange_weights,
    monomial_coefficients,
    variable_corrector_nodes,
    variable_predictor_nodes,
)
from ..engine.problem import CosimulationProblem
from ..errors import ParameterError
from .conditions import CONDITIONS, check_decomposition
from .integrator.compiled import CompiledLink
from .integrator.radau import _fd_jacobian, radau_batch
from .links import Link1, Link2
from .manifold import project_state
from .model import PendulumParameters, joint_constraint
from .names import coupling_variables

__all__ = ["PendulumCosimulation"]


# -- the co-simulation problem (protocol of icosim.engine.macrostep) ----------------------
class PendulumCosimulation(CosimulationProblem):
    """The double pendulum split into link 1 and link 2 (decomposition ff, fd or dd).

    State: ``s = (phi1, omega1, x_S2, y_S2, phi2, vx2, vy2, omega2)`` at ``T_N``.
    History: ``h[j, :] = e_N-j``, ``j = 0..k`` (names :func:`~icosim.pendulum.names.coupling_variables`).
    Outputs at ``T_N+1``: ``y[i, :, :] = (P_i, P_i', P_i'', f_i)`` per link
    (joint point position, velocity, acceleration, joint force on link 2 as
    seen by link ``i``: the input ``lambda_c`` for a force-driven link, the
    multiplier for a kinematically driven one).
    """

    #: Integrate the links with the compiled transcription of icosim.pendulum.integrator.radau (:mod:`.integrator.compiled`);
    #: False: with :func:`icosim.pendulum.integrator.radau.radau_batch` on the links' closures (the reference, for comparisons).
    compiled = True

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
        # monomial coefficients of the interpolation polynomial (Eq. 11) in tau = (t - T_N)/H
        self.C_corr = np.array(monomial_coefficients(self.corr_nodes), dtype=float)
        self._cache = None
        self._jac0 = {}
        # split: integrations that took more than one step or rejected one (docs/pendulum.md)
        self.stats = {"integrations": 0, "steps": 0, "rejected": 0, "fev": 0, "split": 0}
        # Jacobians of the links' right-hand sides (Radau's own and the shared first-step one) and the
        # right-hand side evaluations spent on the shared ones (not in stats["fev"])
        self.jacobian_stats = {"jev": 0, "fev": 0}

    @classmethod
    def check_decomposition(cls, decomposition):
        """Refuse a decomposition for which the pendulum has no coupling conditions (:mod:`.conditions`)."""
        check_decomposition(decomposition)

    @property
    def n_coupling(self) -> int:
        """Coupling variables per time point: two per joint quantity (:func:`~icosim.pendulum.names.coupling_variables`)."""
        return len(coupling_variables(self.decomposition))

    # -- helpers --------------------------------------------------------------
    def _split(self, state):
        return state[:2], state[2:]

    def _integrate(self, i, state, samples):
        """Integrate link ``i`` over one macro step for a batch of input samples.

        ``samples`` (B, k+1, n_u) at the corrector nodes ``1, 0, ..., -k+1``.
        Returns end states (B, n) and outputs (B, 4, 2).
        """
        link = self.links[i]
        coef = np.einsum("mj,bju->bmu", self.C_corr, samples)
        y0 = np.broadcast_to(self._split(state)[i], (samples.shape[0], link.n))
        options = dict(rtol=self.rtol, atol=self.atol, newton_tol=self.newton_tol)
        if self.compiled:
            kernel = self.compiled_links[i]
            jacobian = lambda: kernel.fd_jacobian(coef[:1], self.H, 0.0, y0[:1])[0]
            integrate = lambda jac0: kernel.radau(coef, self.H, 0.0, self.H, y0, jac0=jac0, **options)
        else:
            fun = link.rhs(coef, self.H)
            jacobian = lambda: _fd_jacobian(fun, 0.0, y0[:1], fun(0.0, y0[:1]))[0]
            integrate = lambda jac0: radau_batch(fun, 0.0, self.H, y0, jac0=jac0, **options)
        # The Newton matrix of the first Radau step is shared by all integrations
        # of this link from this state (predictor, sensitivities, corrector).
        if self._jac0.get(i, (None,))[0] is not state:
            self._jac0[i] = (state, jacobian())
            self.jacobian_stats["jev"] += 1
            self.jacobian_stats["fev"] += 2
        r = integrate(self._jac0[i][1])
        self.work.subsystem_integrations += 1
        st = self.stats
        st["integrations"] += 1
        st["steps"] += r.n_steps
        st["rejected"] += r.n_rejected
        st["fev"] += r.n_fev
        st["split"] += r.n_steps > 1 or r.n_rejected > 0
        self.jacobian_stats["jev"] += r.n_jev
        u1 = np.add.reduce(coef, axis=1)  # input at tau = 1
        return r.y, link.outputs(r.y, r.f, u1)

    def _respond(self, i, state, history, e, fixed=None):
        """Outputs of link ``i`` at ``e`` and, per coupling variable ``j`` driving it, at ``e + h_j``.

        ``fixed is None``: through link ``i``'s corrector integration, one batch
        of the base and the perturbed inputs (full gradients); otherwise
        ``fixed`` is the link's final end state and its outputs are re-evaluated
        there (algebraic gradients of a leading link, no integration).
        Returns ``(end_i, y_i, {j: y_i(e + h_j)})`` (``end_i`` the end state of the base member).
        """
        base = self.corrector_samples(history, e)
        n_e = self.n_coupling
        h = self.fd_step * np.maximum(1.0, np.abs(e))
        sl = self.inputs[i]
        idx = np.arange(n_e)[sl]
        batch = np.broadcast_to(base, (1 + idx.size,) + base.shape).copy()
        batch[1 + np.arange(idx.size), 0, idx] += h[idx]
        if fixed is None:
            ends, y = self._integrate(i, state, batch[:, :, sl])
            end = ends[0]
        else:
            end, y = fixed, self._outputs_at(i, fixed, batch[:, 0, sl])
        return end, y[0], dict(zip(idx.tolist(), y[1:]))

    def _linearise(self, state, history, e, fixed=(None, None), responses=None):
        """Outputs at ``e`` and ``d residuals / d e`` by forward differences.

        ``responses[i]`` (optional) is link ``i``'s :meth:`_respond` at ``e``
        already computed (the predictor's batch).
        """
        n_e = self.n_coupling
        h = self.fd_step * np.maximum(1.0, np.abs(e))
        ys, perturbed = [], []
        for i in range(2):
            got = responses[i] if responses is not None else None
            _, y_i, pert_i = got if got is not None else self._respond(i, state, history, e, fixed[i])
            ys.append(y_i)
            perturbed.append(pert_i)
        y0 = np.stack(ys)
        r0 = self.residuals(y0)
        jac = {key: np.zeros(val.shape + (n_e,)) for key, val in r0.items()}
        for j in range(n_e):
            # every link driven by e_j responds (in ff and dd both links are)
            y = y0.copy()
            for i in range(2):
                if j in perturbed[i]:
                    y[i] = perturbed[i][j]
            for key, val in self.residuals(y).items():
                jac[key][..., j] = (val - r0[key]) / h[j]
        return y0, jac

    def _outputs_at(self, i, end, u1):
        """Outputs of link ``i`` at its end state ``end`` for inputs ``u1`` (B, n_u) at ``T_N+1``."""
        link = self.links[i]
        Y = np.broadcast_to(end, (u1.shape[0], link.n))
        f = link.rhs(u1[:, None, :], self.H)(self.H, Y)  # constant polynomial: u(tau) = u1
        return link.outputs(Y, f, u1)

    # -- the problem interface ------------------------------------------------
    def extrapolate(self, history):
        # The base class's sum, formed as one BLAS dot product: equal up to rounding, and kept so
        # that the pendulum's results stay bitwise those computed before the base class existed.
        return np.tensordot(self.w_pred, history, axes=(0, 0))

    def predict(self, i, state, history, *, final=False):
        """Link ``i`` with the extrapolation polynomial, i.e. the interpolation polynomial through ``e_p``.

        A link to be corrected is integrated in one batch with its forward-difference
        perturbations (kept for :meth:`jacobians`); a leading (``final``) link alone.
        """
        e_p = self.extrapolate(history)
        if final:
            end, y = self._integrate(i, state, self.corrector_samples(history, e_p)[None][:, :, self.inputs[i]])
            return end[0], y[0]
        if self._cache is None or self._cache[0] is not state or self._cache[1] is not history:
            self._cache = (state, history, e_p, [None, None])
        end, y_i, _ = self._cache[3][i] = self._respond(i, state, history, e_p)
        return end, y_i

    def jacobians(self, state, history, e, y, fixed=(None, None), algebraic=True):
        c = self._cache
        responses = [None, None]
        if c is not None and c[0] is state and c[1] is history and np.array_equal(c[2], e):
            responses = [c[3][i] if fixed[i] is None else None for i in range(2)]
        if not algebraic:  # a finished link's outputs stay as integrated: it does not respond
            responses = [(f, y[i], {}) if f is not None else r for i, (f, r) in enumerate(zip(fixed, responses))]
        return self._linearise(state, history, e, fixed, responses)[1]

    def correct(self, i, state, history, e_new):
        samples = self.corrector_samples(history, e_new)[None]
        end, y = self._integrate(i, state, samples[:, :, self.inputs[i]])
        return end[0], y[0]

    def reevaluate(self, i, end, y, e_old, e_new):
        """Link ``i``'s outputs at its fixed end state with the input ``e_new`` at ``T_N+1`` (exact)."""
        return self._outputs_at(i, end, np.asarray(e_new)[None, self.inputs[i]])[0]

    def join(self, ends):
        return np.concatenate(ends)

    def stack(self, ys):
        return np.stack(ys)

    def residuals(self, y):
        """Joint constraint on each level (2 rows; both links kinematic: its normal component) and force balance
        (:data:`~icosim.pendulum.conditions.CONDITIONS`, by the kinds of the two links)."""
        d = y[..., 0, :, :] - y[..., 1, :, :]  # link 1 minus link 2: g_c, g_c', g_c'', f1 - f2
        return CONDITIONS[self.decomposition.kinds](y, d)

    def project(self, state):
        return project_state(self.params, state)

    # -- quantities of a state ----------------------------------------------------
    def constraint(self, state):
        return joint_constraint(self.params, state)

    # -- variable macro steps (icosim.control.driver) ------------------------------------
    def set_macro_step(self, H: float, past_steps=None):
        """Size ``H`` of the next macro step and the sizes ``H_N-1, ..., H_N-k`` of the past ones.

        The extrapolation (Eq. 9) and interpolation (Eq. 11) polynomials then
        run through the non-equidistant nodes of :mod:`icosim.engine.lagrange`
        (:func:`~icosim.engine.lagrange.variable_predictor_nodes`), their weights
        computed exactly from the float step sizes and rounded once;
        ``past_steps=None`` means equal steps (the nodes of a fixed ``H``).
        """
        if not (isinstance(H, (int, float)) and math.isfinite(H) and H > 0):
            raise ParameterError(f"H must be a finite number > 0, got {H!r}")
        self.H = float(H)
        past = [self.H] * self.k if past_steps is None else [float(h) for h in past_steps][: self.k]
        if len(past) != self.k or not all(math.isfinite(h) and h > 0 for h in past):
            raise ParameterError(f"need {self.k} past step sizes > 0, got {past_steps!r}")
        exact = [Fraction(h) for h in [self.H] + past]  # binary floats are exact rationals
        pred = variable_predictor_nodes(exact[0], exact[1:])
        corr = variable_corrector_nodes(exact[0], exact[1:])
        self.w_pred = np.array([float(w) for w in lagrange_weights(pred, 1)], dtype=float)
        self.C_corr = np.array(lagrange_coefficients(corr), dtype=float)
        self._cache = None  # the predictor's responses (kept for the Jacobians) belong to the old nodes
