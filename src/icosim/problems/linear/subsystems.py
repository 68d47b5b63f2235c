"""Exact macro-step propagators of linear subsystems: segments of masses with springs and dampers (Sects.
2.1-2.3 for one mass).

A segment has ``n`` masses on a line, state ``s = (x_1 ... x_n, v_1 ... v_n)``, and ports -- masses where a
joint attaches (a chain segment's first and last) -- each with one scalar coupling input ``u_p``:

* at a **force-driven** port the input is a force: mass ``q`` obeys
  ``v_q' = -sum_j k_qj x_j - sum_j delta_qj v_j + g_q sum_p u_p`` (Eqs. 7a, 7b for one mass) with the
  stiffness and damping per unit mass ``k_qj``, ``delta_qj`` and the gain ``g_q``, the inverse mass;
* at a **kinematically driven** port (on acceleration level, index 1; Eqs. 33b, 57) the input is the
  prescribed acceleration of its mass, ``v_q' = u_p``; the force its drive exerts to realise the rheonomic
  constraint follows from the mass's equation of motion,
  ``R = (u_p + sum_j k_qj x_j + sum_j delta_qj v_j - g_q sum_f u_f) / g_q`` (``u_f`` the forces at other ports
  of that mass).

The paper's subsystems are single masses with one port.  Because the model is linear and the input over one
macro step is a polynomial, the solution at the end of the step is exact:
``s(1) = Phi s(0) + sum_p sum_m R_p[:, m] c_p,m`` where ``u_p(tau) = sum_m c_p,m tau^m`` and
``R_p[:, m] = int_0^1 exp(A (1 - s)) b_p s^m ds``.  ``Phi`` and the ``R_p`` are read off one matrix exponential
of the augmented matrix ``[[A, b_1 e_1^T, ..., b_P e_1^T], [0, J], ...]`` (``J`` the nilpotent shift, one
block per port), whose top-right blocks hold ``phi_1(A) b_p, ..., phi_{k+1}(A) b_p`` (the phi-functions of
exponential integrators).  This works for any damping: underdamped, critically damped, overdamped and
undamped alike.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...engine import layout
from ...engine.lagrange import monomial_coefficients, weights_at

__all__ = ["LinearSubsystem", "FORCE", "KINEMATIC", "decay_rate"]

FORCE = "force"
KINEMATIC = "kinematic"

#: Order of the components in a port's output vector at ``T_N+1``.
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
class LinearSubsystem:
    """A segment of masses with polynomial coupling inputs at its ports.

    Parameters
    ----------
    ports : per port ``(mass, kind)``: the mass it is at (0-based) and ``"force"`` or ``"kinematic"``.
    stiffness, damping : ``[q][j]``: per-unit-mass coefficients of mass ``q`` on mass ``j`` (arrays broadcast;
        ``None`` where structurally zero).
    gain : per mass, its inverse mass (arrays broadcast).
    k : degree of the approximation polynomials.
    backend : :mod:`icosim.engine.backends` arithmetic.
    """

    ports: tuple
    stiffness: Sequence[Sequence[Any]]
    damping: Sequence[Sequence[Any]]
    gain: Sequence[Any]
    k: int
    backend: Any
    _node_cache: dict = field(default_factory=dict, repr=False)

    @classmethod
    def single(cls, kind, stiffness, damping, gain, k, backend) -> LinearSubsystem:
        """One mass with one port (the paper's subsystems)."""
        return cls(((0, kind),), [[stiffness]], [[damping]], [gain], k, backend)

    def __post_init__(self):
        be = self.backend
        self.ports = tuple((int(q), kind) for q, kind in self.ports)
        for _, kind in self.ports:
            if kind not in (FORCE, KINEMATIC):
                raise ValueError(f"port kinds are 'force' or 'kinematic', got {kind!r}")
        n = self.n_masses = len(self.gain)
        self.gain = [be.asarray(g) for g in self.gain]
        self.stiffness = [[None if c is None else be.asarray(c) for c in row] for row in self.stiffness]
        self.damping = [[None if c is None else be.asarray(c) for c in row] for row in self.damping]
        #: the kinematically driven masses and the port that drives each
        self.driven = {q: p for p, (q, kind) in enumerate(self.ports) if kind == KINEMATIC}
        if len(self.driven) < sum(kind == KINEMATIC for _, kind in self.ports):
            raise ValueError("two kinematically driven ports at one mass")
        #: per mass, the force-driven ports at it
        self.forces = [[p for p, (qq, kind) in enumerate(self.ports) if qq == q and kind == FORCE] for q in range(n)]
        m = self.k + 1
        P = len(self.ports)
        params = self._parameters()
        # a segment whose masses are all driven has a propagator that does not depend on its parameters
        shape = np.broadcast_shapes(*(np.shape(a) for a in params)) if params else ()
        zero, one = be.const(0), be.const(1)
        size = 2 * n + P * m
        M = np.full(shape + (size, size), zero, dtype=be.dtype)
        for q in range(n):
            M[..., q, n + q] = one
            if q in self.driven:
                M[..., n + q, 2 * n + self.driven[q] * m] = one
                continue
            for j in range(n):
                if self.stiffness[q][j] is not None:
                    M[..., n + q, j] = -self.stiffness[q][j]
                if self.damping[q][j] is not None:
                    M[..., n + q, n + j] = -self.damping[q][j]
            for p in self.forces[q]:
                M[..., n + q, 2 * n + p * m] = self.gain[q]
        for p in range(P):
            for j in range(m - 1):
                M[..., 2 * n + p * m + j, 2 * n + p * m + j + 1] = one
        self._factorials = be.asarray([math.factorial(j) for j in range(m)] * P)
        if hasattr(be, "identity"):  # balls: each matrix is determined by the structure and the parameters
            self.set_blocks(be.expm(M, keys=self._expm_keys(shape, params)))
        else:
            self.set_blocks(be.expm(M, decay=self.decay_rate() if getattr(be, "uses_decay", False) else 0.0))

    def _parameters(self) -> list:
        """The coefficients the augmented matrix holds (those of the masses not kinematically driven)."""
        out = []
        for q in range(self.n_masses):
            if q in self.driven:
                continue
            out += [c for c in self.stiffness[q] if c is not None] + [c for c in self.damping[q] if c is not None]
            if self.forces[q]:
                out.append(self.gain[q])
        return out

    def _expm_keys(self, shape, params):
        """Per matrix of the batch, what determines it: the structure and the coefficients' identities
        (:meth:`icosim.engine.backends.Ball.identity`); None where one is not finite."""
        be = self.backend
        structure = (self.ports, self.n_masses, self.k + 1)
        keys = np.empty(shape, dtype=object)
        parts = [np.broadcast_to(np.asarray(a, dtype=object), shape) for a in params]
        for idx in np.ndindex(shape):
            ids = tuple(be.identity(a[idx]) for a in parts)
            keys[idx] = None if None in ids else structure + ids
        return keys

    @property
    def kind(self) -> str:
        """The kind of a single-port subsystem."""
        (_, kind), = self.ports  # fmt: skip
        return kind

    def decay_rate(self) -> float:
        """Largest ``-Re(eigenvalue of A)`` over the batch: entries of the propagator can be as small as
        ``exp(-decay_rate)``."""
        n = self.n_masses
        free = [q for q in range(n) if q not in self.driven]
        if not free:
            return 0.0
        if n == 1:
            k = np.asarray(self.stiffness[0][0], dtype=float)
            return float(np.max(decay_rate(k, self.damping[0][0]))) if k.size else 0.0
        shape = np.broadcast_shapes(*(np.shape(a) for a in self._parameters()))
        A = np.zeros(shape + (2 * n, 2 * n))
        for q in range(n):
            A[..., q, n + q] = 1
            if q in self.driven:
                continue
            for j in range(n):
                if self.stiffness[q][j] is not None:
                    A[..., n + q, j] = -np.asarray(self.stiffness[q][j], dtype=float)
                if self.damping[q][j] is not None:
                    A[..., n + q, n + j] = -np.asarray(self.damping[q][j], dtype=float)
        return float(np.max(-np.linalg.eigvals(A).real)) if A.size else 0.0

    def norm_bound(self):
        """``max(1, ||A||_1)`` per point: the largest column sum of the augmented matrix's magnitudes (a
        kinematically driven mass's column has ones and zeros only)."""
        n = self.n_masses
        nu = 1.0
        for j in range(n):
            col_x, col_v = 0.0, 1.0
            for q in range(n):
                if q in self.driven:
                    continue
                if self.stiffness[q][j] is not None:
                    col_x = col_x + np.abs(self.stiffness[q][j])
                if self.damping[q][j] is not None:
                    col_v = col_v + np.abs(self.damping[q][j])
            nu = np.maximum(nu, np.maximum(col_x, col_v))
        for q in range(n):
            if self.forces[q] and q not in self.driven:
                nu = np.maximum(nu, np.abs(self.gain[q]))
        return nu

    def set_blocks(self, E):
        """Take ``Phi`` and the ``R_p`` from the exponential of the augmented matrix.

        ``E`` is kept so that the precision policy can disturb it.
        """
        E = layout.batched(E)  # a grid's blocks with the grid axes fastest (the same values)
        n2 = 2 * self.n_masses
        self.blocks = E
        self.Phi = E[..., :n2, :n2]
        self.R = E[..., :n2, n2:] * self._factorials  # R[:, p m + j] = j! phi_{j+1}(A) b_p
        self._node_cache = {}

    def node_matrices(self, nodes):
        """Matrices for inputs given by samples ``U_p`` at ``nodes``.

        Returns ``(Gamma, dGamma, w0, w1)``, ``Gamma`` and ``dGamma`` one matrix per port, with
        ``s(1) = Phi s(0) + sum_p Gamma_p U_p``, ``s'(1) = Phi s'(0) + sum_p dGamma_p U_p`` (the response to
        the derivative of the input polynomial), and the Lagrange weights at ``tau = 0`` and 1.  The rate
        ``s'`` is propagated instead of being formed as ``A s(1) + b u(1)``: for a stiff subsystem the
        acceleration at the end of a step is exponentially small and that difference would cancel
        catastrophically, in float64 and at 128 digits alike.
        """
        nodes = tuple(nodes)
        cache = self._node_cache
        if nodes not in cache:
            be = self.backend
            C = monomial_coefficients(nodes)
            m = len(nodes)
            Cm = np.array([[be.const(c) for c in row] for row in C], dtype=be.dtype)
            # coefficients of the derivative polynomial: c'_j = (j+1) c_{j+1}
            dC = np.array(
                [[be.const((j + 1) * C[j + 1][i]) if j + 1 < m else be.const(0) for i in range(m)] for j in range(m)],
                dtype=be.dtype,
            )
            w0 = np.array([be.const(w) for w in weights_at(nodes, 0)], dtype=be.dtype)
            w1 = np.array([be.const(w) for w in weights_at(nodes, 1)], dtype=be.dtype)
            Gamma, dGamma = [], []
            for p in range(len(self.ports)):
                # the products as ever (BLAS sees the layout), then laid out for the grid
                R = np.ascontiguousarray(self.R[..., p * m : (p + 1) * m])
                Gamma.append(layout.batched(R @ Cm))
                dGamma.append(layout.batched(R @ dC))
            cache[nodes] = (Gamma, dGamma, w0, w1)
        return cache[nodes]

    def _rate(self, s, u):
        """``s' = A s + B u`` (velocities, accelerations) at a given instant; ``u`` per port on the last axis."""
        n = self.n_masses
        x, v = s[..., :n], s[..., n:]
        acc = []
        for q in range(n):
            if q in self.driven:
                acc.append(u[..., self.driven[q]] + 0 * x[..., q])
                continue
            a = None
            for j in range(n):
                if self.stiffness[q][j] is not None:
                    a = -self.stiffness[q][j] * x[..., j] if a is None else a - self.stiffness[q][j] * x[..., j]
            for j in range(n):
                if self.damping[q][j] is not None:
                    a = -self.damping[q][j] * v[..., j] if a is None else a - self.damping[q][j] * v[..., j]
            for p in self.forces[q]:
                a = self.gain[q] * u[..., p] if a is None else a + self.gain[q] * u[..., p]
            acc.append(0 * x[..., q] if a is None else a)
        return layout.stack(np.broadcast_arrays(*[v[..., j] for j in range(n)], *acc), axis=-1)

    def step(self, s0, U, nodes):
        """Exact end-of-step state and outputs at the ports for samples ``U``.

        ``s0`` has shape ``(..., 2n)`` and ``U`` ``(..., P, k+1)`` (samples of each port's input at
        ``nodes``); the outputs ``(..., P, 4)`` are each port's ``(x, v, a, f)``.
        """
        Gamma, dGamma, w0, w1 = self.node_matrices(nodes)
        m = len(nodes)
        u0 = sum(w0[j] * U[..., :, j] for j in range(m))
        u1 = sum(w1[j] * U[..., :, j] for j in range(m))
        s1 = _matvec(self.Phi, s0)
        rate1 = _matvec(self.Phi, self._rate(s0, u0))
        for p in range(len(self.ports)):
            s1 = s1 + _matvec(Gamma[p], U[..., p, :])
            rate1 = rate1 + _matvec(dGamma[p], U[..., p, :])
        return s1, self._outputs(s1, rate1, u1)

    def step_sensitivity(self, nodes):
        """``d outputs / d U_p,0`` (each port's sample at ``nodes[0]``), ``(..., P_in, P, 4)``: constant by
        linearity."""
        Gamma, dGamma, w0, w1 = self.node_matrices(nodes)
        one = self.backend.const(1)
        out = []
        for p in range(len(self.ports)):
            ds = Gamma[p][..., :, 0]
            zero = 0 * ds[..., 0]
            b_u0 = self._rate(0 * ds, self._unit(p, w0[0] * one, zero))  # B e_p l_0(0): zero state, unit sample
            drate = _matvec(self.Phi, b_u0) + dGamma[p][..., :, 0]
            out.append(self._outputs(ds, drate, self._unit(p, w1[0] * one, zero)))
        return layout.stack(np.broadcast_arrays(*out), axis=-3)

    def algebraic_sensitivity(self):
        """``d outputs / d u_p(1)`` at a fixed end state, ``(..., P_in, P, 4)``: the outputs that the equations
        of motion at ``T_N+1`` tie to the inputs there.

        One force-driven mass: ``a = -k x - delta v + g u`` and ``f = u`` give ``(0, 0, g, 1)``; one
        kinematically driven mass: ``a = u`` and ``R = (u + k x + delta v) / g`` give ``(0, 0, 1, 1/g)``.  This
        is what a subsystem that has already finished its macro step contributes to the corrected coupling
        variables of a Gauss-Seidel scheme.
        """
        one = self.backend.const(1)
        n = self.n_masses
        zero = 0 * self.gain[0]
        state = layout.stack(np.broadcast_arrays(*[zero] * (2 * n)), axis=-1)
        out = []
        for p in range(len(self.ports)):
            q, kind = self.ports[p]
            rate = [zero] * (2 * n)
            if kind == FORCE and q not in self.driven:
                rate[n + q] = self.gain[q] * one
            rate = layout.stack(np.broadcast_arrays(*rate), axis=-1)
            out.append(self._outputs(state, rate, self._unit(p, one + zero, zero)))
        return layout.stack(np.broadcast_arrays(*out), axis=-3)

    def _unit(self, p, value, zero):
        """``value`` at port ``p`` and zero at the others, on a last axis (``zero``: a zero of the batch's shape)."""
        zero = 0 * value + zero
        parts = [value + zero if r == p else zero for r in range(len(self.ports))]
        return layout.stack(np.broadcast_arrays(*parts), axis=-1)

    def _outputs(self, s, rate, u):
        """Each port's ``(x, v, a, f)``, ``(..., P, 4)``, from the state, the rate and the inputs at an instant."""
        n = self.n_masses
        out = []
        for p, (q, kind) in enumerate(self.ports):
            x, v = s[..., q], s[..., n + q]
            if kind == FORCE:
                a, f = rate[..., n + q], u[..., p] + 0 * x
            else:
                a = u[..., p] + 0 * x
                total = u[..., p]
                for j in range(n):
                    if self.stiffness[q][j] is not None:
                        total = total + self.stiffness[q][j] * s[..., j]
                for j in range(n):
                    if self.damping[q][j] is not None:
                        total = total + self.damping[q][j] * s[..., n + j]
                for r in self.forces[q]:
                    total = total - self.gain[q] * u[..., r]
                f = total / self.gain[q]
            out.append(layout.stack(np.broadcast_arrays(x, v, a, f), axis=-1))
        return out[0][..., None, :] if len(out) == 1 else layout.stack(np.broadcast_arrays(*out), axis=-2)


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
