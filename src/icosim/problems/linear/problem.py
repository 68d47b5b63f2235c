"""The linear two-mass test model as a co-simulation problem (Sect. 2).

State: ``s[..., i, :] = (x_i, v_i)`` for subsystems ``i = 0, 1`` (the paper's
``z_N``).  Coupling history: ``h[..., j, :] = e_N-j`` for ``j = 0..k`` (the
paper's ``lambda_c,N ... lambda_c,N-k`` and/or ``a_tilde``).  Outputs at
``T_N+1``: ``y[..., i, 0, :, 0] = (x_i, v_i, a_i, f_i)`` (one port, one component) with ``f_i`` the
coupling force acting on subsystem ``i``: its input for a force-driven one, the force its drive exerts for
a kinematically driven one (:mod:`icosim.engine.graph`).

All arrays may carry leading batch axes; the coefficients broadcast against
them.  This is what lets :mod:`icosim.studies.stability` build the amplification
matrices of a whole parameter grid in one pass.
"""

from __future__ import annotations

import copy

import numpy as np

from ...engine import layout
from ...engine.problem import CosimulationProblem
from ...engine.projection import joined_clusters, mass_weighted_projection
from .model import Coefficients
from .subsystems import FORCE, OscillatorSubsystem

__all__ = ["LinearCosimulation"]


