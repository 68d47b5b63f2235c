"""A chain of linear oscillator segments joined by rigid joints, and its exact monolithic solution.

A **segment** is ``n`` masses on a line, each with a spring and a damper to the ground and, between neighbours,
a spring and a damper inside the segment (:class:`ChainSegment`, SI units).  The **chain** is ``N`` segments
in a row, joint ``j`` holding the last mass of segment ``j`` and the first mass of segment ``j + 1`` together
(positions equal), each joint with its own decomposition; a single-mass segment has one port, where its
joints attach, a longer one two (its first and last mass).  Every segment of a chain has the same number of
masses.  The paper's two-mass model is the chain of two single-mass segments joined ``ff``, ``fd``, ``df``
or ``dd`` (:meth:`Chain.two_mass`).

Co-simulation runs in the engine's dimensionless form (as :mod:`icosim.problems.linear.model` for two
masses): time in macro steps ``t / H``, masses relative to the first segment's first mass ``m_ref``,
stiffness and damping per unit mass ``K_qj H^2 / m_q`` and ``D_qj H / m_q``, coupling forces
``lambda H^2 / m_ref`` (:meth:`Chain.segments`).  ``H`` may be an array: a family of points for the
spectral analysis (:class:`ChainFamily`).

**Monolithic solution.**  The rigid joints hold clusters of masses together (a chain of single masses is one
rigid body); in coordinates ``x = P r`` -- one per cluster and one per mass in no joint -- the chain obeys
``P^T M P r'' = -P^T K P r - P^T D P r'``, solved exactly by the matrix exponential of the first-order system
(:class:`ChainSolution`).  The joint forces follow from the masses' equations of motion,
``M a + K x + D v = G^T lambda`` (``G`` a joint's ``+1`` at its first mass, ``-1`` at its second), solved
exactly on a chain (the joints form a tree).

>>> chain = Chain.uniform(3, masses=(1.0,), ground_stiffness=(100.0,), ground_damping=(1.0,), H=1e-2)
>>> chain.graph().n_joints, [float(sg.masses[0]) for sg in chain.segments()]
(2, [1.0, 1.0, 1.0])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from fractions import Fraction

import numpy as np

from ...engine import layout
from ...engine.decompositions import DECOMPOSITIONS, get_decomposition
from ...engine.graph import CouplingGraph
from ...engine.projection import joined_clusters
from ...engine.spectral.family import LinearFamily
from ...errors import ParameterError
from .model import Segment
from .problem import LinearCosimulation
from .subsystems import decay_rate

__all__ = ["ChainSegment", "Chain", "ChainSolution", "ChainFamily", "chain_start", "read_segments"]


def _numbers(name, values, *, positive=False, length=None):
    """``values`` as a tuple of finite floats (>= 0, or > 0), the error naming ``name``."""
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a list of numbers, got {values!r}") from None
    if length is not None and len(out) != length:
        raise ParameterError(f"{name} must have {length} entries, got {len(out)}")
    for v in out:
        if not math.isfinite(v) or (v <= 0 if positive else v < 0):
            raise ParameterError(f"{name} must be finite numbers {'> 0' if positive else '>= 0'}, got {values!r}")
    return out


@dataclass(frozen=True)
class ChainSegment:
    """``n`` masses (kg) with springs (N/m) and dampers (N s/m) to the ground, and between neighbours
    ``stiffness``/``damping`` (``n - 1`` each).  Ground springs default to none, like the inner ones."""

    masses: tuple
    ground_stiffness: tuple = ()
    ground_damping: tuple = ()
    stiffness: tuple = ()
    damping: tuple = ()

    def __post_init__(self):
        masses = _numbers("masses", self.masses, positive=True)
        n = len(masses)
        if n == 0:
            raise ParameterError("a segment has at least one mass")
        object.__setattr__(self, "masses", masses)
        for name, length in (("ground_stiffness", n), ("ground_damping", n), ("stiffness", n - 1), ("damping", n - 1)):
            given = getattr(self, name) or (0.0,) * length
            object.__setattr__(self, name, _numbers(name, given, length=length))

    @property
    def n_masses(self) -> int:
        return len(self.masses)

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(M, K, D)`` of the segment alone (SI, float64)."""
        K, D = self.entries(float)
        n = self.n_masses
        full = [np.array([[0.0 if e is None else e for e in row] for row in A]).reshape(n, n) for A in (K, D)]
        return np.diag(self.masses), full[0], full[1]

    def entries(self, num) -> tuple[list, list]:
        """The stiffness and damping matrices as rows of numbers of ``num`` (a backend's ``const`` takes the
        parameters exactly), ``None`` off the band: ground plus inner springs on the diagonal, minus the inner
        spring between neighbours."""
        n = self.n_masses
        out = []
        for ground, inner in ((self.ground_stiffness, self.stiffness), (self.ground_damping, self.damping)):
            rows = [[None] * n for _ in range(n)]
            for q in range(n):
                total = num(ground[q])
                for c in ([inner[q - 1]] if q > 0 else []) + ([inner[q]] if q < n - 1 else []):
                    total = total + num(c)
                rows[q][q] = total
                if q < n - 1:
                    rows[q][q + 1] = -num(inner[q])
                    rows[q + 1][q] = -num(inner[q])
            out.append(rows)
        return out[0], out[1]


