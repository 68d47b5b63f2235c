"""The planar double pendulum of Sect. 4 as a co-simulation problem.

Model (Sect. 4, Fig. 5)
-----------------------
Two rigid links (mass ``m``, moment of inertia ``J`` about the centre of mass
``S``, length ``l``), gravity ``g`` in ``-y``, viscous damping
``F_d = -d v_S`` at each centre of mass.  Link ``i`` has the angle ``phi_i``
from the x axis, the unit vector ``e_i = (cos phi_i, sin phi_i)`` and its
normal ``n_i = (-sin phi_i, cos phi_i)``.  The joint points are
``P_1 = S_1 + l_1/2 e_1`` on link 1 and ``P_2 = S_2 - l_2/2 e_2`` on link 2,
so that the joint constraint is the paper's

    g_c = (g_cax, g_cay) = P_1 - P_2 = 0.

Link 1 is pinned to ground at its other end, ``S_1 - l_1/2 e_1 = 0``.

Sign of the multiplier: ``lambda_c = (lambda_cax, lambda_cay)`` is the joint
force that link 1 exerts on link 2 (``-lambda_c`` acts on link 1), i.e. the
Lagrange form ``M q'' = f - G^T lambda`` with ``G = dg_c/dq``, the same
convention as the linear model (``g = x2 - x1``, ``+lambda`` on subsystem 1).
At rest ``lambda_cay = m g > 0``.

Subsystems (each a small ODE integrated by Radau IIA, :mod:`icosim.radau`)
---------------------------------------------------------------------------
*Link 1* has one degree of freedom (the ground pin is internal to subsystem 1
and is eliminated exactly): state ``(phi_1, omega_1)``, inertia about the pin
``J_O = J_1 + m_1 l_1^2/4``.

* force-driven (ff, fd):
  ``J_O phi_1'' = -m_1 g l_1/2 cos phi_1 - d l_1^2/4 omega_1 - l_1 n_1 . lambda``;
* kinematically driven (dd): see *displacement/displacement* below.

*Link 2* is a free body, state ``(x_S2, y_S2, phi_2, vx, vy, omega_2)``.

* force-driven (ff): ``m a_S = F + lambda``,
  ``J phi_2'' = -(l_2/2) e_2 x lambda`` with ``F = (-d vx, -m g - d vy)``;
* kinematically driven (fd, dd) on acceleration level (index 1): the joint
  acceleration is prescribed, ``P_2'' = a_tilde`` (rheonomic constraint with the
  multiplier ``mu_2``, the force of link 1 on link 2).  Eliminating ``mu_2``:
  ``(J + m l^2/4) phi_2'' = (l/2) e_2 x F - (m l/2) e_2 x a_tilde``,
  ``a_S = a_tilde + (l/2)(phi_2'' n_2 - omega_2^2 e_2)``, and the multiplier
  is an output, ``mu_2 = m a_S - F``.

Coupling variables and conditions (Sect. 2 carried over to 2D joints)
---------------------------------------------------------------------
=====  ===============================  ========================================
dec.   coupling variables ``e``          conditions at ``T_N+1``
=====  ===============================  ========================================
ff     ``lambda_c`` (2)                  ``g_c`` on the method's levels (2)
fd     ``lambda_c`` (2), ``a_tilde`` (2)  ``g_c`` (2) and ``mu_2 - lambda_c = 0`` (2)
dd     ``a_tilde`` (2)                   ``n_1 . (mu_2) - mu_1 = 0`` (1) and
                                        ``e_1 . g_c'' = 0`` (1)
=====  ===============================  ========================================

In fd, link 1 is force-driven by ``lambda_c`` and link 2 follows the joint
acceleration ``a_tilde`` (the paper's ``a_tilde_1``: the acceleration of the
joint point of link 1, unknown to subsystem 2).

Displacement/displacement (our formulation; the paper does not spell it out)
---------------------------------------------------------------------------
Link 1 has one degree of freedom: its joint point moves on a circle, and its
acceleration ``P_1'' = l_1 phi_1'' n_1 - l_1 omega_1^2 e_1`` has a *normal*
component fixed by the state.  It therefore cannot follow an arbitrary 2D
``a_tilde``.  Link 1 follows the **tangential** component through one
rheonomic constraint ``n_1 . (P_1'' - a_tilde) = 0``, i.e.
``l_1 phi_1'' = n_1 . a_tilde``, realised by one multiplier ``mu_1``: the
tangential joint force (force on link 2 along ``n_1``; link 1 feels
``-mu_1 n_1``), ``mu_1 = (-m_1 g l_1/2 cos phi_1 - d l_1^2/4 omega_1 - J_O phi_1'')/l_1``.
The normal component of the joint force is carried by link 1's ground pin and
does not enter its motion.  Link 2 follows all of ``a_tilde`` (``mu_2`` in 2D).

Unknowns: ``a_tilde`` (2).  Conditions (2):

* tangential force balance ``n_1 . mu_2 - mu_1 = 0`` -- the paper's
  ``mu_2 - mu_1 = 0`` (Eq. 57c) in the one direction where link 1 has a
  multiplier;
* normal kinematic compatibility ``e_1 . (P_1'' - P_2'') = 0``, i.e.
  ``e_1 . a_tilde = -l_1 omega_1^2``: the acceleration-level joint constraint in
  the direction in which link 1 cannot be driven.  (Its tangential component
  vanishes identically, by link 1's rheonomic constraint.)

The exact solution satisfies both (``a_tilde = P''``, ``mu_2 = lambda_c``,
``mu_1 = n_1 . lambda_c``); the 2x2 Jacobian is ``[[n_1^T (M_2 + J_O/l^2)],
[e_1^T]]``-like and regular.  In the engine's terms the normal component is the
``acc`` level of the constraint (``pos``, ``vel`` are the normal components too;
only the projection method is defined for dd), the balance the ``force`` row.
``lambda_c`` reported for dd is ``mu_2`` (the full joint force on link 2).

Sensitivities (step 2)
----------------------
Numerical, by forward differences with respect to the new sample ``e_N+1`` of
the interpolation polynomial: each subsystem is integrated for a batch of
``1 + n_u`` inputs (the unperturbed polynomial and one per input component,
``e_j + h_j`` with ``h_j = fd_step * max(1, |e_j|)``), in ONE batched Radau
call with a shared step sequence, so the difference quotient is the
derivative of one smooth discrete map.  Over one macro step the map
``e_N+1 -> outputs`` is affine up to small nonlinear terms, so a relatively
large step is best: with ``fd_step = 1e-3`` the truncation error is ~1e-8
(relative) and the round-off error ~1e-8 on velocity, acceleration and force
level, ~5e-7 on position level (positions of order 1 change by ~1e-8);
``tests/test_pendulum.py`` checks them against central differences through
separate corrector integrations.  In the first corrector pass the unperturbed member *is*
the predictor: the interpolation polynomial through ``e_p`` at ``T_N+1`` and
``e_N .. e_N-k+1`` equals the extrapolation polynomial (same degree, same
values at ``k+1`` nodes), so predictor and sensitivities cost one call per
subsystem.  Further corrector passes (fully implicit option) re-linearise
about the latest ``e``.

Projection (step 4)
-------------------
Mass-weighted projection of positions and velocities onto the joint
constraint manifold, the generalisation of Eq. (30): with
``q = (phi_1, x_S2, y_S2, phi_2)`` and ``M = diag(J_O, m_2, m_2, J_2)`` the
positions minimise ``(q - q*)^T M (q - q*)`` subject to ``g_c(q) = 0``
(Gauss-Newton on the KKT conditions ``M (q - q*) + G(q)^T nu = 0``,
``g_c(q) = 0``, whose fixed point is the exact projection), then the
velocities are projected linearly onto ``G(q) q' = 0`` in the same metric.
For the linear model this reduces to Eq. (30).

Linearisation and corrector: step sequences
-------------------------------------------
The finite-difference batch shares one Radau step sequence, but the corrector
pass integrates its single member alone, with its own step sequence.  When
these differ, the map that was linearised and the map the corrector evaluates
differ by the integration error, O(rtol) relative: the corrected coupling
variables then satisfy the conditions only to that level, not to round-off.
In practice a macro step is one Radau step (the first trial step is the whole
macro step) for every member, and then both sequences coincide exactly;
:attr:`PendulumCosimulation.stats` counts in ``split`` the integrations that
needed more than one step or rejected one, and every run dataset stores that
count (``n_split``) with the attribute ``sensitivities`` saying so.

Starting values, reference, divergence
--------------------------------------
Both links start at the consistent initial state; the coupling history at
``T_0, T_-1, ..., T_-k`` is taken from the monolithic solution (integrated
backwards from ``t = 0``), as for the linear model
(:func:`icosim.exact.consistent_start`).  The monolithic reference is the
pendulum in minimal coordinates ``(phi_1, phi_2)`` (:class:`Monolithic`),
integrated at tight tolerance.  A run (:func:`run_cosimulation`, through
:func:`icosim.macrostep.simulate`) stops cleanly at the first macro step that
is not finite or exceeds the bounds on ``|g_c|``, ``|lambda_c|`` or the
angular rates (status ``diverged``), or that cannot be computed: a subsystem
integration fails (:class:`icosim.radau.IntegrationError`), the projection does
not converge (:class:`ProjectionError`) or the coupling system is singular
(:class:`CouplingSolveError`), all :class:`icosim.macrostep.StepFailure`
(status ``failed``: it says nothing about stability, and a claim about
stability is ``undecided`` for such a run).  The stored series end at the step
before.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .backend import Float64
from .claims import Outcome, combine_holds, register_check
from .coupling import CouplingMethod, get_decomposition
from .lagrange import corrector_nodes, monomial_coefficients, predictor_nodes, weights_at
from .macrostep import StepFailure, simulate
from .model import ParameterError
from .radau import _fd_jacobian, radau_batch

__all__ = [
    "PendulumParameters",
    "PendulumCosimulation",
    "Monolithic",
    "RunResult",
    "run_cosimulation",
    "reference_solution",
    "consistent_history",
    "joint_constraint",
    "project_state",
    "ProjectionError",
    "CouplingSolveError",
    "linear_test_model_rho",
    "pendulum_test_model",
    "run_name",
    "run_dataset",
    "reference_dataset",
    "configured_runs",
    "expected_outcome",
    "run_verdict",
    "check_pendulum_stability",
    "summarize",
    "VARIABLES",
    "COUPLING_VARIABLES",
]

#: Names of the coupling variables per decomposition.
COUPLING_VARIABLES = {
    "ff": ("lambda_cax", "lambda_cay"),
    "fd": ("lambda_cax", "lambda_cay", "a_tilde_x", "a_tilde_y"),
    "dd": ("a_tilde_x", "a_tilde_y"),
}
#: Slices of ``e`` driving (link 1, link 2).
_INPUTS = {
    "ff": (slice(0, 2), slice(0, 2)),
    "fd": (slice(0, 2), slice(2, 4)),
    "dd": (slice(0, 2), slice(0, 2)),
}

#: Time series of every dataset: name -> (units, long name).
VARIABLES = {
    "phi1": ("rad", "angle of link 1"),
    "phi2": ("rad", "angle of link 2"),
    "g_cax": ("m", "joint constraint g_cax = (x_S1 + l1/2 cos phi1) - (x_S2 - l2/2 cos phi2)"),
    "g_cay": ("m", "joint constraint g_cay = (y_S1 + l1/2 sin phi1) - (y_S2 - l2/2 sin phi2)"),
    "lambda_cax": ("N", "joint force of link 1 on link 2, x"),
    "lambda_cay": ("N", "joint force of link 1 on link 2, y"),
}


@dataclass(frozen=True)
class PendulumParameters:
    """Physical parameters and initial angles (SI units), defaults from Sect. 4."""

    m1: float = 1.0
    m2: float = 1.0
    J1: float = 1.0 / 12.0
    J2: float = 1.0 / 12.0
    l1: float = 1.0
    l2: float = 1.0
    g: float = 9.81
    d: float = 2.0
    phi1_0: float = math.pi / 4
    phi2_0: float = -math.pi / 4

    def __post_init__(self):
        for name in ("m1", "m2", "J1", "J2", "l1", "l2"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"pendulum parameter {name} must be a finite number > 0, got {v!r}")
        for name in ("g", "d", "phi1_0", "phi2_0"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ParameterError(f"pendulum parameter {name} must be a finite number, got {v!r}")
        if self.d < 0:
            raise ParameterError(f"pendulum parameter d must be >= 0, got {self.d!r}")

    @property
    def JO1(self) -> float:
        """Moment of inertia of link 1 about its ground pin."""
        return self.J1 + self.m1 * self.l1**2 / 4

    def initial_state(self) -> np.ndarray:
        """Consistent co-simulation state at rest: ``(phi1, w1, x2, y2, phi2, vx2, vy2, w2)``."""
        e1 = np.array([math.cos(self.phi1_0), math.sin(self.phi1_0)])
        e2 = np.array([math.cos(self.phi2_0), math.sin(self.phi2_0)])
        s2 = self.l1 * e1 + self.l2 / 2 * e2
        return np.array([self.phi1_0, 0.0, s2[0], s2[1], self.phi2_0, 0.0, 0.0, 0.0])


def _poly(coef, tau):
    """``sum_m coef[:, m, :] tau^m`` (Horner); ``coef`` (B, K, n_u), ``tau`` broadcasts to (..., B)."""
    tau = np.asarray(tau, dtype=float)[..., None]
    u = coef[:, -1, :]
    for m in range(coef.shape[1] - 2, -1, -1):
        u = u * tau + coef[:, m, :]
    return u


def _cross(a, b):
    """Planar cross product ``a_x b_y - a_y b_x``."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


