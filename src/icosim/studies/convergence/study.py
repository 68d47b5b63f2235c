"""The runs of one convergence curve over all step sizes.

Stepping
--------
For the linear model one macro step is a fixed linear map of the packed state
``w = (x1, v1, x2, v2, e_N, ..., e_N-k)`` (that is how :mod:`icosim.studies.stability`
obtains the amplification matrix, from the very macro-step algorithm).

* ``stepping="error"`` (default) propagates the *error* ``w_N - w*_N`` itself,
  driven by the one-step defect formed in ball arithmetic
  (:mod:`icosim.studies.convergence.errors`): its relative accuracy does not depend on
  its size, so there is no round-off floor (NRMSE down to 1e-22 and below).
* ``stepping="matrix"`` iterates the float64 matrix on the state and subtracts
  the exact solution: a floor near NRMSE ~ 1e-11 (kept to show it).
* ``stepping="simulate"`` runs :func:`icosim.engine.run.simulate` (float64, the
  same floor, ~100x slower).

All three agree up to their round-off (tested, and the error path against
40-digit mpmath time stepping).  The linear map is what makes 10^6-step runs
affordable.

Unstable runs
-------------
A run counts as unstable when (a) its state stops being finite or grows beyond
``growth_bound`` times the initial amplitude (the run is stopped there), or (b)
the spectral radius of the recurrence at that ``H`` exceeds 1, decided with the
engine's precision policy (:func:`icosim.problems.linear.spectral.spectral_radius`, float64
with mpmath rechecks).  (b) catches runs that grow too slowly to blow up within
the end time: their error would otherwise look small.  The NRMSE of an
unstable run is never reported as an error (``nrmse`` is NaN there; the value
of a finished run is kept separately as ``nrmse_unfiltered``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ...engine.decompositions import get_decomposition
from ...engine.run import simulate
from ...engine.schemes import JACOBI, get_scheme
from ...engine.stages import check
from ...errors import ParameterError
from ...problems.linear import exact
from ...problems.linear.problem import LinearCosimulation
from ...problems.linear.spectral import amplification_matrix, spectral_radius
from .errors import ErrorSeries, error_recurrences, local_defects
from .experiment import Setup, dimensional_method
from .metric import ratio_root, variances

#: How a curve's errors are computed (module docstring).
STEPPINGS = ("error", "matrix", "simulate")
#: Times per piece of the exact reference (:meth:`Study.reference`).
REFERENCE_CHUNK = 16384

__all__ = ["Study", "CurveResult", "iterate_linear_map"]


# --------------------------------------------------------------------------- stepping
def iterate_linear_map(M, w0, n_steps: int, *, bound: float | None = None, block: int = 256):
    """``w_n = M^n w0`` for ``n = 0 ... n_steps``, stopping where the state diverges.

    Blocks of ``block`` steps are formed at once from the powers
    ``M^0 ... M^(block-1)`` (vectorised), the block start advances by
    ``M^block``.  Divergence is judged like :func:`icosim.engine.run.simulate`:
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


def _midpoint(cert) -> float:
    """A float within the proven enclosure of the spectral radius (its lower end if unbounded above)."""
    return float(cert.rho_lower if cert.rho_upper is None else (cert.rho_lower + cert.rho_upper) / 2)


def _eq72_sums(t, H, lam):
    """Sums of squared errors in the engine's columns (x1, v1_bar, x2, v2_bar, e_N) in Eq. (72)'s order
    (x1, x2, v1, v2), physical units (``v = v_bar / H``, applied to the sums), and the multiplier's sum."""
    return np.array([t[0], t[2], t[1] / H**2, t[3] / H**2]), (t[4 + lam] if lam is not None else None)