def read_segments(items, key: str = "segments") -> tuple[ChainSegment, ...]:
    """Segments from a list of mappings of :class:`ChainSegment`'s parameters, an error naming ``key[i]``."""
    if not isinstance(items, list) or not items:
        raise ParameterError(f"{key}: must be a non-empty list of segments")
    allowed = ("masses", "ground_stiffness", "ground_damping", "stiffness", "damping")
    out = []
    for i, seg in enumerate(items):
        unknown = sorted(set(seg) - set(allowed)) if isinstance(seg, dict) else []
        if not isinstance(seg, dict) or "masses" not in seg or unknown:
            got = f"unknown key {unknown[0]!r}" if unknown else f"{seg!r}"
            raise ParameterError(f"{key}[{i}]: must be a mapping with masses and {', '.join(allowed[1:])}; {got}")
        try:
            out.append(ChainSegment(**seg))
        except ParameterError as exc:
            raise ParameterError(f"{key}[{i}]: {exc}") from None
    return tuple(out)


@dataclass(frozen=True)
class Chain:
    """``N`` segments in a row, joint ``j`` between segment ``j``'s last mass and segment ``j + 1``'s first with
    ``decompositions[j]``; macro step ``H`` (s; an array for a family of points)."""

    segments_: tuple
    decompositions: tuple
    H: object = 1e-3

    def __post_init__(self):
        segs = tuple(s if isinstance(s, ChainSegment) else ChainSegment(**s) for s in self.segments_)
        object.__setattr__(self, "segments_", segs)
        if len(segs) < 2:
            raise ParameterError(f"a chain has at least 2 segments, got {len(segs)}")
        sizes = {s.n_masses for s in segs}
        if len(sizes) != 1:
            raise ParameterError(f"every segment of a chain has the same number of masses, got {sorted(sizes)}")
        decs = tuple(get_decomposition(d).name for d in self.decompositions)
        if len(decs) != len(segs) - 1:
            raise ParameterError(f"{len(segs)} segments need {len(segs) - 1} joints, got {len(decs)} decompositions")
        object.__setattr__(self, "decompositions", decs)
        if np.asarray(self.H).dtype != object:  # (an exact stack's H was checked as floats)
            H = np.asarray(self.H, dtype=float)
            if not np.all(np.isfinite(H)) or not np.all(H > 0):
                raise ParameterError(f"H must be finite and > 0, got {self.H!r}")
        self.graph()  # refuses a kinematically driven single mass in two joints

    @classmethod
    def uniform(cls, n_segments: int, *, decomposition="ff", H=1e-3, **segment) -> Chain:
        """``n_segments`` equal segments joined by ``decomposition``."""
        return cls((ChainSegment(**segment),) * n_segments, (decomposition,) * (n_segments - 1), H)

    @classmethod
    def from_dict(cls, d, H=1e-3) -> Chain:
        """``{segments: [...], joints: [...]}``: one segment per unit, one decomposition per joint or a single one
        for all (``docs/chains.md``); an error names the key and the values allowed."""
        if not isinstance(d, dict):
            raise ParameterError("a chain is a mapping with the keys segments and joints")
        if missing := [key for key in ("segments", "joints") if key not in d]:
            raise ParameterError(f"{missing[0]}: is missing (a chain has the keys segments and joints)")
        if unknown := sorted(set(d) - {"segments", "joints"}):
            raise ParameterError(f"{unknown[0]}: not a key of a chain; allowed: segments, joints")
        segs = read_segments(d["segments"])
        joints = d["joints"] if isinstance(d["joints"], list) else [d["joints"]] * (len(segs) - 1)
        for j, dec in enumerate(joints):
            if dec not in DECOMPOSITIONS:
                raise ParameterError(f"joints[{j}]: must be one of {', '.join(DECOMPOSITIONS)}, got {dec!r}")
        if len(joints) != len(segs) - 1:
            raise ParameterError(f"joints: {len(segs)} segments need {len(segs) - 1} joints (or one for all)")
        try:
            return cls(segs, tuple(joints), H)
        except ParameterError as exc:
            raise ParameterError(f"{'segments' if 'segment' in str(exc) else 'joints'}: {exc}") from None

    @classmethod
    def two_mass(cls, m1, m2, c1, c2, d1, d2, H, decomposition="ff") -> Chain:
        """The paper's two masses (:class:`~icosim.problems.linear.model.PhysicalModel`'s parameters)."""
        seg = [ChainSegment((m,), (c,), (d,)) for m, c, d in ((m1, c1, d1), (m2, c2, d2))]
        return cls(tuple(seg), (decomposition,), H)

    @property
    def n_segments(self) -> int:
        return len(self.segments_)

    @property
    def n_masses(self) -> int:
        """Masses per segment."""
        return self.segments_[0].n_masses

    def graph(self) -> CouplingGraph:
        """The joints: a single-mass segment's at its one port, a longer one's at its first and last mass
        (:meth:`port_masses`)."""
        return CouplingGraph.chain(self.decompositions, ports="ends" if self.n_masses > 1 else "one")

    def port_masses(self) -> list[tuple[int, ...]]:
        """Per segment, the mass of each port: the first segment's one port at its last mass, the last one's at
        its first, the others' at their first and last."""
        n, N = self.n_masses, self.n_segments
        if n == 1:
            return [(0,)] * N
        return [(n - 1,)] + [(0, n - 1)] * (N - 2) + [(0,)]

    def with_H(self, H) -> Chain:
        return replace(self, H=H)

    # -- the engine's dimensionless form ------------------------------------------------------------
    @property
    def reference_mass(self) -> float:
        return self.segments_[0].masses[0]

    def segments(self, backend=None) -> list[Segment]:
        """The segments in the engine's form (:class:`~icosim.problems.linear.model.Segment`) at ``H``; with
        ``backend``, every coefficient formed in its arithmetic from the parameters taken exactly."""
        if backend is None:
            num = float
            H = np.asarray(self.H, dtype=float)
        else:
            num = backend.const
            H = self.H if np.asarray(self.H).dtype == object else _exact_array(self.H, backend)
        m_ref = num(self.reference_mass)
        out = []
        for sg in self.segments_:
            K, D = sg.entries(num)
            n = sg.n_masses
            m = [num(v) for v in sg.masses]
            masses = tuple(mq / m_ref + 0 * H for mq in m)
            stiffness = tuple(
                tuple(None if K[q][j] is None else K[q][j] * H * H / m[q] for j in range(n)) for q in range(n)
            )
            damping = tuple(tuple(None if D[q][j] is None else D[q][j] * H / m[q] for j in range(n)) for q in range(n))
            out.append(Segment(masses, stiffness, damping))
        return out

    def problem(self, k: int, backend=None, *, exact: bool = False) -> LinearCosimulation:
        """The co-simulation problem of the chain at its ``H`` (:class:`LinearCosimulation`)."""
        return LinearCosimulation(
            self.segments(backend if exact else None), self.graph(), k, backend, port_masses=self.port_masses()
        )

    # -- the monolithic system -----------------------------------------------------------------------
    def full_matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(M, K, D)`` of all masses, segment after segment (SI)."""
        import scipy.linalg  # here: a job that predicts a scene's rho from the chain never needs it

        mats = [sg.matrices() for sg in self.segments_]
        return tuple(scipy.linalg.block_diag(*(m[i] for m in mats)) for i in range(3))

    def bodies_of_ports(self) -> list[int]:
        """The mass (numbered over the chain) of every port, in the graph's numbering of ports."""
        n = self.n_masses
        return [i * n + q for i, pm in enumerate(self.port_masses()) for q in pm]

    def reduction(self) -> np.ndarray:
        """``P`` with ``x = P r``: one coordinate per cluster of joined masses and per free mass."""
        n_all = self.n_segments * self.n_masses
        clusters = joined_clusters(self.graph(), self.bodies_of_ports())
        joined = {b for c in clusters for b in c}
        groups = list(clusters) + [(b,) for b in range(n_all) if b not in joined]
        groups.sort(key=min)
        P = np.zeros((n_all, len(groups)))
        for r, g in enumerate(groups):
            P[list(g), r] = 1.0
        return P

    def joint_matrix(self) -> np.ndarray:
        """``G`` (joints x masses): ``+1`` at a joint's first mass, ``-1`` at its second."""
        bodies = self.bodies_of_ports()
        graph = self.graph()
        offsets = graph.port_offsets
        G = np.zeros((graph.n_joints, self.n_segments * self.n_masses))
        for j, jt in enumerate(graph.joints):
            G[j, bodies[offsets[jt.first] + jt.ports[0]]] += 1
            G[j, bodies[offsets[jt.second] + jt.ports[1]]] -= 1
        return G


