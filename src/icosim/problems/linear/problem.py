"""Linear segments joined by rigid joints as a co-simulation problem: the paper's two-mass test model (Sect. 2)
and chains of it.

Every subsystem is a segment of ``n`` masses (:class:`~icosim.problems.linear.subsystems.LinearSubsystem`), the
same ``n`` for all; its joints attach at its first mass (port 1) and its last (port 2; a single mass has both
there).  State: ``s[..., i, :] = (x_i1 ... x_in, v_i1 ... v_in)`` for subsystem ``i`` (the paper's ``z_N``:
``(x_i, v_i)``).  Coupling history: ``h[..., j, :] = e_N-j`` for ``j = 0..k`` (the paper's
``lambda_c,N ... lambda_c,N-k`` and/or ``a_tilde``; for a graph, :meth:`~icosim.engine.graph.CouplingGraph.columns`).
Outputs at ``T_N+1``: ``y[..., i, p, :, 0] = (x, v, a, f)`` of port ``p`` of subsystem ``i`` (one component)
with ``f`` the coupling force acting there: its input for a force-driven port, the force its drive exerts for a
kinematically driven one (:mod:`icosim.engine.graph`).

All arrays may carry leading batch axes; the coefficients broadcast against them.  This is what lets
:mod:`icosim.studies.stability` build the amplification matrices of a whole parameter grid in one pass.
"""

from __future__ import annotations

import copy

import numpy as np

from ...engine import layout
from ...engine.graph import CouplingGraph
from ...engine.problem import CosimulationProblem
from ...engine.projection import joined_clusters, mass_weighted_projection
from ...errors import ParameterError
from .model import Coefficients
from .subsystems import LinearSubsystem

__all__ = ["LinearCosimulation"]


