"""Exact macro-step propagators of the single-mass subsystems (Sects. 2.1-2.3).

A subsystem has the state ``s = (x, v)`` and one scalar coupling input ``u``:

* **force-driven** (Eqs. 7a, 7b): ``x' = v``, ``v' = -k x - delta v + g u`` with
  ``u`` the coupling force on it and ``g`` its gain, the inverse mass (``1`` or ``1/am21``);
* **kinematically driven** on acceleration level, index 1 (Eqs. 33b, 57):
  ``v' = u`` with ``u = a_tilde`` the prescribed acceleration; the force
  its drive exerts to realise the rheonomic constraint follows from the equation of motion,
  ``R = (u + k x + delta v) / g``.

Because the model is linear and the input over one macro step is a polynomial,
the solution at the end of the step is exact:
``s(1) = Phi s(0) + sum_m R[:, m] c_m`` where ``u(tau) = sum_m c_m tau^m`` and
``R[:, m] = int_0^1 exp(A (1 - s)) b s^m ds``.  ``Phi`` and ``R`` are read off
one matrix exponential of the augmented matrix ``[[A, b e_1^T], [0, J]]``
(``J`` the nilpotent shift), whose top-right block holds
``phi_1(A) b, ..., phi_{k+1}(A) b`` (the phi-functions of exponential
integrators).  This works for any damping: underdamped, critically damped,
overdamped and undamped alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...engine import layout
from ...engine.lagrange import monomial_coefficients, weights_at

__all__ = ["OscillatorSubsystem", "FORCE", "KINEMATIC", "decay_rate"]

FORCE = "force"
KINEMATIC = "kinematic"

#: Order of the components in a subsystem's output vector at ``T_N+1``.
OUTPUTS = ("x", "v", "a", "f")  # position, velocity, acceleration, coupling force


def decay_rate(stiffness, damping):
    """Largest ``-Re`` of the eigenvalues of ``x'' + damping x' + stiffness x = 0``: ``d/2 + sqrt(d^2/4 - k)``.

    Formed as ``h (1 + sqrt(1 - k/h^2))`` with ``h = d/2`` so that no square overflows (``d`` up to the
    largest double); ``inf`` only where the decay itself is not a finite double.
    """
    k = np.asarray(stiffness, dtype=float)
    h = np.asarray(damping, dtype=float) / 2
    with np.errstate(all="ignore"):
        ratio = np.where(h > 0, np.sqrt(k) / np.where(h > 0, h, 1.0), np.inf)
        return np.where(ratio < 1, h + h * np.sqrt(np.maximum(1 - ratio * ratio, 0.0)), np.maximum(h, 0.0))


@dataclass
class OscillatorSubsystem:
    """One single-mass oscillator with a polynomial coupling input.

    Parameters
    ----------
    kind : ``"force"`` or ``"kinematic"``.
    stiffness, damping, gain : per-unit-mass coefficients (arrays broadcast).
    input : index of the coupling variable that drives this subsystem.
    k : degree of the approximation polynomials.
    backend : :mod:`icosim.engine.backends` arithmetic.
    """

    kind: str
    stiffness: object
    damping: object
    gain: object
    input: int
    k: int
    backend: object

    def __post_init__(self):
        if self.kind not in (FORCE, KINEMATIC):
            raise ValueError(f"kind must be 'force' or 'kinematic', got {self.kind!r}")
        be = self.backend
        kk = be.asarray(self.stiffness)
        dd = be.asarray(self.damping)
        self.stiffness, self.damping = kk, dd
        self.gain = be.asarray(self.gain)
        n = self.k + 1
        # a kinematic subsystem's propagator does not depend on its parameters
        shape = np.broadcast_shapes(kk.shape, dd.shape) if self.kind == FORCE else ()
        zero, one = be.const(0), be.const(1)
        # A kinematic subsystem's state is a double integrator of its input:
        # its own dynamics only enter the force of its drive (an output).
        M = np.full(shape + (2 + n, 2 + n), zero, dtype=be.dtype)
        M[..., 0, 1] = one
        if self.kind == FORCE:
            M[..., 1, 0] = -kk
            M[..., 1, 1] = -dd
            M[..., 1, 2] = self.gain
        else:
            M[..., 1, 2] = one
        for j in range(n - 1):
            M[..., 2 + j, 3 + j] = one
        self._factorials = be.asarray([math.factorial(m) for m in range(n)])
        if hasattr(be, "identity"):  # balls: each matrix is determined by the kind, k and (k, delta, gain)
            self.set_blocks(be.expm(M, keys=self._expm_keys(shape, n)))
        else:
            self.set_blocks(be.expm(M, decay=self.decay_rate() if getattr(be, "uses_decay", False) else 0.0))

    def _expm_keys(self, shape, n):
        """Per matrix of the batch, what determines it: ``(kind, n)`` and, force driven, the coefficients'
        identities (:meth:`icosim.engine.backends.Ball.identity`); None where one is not finite."""
        be = self.backend
        keys = np.empty(shape, dtype=object)
        if self.kind == KINEMATIC:
            keys[()] = (KINEMATIC, n)
            return keys
        parts = [np.broadcast_to(np.asarray(a, dtype=object), shape) for a in (self.stiffness, self.damping, self.gain)]
        for idx in np.ndindex(shape):
            ids = tuple(be.identity(a[idx]) for a in parts)
            keys[idx] = None if None in ids else (FORCE, n) + ids
        return keys

    def decay_rate(self) -> float:
        """Largest ``-Re(eigenvalue of A)`` over the batch: entries of the
        propagator can be as small as ``exp(-decay_rate)``."""
        if self.kind == KINEMATIC:
            return 0.0
        k = np.asarray(self.stiffness, dtype=float)
        return float(np.max(decay_rate(k, self.damping))) if k.size else 0.0

    def set_blocks(self, E):
        """Take ``Phi`` and ``R`` from the exponential of the augmented matrix.

        ``E`` is kept so that the precision policy can disturb it.
        """
        E = layout.batched(E)  # a grid's blocks with the grid axes fastest (the same values)
        self.blocks = E
        self.Phi = E[..., :2, :2]
        self.R = E[..., :2, 2:] * self._factorials  # R[:, m] = m! phi_{m+1}(A) b

    def node_matrices(self, nodes):
        """Matrices for an input given by samples ``U`` at ``nodes``.

        Returns ``(Gamma, dGamma, w0, w1)`` with ``s(1) = Phi s(0) + Gamma U``,
        ``s'(1) = Phi s'(0) + dGamma U`` (the response to the derivative of
        the input polynomial), and the Lagrange weights at ``tau = 0`` and 1.
        The rate ``s'`` is propagated instead of being formed as
        ``A s(1) + b u(1)``: for a stiff subsystem the acceleration at the end
        of a step is exponentially small and that difference would cancel
        catastrophically, in float64 and at 128 digits alike.
        """
        nodes = tuple(nodes)
        cache = self.__dict__.setdefault("_node_cache", {})
        if nodes not in cache:
            be = self.backend
            C = monomial_coefficients(nodes)
            n = len(nodes)
            Cm = np.array([[be.const(c) for c in row] for row in C], dtype=be.dtype)
            # coefficients of the derivative polynomial: c'_m = (m+1) c_{m+1}
            dC = np.array(
                [[be.const((m + 1) * C[m + 1][j]) if m + 1 < n else be.const(0) for j in range(n)] for m in range(n)],
                dtype=be.dtype,
            )
            w0 = np.array([be.const(w) for w in weights_at(nodes, 0)], dtype=be.dtype)
            w1 = np.array([be.const(w) for w in weights_at(nodes, 1)], dtype=be.dtype)
            R = np.ascontiguousarray(self.R)  # the products as ever (BLAS sees the layout), then laid out for the grid
            cache[nodes] = (layout.batched(R @ Cm), layout.batched(R @ dC), w0, w1)
        return cache[nodes]

    def _rate(self, s, u):
        """``s' = A s + b u`` (velocity, acceleration) at a given instant."""
        x, v = s[..., 0], s[..., 1]
        if self.kind == FORCE:
            a = -self.stiffness * x - self.damping * v + self.gain * u
        else:
            a = u + 0 * x
        return layout.stack(np.broadcast_arrays(v, a), axis=-1)

    def step(self, s0, U, nodes):
        """Exact end-of-step state and outputs ``(x, v, a, f)`` for samples ``U``.

        ``s0`` has shape ``(..., 2)`` and ``U`` ``(..., k+1)`` (samples of this
        subsystem's coupling input at ``nodes``).
        """
        Gamma, dGamma, w0, w1 = self.node_matrices(nodes)
        u0 = sum(w0[j] * U[..., j] for j in range(len(nodes)))
        u1 = sum(w1[j] * U[..., j] for j in range(len(nodes)))
        s1 = _matvec(self.Phi, s0) + _matvec(Gamma, U)
        rate1 = _matvec(self.Phi, self._rate(s0, u0)) + _matvec(dGamma, U)
        return s1, self._outputs(s1, rate1[..., 1], u1)

    def step_sensitivity(self, nodes):
        """``d outputs / d U_0`` (the sample at ``nodes[0]``), constant by linearity."""
        Gamma, dGamma, w0, w1 = self.node_matrices(nodes)
        one = self.backend.const(1)
        ds = Gamma[..., :, 0]
        b_u0 = self._rate(0 * ds, w0[0] * one)  # b l_0(0): zero state, unit sample
        drate = _matvec(self.Phi, b_u0) + dGamma[..., :, 0]
        return self._outputs(ds, drate[..., 1], w1[0] * one)

    def algebraic_sensitivity(self):
        """``d outputs / d u(1)`` at a fixed end state: the outputs that the
        equation of motion at ``T_N+1`` ties to the input there.

        Force-driven: ``a = -k x - delta v + g u`` and ``f = u`` give
        ``(0, 0, g, 1)``; kinematically driven: ``a = u`` and
        ``R = (u + k x + delta v) / g`` give ``(0, 0, 1, 1/g)``.  This is
        what a subsystem that has already finished its macro step contributes
        to the corrected coupling variables of a Gauss-Seidel scheme.
        """
        one = self.backend.const(1)
        zero = 0 * self.gain
        return self._outputs(layout.stack([zero, zero], axis=-1), self.gain * one, one + zero)

    def _outputs(self, s, a, u):
        x, v = s[..., 0], s[..., 1]
        if self.kind == FORCE:
            f = u + 0 * x
        else:
            a = u + 0 * x
            f = (u + self.stiffness * x + self.damping * v) / self.gain
        return layout.stack(np.broadcast_arrays(x, v, a, f), axis=-1)


def _matvec(A, x):
    """``A @ x`` over leading axes; a broadcast sum beats batched matmul for 2 x n.

    The sum is ``0 + t_0 + t_1 + ...`` with ``t_j = A[..., :, j] x_j``, as :func:`sum` forms it; over a
    grid in float64 it is formed in place in arrays laid out with the grid axes fastest
    (:mod:`icosim.engine.layout`): the same operations on the same values, hence the same bits.
    """
    m = A.shape[-1]
    if A.dtype.kind == "f" and x.dtype.kind == "f" and m:
        shape = np.broadcast_shapes(A.shape[:-1], x.shape[:-1] + (1,))
        if len(shape) >= 3 and math.prod(shape) >= layout.BATCH_SIZE:
            acc, term = np.empty(shape, order="F"), np.empty(shape, order="F")
            np.multiply(A[..., :, 0], x[..., None, 0], out=acc)
            np.add(acc, 0, out=acc)  # sum() starts from 0 (0 + -0.0 is +0.0)
            for j in range(1, m):
                np.multiply(A[..., :, j], x[..., None, j], out=term)
                np.add(acc, term, out=acc)
            return acc
    return sum(A[..., :, j] * x[..., None, j] for j in range(m))