class LinearCosimulation(CosimulationProblem):
    """Two single-mass oscillators coupled by a rigid link, integrated exactly.

    Parameters
    ----------
    coefficients : :class:`icosim.problems.linear.model.Coefficients` (arrays broadcast).
    decomposition : ``"ff"``, ``"fd"`` or ``"dd"`` (or a Decomposition).
    k : degree of the Lagrange polynomials (any integer >= 0).
    backend : arithmetic; float64 by default.

    Examples
    --------
    One macro step with projection, from both masses at rest at ``x = 1``,
    leaves them at one position and velocity, after four subsystem
    integrations (predictor and corrector of each), one coupling solve and one
    projection; with Gauss-Seidel (subsystem 1 first) after three:

    >>> from icosim import TestModel, make_method
    >>> from icosim.engine.macrostep import macro_step
    >>> p = LinearCosimulation(TestModel(-0.1, 0.5).coefficients(), "ff", k=0)
    >>> state, history = np.array([[1.0, 0.0], [1.0, 0.0]]), np.zeros((1, 1))
    >>> s1, h1, y = macro_step(p, make_method("projection"), state, history)
    >>> bool(np.allclose(s1[0], s1[1])), p.work.as_dict()
    (True, {'subsystem_integrations': 4, 'coupling_solves': 1, 'projections': 1})
    >>> p.work.reset()
    >>> s1, h1, y = macro_step(p, make_method("projection"), state, history, scheme="gauss-seidel-12")
    >>> bool(np.allclose(s1[0], s1[1])), p.work.subsystem_integrations
    (True, 3)
    """

    def __init__(self, coefficients: Coefficients, decomposition, k: int, backend=None):
        super().__init__(decomposition, k, backend)
        be = self.backend
        decomposition = self.decomposition
        c = coefficients.map(be.asarray)
        self.coefficients = c
        # the multiplier acts with +lambda on subsystem 1 and -lambda on 2 (the graph's inputs): the gains are
        # the inverse masses, 1 and 1/am21
        self.subsystems = tuple(
            OscillatorSubsystem(kind, kk, dd, g, 0, k, be)
            for kind, kk, dd, g in zip(
                decomposition.kinds,
                (c.k1, c.k2),
                (c.delta1, c.delta2),
                (be.const(1) + 0 * c.am21, be.const(1) / c.am21),
            )
        )

    # -- sizes and packing ---------------------------------------------------
    @property
    def n_state(self) -> int:
        """Length of the packed state ``(x1, v1, x2, v2, e_N, ..., e_N-k)``."""
        return 4 + (self.k + 1) * self.n_coupling

    def pack(self, state, history):
        lead = np.broadcast_shapes(state.shape[:-2], history.shape[:-2])
        state = np.broadcast_to(state, lead + (2, 2))
        history = np.broadcast_to(history, lead + history.shape[-2:])
        # (x1, v1, x2, v2, e_N, ..., e_N-k): the rows of state and history one after the other (no reshape: that
        # would copy a grid laid out with its grid axes fastest into C order first)
        parts = [state[..., i, :] for i in range(2)] + [history[..., j, :] for j in range(history.shape[-2])]
        return layout.concatenate(parts, axis=-1)

    def unpack(self, w):
        lead = w.shape[:-1]
        return w[..., :4].reshape(lead + (2, 2)), w[..., 4:].reshape(lead + (self.k + 1, self.n_coupling))

    # -- what the float64 error estimate asks (icosim.engine.spectral.radius) ------
    def disturbed(self, rng, rel):
        """A copy whose exponential blocks carry absolute noise ``rel * max|E|`` (the size of their rounding)."""
        p = copy.copy(self)
        subs = []
        for sub in self.subsystems:
            s = copy.copy(sub)
            s.__dict__.pop("_node_cache", None)
            E = sub.blocks
            scale = rel * np.max(np.abs(E), axis=(-1, -2), keepdims=True)
            s.set_blocks(E + scale * rng.standard_normal(E.shape))
            subs.append(s)
        p.subsystems = tuple(subs)
        p._jacobians = {}
        return p

    def generator_norm(self):
        """``nu = max(1, ||A||_1)`` over the subsystems, ``A`` the matrix whose exponential a subsystem's blocks
        are (per point; a kinematically driven subsystem's ``A`` has ones and zeros only)."""
        nu = 1.0
        for sub in self.subsystems:
            if sub.kind == FORCE:  # columns of A: k, 1 + delta, the gain, then the input's shift (ones)
                nu = np.maximum(nu, np.maximum(np.abs(sub.stiffness), 1 + np.abs(sub.damping)))
                nu = np.maximum(nu, np.abs(sub.gain))
        return nu[..., 0] if np.ndim(nu) else nu  # without the axis the basis vectors ride on (length 1)

    # -- the problem interface used by icosim.engine.macrostep ----------------------
    def _integrate(self, i, state, samples, nodes):
        self.work.subsystem_integrations += 1
        end, y = self.subsystems[i].step(state[..., i, :], self.inputs(i, samples)[..., 0], nodes)
        return end, y[..., None, :, None]

    def predict(self, i, state, history, *, final=False):
        return self._integrate(i, state, history, self.pred_nodes)

    def correct(self, i, state, history, e_new):
        return self._integrate(i, state, self.corrector_samples(history, e_new), self.corr_nodes)

    def reevaluate(self, i, end, y, e_old, e_new):
        """Exact (the outputs are affine in the input at a fixed state): ``y + dy/du(1) (u_new - u_old)``.

        The increment form keeps the propagated acceleration (no cancellation
        in ``-k x - delta v + g u`` when the acceleration is exponentially small).
        """
        du = self.inputs(i, e_new)[..., 0] - self.inputs(i, e_old)[..., 0]
        dy = self.subsystems[i].algebraic_sensitivity() * du[..., None]
        return y + dy[..., None, :, None]

    def join(self, ends):
        return _stack(ends)

    #: exact and constant (Eq. 13): the Jacobians are formed once per stage, not counted as work
    constant_sensitivities = True

    def sensitivity(self, i, state, history, e, end=None, y=None):
        """``dy_i/du_i``, shape ``(..., 1, 1, 4, 1)``: through the interpolation polynomial of the corrector
        (Eq. 13) or, at a fixed end state, algebraically
        (:meth:`~icosim.problems.linear.subsystems.OscillatorSubsystem.algebraic_sensitivity`)."""
        sub = self.subsystems[i]
        dy = sub.step_sensitivity(self.corr_nodes) if end is None else sub.algebraic_sensitivity()
        return dy[..., None, None, :, None]

    def project(self, state):
        """Mass-weighted projection of positions and velocities (Eq. 30,
        :func:`icosim.engine.projection.mass_weighted_projection`)."""
        am = self.coefficients.am21
        masses = layout.stack(np.broadcast_arrays(1 + 0 * am, am), axis=-1)
        return mass_weighted_projection(joined_clusters(self.graph, (0, 1)), masses, state)


def _stack(arrays):
    return layout.stack(np.broadcast_arrays(*arrays), axis=-2)