# -- the subsystems --------------------------------------------------------------
class _Link1:
    """Link 1 pinned to ground: state ``(phi1, omega1)``."""

    n = 2

    def __init__(self, p: PendulumParameters, kind: str):
        self.p, self.kind = p, kind

    def _torque_ext(self, phi, w):
        p = self.p
        return -p.m1 * p.g * p.l1 / 2 * np.cos(phi) - p.d * p.l1**2 / 4 * w

    def accel(self, Y, u):
        p = self.p
        phi, w = Y[..., 0], Y[..., 1]
        c, s = np.cos(phi), np.sin(phi)
        tangential = c * u[..., 1] - s * u[..., 0]  # n1 . u
        if self.kind == "force":
            return (self._torque_ext(phi, w) - p.l1 * tangential) / p.JO1
        return tangential / p.l1

    def rhs(self, coef, H):
        def fun(t, Y):
            u = _poly(coef, np.asarray(t) / H)
            alpha = self.accel(Y, u)
            out = np.empty(alpha.shape + (2,))
            out[..., 0] = Y[..., 1]
            out[..., 1] = alpha
            return out

        return fun

    def outputs(self, Y, f, u):
        """``(P, P', P'', f)`` of the joint point, shape (B, 4, 2)."""
        p = self.p
        phi, w, alpha = Y[..., 0], Y[..., 1], f[..., 1]
        e = np.stack([np.cos(phi), np.sin(phi)], axis=-1)
        nrm = np.stack([-e[..., 1], e[..., 0]], axis=-1)
        P = p.l1 * e
        V = p.l1 * w[..., None] * nrm
        A = p.l1 * alpha[..., None] * nrm - p.l1 * (w * w)[..., None] * e
        if self.kind == "force":
            F = u
        else:  # tangential joint force that realises l1 phi1'' = n1 . a_tilde
            mu1 = (self._torque_ext(phi, w) - p.JO1 * alpha) / p.l1
            F = mu1[..., None] * nrm
        return np.stack([P, V, A, F], axis=-2)