# --------------------------------------------------------------------------- one curve
@dataclass
class CurveResult:
    """One convergence curve: per ``H`` the NRMSE, stability and run status."""

    H: np.ndarray
    n_steps: np.ndarray
    nrmse: np.ndarray  # NaN where unstable
    nrmse_unfiltered: np.ndarray  # as computed for every run that finished
    nrmse_second_half: np.ndarray  # Eq. (72) over T_N in (T/2, T], NaN where unstable
    nrmse_startup: np.ndarray  # the first `startup_steps` terms of Eq. (72)'s sums (whole-run denominators)
    nrmse_x: np.ndarray  # the position terms (x1, x2) of Eq. (72), NaN where unstable
    nrmse_v: np.ndarray  # the velocity terms (v1, v2), NaN where unstable
    nrmse_lambda: np.ndarray  # the constraint force lambda_c (ff, fd; NaN for dd or unstable)
    spectral_radius: np.ndarray
    spectral_radius_digits: np.ndarray
    spectral_verdict: np.ndarray  # stable / unstable / marginal (certified for stepping "error")
    diverged_at: np.ndarray  # first diverged step, -1 if none
    unstable: np.ndarray
    defect_bits: np.ndarray  # Arb precision that proved the defect (stepping "error"; 0 otherwise)
    seconds: float = 0.0  # wall time of the call that computed it (curves computed together share it)
    meta: dict = field(default_factory=dict)


