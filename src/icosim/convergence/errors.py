"""Floor-free co-simulation errors: the error recurrence with a defect formed in ball arithmetic.

Why: the co-simulation state ``w_N`` (both subsystems and the coupling-variable
history, the packed state of :mod:`icosim.stability`) is O(1), its error
``w_N - w*_N`` can be 1e-20.  Subtracting two float64 numbers of size 1 leaves
a round-off floor near 1e-16 (NRMSE ~1e-11 after the sums of Eq. 72), below
which an order of convergence cannot be read.

How: the linear macro step is ``w_N+1 = M w_N`` (the amplification matrix,
taken from the engine's macro step by linearity).  The exact solution, written
in the same packed variables, is ``w*_N = W z_N``: ``z_N = (x, v_bar)`` of the
rigidly coupled (monolithic) system at ``T_N``, ``z_N+1 = E z_N`` with
``E = exp(A)`` (time in macro steps), and the rows of ``W`` give the
subsystem states (both equal to ``z``) and the exact coupling variables at
``T_N, ..., T_N-k`` (``lambda = a + k1 x + delta1 v``, ``a = A[1] z``, at
``E^-j z_N``).  The error ``eps_N = w_N - w*_N`` therefore obeys

    eps_N+1 = M eps_N + D z_N,    eps_0 = 0 (consistent start),
    D = M W - W E                 (the one-step defect, n x 2).

``D`` is a difference of O(1) matrices with entries down to 1e-26: it is
formed in Arb ball arithmetic (:class:`icosim.engine.backends.Ball`), so its error
bound is proven, with the working precision raised until every row is known
to 2^-40 relative (or is negligible: below 2^-40 of the largest row), and only
then rounded to float64.  From there float64 carries the error itself, whose
relative accuracy no longer depends on its size.  The same ``M`` (rounded) and
``E`` (rounded) drive the recurrence; their rounding errors are relative to
the error, not to the state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..engine.backends import Ball
from ..engine.decompositions import get_decomposition
from ..engine.exact import exact_coupling, monolithic_matrix
from ..engine.schemes import JACOBI
from ..engine.spectral.certified import MAX_BITS, SpectralCertificate, certify_matrix
from ..engine.spectral.matrix import amplification_matrix

__all__ = ["ExactExtension", "exact_extension", "local_defect", "Defect", "propagate_errors", "ErrorSeries"]

#: Every row of D is known to this relative accuracy (or is negligible at this level).
DEFECT_REL_ACCURACY = 2.0**-40


@dataclass
class ExactExtension:
    """The exact solution in the co-simulation's packed variables: ``w*_N = W z_N``, ``z_N+1 = E z_N``."""

    W: np.ndarray  # (n, 2)
    E: np.ndarray  # (2, 2)
    A: np.ndarray  # (2, 2): z' = A z (time in macro steps)


def exact_extension(coefficients, decomposition, k, backend) -> ExactExtension:
    """``W``, ``E = exp(A)`` and ``A`` in the backend's arithmetic (one parameter point)."""

    be = backend
    dec = get_decomposition(decomposition)
    c = coefficients
    zero, one = be.const(0), be.const(1)
    A = monolithic_matrix(c, be)
    E = be.expm(A[None])[0]
    E_back = be.expm((-A)[None])[0]  # one macro step backwards: the history lies before T_N
    n_c = dec.n_coupling
    W = np.full((4 + (k + 1) * n_c, 2), zero, dtype=be.dtype)
    W[0, 0] = W[2, 0] = one  # x1 = x2 = x
    W[1, 1] = W[3, 1] = one  # v1 = v2 = v_bar
    back = np.array([[one, zero], [zero, one]], dtype=be.dtype)  # E^-j: z at T_N-j from z at T_N
    for j in range(k + 1):
        x, v = back[0, :], back[1, :]
        a = A[1, 0] * x + A[1, 1] * v
        for i, name in enumerate(dec.variables):
            W[4 + j * n_c + i, :] = exact_coupling(name, c, x, v, a)
        back = back @ E_back
    return ExactExtension(W, E, A)