class _Link2:
    """Free link 2: state ``(x_S2, y_S2, phi2, vx, vy, omega2)``."""

    n = 6

    def __init__(self, p: PendulumParameters, kind: str):
        self.p, self.kind = p, kind

    def rhs(self, coef, H):
        """``(v, a_S, phi2'')`` for the input ``u`` (force lambda or joint acceleration a_tilde)."""
        p = self.p
        l2h = p.l2 / 2
        if self.kind == "force":

            def fun(t, Y):
                u = _poly(coef, np.asarray(t) / H)
                c, s = np.cos(Y[..., 2]), np.sin(Y[..., 2])
                ux, uy = u[..., 0], u[..., 1]
                out = np.empty(np.broadcast_shapes(Y.shape[:-1], u.shape[:-1]) + (6,))
                out[..., 0:3] = Y[..., 3:6]
                out[..., 3] = (ux - p.d * Y[..., 3]) / p.m2
                out[..., 4] = (uy - p.d * Y[..., 4]) / p.m2 - p.g
                out[..., 5] = -l2h * (c * uy - s * ux) / p.J2
                return out

        else:
            inertia = p.J2 + p.m2 * l2h**2

            def fun(t, Y):
                u = _poly(coef, np.asarray(t) / H)
                c, s = np.cos(Y[..., 2]), np.sin(Y[..., 2])
                w = Y[..., 5]
                ux, uy = u[..., 0], u[..., 1]
                Fx = -p.d * Y[..., 3]
                Fy = -p.m2 * p.g - p.d * Y[..., 4]
                # (J + m l^2/4) phi2'' = (l/2) e2 x F - (m l/2) e2 x a_tilde
                alpha = l2h * ((c * Fy - s * Fx) - p.m2 * (c * uy - s * ux)) / inertia
                ww = w * w
                out = np.empty(np.broadcast_shapes(Y.shape[:-1], u.shape[:-1]) + (6,))
                out[..., 0:3] = Y[..., 3:6]
                # a_S = a_tilde + (l/2)(phi2'' n2 - omega2^2 e2)
                out[..., 3] = ux + l2h * (-alpha * s - ww * c)
                out[..., 4] = uy + l2h * (alpha * c - ww * s)
                out[..., 5] = alpha
                return out

        return fun

    def _force_ext(self, Y):
        p = self.p
        return np.stack([-p.d * Y[..., 3], -p.m2 * p.g - p.d * Y[..., 4]], axis=-1)

    def outputs(self, Y, f, u):
        p = self.p
        phi, w, alpha = Y[..., 2], Y[..., 5], f[..., 5]
        e = np.stack([np.cos(phi), np.sin(phi)], axis=-1)
        nrm = np.stack([-e[..., 1], e[..., 0]], axis=-1)
        P = Y[..., 0:2] - p.l2 / 2 * e
        V = Y[..., 3:5] - p.l2 / 2 * w[..., None] * nrm
        A = f[..., 3:5] - p.l2 / 2 * (alpha[..., None] * nrm - (w * w)[..., None] * e)
        F = u if self.kind == "force" else self.p.m2 * f[..., 3:5] - self._force_ext(Y)
        return np.stack([P, V, A, F], axis=-2)