class Study:
    """Convergence runs of one :class:`Setup` over a fixed list of step counts.

    The exact reference at every ``T_N`` is computed once per ``H`` and shared
    by all curves.
    """

    def __init__(
        self, setup: Setup, n_steps, *, spectral_policy: str = "auto", digits: int = 128, startup_steps: int = 50
    ):
        if isinstance(startup_steps, bool) or int(startup_steps) != startup_steps or startup_steps < 1:
            raise ParameterError(f"startup_steps must be an integer >= 1, got {startup_steps!r}")
        self.startup_steps = int(startup_steps)
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
            solution, ref, lam = self.solution(H), np.empty((N, 4)), np.empty(N)
            # in pieces that stay in the cache (each time on its own: the same values as at once)
            for start in range(0, N, REFERENCE_CHUNK):
                st = solution.state(np.arange(start + 1, min(start + REFERENCE_CHUNK, N) + 1, dtype=float))
                x, v = st[:, 0], st[:, 1] / H
                ref[start : start + len(st)] = np.stack([x, x, v, v], axis=-1)
                lam[start : start + len(st)] = st[:, 3]
            self._references[i] = (ref, lam)
        return self._references[i]

    def _variances(self, i):
        """Eq. (72)'s denominators for ``H[i]``: whole run, second half, and the multiplier."""
        key = ("variances", i)
        if key not in self._references:
            ref, N = self.reference(i), int(self.n_steps[i])
            self._references[key] = (
                variances(ref),
                variances(ref[N // 2 :]),
                variances(self.reference_multiplier(i)[:, None])[0],
            )
        return self._references[key]

    def _exact_max(self, i):
        """The largest ``|x|`` and ``|v_bar| = H |v|`` of the exact solution at ``T_1 ... T_N`` for ``H[i]``."""
        key = ("exact_max", i)
        if key not in self._references:
            ref, H = self.reference(i), self.H[i]
            self._references[key] = float(max(np.max(np.abs(ref[:, 0])), H * np.max(np.abs(ref[:, 2]))))
        return self._references[key]

    def bound(self, H):
        s = self.setup
        return s.growth_bound * max(abs(s.x0), abs(s.v0) * H)

    # -- curves ------------------------------------------------------------------------
    def run(
        self, method: str, params: dict, decomposition: str, k: int, *, stepping: str = "error", scheme=JACOBI
    ) -> CurveResult:
        """NRMSE over all step sizes for one scheme (dimensional ``params``; ``scheme``: Jacobi or Gauss-Seidel)."""
        return self.run_curves(method, [params], decomposition, k, stepping=stepping, scheme=scheme)[0]

    def run_curves(
        self, method: str, rows, decomposition: str, k: int, *, stepping: str = "error", scheme=JACOBI
    ) -> list[CurveResult]:
        """:meth:`run` of every parameter set of ``rows`` (e.g. the rows of a panel), in that order.

        With stepping "error" the error recurrences of every curve and step size are stepped together:
        each product of a stacked step is the one of a curve alone, so these are the numbers of :meth:`run`.
        """
        if stepping not in STEPPINGS:
            raise ParameterError(f"stepping must be one of {', '.join(STEPPINGS)}, got {stepping!r}")
        scheme = get_scheme(scheme)
        dec = get_decomposition(decomposition)
        t0 = time.perf_counter()
        curves = []
        for params in rows:
            methods = [dimensional_method(method, H, **params) for H in self.H]
            methods[0].check_decomposition(dec)
            curves.append(methods)
        check(scheme, dec)
        nH = self.H.size
        if stepping == "error":  # every curve's and step size's recurrence stepped together
            runs = self._floor_free_curves(curves, dec.name, k, range(nH), scheme)
        else:
            runs = [None] * len(curves)
        out = []
        for params, methods, curve_runs in zip(rows, curves, runs):
            result = self._curve(methods, dec, k, stepping, scheme, curve_runs)
            result.meta = {
                "method": method,
                "decomposition": dec.name,
                "k": int(k),
                "stepping": stepping,
                "scheme": scheme.name,
                **params,
            }
            out.append(result)
        seconds = time.perf_counter() - t0
        for result in out:
            result.seconds = seconds
        return out

    def _curve(self, methods, dec, k, stepping, scheme, runs) -> CurveResult:
        """One curve from its methods per ``H`` (and, for stepping "error", its :meth:`_floor_free` runs)."""
        nH = self.H.size
        if stepping == "error":  # certified from the ball matrices of the defects, in the loop below
            rho, digits = np.full(nH, np.nan), np.zeros(nH, dtype=int)
            verdict = np.full(nH, "", dtype=object)
        else:
            rho, digits, verdict = self._spectral_radii(methods, dec.name, k, scheme)
        names = ("nrmse_unfiltered", "nrmse_second_half", "nrmse_startup", "nrmse_x", "nrmse_v", "nrmse_lambda")
        out = {name: np.full(nH, np.nan) for name in names}
        out["diverged_at"] = np.full(nH, -1, dtype=np.int64)
        out["defect_bits"] = np.zeros(nH, dtype=np.int32)
        # the constraint force is a coupling variable with ff and fd only
        lam = dec.variables.index("lambda_c") if "lambda_c" in dec.variables else None
        for i, (H, N) in enumerate(zip(self.H, self.n_steps)):
            if stepping == "error":
                errors, diverged, bits, cert = runs[i]
            else:
                errors, diverged, bits, cert = self._errors(methods[i], dec.name, k, i, stepping, scheme)
            out["defect_bits"][i] = bits
            if cert is not None:
                rho[i], digits[i], verdict[i] = _midpoint(cert), int(cert.bits * np.log10(2)), cert.verdict
            if diverged is not None:
                out["diverged_at"][i] = diverged
                continue
            # Eq. (72) and its parts from sums of squared errors at T_1 ... T_N (metric.nrmse_of_errors without
            # a pass per part over 10^6 steps)
            columns = slice(0, 4 + (0 if lam is None else lam + 1))
            with np.errstate(over="ignore", invalid="ignore"):
                total, lam_total = _eq72_sums(errors.sum_squares(columns, 1), H, lam)
                startup, _ = _eq72_sums(errors.sum_squares(columns, 1, self.startup_steps), H, lam)
                half, _ = _eq72_sums(errors.sum_squares(columns, int(N) // 2 + 1), H, lam)  # T_N in (T/2, T]
            var, var_half, var_lam = self._variances(i)
            out["nrmse_unfiltered"][i] = ratio_root(total, var)
            out["nrmse_x"][i] = ratio_root(total[:2], var[:2])
            out["nrmse_v"][i] = ratio_root(total[2:], var[2:])
            out["nrmse_startup"][i] = ratio_root(startup, var)
            out["nrmse_second_half"][i] = ratio_root(half, var_half)
            if lam is not None:  # Eq. (72)'s measure is scale-free: lambda_bar needs no conversion
                out["nrmse_lambda"][i] = ratio_root(lam_total, var_lam)
        # diverged, or the spectral radius proven (or, for the float64 steppings, computed) above 1
        unstable = (out["diverged_at"] >= 0) | ~np.isfinite(out["nrmse_unfiltered"]) | (verdict == "unstable")
        filtered = {name: np.where(unstable, np.nan, out[name]) for name in names[1:]}
        return CurveResult(
            H=self.H.copy(),
            n_steps=self.n_steps.copy(),
            nrmse=np.where(unstable, np.nan, out["nrmse_unfiltered"]),
            nrmse_unfiltered=out["nrmse_unfiltered"],
            **filtered,
            spectral_radius=rho,
            spectral_radius_digits=digits,
            spectral_verdict=verdict.astype(str),
            diverged_at=out["diverged_at"],
            unstable=unstable,
            defect_bits=out["defect_bits"],
        )

    def _spectral_radii(self, methods, decomposition, k, scheme=JACOBI):
        """Spectral radius, digits and verdict per H with the precision policy (the float64 steppings)."""
        models = self.setup.model(self.H)  # physical: overdamped subsystems are fine
        kw = {"digits": self.digits, "policy": self.spectral_policy, "scheme": scheme}
        if all(m.params == methods[0].params for m in methods):  # one batched call
            res = spectral_radius(models, methods[0], decomposition, k, **kw)
            return np.asarray(res.rho, float), np.asarray(res.digits), np.asarray(res.verdict, dtype=object)
        rho, digits = np.empty(self.H.size), np.empty(self.H.size, dtype=int)
        verdict = np.empty(self.H.size, dtype=object)
        for i, m in enumerate(methods):
            res = spectral_radius(self.setup.model(self.H[i]), m, decomposition, k, **kw)
            rho[i], digits[i], verdict[i] = float(res.rho), int(res.digits), str(res.verdict)
        return rho, digits, verdict

    def _exact_z(self, i, A, steps):
        """The exact ``z = (x, v_bar)`` at the steps ``steps`` (an arange) for ``H[i]`` from the rounded ``A``
        of a defect (the same for every curve at that step size: kept per ``A``)."""
        key = ("z", i, A.tobytes(), int(steps[0]), int(steps[-1]) if steps.size else -1, steps.size)
        if key not in self._references:
            z0 = np.array([self.setup.x0, self.setup.v0 * self.H[i]])
            self._references[key] = exact.expm_2x2(A, steps) @ z0
        return self._references[key]

    def _floor_free(self, methods, decomposition, k, indices, scheme=JACOBI):
        """``_errors`` of stepping "error" for the step sizes ``H[indices]`` (``methods[i]`` the method at
        ``H[i]``), their error recurrences stepped together (:func:`~icosim.studies.convergence.errors.error_recurrences`)."""
        return self._floor_free_curves([methods], decomposition, k, indices, scheme)[0]

    def _floor_free_curves(self, curves, decomposition, k, indices, scheme=JACOBI):
        """:meth:`_floor_free` of several curves (each a ``methods``), every recurrence stepped together."""
        indices = list(indices)
        coefficients = [self.setup.model(self.H[i]).coefficients() for i in indices]
        defects, runs = [], []
        for methods in curves:
            curve = local_defects(coefficients, [methods[i] for i in indices], decomposition, k, scheme=scheme)
            defects += curve
            runs += [
                (d.M, d.D, d.E, lambda steps, i=i, A=d.A: self._exact_z(i, A, steps), int(self.n_steps[i]))
                for i, d in zip(indices, curve)
            ]
        out = self._checked_runs(indices * len(curves), defects, error_recurrences(runs))
        return [out[c * len(indices) : (c + 1) * len(indices)] for c in range(len(curves))]

    def _checked_runs(self, indices, defects, recurrences):
        """Per run ``(errors, diverged_at, defect_bits, certificate)``: its errors, or the first step its
        state left the growth bound."""
        out = []
        for i, d, errors in zip(indices, defects, recurrences):
            # the state itself (exact + error, engine units) against the growth bound, as the other steppings;
            # step by step only where a bound of the errors and the largest exact value together could cross it
            H = self.H[i]
            bound, exact_max = self.bound(H), self._exact_max(i)
            err_max = errors.max_abs_bound(slice(0, 4))
            if not (np.isfinite(err_max) and err_max + exact_max <= bound):
                ref, scale = self.reference(i), np.array([1.0, H, 1.0, H])

                def exact_state(steps, ref=ref, scale=scale):  # (x, v_bar, x, v_bar) at T_steps, engine units
                    return ref[steps - 1][:, [0, 2, 0, 2]] * scale

                diverged = errors.first_step_beyond(exact_state, bound, slice(0, 4), exact_max=exact_max)
                if diverged is not None:
                    out.append((None, diverged, d.bits, d.certificate))
                    continue
            out.append((errors, None, d.bits, d.certificate))
        return out

    def _errors(self, method, decomposition, k, i, stepping, scheme=JACOBI):
        """``(errors, diverged_at, defect_bits, certificate)`` for step size ``H[i]`` under ``scheme``.

        ``errors`` (an :class:`~icosim.studies.convergence.errors.ErrorSeries`) holds
        ``w_N - w*_N`` at ``T_0 ... T_N_total`` in the engine's variables
        ``(x1, v1_bar, x2, v2_bar, e_N, ...)`` (``e_N`` the corrected coupling
        variables at ``T_N``, dimensionless like the engine's; the floor-free
        stepping keeps the history of ``e`` as further columns), or is None
        with the first step whose state left the growth bound or was not
        finite.
        """
        H, N = self.H[i], int(self.n_steps[i])
        c = self.setup.model(H).coefficients()
        bound = self.bound(H)
        if stepping == "error":
            methods = {i: method}
            return self._floor_free(methods, decomposition, k, [i], scheme)[0]
        problem = LinearCosimulation(c, decomposition, k)
        solution = self.solution(H)
        state, history = exact.consistent_start(problem, solution)
        if stepping == "simulate":
            traj = simulate(problem, method, state, history, N, bound=bound, scheme=scheme)
            if traj.diverged_at is not None:
                return None, traj.diverged_at, 0, None
            states = np.array(traj.states).reshape(N + 1, 4)
            W = np.concatenate([states, np.array(traj.coupling).reshape(N + 1, -1)], axis=-1)
        else:
            M = amplification_matrix(c, method, decomposition, k, scheme=scheme)
            W, diverged = iterate_linear_map(M, problem.pack(state, history), N, bound=bound)
            if diverged is not None:
                return None, diverged, 0, None
        W = W[:, : 4 + problem.n_coupling]
        # the exact solution in the same variables, subtracted: the round-off floor of these steppings
        st = solution.state(np.arange(N + 1, dtype=float))
        exact_w = np.stack([st[:, 0], st[:, 1], st[:, 0], st[:, 1]], axis=-1)
        cols = [exact.exact_coupling(n, c, st[:, 0], st[:, 1], st[:, 2]) for n in problem.decomposition.variables]
        exact_w = np.concatenate([exact_w, np.stack(cols, axis=-1)], axis=-1)
        return ErrorSeries.from_array(W - exact_w), None, 0, None