@dataclass
class Defect:
    """float64 roundings of the proven ``M``, ``D``, ``E``, ``A``, the precision that proved them, and the
    certified verdict on the spectral radius of the same ball ``M`` (:mod:`icosim.engine.spectral.certified`)."""

    M: np.ndarray
    D: np.ndarray
    E: np.ndarray
    A: np.ndarray
    bits: int
    rel_radius: float  # largest radius of a D row relative to the row (negligible rows excluded)
    certificate: SpectralCertificate


def local_defect(
    coefficients,
    method,
    decomposition,
    k,
    *,
    bits: int = 256,
    max_bits: int = 4096,
    certify_bits: int = MAX_BITS,
    scheme=JACOBI,
) -> Defect:
    """``D = M W - W E`` of one parameter point, proven in ball arithmetic, then rounded.

    ``M`` is the amplification matrix of ``scheme`` (:mod:`icosim.engine.schemes`); the
    exact solution's packed form ``W`` is the same for every scheme (the
    history holds the corrected coupling variables, exact on the exact solution).

    The same ball ``M`` certifies the stability verdict of this step size; the
    precision is also raised (up to ``certify_bits``) until that verdict is
    decided, else it is ``marginal``.
    """

    b = int(bits)
    while True:
        be = Ball(b)
        with be.context():
            c = coefficients.map(be.const)
            M = amplification_matrix(c, method, decomposition, k, backend=be, scheme=scheme)
            ext = exact_extension(c, decomposition, k, be)
            D = M @ ext.W - ext.W @ ext.E
            mid, rad = be.mid(D), be.rad(D)
            size = np.max(np.abs(mid), axis=1)
            floor = DEFECT_REL_ACCURACY * np.max(size)
            rel = np.where(size > floor, np.max(rad, axis=1) / np.where(size > 0, size, 1), 0.0)
            ok = np.all(np.max(rad, axis=1) <= DEFECT_REL_ACCURACY * np.maximum(size, floor)) and np.all(
                np.isfinite(mid)
            )
            cert = certify_matrix(M, b, final=b >= min(certify_bits, max_bits))
            if (ok and cert is not None) or b >= max_bits:
                if not ok:
                    raise ArithmeticError(
                        f"defect not resolved at {max_bits} bits (max relative radius {np.max(rel):.1e})"
                    )
                cert = cert or certify_matrix(M, b)
                return Defect(be.mid(M), mid, be.mid(ext.E), be.mid(ext.A), b, float(np.max(rel)), cert)
        b = min(2 * b, max_bits)


