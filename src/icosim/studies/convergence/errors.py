"""Floor-free co-simulation errors: the error recurrence with a defect formed in ball arithmetic.

Why: the co-simulation state ``w_N`` (both subsystems and the coupling-variable
history, the packed state of :mod:`icosim.studies.stability`) is O(1), its error
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
the error, not to the state.  The recurrence is stepped in blocks (:mod:`icosim.studies.convergence.blocks`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, fields

import numpy as np

from ...engine.backends import Ball
from ...engine.decompositions import get_decomposition
from ...engine.schemes import JACOBI
from ...engine.spectral.certified import MAX_BITS, SpectralCertificate, certify_matrix
from ...problems.linear.exact import exact_coupling, monolithic_matrix
from ...problems.linear.spectral import amplification_matrix
from .blocks import BlockErrors, ErrorSeries, error_recurrence, error_recurrences

__all__ = [
    "ExactExtension",
    "exact_extension",
    "local_defect",
    "local_defects",
    "Defect",
    "error_recurrence",
    "error_recurrences",
    "propagate_errors",
    "BlockErrors",
    "ErrorSeries",
]

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


#: :func:`_exact_parts` per parameter point, decomposition, k and precision: shared by every method, index
#: and scheme at that point (the curves of a panel, the panels of a job).
_EXACT_PARTS: dict = {}


def _exact_parts(coefficients, decomposition, k, be):
    """The coefficients as balls, :func:`exact_extension`, ``W E`` and the midpoints of ``E`` and ``A`` at
    ``be``'s precision (inside its context), cached: Arb balls are values, and the same inputs at the same
    precision give the same balls."""
    try:
        values = tuple(float(getattr(coefficients, f.name)) for f in fields(coefficients))
        key = (type(coefficients), values, get_decomposition(decomposition).name, int(k), be.bits)
    except (TypeError, ValueError):  # not scalar floats: no cache
        key = None
    parts = _EXACT_PARTS.get(key) if key is not None else None
    if parts is None:
        c = coefficients.map(be.const)
        ext = exact_extension(c, decomposition, k, be)
        parts = (c, ext, ext.W @ ext.E, be.mid(ext.E), be.mid(ext.A))
        if key is not None:
            if len(_EXACT_PARTS) >= 1024:
                _EXACT_PARTS.clear()
            _EXACT_PARTS[key] = parts
    return parts


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
            parts = _exact_parts(coefficients, decomposition, k, be)
            M = amplification_matrix(parts[0], method, decomposition, k, backend=be, scheme=scheme)
            defect = _resolved_defect(M, parts, be, max_bits, certify_bits)
        if defect is not None:
            return defect
        b = min(2 * b, max_bits)


def _resolved_defect(M, parts, be, max_bits, certify_bits) -> Defect | None:
    """The :class:`Defect` of the ball ``M`` at ``be``'s precision (inside its context), or None where this
    precision leaves a row of ``D`` or the stability verdict unresolved (below ``max_bits``)."""
    b = be.bits
    c, ext, WE, E_mid, A_mid = parts
    D = M @ ext.W - WE
    mid, rad = be.mid(D), be.rad(D)
    size = np.max(np.abs(mid), axis=1)
    floor = DEFECT_REL_ACCURACY * np.max(size)
    rel = np.where(size > floor, np.max(rad, axis=1) / np.where(size > 0, size, 1), 0.0)
    ok = np.all(np.max(rad, axis=1) <= DEFECT_REL_ACCURACY * np.maximum(size, floor)) and np.all(np.isfinite(mid))
    cert = certify_matrix(M, b, final=b >= min(certify_bits, max_bits))
    if (ok and cert is not None) or b >= max_bits:
        if not ok:
            raise ArithmeticError(f"defect not resolved at {max_bits} bits (max relative radius {np.max(rel):.1e})")
        cert = cert or certify_matrix(M, b)
        return Defect(be.mid(M), mid, E_mid.copy(), A_mid.copy(), b, float(np.max(rel)), cert)
    return None


def local_defects(
    coefficients,
    methods,
    decomposition,
    k,
    *,
    bits: int = 256,
    max_bits: int = 4096,
    certify_bits: int = MAX_BITS,
    scheme=JACOBI,
) -> list[Defect]:
    """:func:`local_defect` of several parameter points (``coefficients[i]`` with ``methods[i]``), each the
    very one it gets alone.

    The ball macro step costs mostly Python calls, not arithmetic: the points with the same method (the
    same levels: a method whose parameters scale with ``H`` has other levels at every step size) have
    their ball matrices at ``bits`` formed in one batched macro step (a leading axis of object arrays: the
    same ball operations on every point as alone, hence the same balls, as
    :func:`icosim.engine.spectral.batched.certify_spectral_radii`).  A point this precision leaves
    unresolved, and every point of a batch that fails, continues alone.
    """
    out: list = [None] * len(methods)
    groups: dict = {}  # the method -> indices of its points
    for i, m in enumerate(methods):
        groups.setdefault((type(m), m.name, m.projection, m.solves), []).append(i)
    kw = {"max_bits": max_bits, "certify_bits": certify_bits, "scheme": scheme}
    for members in groups.values():
        if len(members) == 1:
            i = members[0]
            out[i] = local_defect(coefficients[i], methods[i], decomposition, k, bits=bits, **kw)
            continue
        method, be = methods[members[0]], Ball(int(bits))
        try:
            with be.context():
                parts = [_exact_parts(coefficients[i], decomposition, k, be) for i in members]
                Ms = amplification_matrix(
                    _stacked([p[0] for p in parts]), method, decomposition, k, backend=be, scheme=scheme
                )
                first = [_resolved_defect(M, p, be, max_bits, certify_bits) for M, p in zip(Ms, parts)]
            again = min(2 * be.bits, max_bits)  # the precision schedule of local_defect from its next step
        except Exception:  # noqa: BLE001 -- the batch cannot tell which point failed: each alone
            first, again = [None] * len(members), be.bits
        for i, defect in zip(members, first):
            out[i] = defect or local_defect(coefficients[i], methods[i], decomposition, k, bits=again, **kw)
    return out


def _stacked(points):
    """Coefficients of single points (balls) as one set of coefficients with a leading axis of the points."""
    columns = []
    for f in dataclasses.fields(points[0]):
        column = np.empty(len(points), dtype=object)
        column[:] = [getattr(c, f.name) for c in points]
        columns.append(column)
    return type(points[0])(*columns)


def propagate_errors(M, D, E, z_at, n_steps: int, *, block: int | None = None) -> ErrorSeries:
    """Every ``eps_0 ... eps_n_steps`` of :func:`error_recurrence` as an :class:`ErrorSeries`."""
    return error_recurrence(M, D, E, z_at, n_steps, block=block).materialize()