class LinearCosimulation(CosimulationProblem):
    """Linear segments coupled by rigid joints, integrated exactly.

    Parameters
    ----------
    model : :class:`icosim.problems.linear.model.Coefficients` (the paper's two single-mass oscillators), or a
        sequence of :class:`~icosim.problems.linear.model.Segment` (arrays broadcast).
    graph : the :class:`~icosim.engine.graph.CouplingGraph` joining the segments; for the two oscillators a
        decomposition, ``"ff"`` ... ``"dd"``.
    k : degree of the Lagrange polynomials (any integer >= 0).
    backend : arithmetic; float64 by default.
    port_masses : per segment, the mass (0-based) each of its ports is at (default: port 1 at the first mass,
        port 2 at the last).

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

    #: exact and constant (Eq. 13): the Jacobians are formed once per stage, not counted as work
    constant_sensitivities = True

    def __init__(self, model, graph, k: int, backend=None, *, port_masses=None):
        if isinstance(model, Coefficients):
            graph = graph if isinstance(graph, CouplingGraph) else CouplingGraph.pair(graph)
        elif not isinstance(graph, CouplingGraph):
            raise ParameterError("segments are joined by a CouplingGraph")
        super().__init__(graph, k, backend)
        be = self.backend
        if isinstance(model, Coefficients):
            c = model.map(be.asarray)
            self.coefficients = c
            segments = c.segments(be)
        else:
            self.coefficients = None
            segments = [sg.map(be.asarray) for sg in model]
        self.segments = tuple(segments)
        sizes = {len(sg.masses) for sg in self.segments}
        if len(self.segments) != graph.n_subsystems or len(sizes) != 1:
            raise ParameterError(
                f"{graph.n_subsystems} subsystems need as many segments of one number of masses, got "
                f"{len(self.segments)} with {sorted(sizes)} masses"
            )
        #: masses per segment
        self.n_masses = n = sizes.pop()
        if port_masses is None:
            if max(graph.ports) > 2:
                raise ParameterError("a segment has two ports by default: its first mass and its last")
            port_masses = [(0, n - 1)[: graph.ports[i]] for i in range(graph.n_subsystems)]
        self.port_masses = tuple(tuple(int(q) for q in pm) for pm in port_masses)
        if [len(pm) for pm in self.port_masses] != list(graph.ports) or not all(
            0 <= q < n for pm in self.port_masses for q in pm
        ):
            raise ParameterError(f"port_masses {port_masses!r}: per segment a mass of {n} for each of its ports")
        self.subsystems = tuple(
            LinearSubsystem(
                tuple((self.port_masses[i][p], graph.port_kind(i, p)) for p in range(graph.ports[i])),
                sg.stiffness,
                sg.damping,
                [be.const(1) / m for m in sg.masses],
                k,
                be,
            )
            for i, sg in enumerate(self.segments)
        )
        bodies = [i * n + q for i in range(graph.n_subsystems) for q in self.port_masses[i]]
        self._clusters = joined_clusters(graph, bodies)

    # -- sizes and packing ---------------------------------------------------
    @property
    def n_state(self) -> int:
        """Length of the packed state ``(s_1, ..., s_N, e_N, ..., e_N-k)`` (two masses: ``(x1, v1, x2, v2, ...)``)."""
        return 2 * self.n_masses * self.graph.n_subsystems + (self.k + 1) * self.n_coupling

    def pack(self, state, history):
        N, width = self.graph.n_subsystems, 2 * self.n_masses
        lead = np.broadcast_shapes(state.shape[:-2], history.shape[:-2])
        state = np.broadcast_to(state, lead + (N, width))
        history = np.broadcast_to(history, lead + history.shape[-2:])
        # the rows of state and history one after the other (no reshape: that would copy a grid laid out with
        # its grid axes fastest into C order first)
        parts = [state[..., i, :] for i in range(N)] + [history[..., j, :] for j in range(history.shape[-2])]
        return layout.concatenate(parts, axis=-1)

    def unpack(self, w):
        lead = w.shape[:-1]
        N, width = self.graph.n_subsystems, 2 * self.n_masses
        split = N * width
        return w[..., :split].reshape(lead + (N, width)), w[..., split:].reshape(lead + (self.k + 1, self.n_coupling))

    # -- what the float64 error estimate asks (icosim.engine.spectral.radius) ------
    def disturbed(self, rng, rel):
        """A copy whose exponential blocks carry absolute noise ``rel * max|E|`` (the size of their rounding)."""
        p = copy.copy(self)
        subs = []
        for sub in self.subsystems:
            s = copy.copy(sub)
            E = sub.blocks
            scale = rel * np.max(np.abs(E), axis=(-1, -2), keepdims=True)
            s.set_blocks(E + scale * rng.standard_normal(E.shape))
            subs.append(s)
        p.subsystems = tuple(subs)
        p._jacobians = {}  # its own Jacobians, with their own factors
        return p

    def side_by_side(self, copies):
        """This problem and ``copies`` of it (:meth:`disturbed`: only their exponential blocks differ) as one, on a
        new leading axis (this one first), for one macro step to form all their matrices; every point's values
        are those it gets alone (a block the same at every point is repeated over the points)."""
        problems = (self, *copies)
        # the points' axes and the basis vectors' (a family's problem's last batch axis, of length one)
        params = [
            a for sub in self.subsystems for a in sub.gain + [c for row in sub.stiffness + sub.damping for c in row]
        ]
        lead = np.broadcast_shapes(
            (1,), *(np.shape(a) for a in params if a is not None),
            *(sub.blocks.shape[:-2] for p in problems for sub in p.subsystems),
        )  # fmt: skip
        p = copy.copy(self)
        subs = []
        for i, sub in enumerate(self.subsystems):
            s = copy.copy(sub)
            blocks = [q.subsystems[i].blocks for q in problems]
            s.set_blocks(np.stack([np.broadcast_to(E, lead + E.shape[-2:]) for E in blocks]))
            subs.append(s)
        p.subsystems = tuple(subs)
        p._jacobians = {}
        return p

    def generator_norm(self):
        """``nu = max(1, ||A||_1)`` over the subsystems, ``A`` the matrix whose exponential a subsystem's blocks
        are (per point; :meth:`~icosim.problems.linear.subsystems.LinearSubsystem.norm_bound`)."""
        nu = 1.0
        for sub in self.subsystems:
            nu = np.maximum(nu, sub.norm_bound())
        return nu[..., 0] if np.ndim(nu) else nu  # without the axis the basis vectors ride on (length 1)

    # -- the problem interface used by icosim.engine.macrostep ----------------------
    def _integrate(self, i, state, samples, nodes):
        self.work.subsystem_integrations += 1
        U = np.swapaxes(self.inputs(i, samples), -1, -2)  # (..., ports, nodes)
        end, y = self.subsystems[i].step(state[..., i, :], U, nodes)
        return end, y[..., None]

    def predict(self, i, state, history, *, final=False):
        return self._integrate(i, state, history, self.pred_nodes)

    def correct(self, i, state, history, e_new):
        return self._integrate(i, state, self.corrector_samples(history, e_new), self.corr_nodes)

    def reevaluate(self, i, end, y, e_old, e_new):
        """Exact (the outputs are affine in the inputs at a fixed state): ``y + sum_p dy/du_p(1) du_p``.

        The increment form keeps the propagated acceleration (no cancellation
        in ``-k x - delta v + g u`` when the acceleration is exponentially small).
        """
        du = self.inputs(i, e_new) - self.inputs(i, e_old)
        S = self.subsystems[i].algebraic_sensitivity()  # (..., inputs, ports, 4)
        for p in range(S.shape[-3]):
            y = y + (S[..., p, :, :] * du[..., p, None, None])[..., None]
        return y

    def join(self, ends):
        return _stack(ends)

    def sensitivity(self, i, state, history, e, end=None, y=None):
        """``dy_i/du_i``, shape ``(..., inputs, ports, 4, 1)``: through the interpolation polynomial of the
        corrector (Eq. 13) or, at a fixed end state, algebraically
        (:meth:`~icosim.problems.linear.subsystems.LinearSubsystem.algebraic_sensitivity`)."""
        sub = self.subsystems[i]
        dy = sub.step_sensitivity(self.corr_nodes) if end is None else sub.algebraic_sensitivity()
        return dy[..., None]

    def masses(self):
        """Every mass of every segment, ``(..., N n)`` (the bodies of :meth:`project`)."""
        ms = [m for sg in self.segments for m in sg.masses]
        return layout.stack(np.broadcast_arrays(*ms), axis=-1)

    def project(self, state):
        """Mass-weighted projection of positions and velocities (Eq. 30,
        :func:`icosim.engine.projection.mass_weighted_projection`): every mass a body."""
        n, N = self.n_masses, self.graph.n_subsystems
        lead = state.shape[:-2]
        # (..., N, 2n) -> bodies (..., N n, 2): each mass's (x, v)
        bodies = np.stack([state[..., :, :n], state[..., :, n:]], axis=-1).reshape(lead + (N * n, 2))
        if n == 1:
            bodies = state
        projected = mass_weighted_projection(self._clusters, self.masses(), bodies)
        if n == 1:
            return projected
        pr = projected.reshape(projected.shape[:-2] + (N, n, 2))
        return np.concatenate([pr[..., 0], pr[..., 1]], axis=-1)


def _stack(arrays):
    return layout.stack(np.broadcast_arrays(*arrays), axis=-2)
