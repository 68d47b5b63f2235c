"""The linear two-mass test model as a co-simulation problem (Sect. 2).

State: ``s[..., i, :] = (x_i, v_i)`` for subsystems ``i = 0, 1`` (the paper's
``z_N``).  Coupling history: ``h[..., j, :] = e_N-j`` for ``j = 0..k`` (the
paper's ``lambda_c,N ... lambda_c,N-k`` and/or ``a_tilde``).  Outputs at
``T_N+1``: ``y[..., i, :] = (x_i, v_i, a_i, f_i)`` with ``f_i`` the coupling
force acting on subsystem ``i`` (``lambda_c`` for a force-driven one, the
multiplier ``mu_i`` for a kinematically driven one).

All arrays may carry leading batch axes; the coefficients broadcast against
them.  This is what lets :mod:`icosim.stability` build the amplification
matrices of a whole parameter grid in one pass.
"""

from __future__ import annotations

import numpy as np

from .backend import Float64
from .coupling import Decomposition, get_decomposition
from .lagrange import corrector_nodes, predictor_nodes, weights_at
from .model import Coefficients
from .subsystems import OscillatorSubsystem

__all__ = ["LinearCosimulation"]


class LinearCosimulation:
    """Two single-mass oscillators coupled by a rigid link, integrated exactly.

    Parameters
    ----------
    coefficients : :class:`icosim.model.Coefficients` (arrays broadcast).
    decomposition : ``"ff"``, ``"fd"`` or ``"dd"`` (or a Decomposition).
    k : degree of the Lagrange polynomials (any integer >= 0).
    backend : arithmetic; float64 by default.
    """

    def __init__(self, coefficients: Coefficients, decomposition, k: int, backend=None):
        self.backend = be = backend or Float64()
        if not isinstance(decomposition, Decomposition):
            decomposition = get_decomposition(decomposition)
        self.decomposition = decomposition
        self.k = k
        c = coefficients.map(be.asarray)
        self.coefficients = c
        self.subsystems = tuple(
            OscillatorSubsystem(kind, kk, dd, g, inp, k, be)
            for kind, kk, dd, g, inp in zip(
                decomposition.kinds,
                (c.k1, c.k2),
                (c.delta1, c.delta2),
                (be.const(1) + 0 * c.am21, -be.const(1) / c.am21),
                decomposition.inputs,
            )
        )
        self.w_pred = np.array([be.const(w) for w in weights_at(predictor_nodes(k), 1)], dtype=be.dtype)

        self.pred_nodes = predictor_nodes(k)
        self.corr_nodes = corrector_nodes(k)

    # -- sizes and packing ---------------------------------------------------
    @property
    def n_coupling(self) -> int:
        return self.decomposition.n_coupling

    @property
    def n_state(self) -> int:
        """Length of the packed state ``(x1, v1, x2, v2, e_N, ..., e_N-k)``."""
        return 4 + (self.k + 1) * self.n_coupling

    def pack(self, state, history):
        lead = np.broadcast_shapes(state.shape[:-2], history.shape[:-2])
        state = np.broadcast_to(state, lead + (2, 2))
        history = np.broadcast_to(history, lead + history.shape[-2:])
        return np.concatenate([state.reshape(lead + (4,)), history.reshape(lead + (-1,))], axis=-1)

    def unpack(self, w):
        lead = w.shape[:-1]
        return w[..., :4].reshape(lead + (2, 2)), w[..., 4:].reshape(lead + (self.k + 1, self.n_coupling))

    # -- the problem interface used by icosim.macrostep ----------------------
    def extrapolate(self, history):
        return sum(self.w_pred[j] * history[..., j, :] for j in range(self.k + 1))

    def _propagate(self, state, samples, nodes):
        ss, ys = zip(
            *(sub.step(state[..., i, :], samples[..., :, sub.input], nodes) for i, sub in enumerate(self.subsystems))
        )
        return _stack(ss), _stack(ys)

    def predict(self, state, history):
        return self._propagate(state, history, self.pred_nodes)[1]

    def correct(self, state, history, e_new):
        return self._propagate(state, _prepend(e_new, history[..., : self.k, :]), self.corr_nodes)

    def residuals(self, y):
        """Constraint on three levels (if a condition here) and force balance."""
        d = y[..., 1, :] - y[..., 0, :]  # subsystem 2 minus subsystem 1
        empty = d[..., :0]
        if self.decomposition.has_constraint_condition:
            out = {"pos": d[..., 0:1], "vel": d[..., 1:2], "acc": d[..., 2:3]}
        else:
            out = {"pos": empty, "vel": empty, "acc": empty}
        out["force"] = d[..., 3:4] if self.decomposition.has_force_balance else empty
        return out

    def output_sensitivities(self):
        """``dy/de_N+1``, shape ``(..., n_e, 2, 4)``: exact, the model is linear."""
        cols = []
        for j in range(self.n_coupling):
            per_sub = []
            for sub in self.subsystems:
                dy = sub.step_sensitivity(self.corr_nodes)
                per_sub.append(dy if sub.input == j else 0 * dy)
            cols.append(np.stack(np.broadcast_arrays(*per_sub), axis=-2))
        return np.stack(cols, axis=-3)

    def jacobians(self, state, history, e, y):
        if not hasattr(self, "_jac"):
            S = self.output_sensitivities()
            res = self.residuals(S)  # linear and homogeneous: maps sensitivities
            self._jac = {key: np.swapaxes(val, -1, -2) for key, val in res.items()}
        return self._jac

    def project(self, state):
        """Mass-weighted projection of positions and velocities (Eq. 30)."""
        am = self.coefficients.am21
        am = am[..., None] if np.ndim(am) else am
        xv = (state[..., 0, :] + am * state[..., 1, :]) / (1 + am)
        return np.stack([xv, xv], axis=-2)

    def shift(self, history, e_new):
        return _prepend(e_new, history[..., :-1, :])


def _stack(arrays):
    return np.stack(np.broadcast_arrays(*arrays), axis=-2)


def _prepend(e_new, older):
    """Stack ``e_new`` in front of older samples (leading axes broadcast)."""
    lead = np.broadcast_shapes(e_new.shape[:-1], older.shape[:-2])
    older = np.broadcast_to(older, lead + older.shape[-2:])
    return np.concatenate([np.broadcast_to(e_new, lead + e_new.shape[-1:])[..., None, :], older], axis=-2)