class ErrorSeries:
    """The errors ``eps_0 ... eps_N`` of one run, kept in the block layout they are computed in.

    ``blocks[j, :, b]`` is ``eps`` at step ``b * B + j``.  The metrics of
    Eq. (72) are sums of squares over step ranges: :meth:`sum_squares` forms
    them without the (N, n) copy, and :meth:`max_abs` the largest entry;
    :meth:`array` gives the plain ``(N + 1, n)`` array when one is needed.
    """

    def __init__(self, blocks: np.ndarray, n_steps: int):
        self.blocks = blocks
        self.n_steps = int(n_steps)
        self.B = blocks.shape[0]

    @classmethod
    def from_array(cls, errors) -> ErrorSeries:
        errors = np.asarray(errors, dtype=float)
        return cls(errors[:, :, None], errors.shape[0] - 1)

    def array(self) -> np.ndarray:
        n = self.blocks.shape[1]
        return self.blocks.transpose(2, 0, 1).reshape(-1, n)[: self.n_steps + 1]

    def max_abs(self, columns: slice = slice(None)) -> float:
        return float(np.max(self.block_max_abs(columns)))

    def block_max_abs(self, columns: slice = slice(None)) -> np.ndarray:
        """The largest ``|eps_N[columns]|`` of each block over the steps that exist (NaN if one is NaN)."""
        B, nb = self.B, self.blocks.shape[2]
        last = self.n_steps - (nb - 1) * B  # the last block's last step
        with np.errstate(invalid="ignore"):
            out = np.abs(self.blocks[:, columns, : nb - 1]).max(axis=(0, 1)) if nb > 1 else np.empty(0)
            return np.append(out, np.abs(self.blocks[: last + 1, columns, nb - 1]).max())

    def first_step_beyond(self, exact: np.ndarray, bound: float, columns: slice = slice(None)) -> int | None:
        """The first step ``N >= 1`` whose ``max |exact[N - 1] + eps_N[columns]|`` exceeds ``bound`` or is not
        finite, else None (``exact``: the exact values at ``T_1 ... T_N``, the same columns).

        Block by block, in order; a block is skipped when ``max |eps| + max |exact|`` is finite and
        ``<= bound`` (rounding is monotone, so no sum in it can exceed the bound or overflow): the same
        answer as checking every step, with the per-step sums formed only from the first block that could
        cross (a diverging run's early blocks are far below the bound).
        """
        B = self.B
        exact_max = float(np.max(np.abs(exact))) if exact.size else 0.0
        for b, err_max in enumerate(self.block_max_abs(columns)):
            screen = err_max + exact_max
            if np.isfinite(screen) and screen <= bound:  # NaN or an overflow: checked step by step
                continue
            steps = np.arange(max(b * B, 1), min((b + 1) * B, self.n_steps + 1))
            with np.errstate(invalid="ignore"):
                mag = np.max(np.abs(exact[steps - 1] + self.blocks[steps - b * B, columns, b]), axis=-1)
            bad = ~np.isfinite(mag) | (mag > bound)
            if bad.any():
                return int(steps[np.argmax(bad)])
        return None

    def sum_squares(self, columns: slice, first: int, last: int | None = None) -> np.ndarray:
        """``sum_{N = first}^{last} eps_N[columns]^2`` per column (``last`` defaults to the final step)."""
        last = self.n_steps if last is None else min(last, self.n_steps)
        if last < first:
            return np.zeros(self.blocks[:, columns, 0].shape[1])
        sq = np.square(self.blocks[:, columns, :])
        b0, j0 = divmod(first, self.B)
        b1, j1 = divmod(last, self.B)
        if b0 == b1:
            return sq[j0 : j1 + 1, :, b0].sum(axis=0)
        return sq[j0:, :, b0].sum(axis=0) + sq[:, :, b0 + 1 : b1].sum(axis=(0, 2)) + sq[: j1 + 1, :, b1].sum(axis=0)


def propagate_errors(M, D, E, z_at, n_steps: int, *, block: int | None = None) -> ErrorSeries:
    """``eps_0 ... eps_n_steps`` of ``eps_N+1 = M eps_N + D z_N``, ``eps_0 = 0``, as an :class:`ErrorSeries`.

    ``z_at(N)`` gives the exact ``z`` at the macro-time points ``N`` (an array
    of step indices; called once, for the block starts).  Inside a block of
    ``B`` steps from ``s``: ``eps_s+j = M^j eps_s + G_j z_s`` with
    ``G_j+1 = M G_j + D E^j``; block starts advance sequentially.  ``B``
    defaults to about ``sqrt(n_steps)``: the Python loops building the block
    (``B`` steps) and advancing it (``n_steps / B``) then cost the least.
    """
    M = np.asarray(M, dtype=float)
    n = M.shape[0]
    if block is None:
        block = int(np.clip(np.sqrt(n_steps + 1), 16, 2048))
    B = max(1, min(block, n_steps + 1))
    with np.errstate(over="ignore", invalid="ignore"):  # an unstable run grows without bound
        P = np.empty((B, n, n))
        G = np.zeros((B, n, 2))
        P[0] = np.eye(n)
        Ej = np.eye(2)
        for j in range(1, B):
            P[j] = M @ P[j - 1]
            G[j] = M @ G[j - 1] + D @ Ej
            Ej = E @ Ej
        MB = M @ P[B - 1]
        GB = M @ G[B - 1] + D @ Ej
        starts = np.arange(0, n_steps + 1, B)
        Z = z_at(starts)
        eps_start = np.empty((starts.size, n))
        e = np.zeros(n)
        for i in range(starts.size):
            eps_start[i] = e
            e = MB @ e + GB @ Z[i]
        blocks = np.matmul(P, eps_start.T) + np.matmul(G, Z.T)  # (B, n, blocks)
    return ErrorSeries(blocks, n_steps)