def _exact_array(H, backend):
    """``H`` (a float or an array of floats) as exact numbers of ``backend`` (an object array)."""
    arr = np.asarray(H, dtype=float)
    out = np.empty(arr.shape, dtype=object)
    for idx in np.ndindex(arr.shape):
        out[idx] = backend.const(Fraction(float(arr[idx])))
    return out[()] if out.ndim == 0 else out


@dataclass
class ChainSolution:
    """The exact monolithic solution of a chain (scalar ``H``) from positions and velocities of every mass
    at ``t = 0`` (SI), in the engine's dimensionless variables: times in macro steps (may be negative: the
    coupling history before ``T_0`` is taken from it), positions as given, velocities ``H v``, forces
    ``lambda H^2 / m_ref``."""

    chain: Chain
    x0: np.ndarray
    v0: np.ndarray
    _A: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        chain = self.chain
        H = float(chain.H)
        M, K, D = chain.full_matrices()
        P = chain.reduction()
        self.P = P
        Mr, Kr, Dr = P.T @ M @ P, P.T @ K @ P, P.T @ D @ P
        nr = P.shape[1]
        # dimensionless time tau = t / H: r'' = -Mr^-1 (H^2 Kr r + H Dr r')  (r' per macro step)
        A = np.zeros((2 * nr, 2 * nr))
        A[:nr, nr:] = np.eye(nr)
        A[nr:, :nr] = -np.linalg.solve(Mr, Kr) * H * H
        A[nr:, nr:] = -np.linalg.solve(Mr, Dr) * H
        self._A = A
        x0, v0 = np.asarray(self.x0, dtype=float), np.asarray(self.v0, dtype=float) * H
        r0, *_ = np.linalg.lstsq(P, x0, rcond=None)
        w0, *_ = np.linalg.lstsq(P, v0, rcond=None)
        if np.max(np.abs(P @ r0 - x0)) > 1e-12 * max(1.0, np.max(np.abs(x0))) or np.max(
            np.abs(P @ w0 - v0)
        ) > 1e-12 * max(1.0, np.max(np.abs(v0))):
            raise ParameterError("the initial positions and velocities of joined masses must be equal")
        self._z0 = np.concatenate([r0, w0])
        self._M, self._K, self._D = M, K, D
        self._G = chain.joint_matrix()

    def state(self, t) -> dict:
        """``x``, ``v``, ``a`` of every mass (``(..., N n)``, dimensionless) and the joint forces ``lam``
        (``(..., M)``) at the times ``t`` (macro steps)."""
        import scipy.linalg  # here, as in full_matrices

        t = np.atleast_1d(np.asarray(t, dtype=float))
        z = np.stack([scipy.linalg.expm(self._A * ti) @ self._z0 for ti in t.ravel()]).reshape(t.shape + (-1,))
        nr = self.P.shape[1]
        r, w = z[..., :nr], z[..., nr:]
        acc = w @ self._A[nr:, nr:].T + r @ self._A[nr:, :nr].T
        x, v, a = r @ self.P.T, w @ self.P.T, acc @ self.P.T
        H, m_ref = float(self.chain.H), self.chain.reference_mass
        # G^T lambda = M a + K x + D v, dimensionless: forces times H^2 / m_ref
        F = (a @ self._M.T + H * H * (x @ self._K.T) + H * (v @ self._D.T)) / m_ref
        lam = np.linalg.lstsq(self._G.T, F.reshape(-1, F.shape[-1]).T, rcond=None)[0].T.reshape(F.shape[:-1] + (-1,))
        return {"x": x, "v": v, "a": a, "lam": lam}


