"""The runs of one convergence curve over all step sizes.

Stepping
--------
For the linear model one macro step is a fixed linear map of the packed state
``w = (x1, v1, x2, v2, e_N, ..., e_N-k)`` (that is how :mod:`icosim.stability`
obtains the amplification matrix, from the very macro-step algorithm).  The
default ``stepping="matrix"`` builds that matrix once per ``(H, scheme)`` and
iterates it (vectorised in blocks of powers); ``stepping="simulate"`` runs
:func:`icosim.macrostep.simulate`.  Both give the same numbers up to round-off
(tested); the matrix path is what makes 10^5-step runs affordable.

Unstable runs
-------------
A run counts as unstable when (a) its state stops being finite or grows beyond
``growth_bound`` times the initial amplitude (the run is stopped there), or (b)
the spectral radius of the recurrence at that ``H`` exceeds 1, decided with the
engine's precision policy (:func:`icosim.stability.spectral_radius`, float64
with mpmath rechecks).  (b) catches runs that grow too slowly to blow up within
the end time: their error would otherwise look small.  The NRMSE of an
unstable run is never reported as an error (``nrmse`` is NaN there; the value
of a finished run is kept separately as ``nrmse_unfiltered``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .. import exact
from ..decompositions import get_decomposition
from ..linear_problem import LinearCosimulation
from ..macrostep import simulate
from ..model import ParameterError
from ..schemes import JACOBI, get_scheme
from ..stability import amplification_matrix, is_stable, spectral_radius
from .experiment import Setup, dimensional_method
from .metric import nrmse

__all__ = ["Study", "CurveResult", "iterate_linear_map"]


# --------------------------------------------------------------------------- stepping
def iterate_linear_map(M, w0, n_steps: int, *, bound: float | None = None, block: int = 256):
    """``w_n = M^n w0`` for ``n = 0 ... n_steps``, stopping where the state diverges.

    Blocks of ``block`` steps are formed at once from the powers
    ``M^0 ... M^(block-1)`` (vectorised), the block start advances by
    ``M^block``.  Divergence is judged like :func:`icosim.macrostep.simulate`:
    the first ``n`` whose first four entries (the subsystem states) are not
    finite or exceed ``bound`` in magnitude.

    Returns
    -------
    W : ``(n_done + 1, len(w0))`` -- the states up to the last good step.
    diverged_at : that first bad step index, or None.
    """
    M = np.asarray(M, dtype=float)
    w = np.asarray(w0, dtype=float)
    n = M.shape[0]
    B = max(1, min(block, n_steps + 1))
    with np.errstate(all="ignore"):
        P = np.empty((B, n, n))
        P[0] = np.eye(n)
        for j in range(1, B):
            P[j] = M @ P[j - 1]
        MB = M @ P[B - 1]
        out = []
        total = n_steps + 1
        for start in range(0, total, B):
            W = (P @ w)[: total - start]
            mag = np.max(np.abs(W[:, :4]), axis=-1)
            bad = ~np.isfinite(mag)
            if bound is not None:
                bad |= mag > bound
            if np.any(bad):
                first = int(np.argmax(bad))
                out.append(W[:first])
                return np.concatenate(out), start + first
            out.append(W)
            w = MB @ w
    return np.concatenate(out), None


# --------------------------------------------------------------------------- one curve
@dataclass
class CurveResult:
    """One convergence curve: per ``H`` the NRMSE, stability and run status."""

    H: np.ndarray
    n_steps: np.ndarray
    nrmse: np.ndarray  # NaN where unstable
    nrmse_unfiltered: np.ndarray  # as computed for every run that finished
    nrmse_second_half: np.ndarray  # Eq. (72) over T_N in (T/2, T], NaN where unstable
    nrmse_x: np.ndarray  # the position terms (x1, x2) of Eq. (72), NaN where unstable
    nrmse_v: np.ndarray  # the velocity terms (v1, v2), NaN where unstable
    nrmse_lambda: np.ndarray  # the constraint force lambda_c (ff, fd; NaN for dd or unstable)
    spectral_radius: np.ndarray
    spectral_radius_digits: np.ndarray
    diverged_at: np.ndarray  # first diverged step, -1 if none
    unstable: np.ndarray
    seconds: float = 0.0
    meta: dict = field(default_factory=dict)


class Study:
    """Convergence runs of one :class:`Setup` over a fixed list of step counts.

    The exact reference at every ``T_N`` is computed once per ``H`` and shared
    by all curves.
    """

    def __init__(self, setup: Setup, n_steps, *, spectral_policy: str = "auto", digits: int = 128):
        self.setup = setup
        self.n_steps = np.asarray(n_steps, dtype=np.int64)
        if self.n_steps.ndim != 1 or self.n_steps.size < 2 or np.any(self.n_steps < 2):
            raise ParameterError("n_steps must list at least two step counts >= 2")
        self.H = setup.end_time / self.n_steps
        self.spectral_policy = spectral_policy
        self.digits = digits
        self._references = {}

    # -- the exact solution ------------------------------------------------------------
    def solution(self, H):
        s = self.setup
        return exact.MonolithicSolution(self.setup.model(H).coefficients(), s.x0, s.v0 * H)

    def reference(self, i):
        """``(x1, x2, v1, v2)`` of the exact solution at ``T_1 ... T_N`` for ``H[i]``."""
        return self._reference(i)[0]

    def reference_multiplier(self, i):
        """The exact constraint force ``lambda_bar = lambda H^2 / m1`` at ``T_1 ... T_N``."""
        return self._reference(i)[1]

    def _reference(self, i):
        if i not in self._references:
            H, N = self.H[i], int(self.n_steps[i])
            st = self.solution(H).state(np.arange(1, N + 1, dtype=float))
            x, v = st[:, 0], st[:, 1] / H
            self._references[i] = (np.stack([x, x, v, v], axis=-1), st[:, 3])
        return self._references[i]

    def bound(self, H):
        s = self.setup
        return s.growth_bound * max(abs(s.x0), abs(s.v0) * H)

    # -- one curve ----------------------------------------------------------------------
    def run(
        self, method: str, params: dict, decomposition: str, k: int, *, stepping: str = "matrix", scheme=JACOBI
    ) -> CurveResult:
        """NRMSE over all step sizes for one scheme (dimensional ``params``; ``scheme``: Jacobi or Gauss-Seidel)."""
        if stepping not in ("matrix", "simulate"):
            raise ParameterError(f"stepping must be 'matrix' or 'simulate', got {stepping!r}")
        scheme = get_scheme(scheme)
        dec = get_decomposition(decomposition)
        t0 = time.perf_counter()
        nH = self.H.size
        methods = [dimensional_method(method, H, **params) for H in self.H]
        methods[0].check_decomposition(dec)
        rho, digits = self._spectral_radii(methods, dec.name, k, scheme)
        out = {
            name: np.full(nH, np.nan)
            for name in ("nrmse_unfiltered", "nrmse_second_half", "nrmse_x", "nrmse_v", "nrmse_lambda")
        }
        out["diverged_at"] = np.full(nH, -1, dtype=np.int64)
        # the constraint force is a coupling variable (first entry of e_N) with ff and fd only
        lam = dec.variables.index("lambda_c") if "lambda_c" in dec.variables else None
        for i, (H, N) in enumerate(zip(self.H, self.n_steps)):
            traj, diverged = self._states(methods[i], dec.name, k, H, int(N), stepping, scheme)
            if diverged is not None:
                out["diverged_at"][i] = diverged
                continue
            # engine variables -> physical: x = x_bar, v = v_bar / H; T_1 ... T_N
            num = np.stack([traj[1:, 0], traj[1:, 2], traj[1:, 1] / H, traj[1:, 3] / H], axis=-1)
            ref = self.reference(i)
            out["nrmse_unfiltered"][i] = nrmse(ref, num)
            out["nrmse_x"][i] = nrmse(ref[:, :2], num[:, :2])
            out["nrmse_v"][i] = nrmse(ref[:, 2:], num[:, 2:])
            if lam is not None:  # Eq. (72)'s measure is scale-free: lambda_bar needs no conversion
                out["nrmse_lambda"][i] = nrmse(self.reference_multiplier(i)[:, None], traj[1:, 4 + lam, None])
            half = slice(int(N) // 2, None)  # T_N in (T/2, T]
            out["nrmse_second_half"][i] = nrmse(ref[half], num[half])
        # diverged, or spectral radius above 1 (with the mp allowance of is_stable)
        unstable = (out["diverged_at"] >= 0) | ~np.isfinite(out["nrmse_unfiltered"]) | ~is_stable(rho, digits)
        filtered = np.where(unstable, np.nan, out["nrmse_unfiltered"])
        return CurveResult(
            H=self.H.copy(),
            n_steps=self.n_steps.copy(),
            nrmse=filtered,
            nrmse_unfiltered=out["nrmse_unfiltered"],
            nrmse_second_half=np.where(unstable, np.nan, out["nrmse_second_half"]),
            nrmse_x=np.where(unstable, np.nan, out["nrmse_x"]),
            nrmse_v=np.where(unstable, np.nan, out["nrmse_v"]),
            nrmse_lambda=np.where(unstable, np.nan, out["nrmse_lambda"]),
            spectral_radius=rho,
            spectral_radius_digits=digits,
            diverged_at=out["diverged_at"],
            unstable=unstable,
            seconds=time.perf_counter() - t0,
            meta={
                "method": method,
                "decomposition": dec.name,
                "k": int(k),
                "stepping": stepping,
                "scheme": scheme.name,
                **params,
            },
        )

    def _spectral_radii(self, methods, decomposition, k, scheme=JACOBI):
        """Spectral radius per H (one batched call when the method does not depend on H)."""
        models = self.setup.model(self.H)  # physical: overdamped subsystems are fine
        if all(m.params == methods[0].params for m in methods):
            res = spectral_radius(
                models, methods[0], decomposition, k, digits=self.digits, policy=self.spectral_policy, scheme=scheme
            )
            return np.asarray(res.rho, float), np.asarray(res.digits)
        rho = np.empty(self.H.size)
        digits = np.empty(self.H.size, dtype=int)
        for i, m in enumerate(methods):
            model_i = self.setup.model(self.H[i])
            res = spectral_radius(
                model_i, m, decomposition, k, digits=self.digits, policy=self.spectral_policy, scheme=scheme
            )
            rho[i], digits[i] = float(res.rho), int(res.digits)
        return rho, digits

    def _states(self, method, decomposition, k, H, N, stepping, scheme=JACOBI):
        """``(x1, v1_bar, x2, v2_bar, e_N)`` at ``T_0 ... T_N`` (or diverged).

        ``e_N`` are the corrected coupling variables at ``T_N`` (the newest
        history entry), dimensionless like the engine's.
        """
        c = self.setup.model(H).coefficients()
        problem = LinearCosimulation(c, decomposition, k)
        state, history = exact.consistent_start(problem, self.solution(H))
        bound = self.bound(H)
        if stepping == "simulate":
            traj = simulate(problem, method, state, history, N, bound=bound, scheme=scheme)
            if traj.diverged_at is not None:
                return None, traj.diverged_at
            states = np.array(traj.states).reshape(N + 1, 4)
            return np.concatenate([states, np.array(traj.coupling).reshape(N + 1, -1)], axis=-1), None
        M = amplification_matrix(c, method, decomposition, k, scheme=scheme)
        W, diverged = iterate_linear_map(M, problem.pack(state, history), N, bound=bound)
        return (None, diverged) if diverged is not None else (W[:, : 4 + problem.n_coupling], None)
