"""Linear units coupled by signal connections: the built-in model of a signal-coupled co-simulation (docs/signals.md).

A unit is a linear state-space model (:class:`StateSpaceUnit`), either continuous, ``x' = A x + B u``, ``y = C x
+ D u``, or the one-step map over a macro step ``H`` with inputs held over it, ``x_N+1 = Phi x_N + Gamma u_N``,
``y = C x + D u`` (what probing steps identify of a co-simulation unit).  Connections ``u_in = factor * y_out +
offset`` (:class:`~icosim.engine.graph.Connection`) couple them; :class:`SignalLinearCosimulation` is the
:class:`~icosim.engine.problem.CosimulationProblem` that the one macro step runs with ``method=None`` (explicit
coupling, Jacobi or Gauss-Seidel, inputs extrapolated by the Lagrange polynomial of order ``k``).  A continuous
unit is integrated exactly over a macro step with its polynomial input (the matrix exponential of the unit and the
input's derivatives, Van Loan's block form), so the spectral radius of the recurrence is the coupling's own.

Its recurrence matrix is that of the macro step, by linearity (:mod:`icosim.engine.spectral.matrix`): the packed
state is ``w_N = (x_N, e_N, ..., e_N-k)`` (the units' states in order, then the connections' input values at the
last ``k + 1`` communication points).  :class:`SignalFamily` is the one point the spectral analysis asks for
(:mod:`icosim.engine.spectral.family`).  Offsets shift the fixed point, not the recurrence: the matrix is that of
the connections without them.

>>> lag = StateSpaceUnit([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
>>> loop = [Connection(0, 0, 1, 0, 2.0), Connection(1, 0, 0, 0, 2.0)]
>>> rho, err = signal_radius((lag, lag), loop, 0, 0.1)
>>> bool(abs(rho - (np.exp(-0.1) + 2 * (1 - np.exp(-0.1)))) < 1e-14)
True
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import expm

from ...engine import graph
from ...engine.backends import Backend, Float64
from ...engine.graph import Connection, CouplingGraph
from ...engine.lagrange import monomial_coefficients
from ...engine.problem import CosimulationProblem
from ...engine.schemes import JACOBI, Scheme
from ...engine.spectral.family import LinearFamily
from ...errors import ParameterError

__all__ = ["StateSpaceUnit", "SignalLinearCosimulation", "SignalFamily", "signal_radius", "signal_limit"]


def _matrix(name: str, value: Any, rows: int | None, cols: int | None) -> np.ndarray:
    a = np.atleast_2d(np.asarray(value, dtype=float))
    if a.ndim != 2 or (rows is not None and a.shape[0] != rows) or (cols is not None and a.shape[1] != cols):
        raise ParameterError(f"state-space unit: {name} must be a {rows or 'n'} x {cols or 'm'} matrix, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"state-space unit: {name} must be finite")
    return a


@dataclass(frozen=True)
class StateSpaceUnit:
    """``x' = A x + B u``, ``y = C x + D u`` (``H`` None: continuous); with ``H`` the one-step map over ``H`` with
    held inputs, ``x_N+1 = A x_N + B u_N`` (``A`` is ``Phi``, ``B`` is ``Gamma``), which serves ``k = 0`` at that
    ``H`` only: the response to an input that changes over the step is not in it."""

    A: Any
    B: Any
    C: Any
    D: Any
    H: float | None = None

    def __post_init__(self) -> None:
        A = _matrix("A", self.A, None, None)
        n = A.shape[0]
        A = _matrix("A", A, n, n)
        B = _matrix("B", self.B, n, None)
        C = _matrix("C", self.C, None, n)
        D = _matrix("D", self.D, C.shape[0], B.shape[1])
        for name, value in zip("ABCD", (A, B, C, D)):
            object.__setattr__(self, name, value)
        if self.H is not None and not (np.isfinite(self.H) and self.H > 0):
            raise ParameterError(f"state-space unit: H must be > 0 (the step of a one-step map), got {self.H!r}")

    @property
    def n_states(self) -> int:
        return int(self.A.shape[0])

    @property
    def n_inputs(self) -> int:
        return int(self.B.shape[1])

    @property
    def n_outputs(self) -> int:
        return int(self.C.shape[0])

    def propagators(self, H: float, k: int) -> tuple[np.ndarray, np.ndarray]:
        """``Phi`` and ``Gamma[m]`` (``(k + 1, n, n_u)``): over ``[0, H]`` with ``u(tau) = sum_m c_m tau^m``,
        ``tau = t / H``, the state goes to ``Phi x + sum_m Gamma[m] c_m``."""
        if self.H is not None:
            if k > 0:
                raise ParameterError(f"a one-step map over held inputs serves k = 0 only, not k = {k}: the "
                                     "response to an extrapolated input needs the continuous model")  # fmt: skip
            if not math.isclose(H, self.H, rel_tol=1e-12):
                raise ParameterError(f"a one-step map over H = {self.H:g} s cannot take a step of {H:g} s")
            return self.A, self.B[None]
        n, m = self.n_states, self.n_inputs
        # z = (x, u, u', ..., u^(k)) in tau: x' = H A x + H B u, each derivative the next one's integral
        size = n + (k + 1) * m
        M = np.zeros((size, size))
        M[:n, :n], M[:n, n : n + m] = H * self.A, H * self.B
        for j in range(k):
            M[n + j * m : n + (j + 1) * m, n + (j + 1) * m : n + (j + 2) * m] = np.eye(m)
        E = expm(M)
        gammas = np.array([math.factorial(j) * E[:n, n + j * m : n + (j + 1) * m] for j in range(k + 1)])
        return E[:n, :n], gammas


class SignalLinearCosimulation(CosimulationProblem):
    """``units`` (:class:`StateSpaceUnit`) coupled by ``connections`` at the macro step ``H``, inputs extrapolated
    at order ``k`` (module docstring).  States ``(..., n_x)`` (the units' states in order), history ``(..., k + 1,
    n_e)``, a unit's outputs ``(..., n_y)`` at ``T_N+1`` with its inputs at ``u(1)``; leading axes broadcast.  An
    input no connection feeds is zero.  ``implicit``: the connections closed by their conditions at ``T_N+1``
    (:mod:`icosim.engine.connection_conditions`)."""

    #: a linear unit's difference quotient is exact at any step: a unit step rounds least
    connection_perturbation = 1.0

    def __init__(self, units: Sequence[StateSpaceUnit], connections: Sequence[graph.Connection], k: int, H: float,
                 *, names: Sequence[str] | None = None, backend: Backend | None = None,
                 implicit: bool = False) -> None:  # fmt: skip
        if backend is not None and not isinstance(backend, Float64):
            raise ParameterError("the signal-coupled linear model computes in float64 only")
        self.units = tuple(units)
        for c, con in enumerate(connections):
            if con.source >= len(self.units) or con.target >= len(self.units):
                raise ParameterError(f"connection {c + 1} names a unit beyond the {len(self.units)} given")
            if con.output >= self.units[con.source].n_outputs or con.input >= self.units[con.target].n_inputs:
                raise ParameterError(f"connection {c + 1}: unit {con.source + 1} has {self.units[con.source].n_outputs} "
                                     f"outputs, unit {con.target + 1} {self.units[con.target].n_inputs} inputs; it "
                                     f"names output {con.output + 1} and input {con.input + 1}")  # fmt: skip
        coupled = CouplingGraph(len(self.units), (), names=() if names is None else tuple(names),
                                connections=tuple(connections))  # fmt: skip
        super().__init__(coupled, k)
        self.implicit_connections = bool(implicit)
        self.H = float(H)
        self.maps = [u.propagators(self.H, k) for u in self.units]
        self.C_pred = np.array(monomial_coefficients(self.pred_nodes), dtype=float)
        self.C_corr = np.array(monomial_coefficients(self.corr_nodes), dtype=float)
        ends = np.cumsum([0] + [u.n_states for u in self.units])
        self.slices = [slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:])]
        self.n_x = int(ends[-1])

    @property
    def n_state(self) -> int:
        """Length of the packed state ``(x, e_N, ..., e_N-k)``."""
        return self.n_x + (self.k + 1) * self.n_coupling

    def unpack(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        w = np.asarray(w)
        return w[..., : self.n_x], w[..., self.n_x :].reshape(w.shape[:-1] + (self.k + 1, self.n_coupling))

    def pack(self, state: np.ndarray, history: np.ndarray) -> np.ndarray:
        lead = np.broadcast_shapes(state.shape[:-1], history.shape[:-2])
        flat = np.broadcast_to(history, lead + history.shape[-2:]).reshape(lead + (-1,))
        return np.concatenate([np.broadcast_to(state, lead + state.shape[-1:]), flat], axis=-1)

    def disturbed(self, rng: Any, rel: float) -> SignalLinearCosimulation:
        """A copy whose propagators carry absolute noise ``rel * max|entry|`` (the size of their rounding)."""
        p = copy.copy(self)
        noise = lambda a: rel * np.max(np.abs(a), initial=1e-300) * rng.standard_normal(a.shape)  # noqa: E731
        p.maps = [(Phi + noise(Phi), G + noise(G)) for Phi, G in self.maps]
        p._jacobians = {}
        return p

    def generator_norm(self) -> float:
        """``max(1, ||H A||_1)`` over the continuous units (whose exponential the propagators are)."""
        return max([1.0] + [self.H * float(np.linalg.norm(u.A, 1)) for u in self.units if u.H is None])

    def _step(self, i: int, state: np.ndarray, rows: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        unit, (Phi, G) = self.units[i], self.maps[i]
        self.work.subsystem_integrations += 1
        fed = self.graph.signal_inputs(i)
        lead = np.broadcast_shapes(state.shape[:-1], rows.shape[:-2])
        coef = np.zeros(lead + (self.k + 1, unit.n_inputs))
        if fed:
            inputs, cols = [a for a, _ in fed], [b for _, b in fed]
            coef[..., inputs] = np.einsum("mj,...jc->...mc", C, rows[..., cols])
        x = state[..., self.slices[i]]
        end = x @ Phi.T + np.einsum("...mc,mnc->...n", coef, G)
        u1 = coef.sum(axis=-2)  # the polynomial at tau = 1: the inputs the outputs are read with
        return end, end @ unit.C.T + u1 @ unit.D.T

    def predict(self, i: int, state: Any, history: Any, *, final: bool = False, e_new: Any = None) -> Any:
        if e_new is not None:  # fed by a connection's new sample: the interpolation polynomial through it
            return self.correct(i, state, history, e_new)
        return self._step(i, state, history[..., : self.k + 1, :], self.C_pred)

    def correct(self, i: int, state: Any, history: Any, e: Any) -> Any:
        return self._step(i, state, self.corrector_samples(history, np.asarray(e)), self.C_corr)

    def signal_output(self, i: int, y: Any, output: int) -> Any:
        return y[..., output]

    def stack(self, ys: Sequence[Any]) -> Any:
        lead = np.broadcast_shapes(*(np.shape(y)[:-1] for y in ys))
        return np.concatenate([np.broadcast_to(y, lead + np.shape(y)[-1:]) for y in ys], axis=-1)

    def join(self, ends: Sequence[Any]) -> Any:
        return self.stack(ends)


class SignalFamily(LinearFamily):
    """The one point ``units``, ``connections`` (their offsets dropped: the recurrence is that of the linear part),
    ``k``, ``H`` of the signal-coupled model (``implicit``: the connections closed at ``T_N+1``), as the spectral
    analysis asks for it (float64 only)."""

    def __init__(self, units: Sequence[StateSpaceUnit], connections: Sequence[graph.Connection], k: int, H: float,
                 *, implicit: bool = False) -> None:  # fmt: skip
        self.units, self.k, self.H, self.implicit = tuple(units), int(k), float(H), bool(implicit)
        self.connections = tuple(Connection(c.source, c.output, c.target, c.input, c.factor, 0.0) for c in connections)
        self.graph = self.problem(Float64()).graph

    @property
    def shape(self) -> tuple:
        return ()

    def problem(self, backend: Backend, *, exact: bool = False) -> SignalLinearCosimulation:
        if exact or not isinstance(backend, Float64):
            raise ParameterError("the signal-coupled linear model computes in float64 only")
        return SignalLinearCosimulation(self.units, self.connections, self.k, self.H, implicit=self.implicit)

    def point(self, index: tuple[int, ...]) -> SignalFamily:
        return self

    def subset(self, mask: np.ndarray) -> SignalFamily:
        return self

    def overflowing(self) -> np.ndarray:
        return np.zeros((), dtype=bool)

    def safe(self, mask: np.ndarray) -> SignalFamily:
        return self

    def guard_bits(self) -> int:
        return 0

    @classmethod
    def stack(cls, points: Sequence[LinearFamily], backend: Backend) -> LinearFamily:
        raise ParameterError("the signal-coupled linear model is one point in float64; it does not stack")


def signal_radius(units: Sequence[StateSpaceUnit], connections: Sequence[graph.Connection], k: int, H: float,
                  scheme: Scheme = JACOBI, *, implicit: bool = False) -> tuple[float, float]:  # fmt: skip
    """The spectral radius of the co-simulation recurrence and its float64 error estimate
    (:func:`~icosim.engine.spectral.radius.spectral_radius_float64` on :class:`SignalFamily`); ``implicit``: the
    connections closed at ``T_N+1``."""
    from ...engine.spectral.radius import spectral_radius_float64

    family = SignalFamily(tuple(units), tuple(connections), k, H, implicit=implicit)
    rho, err = spectral_radius_float64(family, None, scheme=scheme)
    return float(rho), float(err)


def signal_limit(units: Sequence[StateSpaceUnit] | Callable[[float], Sequence[StateSpaceUnit]],
                 connections: Sequence[graph.Connection], k: int, H: float, scheme: Scheme = JACOBI, *,
                 decades: float = 3.0, per_decade: int = 4, resolution: float = 1e-3,
                 implicit: bool = False) -> Any:  # fmt: skip
    """The largest stable macro step (:func:`~icosim.step_limit.stability_limit`: a geometric scan of ``per_decade``
    step sizes a decade over ``decades`` either side of ``H``, then a bisection to ``resolution``): stable where the
    spectral radius and its error estimate stay below one.  A band of instability between two neighbouring scan
    points is not seen, so the scan's ratio ``10**(1/per_decade)`` bounds the narrowest band it finds (implicit
    coupling of units with their own oscillations has such bands).  ``units``: continuous units, or a function of
    the step giving the units at it (one-step maps identified anew at each step).  Each evaluation's info is
    ``(rho, err)``."""
    from ...step_limit import stability_limit

    if not callable(units) and any(u.H is not None for u in units):
        raise ParameterError("the largest stable H needs every unit's continuous model; a one-step map is at one H")
    at = units if callable(units) else lambda h: units

    def stable(h: float) -> tuple[bool, tuple[float, float]]:
        rho, err = signal_radius(at(h), connections, k, h, scheme, implicit=implicit)
        return bool(rho + err < 1), (rho, err)

    scan = np.geomspace(H * 10.0**-decades, H * 10.0**decades, int(round(2 * decades * per_decade)) + 1)
    return stability_limit(stable, scan, resolution=resolution)