def chain_start(problem: LinearCosimulation, solution: ChainSolution):
    """Initial state and coupling history of a chain problem from the exact solution: every segment at its
    exact ``(x, v)``; the history the exact coupling variables at ``T_0, T_-1, ..., T_-k`` (a joint's
    multiplier, or the acceleration of its joint point)."""
    k = problem.k
    exact = solution.state(-np.arange(k + 1, dtype=float))
    graph, n = problem.graph, problem.n_masses
    cols = []
    for j, jt in enumerate(graph.joints):
        mass = solution.chain.bodies_of_ports()[graph.port_offsets[jt.first] + jt.ports[0]]
        for var in jt.decomposition.variables:
            cols.append(exact["lam"][:, j] if var.startswith("lambda") else exact["a"][:, mass])
    history = np.stack(cols, axis=-1)
    x, v = exact["x"][0], exact["v"][0]
    N = graph.n_subsystems
    state = np.concatenate([x.reshape(N, n), v.reshape(N, n)], axis=-1)
    be = problem.backend
    return be.asarray(state), be.asarray(history)


@dataclass(frozen=True)
class ChainFamily(LinearFamily):
    """Points of a chain over its ``H`` (an array), one order ``k``, for the spectral analysis.

    ``converted``: ``H`` holds numbers of the backend already (a stack of exact points, :meth:`stack`).
    """

    chain: Chain
    k: int
    converted: bool = False

    @property
    def graph(self) -> CouplingGraph:  # type: ignore[override]
        return self.chain.graph()

    @property
    def shape(self) -> tuple:
        return np.shape(self.chain.H)

    def problem(self, backend, *, exact: bool = False):
        if self.converted:
            segs = self.chain.segments(backend)
        else:
            segs = self.chain.segments(backend if exact else None)
        segs = [sg.map(lambda a: layout.batched(backend.asarray(a)[..., None])) for sg in segs]
        return LinearCosimulation(segs, self.graph, self.k, backend, port_masses=self.chain.port_masses())

    def point(self, index) -> ChainFamily:
        return ChainFamily(self.chain.with_H(float(np.asarray(self.chain.H, dtype=float)[index])), self.k)

    def subset(self, mask) -> ChainFamily:
        H = np.broadcast_to(np.asarray(self.chain.H, dtype=float), self.shape)[mask]
        return ChainFamily(self.chain.with_H(H), self.k)

    def overflowing(self):
        with np.errstate(all="ignore"):
            bad = np.zeros(self.shape, dtype=bool)
            for sg in self.chain.segments():
                for row in sg.stiffness + sg.damping:
                    for c in row:
                        if c is not None:
                            bad |= ~np.isfinite(np.broadcast_to(np.asarray(c, dtype=float), self.shape))
        return bad

    overflow_reason = "overflow: a derived coefficient (K H^2/m, D H/m) is not finite in float64"

    def safe(self, mask) -> ChainFamily:
        H = np.where(mask, 1e-3, np.asarray(self.chain.H, dtype=float))
        return ChainFamily(self.chain.with_H(H), self.k)

    def guard_bits(self) -> int:
        """Extra bits for entries as small as ``exp(-decay)`` (:meth:`icosim.problems.linear.family.TwoMass.guard_bits`):
        ``decay`` the largest ``-Re`` of an eigenvalue of a segment, in macro steps."""
        decay = 0.0
        H = float(np.max(np.asarray(self.chain.H, dtype=float)))
        for sg in self.chain.segments_:
            M, K, D = sg.matrices()
            if sg.n_masses == 1:
                decay = max(decay, float(decay_rate(K[0, 0] * H * H / M[0, 0], D[0, 0] * H / M[0, 0])))
            else:
                n = sg.n_masses
                A = np.zeros((2 * n, 2 * n))
                A[:n, n:] = np.eye(n)
                A[n:, :n], A[n:, n:] = -np.linalg.solve(M, K) * H * H, -np.linalg.solve(M, D) * H
                decay = max(decay, float(np.max(-np.linalg.eigvals(A).real)))
        bits = decay / math.log(2)
        return int(math.ceil(bits)) if bits < 2**62 else 2**62

    @classmethod
    def stack(cls, points, backend) -> ChainFamily:
        H = np.empty(len(points), dtype=object)
        H[:] = [_exact_array(p.chain.H, backend) for p in points]
        first = points[0]
        return cls(replace(first.chain, H=H), first.k, converted=True)