# -- the co-simulation problem (protocol of icosim.macrostep) ----------------------
class PendulumCosimulation:
    """The double pendulum split into link 1 and link 2 (decomposition ff, fd or dd).

    State: ``s = (phi1, omega1, x_S2, y_S2, phi2, vx2, vy2, omega2)`` at ``T_N``.
    History: ``h[j, :] = e_N-j``, ``j = 0..k`` (names :data:`COUPLING_VARIABLES`).
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
        if not (isinstance(k, int) and not isinstance(k, bool) and k >= 0):
            raise ParameterError(f"k must be an integer >= 0, got {k!r}")
        for name, v in (("H", H), ("rtol", rtol), ("atol", atol), ("fd_step", fd_step), ("newton_tol", newton_tol)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
        self.backend = Float64()
        self.params, self.decomposition, self.k, self.H = params, dec, k, float(H)
        self.rtol, self.atol, self.fd_step, self.newton_tol = rtol, atol, fd_step, newton_tol
        self.links = (_Link1(params, dec.kinds[0]), _Link2(params, dec.kinds[1]))
        self.inputs = _INPUTS[dec.name]
        self.n_coupling = len(COUPLING_VARIABLES[dec.name])
        self.w_pred = np.array([float(w) for w in weights_at(predictor_nodes(k), 1)])
        # monomial coefficients of the interpolation polynomial (Eq. 11) in tau = (t - T_N)/H
        self.C_corr = np.array(monomial_coefficients(corrector_nodes(k)), dtype=float)
        self._cache = None
        self._jac0 = {}
        # split: integrations that took more than one step or rejected one (see the module docstring)
        self.stats = {"integrations": 0, "steps": 0, "rejected": 0, "fev": 0, "split": 0}

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
        fun = link.rhs(coef, self.H)
        # The Newton matrix of the first Radau step is shared by all integrations
        # of this link from this state (predictor, sensitivities, corrector).
        if self._jac0.get(i, (None,))[0] is not state:
            self._jac0[i] = (state, _fd_jacobian(fun, 0.0, y0[:1], fun(0.0, y0[:1]))[0])
        r = radau_batch(
            fun, 0.0, self.H, y0, rtol=self.rtol, atol=self.atol, newton_tol=self.newton_tol, jac0=self._jac0[i][1]
        )
        st = self.stats
        st["integrations"] += 1
        st["steps"] += r.n_steps
        st["rejected"] += r.n_rejected
        st["fev"] += r.n_fev
        st["split"] += r.n_steps > 1 or r.n_rejected > 0
        u1 = coef.sum(axis=1)  # input at tau = 1
        return r.y, link.outputs(r.y, r.f, u1)

    def _samples(self, history, e):
        """Corrector samples (k+1, n_e): ``e`` at ``T_N+1``, then ``e_N, ..., e_N-k+1``."""
        return np.concatenate([e[None, :], history[: self.k]], axis=0)

    def _linearise(self, state, history, e):
        """Outputs at ``e`` and ``d residuals / d e`` by forward differences (one batch per link)."""
        base = self._samples(history, e)
        n_e = self.n_coupling
        h = self.fd_step * np.maximum(1.0, np.abs(e))
        ys, perturbed = [], []
        for i in range(2):
            sl = self.inputs[i]
            idx = np.arange(n_e)[sl]
            batch = np.broadcast_to(base, (1 + idx.size,) + base.shape).copy()
            batch[1 + np.arange(idx.size), 0, idx] += h[idx]
            _, y = self._integrate(i, state, batch[:, :, sl])
            ys.append(y[0])
            perturbed.append(dict(zip(idx.tolist(), y[1:])))
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

    # -- the problem interface ------------------------------------------------
    def extrapolate(self, history):
        return np.tensordot(self.w_pred, history, axes=(0, 0))

    def predict(self, state, history):
        e_p = self.extrapolate(history)
        y, jac = self._linearise(state, history, e_p)
        self._cache = (state, history, e_p, jac)
        return y

    def jacobians(self, state, history, e, y):
        c = self._cache
        if c is not None and c[0] is state and c[1] is history and np.array_equal(c[2], e):
            return c[3]
        return self._linearise(state, history, e)[1]

    def correct(self, state, history, e_new):
        samples = self._samples(history, e_new)[None]
        ends, ys = [], []
        for i in range(2):
            end, y = self._integrate(i, state, samples[:, :, self.inputs[i]])
            ends.append(end[0])
            ys.append(y[0])
        return np.concatenate(ends), np.stack(ys)

    def residuals(self, y):
        """Joint constraint on each level (2 rows; dd: its normal component) and force balance."""
        d = y[..., 0, :, :] - y[..., 1, :, :]  # link 1 minus link 2: g_c, g_c', g_c'', f1 - f2
        if self.decomposition.name == "dd":
            P1 = y[..., 0, 0, :]
            e1 = P1 / np.linalg.norm(P1, axis=-1, keepdims=True)
            n1 = np.stack([-e1[..., 1], e1[..., 0]], axis=-1)
            proj = lambda v: np.sum(e1 * v, axis=-1, keepdims=True)  # noqa: E731
            return {
                "pos": proj(d[..., 0, :]),
                "vel": proj(d[..., 1, :]),
                "acc": proj(d[..., 2, :]),
                # n1 . mu_2 - mu_1 (f_1 = mu_1 n1)
                "force": -np.sum(n1 * d[..., 3, :], axis=-1, keepdims=True),
            }
        out = {"pos": d[..., 0, :], "vel": d[..., 1, :], "acc": d[..., 2, :]}
        out["force"] = -d[..., 3, :] if self.decomposition.name == "fd" else d[..., 3, :0]
        return out

    def project(self, state):
        return project_state(self.params, state)

    def shift(self, history, e_new):
        return np.concatenate([e_new[None, :], history[:-1]], axis=0)

    # -- quantities of a state ----------------------------------------------------
    def constraint(self, state):
        return joint_constraint(self.params, state)


def joint_points(p: PendulumParameters, state):
    """Joint point of link 1 and of link 2 (each ``(..., 2)``) for a co-simulation state."""
    phi1, x2, y2, phi2 = state[..., 0], state[..., 2], state[..., 3], state[..., 4]
    P1 = np.stack([p.l1 * np.cos(phi1), p.l1 * np.sin(phi1)], axis=-1)
    P2 = np.stack([x2 - p.l2 / 2 * np.cos(phi2), y2 - p.l2 / 2 * np.sin(phi2)], axis=-1)
    return P1, P2


def joint_constraint(p: PendulumParameters, state):
    """``(g_cax, g_cay)`` of Sect. 4 for a co-simulation state."""
    P1, P2 = joint_points(p, state)
    return P1 - P2


def _constraint_jacobian(p, q):
    """``G = d g_c / d q`` for ``q = (phi1, x2, y2, phi2)``, shape (2, 4)."""
    phi1, phi2 = q[0], q[3]
    return np.array(
        [
            [-p.l1 * math.sin(phi1), -1.0, 0.0, -p.l2 / 2 * math.sin(phi2)],
            [p.l1 * math.cos(phi1), 0.0, -1.0, p.l2 / 2 * math.cos(phi2)],
        ]
    )


class ProjectionError(StepFailure):
    """The projection onto the joint constraint did not converge (or met a singular system)."""


class CouplingSolveError(StepFailure):
    """The linear system for the corrected coupling variables is singular."""


def project_state(p: PendulumParameters, state, *, tol: float = 1e-14, max_iter: int = 20):
    """Mass-weighted projection of positions, then velocities, onto ``g_c = 0``, ``g_c' = 0``.

    Raises :class:`ProjectionError` if Gauss-Newton does not bring ``|g_c|`` to
    ``tol`` (m) within ``max_iter`` iterations: an unprojected state is never returned.
    """
    pos, vel = [0, 2, 3, 4], [1, 5, 6, 7]
    q_star = state[pos]
    Minv = 1.0 / np.array([p.JO1, p.m2, p.m2, p.J2])
    q = q_star.copy()
    g = None
    try:
        for _ in range(max_iter + 1):
            s = state.copy()
            s[pos] = q
            g = joint_constraint(p, s)
            if np.max(np.abs(g)) <= tol or not np.all(np.isfinite(g)):
                break
            G = _constraint_jacobian(p, q)
            # KKT fixed point: q = q* - M^-1 G^T nu, linearised g(q) + G (q_new - q) = 0
            nu = np.linalg.solve((G * Minv) @ G.T, g + G @ (q_star - q))
            q = q_star - Minv * (G.T @ nu)
        if not np.max(np.abs(g)) <= tol:  # also catches nan
            raise ProjectionError(
                f"projection: |g_c| = {np.max(np.abs(g)):.3g} m > {tol:g} m after {max_iter} Gauss-Newton iterations"
            )
        G = _constraint_jacobian(p, q)
        v = state[vel]
        nu = np.linalg.solve((G * Minv) @ G.T, G @ v)
    except np.linalg.LinAlgError as exc:
        raise ProjectionError(f"projection: singular constraint Jacobian ({exc})") from exc
    out = state.copy()
    out[pos] = q
    out[vel] = v - Minv * (G.T @ nu)
    return out


# -- monolithic model -----------------------------------------------------------
class Monolithic:
    """The whole pendulum in minimal coordinates ``(phi1, phi2)``; state ``(phi1, phi2, w1, w2)``.

    ``S_1 = l_1/2 e_1``, ``S_2 = l_1 e_1 + l_2/2 e_2``; Lagrange's equations of the
    second kind with the applied forces (gravity, damping at the centres of mass).
    """

    def __init__(self, params: PendulumParameters):
        self.p = params

    def _kinematics(self, Y):
        p = self.p
        phi1, phi2, w1, w2 = (Y[..., i] for i in range(4))
        e1 = np.stack([np.cos(phi1), np.sin(phi1)], axis=-1)
        e2 = np.stack([np.cos(phi2), np.sin(phi2)], axis=-1)
        n1 = np.stack([-e1[..., 1], e1[..., 0]], axis=-1)
        n2 = np.stack([-e2[..., 1], e2[..., 0]], axis=-1)
        w1c, w2c = w1[..., None], w2[..., None]
        v1 = p.l1 / 2 * w1c * n1
        v2 = p.l1 * w1c * n1 + p.l2 / 2 * w2c * n2
        c1 = -p.l1 / 2 * w1c**2 * e1  # convective accelerations of S1, S2
        c2 = -p.l1 * w1c**2 * e1 - p.l2 / 2 * w2c**2 * e2
        # Jacobians of S1, S2 w.r.t. (phi1, phi2): columns
        J1 = (p.l1 / 2 * n1, 0 * n1)
        J2 = (p.l1 * n1, p.l2 / 2 * n2)
        return e1, n1, e2, n2, v1, v2, c1, c2, J1, J2

    def _solve(self, Y):
        p = self.p
        e1, n1, e2, n2, v1, v2, c1, c2, J1, J2 = self._kinematics(Y)
        F1 = np.stack([-p.d * v1[..., 0], -p.m1 * p.g - p.d * v1[..., 1]], axis=-1)
        F2 = np.stack([-p.d * v2[..., 0], -p.m2 * p.g - p.d * v2[..., 1]], axis=-1)
        dot = lambda a, b: np.sum(a * b, axis=-1)  # noqa: E731
        M11 = p.m1 * dot(J1[0], J1[0]) + p.m2 * dot(J2[0], J2[0]) + p.J1
        M12 = p.m2 * dot(J2[0], J2[1])
        M22 = p.m2 * dot(J2[1], J2[1]) + p.J2
        Q1 = dot(J1[0], F1 - p.m1 * c1) + dot(J2[0], F2 - p.m2 * c2)
        Q2 = dot(J2[1], F2 - p.m2 * c2)
        det = M11 * M22 - M12 * M12
        a1 = (M22 * Q1 - M12 * Q2) / det
        a2 = (M11 * Q2 - M12 * Q1) / det
        return a1, a2, (e1, n1, J2, c2, F2)

    def rhs(self, t, Y):
        a1, a2, _ = self._solve(Y)
        return np.stack(np.broadcast_arrays(Y[..., 2], Y[..., 3], a1, a2), axis=-1)

    def joint_quantities(self, Y):
        """``lambda_c`` (force of link 1 on link 2) and the joint acceleration ``P''``, each ``(..., 2)``."""
        p = self.p
        a1, a2, (e1, n1, J2, c2, F2) = self._solve(Y)
        aS2 = J2[0] * a1[..., None] + J2[1] * a2[..., None] + c2
        lam = p.m2 * aS2 - F2
        w1 = Y[..., 2]
        acc = p.l1 * a1[..., None] * n1 - p.l1 * (w1 * w1)[..., None] * e1
        return lam, acc

    def initial_state(self):
        return np.array([self.p.phi1_0, self.p.phi2_0, 0.0, 0.0])

    def cosim_state(self, Y):
        """The co-simulation state ``(phi1, w1, x2, y2, phi2, vx2, vy2, w2)`` of a monolithic state."""
        p = self.p
        phi1, phi2, w1, w2 = Y
        e1 = np.array([math.cos(phi1), math.sin(phi1)])
        n1 = np.array([-e1[1], e1[0]])
        e2 = np.array([math.cos(phi2), math.sin(phi2)])
        n2 = np.array([-e2[1], e2[0]])
        s2 = p.l1 * e1 + p.l2 / 2 * e2
        v2 = p.l1 * w1 * n1 + p.l2 / 2 * w2 * n2
        return np.array([phi1, w1, s2[0], s2[1], phi2, v2[0], v2[1], w2])


def reference_solution(
    params: PendulumParameters, t, *, method: str = "DOP853", rtol: float = 1e-12, atol: float = 1e-12
):
    """Monolithic solution at the times ``t`` (any sign order: integrates from 0 both ways).

    Returns a dict of arrays ``phi1, phi2, omega1, omega2, lambda_cax, lambda_cay,
    a_x, a_y`` (the last two: joint acceleration) over ``t``.
    """
    from scipy.integrate import solve_ivp

    mono = Monolithic(params)
    t = np.asarray(t, dtype=float)
    Y = np.empty(t.shape + (4,))
    y0 = mono.initial_state()
    for sign in (1.0, -1.0):
        sel = np.flatnonzero(t * sign > 0)
        if not sel.size:
            continue
        sel = sel[np.argsort(t[sel] * sign)]  # in the direction of integration
        sol = solve_ivp(mono.rhs, (0.0, t[sel[-1]]), y0, method=method, rtol=rtol, atol=atol, t_eval=t[sel])
        if not sol.success:
            raise RuntimeError(f"reference integration failed: {sol.message}")
        Y[sel] = sol.y.T
    Y[t == 0] = y0
    lam, acc = mono.joint_quantities(Y)
    return {
        "phi1": Y[:, 0],
        "phi2": Y[:, 1],
        "omega1": Y[:, 2],
        "omega2": Y[:, 3],
        "lambda_cax": lam[:, 0],
        "lambda_cay": lam[:, 1],
        "a_x": acc[:, 0],
        "a_y": acc[:, 1],
    }


def consistent_history(params: PendulumParameters, decomposition: str, k: int, H: float, **ref_kw):
    """Exact coupling variables at ``T_0, T_-1, ..., T_-k`` from the monolithic solution.

    Backwards in time from the initial state, as for the linear model
    (:func:`icosim.exact.consistent_start`): ``lambda_c`` and/or the joint
    acceleration ``a_tilde``.
    """
    ref = reference_solution(params, -H * np.arange(k + 1), **ref_kw)
    cols = {
        "lambda_cax": ref["lambda_cax"],
        "lambda_cay": ref["lambda_cay"],
        "a_tilde_x": ref["a_x"],
        "a_tilde_y": ref["a_y"],
    }
    return np.stack([cols[name] for name in COUPLING_VARIABLES[decomposition]], axis=-1)


# -- a whole run ------------------------------------------------------------------
@dataclass
class RunResult:
    """Time series of one co-simulation run up to the end time, divergence or failure.

    ``status`` is ``stable`` (reached the end time), ``diverged`` (a step
    exceeded a bound or was not finite, at ``t_diverged``) or ``failed`` (a
    step could not be computed, at ``t_failed``); ``reason`` says why.
    """

    t: np.ndarray
    series: dict  # name -> array over t (VARIABLES plus g_cax_corrector, g_cay_corrector)
    status: str
    t_diverged: float  # nan unless diverged
    t_failed: float  # nan unless failed
    reason: str
    stats: dict
    wall_time: float

    @property
    def diverged(self) -> bool:
        return self.status == "diverged"

    @property
    def failed(self) -> bool:
        return self.status == "failed"


class _SingularSolveAsFailure:
    """A coupling method whose singular linear solve is a failed step (:class:`CouplingSolveError`)."""

    def __init__(self, method: CouplingMethod):
        self._method = method

    def __getattr__(self, name):
        return getattr(self._method, name)

    def corrected_coupling(self, *args, **kwargs):
        try:
            return self._method.corrected_coupling(*args, **kwargs)
        except np.linalg.LinAlgError as exc:
            raise CouplingSolveError(f"singular coupling system ({exc})") from exc


def _series_row(p: PendulumParameters, state, g_corrector, lam) -> dict:
    """One time point of the stored series."""
    g = joint_constraint(p, state)
    return dict(
        phi1=state[0],
        phi2=state[4],
        g_cax=g[0],
        g_cay=g[1],
        lambda_cax=lam[0],
        lambda_cay=lam[1],
        g_cax_corrector=g_corrector[0],
        g_cay_corrector=g_corrector[1],
    )


def run_cosimulation(
    params: PendulumParameters,
    method: CouplingMethod,
    decomposition: str,
    k: int,
    *,
    H: float,
    t_end: float,
    rtol: float = 1e-6,
    atol: float = 1e-6,
    fd_step: float = 1e-3,
    newton_tol: float = 1e-8,
    iterations: int = 1,
    tol: float | None = None,
    max_constraint: float = 1e-2,
    max_multiplier: float = 1e3,
    max_rate: float = 1e2,
) -> RunResult:
    """Co-simulate from ``t = 0`` to ``t_end`` with macro step ``H`` (:func:`icosim.macrostep.simulate`).

    The run *diverges* at the first macro step whose state, coupling variables
    or outputs are not finite, whose joint constraint (after the step or after
    the corrector) exceeds ``max_constraint`` (m), whose joint force exceeds
    ``max_multiplier`` (N) or whose angular rates exceed ``max_rate`` (rad/s);
    it *fails* at the first step that raises a
    :class:`~icosim.macrostep.StepFailure`.  The series end at the step before.
    """
    dec = get_decomposition(decomposition)
    method.check_decomposition(dec)
    if not (isinstance(iterations, int) and iterations >= 1):
        raise ParameterError(f"iterations must be an integer >= 1, got {iterations!r}")
    for name, v in (
        ("t_end", t_end),
        ("max_constraint", max_constraint),
        ("max_multiplier", max_multiplier),
        ("max_rate", max_rate),
    ):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
    if tol is not None and not (math.isfinite(tol) and tol > 0):
        raise ParameterError(f"tol must be a finite number > 0 or null, got {tol!r}")
    n_steps = int(round(t_end / H))
    if abs(n_steps * H - t_end) > 1e-9 * t_end:
        raise ParameterError(f"t_end = {t_end!r} must be a whole number of macro steps H = {H!r}")
    problem = PendulumCosimulation(params, dec.name, k, H, rtol=rtol, atol=atol, fd_step=fd_step, newton_tol=newton_tol)
    state = params.initial_state()
    history = consistent_history(params, dec.name, k, H)

    def joint_force(e, y):
        return y[1, 3] if dec.name == "dd" else e[:2]

    def check(state, history, y):
        """Reason for divergence of a step, or None."""
        g = problem.constraint(state)
        g_corr = y[0, 0] - y[1, 0]
        lam = joint_force(history[0], y)
        if not np.all(np.isfinite(np.concatenate([state, history[0], g, g_corr, lam]))):
            return "not finite"
        if np.max(np.abs(g)) > max_constraint or np.max(np.abs(g_corr)) > max_constraint:
            return f"|g_c| > {max_constraint} m"
        if np.max(np.abs(lam)) > max_multiplier:
            return f"|lambda_c| > {max_multiplier} N"
        if max(abs(state[1]), abs(state[7])) > max_rate:
            return f"|omega| > {max_rate} rad/s"
        return None

    t0 = time.perf_counter()
    with np.errstate(all="ignore"):
        traj = simulate(
            problem,
            _SingularSolveAsFailure(method),
            state,
            history,
            n_steps,
            check=check,
            iterations=iterations,
            tol=tol,
        )
    wall = time.perf_counter() - t0
    g0 = problem.constraint(state)
    rows = [_series_row(params, state, g0, consistent_history(params, "ff", 0, H)[0])]
    for s, e, y in zip(traj.states[1:], traj.coupling[1:], traj.outputs[1:]):
        rows.append(_series_row(params, s, y[0, 0] - y[1, 0], joint_force(e, y)))
    n_done = len(rows) - 1
    series = {name: np.array([row[name] for row in rows], dtype=float) for name in rows[0]}
    status = "failed" if traj.failed_at else "diverged" if traj.diverged_at else "stable"
    t_div = traj.diverged_at * H if traj.diverged_at else math.nan
    t_fail = traj.failed_at * H if traj.failed_at else math.nan
    stats = dict(problem.stats, macro_steps=n_done)
    return RunResult(H * np.arange(n_done + 1), series, status, t_div, t_fail, traj.reason or "", stats, wall)


# -- datasets, summary and claims ------------------------------------------------------
def run_name(method: str, decomposition: str, k: int) -> str:
    """File stem of a run: ``{method}_{decomposition}_k{k}``."""
    return f"{method}_{decomposition}_k{k}"


def _series_dataset(t, series, attrs):
    import xarray as xr

    data_vars = {}
    for name, values in series.items():
        if name in VARIABLES:
            units, long_name = VARIABLES[name]
        else:  # the constraint after the corrector, before a projection
            units, long_name = (
                "m",
                VARIABLES[name.replace("_corrector", "")][1] + " after the corrector (before projection)",
            )
        data_vars[name] = ("t", np.asarray(values, dtype=float), {"units": units, "long_name": long_name})
    coords = {"t": ("t", np.asarray(t, dtype=float), {"units": "s", "long_name": "time", "standard_name": "time"})}
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


#: Units of the dimensional method parameters (the pendulum works in SI units).
_METHOD_UNITS = {"mu": "s", "beta": "s", "gamma": "s2", "a": "1", "b": "1"}


def run_dataset(
    result: RunResult, method: CouplingMethod, decomposition: str, k: int, settings: dict, provenance: dict
):
    """The NetCDF contract of a co-simulation run (see the issue): series over ``t`` and attributes.

    ``settings`` (H, t_end, tolerances, ...) are copied into the attributes; ``None`` values are
    written as the string ``"none"`` (NetCDF attributes cannot be empty).
    """
    attrs = dict(provenance)
    attrs.update(
        method=method.name,
        decomposition=decomposition,
        k=int(k),
        status=result.status,
        reason=result.reason or "none",
        diverged=int(result.diverged),
        t_diverged=float(result.t_diverged),
        failed=int(result.failed),
        t_failed=float(result.t_failed),
        wall_time_s=float(result.wall_time),
        sensitivities=(
            "forward differences w.r.t. e_N+1, step fd_step * max(1, |e_j|), in one batched Radau call per link "
            "(shared step sequence); the corrector "
            "integrates alone with its own step sequence, which differs from the batch's only in the "
            f"n_split = {int(result.stats.get('split', 0))} integrations that took more than one step "
            "(then an O(rtol) mismatch between linearisation and corrector)"
        ),
    )
    for key, value in method.params.items():
        attrs[f"method_{key}"] = value
        if key in _METHOD_UNITS:  # SI units: unlike the stability datasets' dimensionless mu_bar = mu/H
            attrs[f"method_{key}_units"] = _METHOD_UNITS[key]
    for key, value in settings.items():
        attrs[key] = "none" if value is None else value
    for key, value in result.stats.items():
        attrs[f"n_{key}"] = int(value)
    return _series_dataset(result.t, result.series, attrs)


def reference_dataset(
    params: PendulumParameters, H: float, t_end: float, provenance: dict, *, method="DOP853", rtol=1e-12, atol=1e-12
):
    """The monolithic reference on the macro-time grid, stored like a run (``method = "monolithic"``)."""
    n = int(round(t_end / H))
    t = H * np.arange(n + 1)
    t0 = time.perf_counter()
    ref = reference_solution(params, t, method=method, rtol=rtol, atol=atol)
    wall = time.perf_counter() - t0
    mono = Monolithic(params)
    states = np.array(
        [mono.cosim_state(Y) for Y in np.stack([ref["phi1"], ref["phi2"], ref["omega1"], ref["omega2"]], axis=-1)]
    )
    g = joint_constraint(params, states)
    series = {
        "phi1": ref["phi1"],
        "phi2": ref["phi2"],
        "g_cax": g[:, 0],
        "g_cay": g[:, 1],
        "lambda_cax": ref["lambda_cax"],
        "lambda_cay": ref["lambda_cay"],
    }
    attrs = dict(provenance)
    attrs.update(
        method="monolithic",
        decomposition="none",
        k=-1,
        status="stable",
        diverged=0,
        t_diverged=math.nan,
        failed=0,
        t_failed=math.nan,
        integrator=f"scipy solve_ivp {method}",
        rtol=rtol,
        atol=atol,
        H=H,
        t_end=t_end,
        formulation="minimal coordinates phi1, phi2 (joint constraint satisfied exactly)",  # not "coordinates": CF reserves it
        wall_time_s=wall,
    )
    return _series_dataset(t, series, attrs)


OUTCOMES = ("stable", "unstable")


def _validate_stability_check(label: str, params: dict):
    """Parameters of a ``pendulum_stability`` check (read with the claims file; errors name claim and key)."""
    if params["default"] not in OUTCOMES:
        raise ParameterError(f"{label}: check.default must be one of {list(OUTCOMES)}, got {params['default']!r}")
    exceptions = params.get("exceptions", [])
    if not isinstance(exceptions, list):
        raise ParameterError(f"{label}: check.exceptions must be a list of {{method, decomposition, k, expected}}")
    for j, ex in enumerate(exceptions):
        where = f"{label}: check.exceptions[{j}]"
        keys = {"method", "decomposition", "k", "expected"}
        if not isinstance(ex, dict) or set(ex) != keys:
            got = sorted(ex) if isinstance(ex, dict) else ex
            raise ParameterError(f"{where} must have exactly the keys {sorted(keys)}, got {got}")
        if ex["expected"] not in OUTCOMES:
            raise ParameterError(f"{where}.expected must be one of {list(OUTCOMES)}, got {ex['expected']!r}")


def expected_outcome(check: dict, method: str, decomposition: str, k: int) -> str:
    """``stable`` or ``unstable`` according to a ``pendulum_stability`` check (default and exceptions)."""
    for ex in check.get("exceptions", []):
        if ex["method"] == method and ex["decomposition"] == decomposition and int(ex["k"]) == int(k):
            return ex["expected"]
    return check["default"]


def run_verdict(expected: str, observed: str) -> str:
    """One run against the claim: a failed run (no step computed) decides nothing."""
    return "undecided" if observed == "failed" else "pass" if expected == observed else "fail"


@register_check("pendulum_stability", validate=_validate_stability_check)
def check_pendulum_stability(datasets, *, default: str, exceptions: list | None = None):
    """Sect. 4: every run behaves as claimed (``default``, or its entry of ``exceptions``).

    ``datasets`` are summaries (:func:`summarize`, one row per run).  Fails if a
    run does not behave as claimed; otherwise undecided if a run failed (no
    verdict of its own) or a configuration named in ``exceptions`` was not run;
    else passes.
    """
    check = {"default": default, "exceptions": exceptions or []}
    numbers, holds, have = {}, [], set()
    for ds in datasets:
        for m, d, k, observed in zip(
            ds["method"].values, ds["decomposition"].values, ds["k"].values, ds["observed"].values
        ):
            m, d, k, observed = str(m), str(d), int(k), str(observed)
            have.add((m, d, k))
            expected = expected_outcome(check, m, d, k)
            verdict = run_verdict(expected, observed)
            numbers[run_name(m, d, k)] = {"expected": expected, "observed": observed, "verdict": verdict}
            holds.append({"pass": True, "fail": False}.get(verdict))
    missing = [
        run_name(ex["method"], ex["decomposition"], ex["k"])
        for ex in check["exceptions"]
        if (ex["method"], ex["decomposition"], int(ex["k"])) not in have
    ]
    holds += [None] * len(missing)
    counts = {v: sum(n["verdict"] == v for n in numbers.values()) for v in ("pass", "fail", "undecided")}
    text = (
        f"{len(numbers)} runs: {counts['pass']} as claimed, {counts['fail']} not, {counts['undecided']} failed"
        + "".join(
            f"; {name}: expected {n['expected']}, observed {n['observed']}"
            for name, n in numbers.items()
            if n["verdict"] != "pass"
        )
        + (f"; not run: {', '.join(missing)}" if missing else "")
    )
    return Outcome(combine_holds(holds), text, {"runs": numbers, "not_run": missing})


def configured_runs(cfg: dict) -> list:
    """``(method, decomposition, k)`` of every run of a ``pendulum:`` config, checked up front.

    Builds each method (so a parameter it does not take, or Baumgarte/weighted with
    dd, fails here naming the configuration) and checks ``t_end`` against ``H``.
    """
    from .coupling import make_method

    H, t_end = cfg["H"], cfg["t_end"]
    n = round(t_end / H)
    if n < 1 or abs(n * H - t_end) > 1e-9 * t_end:
        raise ParameterError(f"pendulum.t_end = {t_end!r} must be a positive whole number of macro steps H = {H!r}")
    runs = []
    for i, c in enumerate(cfg["configurations"]):
        name, dec = c["method"], c["decomposition"]
        if name not in cfg["methods"]:
            raise ParameterError(
                f"pendulum.configurations[{i}]: method {name!r} has no parameters under pendulum.methods (give {name}: {{}} if it takes none)"
            )
        try:
            method = make_method(name, **cfg["methods"][name])
            method.check_decomposition(get_decomposition(dec))
        except ParameterError as exc:
            raise ParameterError(f"pendulum.configurations[{i}] ({name}, {dec}): {exc}") from None
        runs += [(name, dec, int(k)) for k in cfg["k"]]
    if len(set(runs)) != len(runs):
        raise ParameterError("pendulum.configurations lists a (method, decomposition) pair twice")
    return runs


def pendulum_test_model(params: PendulumParameters, H: float):
    """The pendulum's point in the parameter plane of Sect. 3: a :class:`~icosim.TestModel` with two points.

    As in the paper's explanation of Fig. 8, ``lr1 = -d H / (2 m1)`` (the
    damping per unit mass of one link, in macro steps).  ``li1 = omega H`` for
    the two modal frequencies ``omega`` of the pendulum linearised about its
    hanging rest (imaginary parts of the eigenvalues of the monolithic model's
    Jacobian, central differences): the two points bracket the frequencies the
    swinging pendulum passes through.  Ratios: ``am21 = m2/m1``,
    ``alr21 = m1/m2`` (the same damping ``d`` on each link), ``ali21 = 1``.
    """
    from .model import TestModel

    mono = Monolithic(params)
    y0 = np.array([-math.pi / 2, -math.pi / 2, 0.0, 0.0])
    h = 1e-6
    jac = np.array([(mono.rhs(0, y0 + h * ej) - mono.rhs(0, y0 - h * ej)) / (2 * h) for ej in np.eye(4)]).T
    omegas = np.sort(np.unique(np.round(np.abs(np.linalg.eigvals(jac).imag), 12)))
    omegas = omegas[omegas > 0]
    lr1 = -params.d * H / (2 * params.m1)
    return TestModel(np.full(omegas.shape, lr1), omegas * H, params.m2 / params.m1, params.m1 / params.m2, 1.0)


def linear_test_model_rho(params: PendulumParameters, H: float, method: CouplingMethod, decomposition: str, k: int):
    """Largest spectral radius of the linear test model (Sect. 3) at the pendulum's points
    (:func:`pendulum_test_model`), for the dimensionless form of ``method``.

    Baumgarte's parameters are in seconds here and become ``beta_bar = beta/H``,
    ``gamma_bar = gamma/H^2``; the weighted multiplier's ``a``, ``b`` are
    dimensionless already.  Returns ``(rho, model)``.
    """
    from .coupling import make_method
    from .stability import spectral_radius

    if method.name == "baumgarte":
        dimensionless = make_method("baumgarte", beta=method.params["beta"] / H, gamma=method.params["gamma"] / H**2)
    else:
        dimensionless = method
    model = pendulum_test_model(params, H)
    result = spectral_radius(model, dimensionless, decomposition, int(k))
    return float(np.max(result.rho)), model


def summarize(runs: list, reference, claims: list, rho_test_model: dict | None = None):
    """One row per run: status, errors against the reference, claim expectation and verdict.

    ``runs`` are run datasets, ``reference`` the monolithic one, ``claims`` the
    :class:`~icosim.claims.Claim` list of ``config/claims/pendulum.yaml`` (each
    ``pendulum_stability`` claim adds ``expected_<id>`` and ``verdict_<id>``).  Errors are maxima over the
    computed part of the run (up to divergence or failure).  A run is observed
    ``unstable`` if it diverged, ``failed`` if a step could not be computed:
    its verdict is then ``undecided`` (a solver failure proves no instability).
    ``rho_test_model`` (run name -> spectral radius of the linear test model,
    :func:`linear_test_model_rho`) adds that column.
    """
    import xarray as xr

    rows = []
    for ds in runs:
        n = ds.sizes["t"]
        if not np.allclose(ds["t"].values, reference["t"].values[:n], rtol=0, atol=1e-12):
            raise ValueError(
                f"run {ds.attrs['method']}/{ds.attrs['decomposition']}/k={ds.attrs['k']} is not on the reference grid"
            )
        err = {
            name: float(np.max(np.abs(ds[name].values - reference[name].values[:n])))
            for name in ("phi1", "phi2", "lambda_cax", "lambda_cay")
        }
        g = np.hypot(ds["g_cax"].values, ds["g_cay"].values)
        g_corr = np.hypot(ds["g_cax_corrector"].values, ds["g_cay_corrector"].values)
        status = str(ds.attrs["status"])
        observed = {"stable": "stable", "diverged": "unstable", "failed": "failed"}[status]
        row = dict(
            method=ds.attrs["method"],
            decomposition=ds.attrs["decomposition"],
            k=int(ds.attrs["k"]),
            status=status,
            reason=str(ds.attrs.get("reason", "none")),
            diverged=int(ds.attrs["diverged"]),
            t_diverged=float(ds.attrs["t_diverged"]),
            failed=int(ds.attrs["failed"]),
            t_failed=float(ds.attrs["t_failed"]),
            t_last=float(ds["t"].values[-1]),
            err_phi1=err["phi1"],
            err_phi2=err["phi2"],
            err_lambda=max(err["lambda_cax"], err["lambda_cay"]),
            max_g=float(np.max(g)),
            max_g_corrector=float(np.max(g_corr)),
            wall_time_s=float(ds.attrs.get("wall_time_s", math.nan)),
            observed=observed,
        )
        if rho_test_model is not None:
            row["rho_test_model"] = float(rho_test_model[run_name(row["method"], row["decomposition"], row["k"])])
        for claim in claims:
            if claim.check["kind"] != "pendulum_stability":
                continue
            exp = expected_outcome(claim.check, row["method"], row["decomposition"], row["k"])
            row[f"expected_{claim.id}"] = exp
            row[f"verdict_{claim.id}"] = run_verdict(exp, observed)
        rows.append(row)
    names = [run_name(r["method"], r["decomposition"], r["k"]) for r in rows]
    data = {key: ("run", [r[key] for r in rows]) for key in rows[0] if key not in ("method", "decomposition", "k")}
    coords = {
        "run": ("run", names),
        "method": ("run", [r["method"] for r in rows]),
        "decomposition": ("run", [r["decomposition"] for r in rows]),
        "k": ("run", [r["k"] for r in rows]),
    }
    units = {
        "t_diverged": "s",
        "t_failed": "s",
        "t_last": "s",
        "err_phi1": "rad",
        "err_phi2": "rad",
        "err_lambda": "N",
        "max_g": "m",
        "max_g_corrector": "m",
        "wall_time_s": "s",
    }
    ds = xr.Dataset(data, coords=coords)
    for key, u in units.items():
        ds[key].attrs["units"] = u
    ds["err_phi1"].attrs["long_name"] = "max |phi1 - phi1_ref| up to the end of the run"
    ds["err_phi2"].attrs["long_name"] = "max |phi2 - phi2_ref| up to the end of the run"
    ds["err_lambda"].attrs["long_name"] = "max |lambda_c - lambda_c_ref| (both components)"
    ds["max_g"].attrs["long_name"] = "max |g_c| of the stored states"
    ds["max_g_corrector"].attrs["long_name"] = "max |g_c| after the corrector, before any projection"
    if rho_test_model is not None:
        ds["rho_test_model"].attrs["long_name"] = (
            "largest spectral radius of the linear test model (Sect. 3) at the pendulum's points (lr1, li1)"
        )
        ds["rho_test_model"].attrs["units"] = "1"
    return ds
