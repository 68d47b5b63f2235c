"""Convergence study of Sect. 3.7 (Figs. 21-23): NRMSE of Eq. (72) over macro-step sizes.

The test model is used in physical units (``m1 = 1, m2 = 2, c1 = c2 = 1000,
d1 = d2 = 10`` in the paper) with a dimensional macro step ``H`` in seconds, and
every co-simulation is compared with the exact monolithic solution
(:class:`icosim.exact.MonolithicSolution`) at the macro-time points.

Eq. (72), decision
------------------
The extracted formula is garbled: it shows two brackets, each closed by
``]^{1/2}``, one with the two position terms and one with the two velocity
terms, and only one opening bracket.  We read it as **one** bracket::

    eps_glo = sqrt( sum_j  sum_N (y_j(T_N) - y_j,N)^2 / sum_N (y_j(T_N) - y_j,mean)^2 ),
    y = (x1, x2, v1, v2),   y_j,mean = sum_N y_j(T_N) / N_total,

the sum over ``N = 1 ... N_total`` (``N_total`` macro steps; ``T_0`` carries no
error by construction and the mean is "sum over N divided by N_total").  This
is the normalised root-mean-square error the text describes ("mean of the
squared difference ... divided by the variance of the reference"), summed over
the four variables.  The other reading (separate square roots for positions and
velocities, added) differs by at most a factor ``sqrt(2)`` and cannot change an
order of convergence.  Both readings can be rebuilt from the datasets, which
also store the two partial sums ``nrmse_x`` (x1, x2) and ``nrmse_v`` (v1, v2):
``nrmse = sqrt(nrmse_x^2 + nrmse_v^2)``, the other reading is
``nrmse_x + nrmse_v``.  ``nrmse_lambda`` is the same measure for the constraint
force ``lambda_c`` (ff, fd; the corrected coupling variable at ``T_N`` against
the exact multiplier), the quantity in which the paper warns of index-3
chattering.

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

Order fit
---------
The order is the slope of ``log(nrmse)`` over ``log(H)`` (:func:`scipy.stats.linregress`)
over the *asymptotic range*: the stable points at the small-``H`` end, after
leaving out the round-off floor, see :func:`fit_order`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.stats

from . import exact
from .coupling import get_decomposition, make_method
from .macrostep import macro_step, simulate
from .claims import Outcome, combine_holds, matches, register_check
from .model import ParameterError, PhysicalModel
from .oscillator import LinearCosimulation
from .stability import amplification_matrix, is_stable, spectral_radius

__all__ = [
    "PAPER_MODEL",
    "Setup",
    "CurveResult",
    "OrderFit",
    "nrmse",
    "step_counts",
    "dimensional_method",
    "method_attrs",
    "Study",
    "iterate_linear_map",
    "fit_order",
    "local_slopes",
    "time_macro_steps",
    "step_cost",
    "study_from_config",
    "oscillation_summary",
    "check_convergence_order",
    "check_claims_against_config",
]

#: Physical parameters of the test model in Sect. 3.7.
PAPER_MODEL = {"m1": 1.0, "m2": 2.0, "c1": 1000.0, "c2": 1000.0, "d1": 10.0, "d2": 10.0}

#: Names of the variables compared by Eq. (72), in the order of the last axis.
VARIABLES = ("x1", "x2", "v1", "v2")


# --------------------------------------------------------------------------- Eq. (72)
def nrmse(reference, numerical):
    """Normalised root-mean-square error of Eq. (72) (see the module docstring).

    Parameters
    ----------
    reference, numerical : arrays ``(..., N_total, n_var)``: the samples at
        ``T_1 ... T_N_total`` (axis -2) of each compared variable (axis -1),
        for Eq. (72) ``(x1, x2, v1, v2)``.

    Returns
    -------
    ``sqrt(sum_j sum_N (ref - num)^2 / sum_N (ref - mean_N ref)^2)`` over the
    leading axes; NaN where the numerical values are not finite.
    """
    ref = np.asarray(reference, dtype=float)
    num = np.asarray(numerical, dtype=float)
    if ref.shape != num.shape:
        raise ValueError(f"reference and numerical must have the same shape, got {ref.shape} and {num.shape}")
    if ref.ndim < 2 or ref.shape[-2] < 2:
        raise ValueError("need at least two time samples (axis -2) per variable")
    variance = np.sum((ref - ref.mean(axis=-2, keepdims=True)) ** 2, axis=-2)
    if np.any(variance <= 0):
        raise ValueError("a reference variable is constant: its NRMSE denominator is zero")
    with np.errstate(over="ignore", invalid="ignore"):
        err = np.sqrt(np.sum(np.sum((ref - num) ** 2, axis=-2) / variance, axis=-1))
    return np.where(np.isfinite(err), err, np.nan)


# --------------------------------------------------------------------------- setup
@dataclass(frozen=True)
class Setup:
    """The convergence experiment: physical model, initial conditions, end time.

    ``x0`` (m) and ``v0`` (m/s) are the common initial position and velocity
    of both masses (consistent with the rigid link: ``x1 = x2``, ``v1 = v2``).
    ``growth_bound``: a run whose state exceeds this multiple of the initial
    amplitude is stopped and reported unstable.
    """

    m1: float = PAPER_MODEL["m1"]
    m2: float = PAPER_MODEL["m2"]
    c1: float = PAPER_MODEL["c1"]
    c2: float = PAPER_MODEL["c2"]
    d1: float = PAPER_MODEL["d1"]
    d2: float = PAPER_MODEL["d2"]
    x0: float = 0.1
    v0: float = 0.0
    end_time: float = 1.0
    growth_bound: float = 1.0e3

    def __post_init__(self):
        PhysicalModel(self.m1, self.m2, self.c1, self.c2, self.d1, self.d2, 1.0)  # validates
        for name in ("x0", "v0", "end_time", "growth_bound"):
            if not np.isfinite(getattr(self, name)):
                raise ParameterError(f"{name} must be a finite number, got {getattr(self, name)!r}")
        if self.end_time <= 0:
            raise ParameterError(f"end_time must be > 0, got {self.end_time!r}")
        if self.growth_bound <= 1:
            raise ParameterError(f"growth_bound must be > 1, got {self.growth_bound!r}")
        if self.x0 == 0 and self.v0 == 0:
            raise ParameterError("x0 and v0 are both zero: the exact solution is identically zero")

    def model(self, H) -> PhysicalModel:
        return PhysicalModel(self.m1, self.m2, self.c1, self.c2, self.d1, self.d2, H)

    def as_dict(self) -> dict:
        return {f: getattr(self, f) for f in self.__dataclass_fields__}


def step_counts(end_time: float, H_min: float, H_max: float, num: int) -> np.ndarray:
    """Numbers of macro steps ``N_total`` for ``num`` log-spaced ``H`` in ``[H_min, H_max]``.

    ``H = end_time / N_total`` exactly, so every run ends exactly at the end
    time; ``N_total`` is rounded from the log-spaced sizes (duplicates after
    rounding are dropped).  Returned in increasing order (decreasing ``H``).
    """
    if not (0 < H_min < H_max):
        raise ParameterError(f"need 0 < H_min < H_max, got H_min={H_min!r}, H_max={H_max!r}")
    if H_max > end_time:
        raise ParameterError(f"H_max = {H_max!r} exceeds end_time = {end_time!r}")
    if num < 2:
        raise ParameterError(f"num must be >= 2, got {num!r}")
    n = np.unique(np.round(end_time / np.logspace(np.log10(H_max), np.log10(H_min), num)).astype(np.int64))
    return n[n >= 1]


def study_from_config(cfg: dict, *, where: str = "convergence") -> "Study":
    """The :class:`Study` a convergence configuration describes, validated.

    Cheap (no run): the workflow calls it at parse time so that a bad value
    fails before any job, with a message naming the configuration key
    (``convergence.step_sizes.H_max`` etc.).
    """
    try:
        PhysicalModel(**cfg["model"], H=1.0)
    except ParameterError as exc:
        raise ParameterError(f"{where}.model: {exc}") from None
    ic = cfg["initial_conditions"]
    for name in ("x0", "v0"):
        if not np.isfinite(ic[name]):
            raise ParameterError(f"{where}.initial_conditions.{name} must be a finite number, got {ic[name]!r}")
    if ic["x0"] == 0 and ic["v0"] == 0:
        raise ParameterError(
            f"{where}.initial_conditions: x0 and v0 are both zero, the exact solution is "
            "identically zero and Eq. (72) has no denominator; give x0 or v0 != 0"
        )
    end_time = cfg["end_time"]
    if not (np.isfinite(end_time) and end_time > 0):
        raise ParameterError(f"{where}.end_time must be a finite number > 0, got {end_time!r}")
    growth_bound = cfg["unstable"]["growth_bound"]
    if not (np.isfinite(growth_bound) and growth_bound > 1):
        raise ParameterError(f"{where}.unstable.growth_bound must be a finite number > 1, got {growth_bound!r}")
    setup = Setup(**cfg["model"], **ic, end_time=end_time, growth_bound=growth_bound)
    st = cfg["step_sizes"]
    H_min, H_max, num = st["H_min"], st["H_max"], st["num"]
    if not (0 < H_min < H_max):
        raise ParameterError(f"{where}.step_sizes: need 0 < H_min < H_max, got H_min = {H_min!r}, H_max = {H_max!r}")
    if H_max > end_time / 2:
        raise ParameterError(
            f"{where}.step_sizes.H_max = {H_max!r} must be at most {where}.end_time / 2 = "
            f"{end_time / 2!r} (at least two macro steps per run)"
        )
    if int(num) != num or num < 2:
        raise ParameterError(f"{where}.step_sizes.num must be an integer >= 2, got {num!r}")
    n_steps = step_counts(end_time, H_min, H_max, int(num))
    if n_steps.size < 2:
        raise ParameterError(
            f"{where}.step_sizes: [H_min, H_max] = [{H_min!r}, {H_max!r}] gives only the step "
            f"count(s) {n_steps.tolist()} after rounding N_total = end_time / H; widen the range"
        )
    min_points = cfg.get("fit", {}).get("min_points")
    if min_points is not None and min_points > n_steps.size:
        raise ParameterError(
            f"{where}.fit.min_points = {min_points} exceeds the {n_steps.size} step sizes of "
            f"{where}.step_sizes: no order could ever be fitted"
        )
    return Study(setup, n_steps, spectral_policy=cfg["unstable"]["spectral_policy"], digits=cfg["unstable"]["digits"])


def oscillation_summary(setup: Setup) -> dict:
    """Frequency, decay and number of periods of the exact (rigidly coupled) solution up to the end time.

    The rigid link makes the two masses one: ``M = m1 + m2``, ``C = c1 + c2``,
    ``D = d1 + d2``; decay rate ``delta = D / (2 M)``, damped angular
    frequency ``omega = sqrt(C/M - delta^2)`` (0 if overdamped).
    """
    M, C, D = setup.m1 + setup.m2, setup.c1 + setup.c2, setup.d1 + setup.d2
    delta = D / (2 * M)
    omega2 = C / M - delta**2
    omega = float(np.sqrt(omega2)) if omega2 > 0 else 0.0
    return {
        "omega": omega,
        "delta": delta,
        "periods": omega * setup.end_time / (2 * np.pi),
        "decay": float(np.exp(-delta * setup.end_time)),
        "overdamped": omega2 <= 0,
    }


# --------------------------------------------------------------------------- methods
_DIMENSIONAL = {"mu": 1, "beta": 1, "gamma": 2}  # Baumgarte: seconds to the power given


def dimensional_method(name: str, H: float, **params):
    """The coupling method at macro step ``H`` from dimensional parameters.

    Baumgarte parameters are given in physical units as in Sect. 3.7
    (``mu``, ``beta`` in s, ``gamma`` in s^2; index 1: ``beta = 2 mu``,
    ``gamma = mu^2``) and scaled to the engine's dimensionless ones,
    ``beta_bar = beta / H``, ``gamma_bar = gamma / H^2`` (``mu_bar = mu / H``).
    The weighted-multiplier weights ``a``, ``b`` are dimensionless already.
    """
    params = {k: v for k, v in params.items() if v is not None}
    if name == "baumgarte":
        params = {k: (v / H ** _DIMENSIONAL[k] if k in _DIMENSIONAL else v) for k, v in params.items()}
    return make_method(name, **params)


def method_attrs(name: str, **params) -> dict:
    """Method parameters under their command-line names, dimensional (s, s^2) for Baumgarte."""
    return dict(dimensional_method(name, 1.0, **params).params)


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
    def run(self, method: str, params: dict, decomposition: str, k: int, *, stepping: str = "matrix") -> CurveResult:
        """NRMSE over all step sizes for one scheme (dimensional ``params``)."""
        if stepping not in ("matrix", "simulate"):
            raise ParameterError(f"stepping must be 'matrix' or 'simulate', got {stepping!r}")
        dec = get_decomposition(decomposition)
        t0 = time.perf_counter()
        nH = self.H.size
        methods = [dimensional_method(method, H, **params) for H in self.H]
        methods[0].check_decomposition(dec)
        rho, digits = self._spectral_radii(methods, dec.name, k)
        out = {
            name: np.full(nH, np.nan)
            for name in ("nrmse_unfiltered", "nrmse_second_half", "nrmse_x", "nrmse_v", "nrmse_lambda")
        }
        out["diverged_at"] = np.full(nH, -1, dtype=np.int64)
        # the constraint force is a coupling variable (first entry of e_N) with ff and fd only
        lam = dec.variables.index("lambda_c") if "lambda_c" in dec.variables else None
        for i, (H, N) in enumerate(zip(self.H, self.n_steps)):
            traj, diverged = self._states(methods[i], dec.name, k, H, int(N), stepping)
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
            meta={"method": method, "decomposition": dec.name, "k": int(k), "stepping": stepping, **params},
        )

    def _spectral_radii(self, methods, decomposition, k):
        """Spectral radius per H (one batched call when the method does not depend on H)."""
        models = self.setup.model(self.H)  # physical: overdamped subsystems are fine
        if all(m.params == methods[0].params for m in methods):
            res = spectral_radius(models, methods[0], decomposition, k, digits=self.digits, policy=self.spectral_policy)
            return np.asarray(res.rho, float), np.asarray(res.digits)
        rho = np.empty(self.H.size)
        digits = np.empty(self.H.size, dtype=int)
        for i, m in enumerate(methods):
            model_i = self.setup.model(self.H[i])
            res = spectral_radius(model_i, m, decomposition, k, digits=self.digits, policy=self.spectral_policy)
            rho[i], digits[i] = float(res.rho), int(res.digits)
        return rho, digits

    def _states(self, method, decomposition, k, H, N, stepping):
        """``(x1, v1_bar, x2, v2_bar, e_N)`` at ``T_0 ... T_N`` (or diverged).

        ``e_N`` are the corrected coupling variables at ``T_N`` (the newest
        history entry), dimensionless like the engine's.
        """
        c = self.setup.model(H).coefficients()
        problem = LinearCosimulation(c, decomposition, k)
        state, history = exact.consistent_start(problem, self.solution(H))
        bound = self.bound(H)
        if stepping == "simulate":
            traj = simulate(problem, method, state, history, N, bound=bound)
            if traj.diverged_at is not None:
                return None, traj.diverged_at
            states = np.array(traj.states).reshape(N + 1, 4)
            return np.concatenate([states, np.array(traj.coupling).reshape(N + 1, -1)], axis=-1), None
        M = amplification_matrix(c, method, decomposition, k)
        W, diverged = iterate_linear_map(M, problem.pack(state, history), N, bound=bound)
        return (None, diverged) if diverged is not None else (W[:, : 4 + problem.n_coupling], None)


# --------------------------------------------------------------------------- order fit
@dataclass
class OrderFit:
    """Slope of ``log nrmse`` over ``log H`` and the range it was fitted on."""

    order: float
    stderr: float
    intercept: float
    rvalue: float
    H_min: float
    H_max: float
    n_points: int
    used: np.ndarray  # mask over the input points
    reason: str = ""

    @property
    def ok(self) -> bool:
        return bool(np.isfinite(self.order))


def local_slopes(H, error):
    """Slopes ``d log(error) / d log(H)`` between neighbouring points (sorted by H)."""
    H = np.asarray(H, float)
    e = np.asarray(error, float)
    order = np.argsort(H)
    with np.errstate(all="ignore"):
        return np.diff(np.log(e[order])) / np.diff(np.log(H[order]))


def fit_order(
    H,
    error,
    n_steps=None,
    *,
    min_points: int = 4,
    tolerance: float = 0.25,
    min_order: float = 0.5,
    floor_factor: float = 10.0,
) -> OrderFit:
    """Order of convergence over the asymptotic range, stopping before the round-off floor.

    Procedure (points = finite, positive errors, i.e. stable runs):

    1. Points with ``error < floor_factor * eps * N_total`` are left out: the
       rounding of ``N_total`` float64 steps alone may reach that size.
    2. Starting at the smallest ``H``, take the window of the ``min_points``
       smallest remaining sizes.  It is *consistent* if every local slope in it
       is within ``tolerance`` of the window's least-squares slope, and that
       slope is at least ``min_order`` (an error that no longer decreases with
       ``H`` is the round-off floor, not convergence).  While it is not, drop
       the smallest ``H`` (round-off floor or the end of a transition) and
       retry.
    3. Grow the window toward larger ``H`` one point at a time while it stays
       consistent: the pre-asymptotic range ends where the local slope starts
       to depart from the fitted one.

    The slope of the final window (``scipy.stats.linregress`` of
    ``log error`` on ``log H``) is the order.  If no consistent window of
    ``min_points`` exists the order is NaN and ``reason`` says why.
    """
    H = np.asarray(H, float)
    e = np.asarray(error, float)
    used = np.zeros(H.shape, dtype=bool)
    nan_fit = lambda reason: OrderFit(np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, 0, used, reason)  # noqa: E731
    ok = np.isfinite(e) & (e > 0) & np.isfinite(H) & (H > 0)
    if n_steps is not None:
        floor = floor_factor * np.finfo(float).eps * np.asarray(n_steps, float)
        below = ok & (e < floor)
        ok &= ~below
    if np.sum(ok) < min_points:
        return nan_fit(f"fewer than {min_points} stable points above the round-off floor")
    idx = np.flatnonzero(ok)
    idx = idx[np.argsort(H[idx])]  # ascending H
    logH, loge = np.log(H[idx]), np.log(e[idx])

    def consistent(lo, hi):
        fit = scipy.stats.linregress(logH[lo:hi], loge[lo:hi])
        slopes = np.diff(loge[lo:hi]) / np.diff(logH[lo:hi])
        return fit.slope >= min_order and np.all(np.abs(slopes - fit.slope) <= tolerance), fit

    lo = 0
    while lo + min_points <= idx.size:
        good, fit = consistent(lo, lo + min_points)
        if good:
            break
        lo += 1
    else:
        return nan_fit(f"no {min_points} consecutive stable points with consistent local slopes")
    hi = lo + min_points
    while hi < idx.size:
        good, trial = consistent(lo, hi + 1)
        if not good:
            break
        fit, hi = trial, hi + 1
    sel = idx[lo:hi]
    used[sel] = True
    return OrderFit(
        order=float(fit.slope),
        stderr=float(fit.stderr),
        intercept=float(fit.intercept),
        rvalue=float(fit.rvalue),
        H_min=float(H[sel].min()),
        H_max=float(H[sel].max()),
        n_points=int(sel.size),
        used=used,
    )


# --------------------------------------------------------------------------- timing
def time_macro_steps(
    setup: Setup,
    H: float,
    method: str,
    params: dict,
    decomposition: str,
    k: int,
    *,
    steps: int = 20,
    repeats: int = 3,
    warmup_steps: int = 5,
) -> dict:
    """CPU time of the co-simulation stepping (:func:`icosim.macrostep.simulate`).

    The problem is built once (its set-up, the subsystem propagators, is timed
    separately: it does not grow with the simulated time); after a warm-up of
    ``warmup_steps``, ``repeats`` runs of ``steps`` macro steps each are timed
    with :func:`time.process_time` and the minimum is kept.  Each macro step of
    the linear model costs the same, so the CPU time per simulated second is
    ``seconds_per_step / H``.
    """
    if steps < 1 or repeats < 1 or warmup_steps < 0:
        raise ParameterError("steps and repeats must be >= 1 and warmup_steps >= 0")
    m = dimensional_method(method, H, **params)
    t0 = time.process_time()
    c = setup.model(H).coefficients()
    problem = LinearCosimulation(c, decomposition, k)
    sol = exact.MonolithicSolution(c, setup.x0, setup.v0 * H)
    state, history = exact.consistent_start(problem, sol)
    setup_seconds = time.process_time() - t0
    if warmup_steps:
        simulate(problem, m, state, history, warmup_steps)
    best = np.inf
    for _ in range(repeats):
        t = time.process_time()
        simulate(problem, m, state, history, steps)
        best = min(best, time.process_time() - t)
    per_step = best / steps
    return {
        "seconds_per_step": per_step,
        "seconds_per_simulated_second": per_step / H,
        "setup_seconds": setup_seconds,
    }


def step_cost(method: str, params: dict, decomposition: str, k: int) -> dict:
    """Work of one macro step, counted on the engine's macro step of the linear model.

    ``subsystem_integrations``: calls of a subsystem integrator (predictor and
    corrector of both subsystems: 4); ``coupling_solves``: linear solves of
    coupling conditions (the method's solves with a nonzero weight: 1 for
    Baumgarte and projection, up to 3 for the weighted multiplier);
    ``projections``: 1 with the projection step.  The sensitivities (Jacobians
    of the coupling conditions) are constant for the linear model and not
    counted; with numerically integrated subsystems they cost extra
    integrations (or are reused).  These counts let the work-precision
    comparison be transferred to subsystems whose integration dominates.
    """
    m = dimensional_method(method, 1.0, **params)  # the counts do not depend on H
    problem = LinearCosimulation(Setup().model(1.0e-3).coefficients(), decomposition, k)
    m.check_decomposition(problem.decomposition)
    state = np.zeros((2, 2))
    history = np.zeros((k + 1, problem.n_coupling))
    problem.jacobians(state, history, None, None)  # constant: built once, outside the count
    calls = {"step": 0, "solve": 0, "project": 0}

    def counting(fn, key):
        def wrapped(*args, **kwargs):
            calls[key] += 1
            return fn(*args, **kwargs)

        return wrapped

    for sub in problem.subsystems:
        sub.step = counting(sub.step, "step")
    problem.project = counting(problem.project, "project")
    macro_step(problem, m, state, history)
    return {
        "subsystem_integrations": calls["step"],
        "coupling_solves": sum(1 for weight, _ in m.solves if weight != 0),
        "projections": calls["project"],
    }


# --------------------------------------------------------------------------- panels
#: Parameters a method does not use at a given index (dropped from a row's parameters).
_UNUSED_AT_INDEX = {("baumgarte", 3): {"mu", "beta", "gamma"}, ("weighted", 2): {"b"}, ("weighted", 3): {"a", "b"}}
#: Parameters that are coordinates along ``index`` in a panel dataset, per method.
ROW_COORDS = {"baumgarte": ("beta", "gamma"), "weighted": ("a", "b"), "projection": ()}
#: Units of the dimensional method parameters.
PARAM_UNITS = {"mu": "s", "beta": "s", "gamma": "s2", "a": "1", "b": "1", "index": "1"}


def effective_params(method: str, column: dict, row: dict) -> dict:
    """A curve's method parameters: the column's and the row's, minus those its index does not use.

    (Baumgarte at index 3 has no ``mu``; the weighted multiplier at index 2
    has ``b = 0``, at index 3 ``a = b = 0``.)  Raises :class:`ParameterError`
    naming the parameter if the method rejects the combination.
    """
    merged = {**column, **row}
    index = merged.get("index")
    for name in _UNUSED_AT_INDEX.get((method, index), ()):
        merged.pop(name, None)
    dimensional_method(method, 1.0, **merged)  # validates (message names the parameter)
    return merged


def panel_name(params: dict) -> str:
    """File-name part for a set of parameters, e.g. ``mu0.005``, ``a0.5_b0.25``, ``index3``."""
    return "_".join(f"{k}{v:g}" for k, v in params.items()) or "all"


@dataclass(frozen=True)
class PanelSpec:
    """One dataset: the curves (rows x k) of one figure column and decomposition.

    Rows whose parameters do not depend on the column (Baumgarte index 3 in
    Fig. 21: no ``mu``) form one *shared* panel per figure and decomposition,
    drawn in every column, so each distinct curve is computed once.
    """

    figure: str
    decomposition: str
    panel: str
    method: str
    column: dict
    rows: tuple  # effective parameters of each row (dicts)
    k: tuple
    shared: bool = False

    def as_dict(self) -> dict:
        return {
            "figure": self.figure,
            "decomposition": self.decomposition,
            "panel": self.panel,
            "method": self.method,
            "column": dict(self.column),
            "rows": [dict(r) for r in self.rows],
            "k": list(self.k),
            "shared": self.shared,
        }

    @classmethod
    def from_dict(cls, d: dict) -> "PanelSpec":
        return cls(
            d["figure"],
            d["decomposition"],
            d["panel"],
            d["method"],
            dict(d["column"]),
            tuple(dict(r) for r in d["rows"]),
            tuple(d["k"]),
            bool(d.get("shared", False)),
        )

    @property
    def indices(self) -> list:
        return [int(dimensional_method(self.method, 1.0, **r).params["index"]) for r in self.rows]


def figure_panels(figure: str, fig_cfg: dict, k) -> list:
    """All panel specs of one configured figure (every decomposition and column).

    ``fig_cfg`` has ``method``, ``columns`` (list of parameter dicts),
    ``rows`` (list of parameter dicts, usually ``{index: i}``) and
    ``decompositions``.  Where each cell of a figure is stored: :func:`figure_layout`.
    """
    method = fig_cfg["method"]
    columns, rows = fig_cfg["columns"], fig_cfg["rows"]
    where = f"figure {figure}"
    try:
        cells = [[effective_params(method, c, r) for r in rows] for c in columns]
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None
    shared_rows = [
        j for j in range(len(rows)) if len(columns) > 1 and all(cells[i][j] == cells[0][j] for i in range(len(columns)))
    ]
    specs = []
    for dec in fig_cfg["decompositions"]:
        try:
            dimensional_method(method, 1.0, **cells[0][0]).check_decomposition(get_decomposition(dec))
        except ParameterError as exc:
            raise ParameterError(f"{where}, decomposition {dec!r}: {exc}") from None
        for i, c in enumerate(columns):
            own = tuple(cells[i][j] for j in range(len(rows)) if j not in shared_rows)
            if own:
                specs.append(PanelSpec(figure, dec, panel_name(c), method, dict(c), own, tuple(k)))
        if shared_rows:
            shared = tuple(cells[0][j] for j in shared_rows)
            name = "_".join(panel_name({"index": r.get("index")}) for r in shared)
            specs.append(PanelSpec(figure, dec, name, method, {}, shared, tuple(k), shared=True))
    for spec in specs:
        idx = spec.indices
        if len(set(idx)) != len(idx):
            raise ParameterError(f"{where}: rows of panel {spec.panel} must have distinct index, got {idx}")
    return specs


def figure_layout(figure: str, fig_cfg: dict, decomposition: str, k) -> list:
    """``[[(panel, index), ...] per column]``: where each cell's curves are stored."""
    specs = {s.panel: s for s in figure_panels(figure, fig_cfg, k) if s.decomposition == decomposition}
    method = fig_cfg["method"]
    layout = []
    for c in fig_cfg["columns"]:
        col = []
        for r in fig_cfg["rows"]:
            eff = effective_params(method, c, r)
            for s in specs.values():
                if eff in s.rows:
                    col.append((s.panel, s.indices[s.rows.index(eff)]))
                    break
        layout.append(col)
    return layout


def run_panel(
    spec: PanelSpec, study: Study, fit: dict | None = None, *, stepping: str = "matrix", provenance: dict | None = None
):
    """Every curve of a panel as an :class:`xarray.Dataset` (dims ``index``, ``k``, ``H``)."""
    import xarray as xr

    fit = dict(fit or {})
    t0 = time.perf_counter()
    nI, nK, nH = len(spec.rows), len(spec.k), study.H.size
    names_f = (
        "nrmse",
        "nrmse_unfiltered",
        "nrmse_second_half",
        "nrmse_x",
        "nrmse_v",
        "nrmse_lambda",
        "spectral_radius",
    )
    arr = {n: np.full((nI, nK, nH), np.nan) for n in names_f}
    arr["spectral_radius_digits"] = np.zeros((nI, nK, nH), dtype=np.int32)
    arr["diverged_at"] = np.full((nI, nK, nH), -1, dtype=np.int64)
    arr["unstable"] = np.zeros((nI, nK, nH), dtype=bool)
    arr["fit_used"] = np.zeros((nI, nK, nH), dtype=bool)
    fits = {
        n: np.full((nI, nK), np.nan)
        for n in ("order", "order_stderr", "order_rvalue", "fit_H_min", "fit_H_max", "order_second_half")
    }
    fit_n = np.zeros((nI, nK), dtype=np.int32)
    fit_note = np.full((nI, nK), "", dtype=object)
    for i, row in enumerate(spec.rows):
        for j, k in enumerate(spec.k):
            r = study.run(spec.method, row, spec.decomposition, k, stepping=stepping)
            for n in names_f + ("spectral_radius_digits", "diverged_at", "unstable"):
                arr[n][i, j] = getattr(r, n)
            f = fit_order(r.H, r.nrmse, r.n_steps, **fit)
            f2 = fit_order(r.H, r.nrmse_second_half, r.n_steps, **fit)
            arr["fit_used"][i, j] = f.used
            fits["order"][i, j], fits["order_stderr"][i, j], fits["order_rvalue"][i, j] = f.order, f.stderr, f.rvalue
            fits["fit_H_min"][i, j], fits["fit_H_max"][i, j] = f.H_min, f.H_max
            fits["order_second_half"][i, j] = f2.order
            fit_n[i, j] = f.n_points
            fit_note[i, j] = f.reason
    dims3, dims2 = ("index", "k", "H"), ("index", "k")
    H_attrs = {"long_name": "macro-step size", "units": "s"}
    ds = xr.Dataset(
        {
            "nrmse": (
                dims3,
                arr["nrmse"],
                {"long_name": "normalised root-mean-square error of Eq. (72) (NaN where unstable)", "units": "1"},
            ),
            "nrmse_unfiltered": (
                dims3,
                arr["nrmse_unfiltered"],
                {"long_name": "Eq. (72) of every run that finished, unstable ones included", "units": "1"},
            ),
            "nrmse_second_half": (
                dims3,
                arr["nrmse_second_half"],
                {"long_name": "Eq. (72) over T_N in (T/2, T] (diagnostic: no start-up transient)", "units": "1"},
            ),
            "nrmse_x": (
                dims3,
                arr["nrmse_x"],
                {
                    "long_name": "position part of Eq. (72): sqrt of the sum of the x1 and x2 ratios (NaN where unstable)",
                    "units": "1",
                    "comment": "nrmse = sqrt(nrmse_x^2 + nrmse_v^2); the other reading of the garbled Eq. (72) is nrmse_x + nrmse_v",
                },
            ),
            "nrmse_v": (
                dims3,
                arr["nrmse_v"],
                {
                    "long_name": "velocity part of Eq. (72): sqrt of the sum of the v1 and v2 ratios (NaN where unstable)",
                    "units": "1",
                },
            ),
            "nrmse_lambda": (
                dims3,
                arr["nrmse_lambda"],
                {
                    "long_name": "Eq. (72)'s measure for the constraint force lambda_c (corrected coupling variable at T_N) against the exact multiplier (NaN where unstable, and for dd: no multiplier among the coupling variables)",
                    "units": "1",
                },
            ),
            "unstable": (
                dims3,
                arr["unstable"],
                {"long_name": "run unstable: diverged, or spectral radius above 1 at this H"},
            ),
            "spectral_radius": (
                dims3,
                arr["spectral_radius"],
                {"long_name": "spectral radius of the co-simulation recurrence at this H", "units": "1"},
            ),
            "spectral_radius_digits": (
                dims3,
                arr["spectral_radius_digits"],
                {"long_name": "significant digits that decided the spectral radius (15: float64)"},
            ),
            "diverged_at": (
                dims3,
                arr["diverged_at"],
                {"long_name": "first macro step that left the growth bound or was not finite (-1: none)"},
            ),
            "fit_used": (dims3, arr["fit_used"], {"long_name": "point used in the order fit (the asymptotic range)"}),
            "order": (
                dims2,
                fits["order"],
                {"long_name": "fitted order of convergence of nrmse over the asymptotic range", "units": "1"},
            ),
            "order_stderr": (
                dims2,
                fits["order_stderr"],
                {"long_name": "standard error of the fitted order", "units": "1"},
            ),
            "order_rvalue": (
                dims2,
                fits["order_rvalue"],
                {"long_name": "correlation coefficient of the order fit", "units": "1"},
            ),
            "fit_H_min": (dims2, fits["fit_H_min"], {"long_name": "smallest H of the fitted range", "units": "s"}),
            "fit_H_max": (dims2, fits["fit_H_max"], {"long_name": "largest H of the fitted range", "units": "s"}),
            "fit_n_points": (dims2, fit_n, {"long_name": "number of step sizes in the fitted range"}),
            "fit_note": (dims2, fit_note.astype(str), {"long_name": "why no order was fitted (empty if fitted)"}),
            "order_second_half": (
                dims2,
                fits["order_second_half"],
                {"long_name": "fitted order of nrmse_second_half", "units": "1"},
            ),
        },
        coords={
            "H": ("H", study.H, H_attrs),
            "n_steps": ("H", study.n_steps, {"long_name": "number of macro steps N_total = end_time / H"}),
            "index": (
                "index",
                np.array(spec.indices, dtype=np.int32),
                {"long_name": "index of the coupling formulation"},
            ),
            "k": ("k", np.array(spec.k, dtype=np.int32), {"long_name": "degree of the approximation polynomials"}),
        },
    )
    # row parameters (dimensional) as coordinates along index
    for name in ROW_COORDS[spec.method]:
        vals = [dimensional_method(spec.method, 1.0, **r).params.get(name, np.nan) for r in spec.rows]
        ds = ds.assign_coords({name: ("index", np.array(vals, dtype=float), {"units": PARAM_UNITS[name]})})
    s = study.setup
    attrs = dict(provenance or {})
    attrs.update(
        figure=spec.figure,
        method=spec.method,
        decomposition=spec.decomposition,
        decomposition_long_name=get_decomposition(spec.decomposition).long_name,
        panel=spec.panel,
        shared_across_columns=int(spec.shared),
        **{name: float(v) for name, v in spec.column.items() if name != "index"},
        **{f"model_{n}": float(getattr(s, n)) for n in PAPER_MODEL},
        x0=s.x0,
        v0=s.v0,
        end_time=s.end_time,
        growth_bound=s.growth_bound,
        initial_conditions=f"x1 = x2 = {s.x0:g} m, v1 = v2 = {s.v0:g} m/s at t = 0 (consistent with the rigid link)",
        history_initialisation="coupling variables at T_0, T_-1, ..., T_-k from the exact monolithic solution "
        "(icosim.exact.consistent_start)",
        nrmse_definition="Eq. (72) read as sqrt of the sum of the four normalised squared-error ratios "
        "(x1, x2, v1, v2), sums over N = 1..N_total; nrmse_x, nrmse_v hold the position and velocity parts "
        "(nrmse^2 = nrmse_x^2 + nrmse_v^2)",
        method_parameters_units="dimensional: mu and beta in s, gamma in s^2 (Baumgarte, Sect. 3.7); "
        "a, b dimensionless; the engine uses beta_bar = beta/H, gamma_bar = gamma/H^2",
        stepping=stepping,
        spectral_policy=study.spectral_policy,
        fit_procedure="icosim.convergence.fit_order: " + ", ".join(f"{k}={v}" for k, v in sorted(fit.items())),
        seconds_total=time.perf_counter() - t0,
    )
    ds.attrs = attrs
    return ds


# --------------------------------------------------------------------------- curves and claims
def curves(datasets) -> list:
    """Flatten panel datasets into one record per curve (dict)."""
    out = []
    for ds in datasets:
        for i, index in enumerate(ds["index"].values):
            for j, k in enumerate(ds["k"].values):
                rec = {
                    "figure": str(ds.attrs["figure"]),
                    "decomposition": ds.attrs["decomposition"],
                    "method": ds.attrs["method"],
                    "panel": ds.attrs["panel"],
                    "index": int(index),
                    "k": int(k),
                }
                for name in ("mu", "a", "b", "beta", "gamma"):
                    if name in ds.coords:
                        rec[name] = float(ds[name].values[i])
                    elif name in ds.attrs:
                        rec[name] = float(ds.attrs[name])
                for name in ("order", "order_stderr", "fit_H_min", "fit_H_max", "order_second_half"):
                    rec[name] = float(ds[name].values[i, j])
                rec["fit_n_points"] = int(ds["fit_n_points"].values[i, j])
                rec["H"] = ds["H"].values
                rec["nrmse"] = ds["nrmse"].values[i, j]
                rec["unstable"] = ds["unstable"].values[i, j].astype(bool)
                out.append(rec)
    return out


def curve_label(rec) -> str:
    parts = [rec["decomposition"], rec["method"]]
    if rec["method"] != "projection":
        parts.append(f"index {rec['index']}")
    for name in ("mu", "a", "b"):
        if (
            name in rec
            and np.isfinite(rec[name])
            and not (rec["method"] == "weighted" and rec["index"] == 2 and name == "b")
        ):
            parts.append(f"{name} = {rec[name]:g}")
    parts.append(f"k = {rec['k']}")
    return ", ".join(parts)


def stable_span(rec) -> str:
    """Human-readable range of H where the curve is stable."""
    H, u = rec["H"], rec["unstable"]
    if u.all():
        return "none"
    if not u.any():
        return "all"
    Hs = H[~u]
    return f"{Hs.min():.2g} to {Hs.max():.2g} s"


#: Keys of a ``convergence_order`` check's ``select`` and of each ``expect`` entry.
SELECT_KEYS = {"figure", "decomposition", "method", "panel", "index", "mu", "a", "b", "beta", "gamma"}
EXPECT_KEYS = {"k", "order", "unstable", "observed", "observed_tolerance", "observed_second_half"}


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x)


def configured_curves(cfg: dict) -> list:
    """The curve records (as :func:`curves` makes from the datasets) a configuration will produce.

    Built from the panel specs without running anything, so that claims can be
    matched against the configuration before any job runs.
    """
    out = []
    for fig, fig_cfg in cfg["figures"].items():
        for spec in figure_panels(str(fig), fig_cfg, cfg["k"]):
            for row, index in zip(spec.rows, spec.indices):
                attrs = method_attrs(spec.method, **row)
                rec = {
                    "figure": spec.figure,
                    "decomposition": spec.decomposition,
                    "method": spec.method,
                    "panel": spec.panel,
                    "index": int(index),
                }
                rec.update({n: float(v) for n, v in spec.column.items() if n != "index"})
                rec.update({n: float(attrs.get(n, np.nan)) for n in ROW_COORDS[spec.method]})
                out += [{**rec, "k": int(k)} for k in spec.k]
    return out


def _validate_order_check(label: str, params: dict):
    """Parameters of a ``convergence_order`` check (read with the claims file; errors name claim and key)."""
    label = f"{label}: check"
    tol = params["tolerance"]
    if not _is_number(tol) or tol <= 0:
        raise ParameterError(f"{label}.tolerance must be a number > 0, got {tol!r}")
    select = params["select"]
    if not isinstance(select, dict) or not select:
        raise ParameterError(f"{label}.select must be a non-empty mapping of {sorted(SELECT_KEYS)}")
    unknown = sorted(set(select) - SELECT_KEYS)
    if unknown:
        raise ParameterError(f"{label}.select: unknown key(s) {unknown}; allowed: {sorted(SELECT_KEYS)}")
    expect = params["expect"]
    if not isinstance(expect, list) or not expect:
        raise ParameterError(f"{label}.expect must be a non-empty list of {{k: ..., order: p | unstable: true}}")
    for j, exp in enumerate(expect):
        elabel = f"{label}.expect[{j}]"
        if not isinstance(exp, dict):
            raise ParameterError(f"{elabel} must be a mapping")
        unknown = sorted(set(exp) - EXPECT_KEYS)
        if unknown:
            raise ParameterError(f"{elabel}: unknown key(s) {unknown}; allowed: {sorted(EXPECT_KEYS)}")
        if not isinstance(exp.get("k"), int) or isinstance(exp.get("k"), bool) or exp["k"] < 0:
            raise ParameterError(f"{elabel}.k must be an integer >= 0, got {exp.get('k')!r}")
        if ("order" in exp) == bool(exp.get("unstable")):
            raise ParameterError(f"{elabel}: give exactly one of order: p or unstable: true")
        if "unstable" in exp and exp["unstable"] is not True:
            raise ParameterError(f"{elabel}.unstable must be true (or left out), got {exp['unstable']!r}")
        for key in ("order", "observed", "observed_second_half", "observed_tolerance"):
            if key in exp and not _is_number(exp[key]):
                raise ParameterError(f"{elabel}.{key} must be a number, got {exp[key]!r}")
        if "observed_tolerance" in exp and exp["observed_tolerance"] <= 0:
            raise ParameterError(f"{elabel}.observed_tolerance must be > 0")


def check_claims_against_config(claims, cfg: dict):
    """Every expectation of every ``convergence_order`` claim selects at least one curve the
    ``convergence`` configuration will produce (checked before any job runs)."""
    recs = configured_curves(cfg)
    for claim in claims:
        if claim.check["kind"] != "convergence_order":
            continue
        select = claim.check["select"]
        for j, exp in enumerate(claim.check["expect"]):
            if not any(matches(r, {**select, "k": exp["k"]}) for r in recs):
                raise ParameterError(
                    f"claim {claim.id}: check.expect[{j}]: no configured curve matches select {select} with "
                    f"k = {exp['k']} (check figure, decomposition, method, parameters and the configured k)"
                )


@register_check("convergence_order", validate=_validate_order_check)
def check_convergence_order(datasets, *, select: dict, expect: list, tolerance: float):
    """The paper's convergence claims (config/claims/convergence.yaml) on the panel datasets.

    Each expectation is checked on every curve ``select`` picks with its ``k``:

    * ``order: p`` -- pass if the fitted order is within ``tolerance`` of
      ``p``, fail otherwise; undecided if no order could be fitted (too few
      stable step sizes: the claim cannot be checked there).
    * ``unstable: true`` -- pass if unstable at every step size, fail if
      stable at every one, undecided if stable at some.

    The claim fails if any curve fails, passes if all pass, else is undecided;
    ``numbers["rows"]`` holds one record per curve.
    """
    recs = curves(datasets)
    rows = []
    for exp in expect:
        sel = {**select, "k": exp["k"]}
        matched = [r for r in recs if matches(r, sel)]
        if not matched:
            raise ParameterError(f"convergence_order: no curve matches {sel}")
        for rec in matched:
            row = {
                "curve": curve_label(rec),
                "k": rec["k"],
                "order": rec["order"],
                "order_second_half": rec["order_second_half"],
                "fit_H_min": rec["fit_H_min"],
                "fit_H_max": rec["fit_H_max"],
                "stable_H": stable_span(rec),
                "observed": exp.get("observed"),
            }
            # local slopes of the stable points from the fitted range upward (round-off floor left out)
            keep = ~rec["unstable"] & (rec["H"] >= rec["fit_H_min"] if np.isfinite(rec["fit_H_min"]) else True)
            slopes = local_slopes(rec["H"][keep], rec["nrmse"][keep])
            slopes = slopes[np.isfinite(slopes)]
            row["local_slopes"] = (float(slopes.min()), float(slopes.max())) if slopes.size else None
            if exp.get("unstable"):
                row["claimed"] = "unstable"
                n_u = int(rec["unstable"].sum())
                holds = True if n_u == rec["unstable"].size else False if n_u == 0 else None
            else:
                p = float(exp["order"])
                row["claimed"] = f"O(H^{p:g})"
                holds = None if not np.isfinite(rec["order"]) else bool(abs(rec["order"] - p) <= tolerance)
            row["verdict"] = {True: "pass", False: "fail"}.get(holds, "undecided")
            row["holds"] = holds
            rows.append(row)
    measured = "; ".join(
        f"{r['curve']}: {r['claimed']}, "
        + (
            f"stable H {r['stable_H']}"
            if r["claimed"] == "unstable" or not np.isfinite(r["order"])
            else f"fitted order {r['order']:.2f}"
        )
        + f" -> {r['verdict']}"
        for r in rows
    )
    holds = combine_holds(r.pop("holds") for r in rows)
    return Outcome(holds, measured, {"rows": rows, "tolerance": tolerance})


# --------------------------------------------------------------------------- work-precision
def resolve_scheme(scheme: dict, figures: dict, k) -> list:
    """Curves of a work-precision scheme: one per decomposition of its figure and per ``k``.

    ``scheme`` names a figure and the column and row parameters as configured
    (e.g. ``{figure: "22", a: 1, b: 1, index: 2}``).
    """
    fig = str(scheme["figure"])
    if fig not in figures:
        raise ParameterError(f"work_precision scheme {scheme}: figure {fig!r} is not configured")
    cfg = figures[fig]
    rest = {key: v for key, v in scheme.items() if key != "figure"}
    col_keys = set().union(*(c.keys() for c in cfg["columns"]))
    col = {key: v for key, v in rest.items() if key in col_keys}
    row = {key: v for key, v in rest.items() if key not in col_keys}
    cols = [c for c in cfg["columns"] if c == col]
    rows = [r for r in cfg["rows"] if r == row]
    if len(cols) != 1 or len(rows) != 1:
        raise ParameterError(
            f"work_precision scheme {scheme}: must match exactly one column of {cfg['columns']} "
            f"and one row of {cfg['rows']} of figure {fig}"
        )
    eff = effective_params(cfg["method"], cols[0], rows[0])
    out = []
    for spec in figure_panels(fig, cfg, k):
        if eff not in spec.rows:
            continue
        index = spec.indices[spec.rows.index(eff)]
        for kk in spec.k:
            entry = {
                "figure": fig,
                "decomposition": spec.decomposition,
                "panel": spec.panel,
                "index": index,
                "k": int(kk),
                "method": cfg["method"],
                "params": dict(eff),
            }
            rec = {**entry, **{n: v for n, v in method_attrs(cfg["method"], **eff).items()}}
            entry["label"] = _scheme_label(rec)
            out.append(entry)
    return out


def _scheme_label(rec) -> str:
    m = rec["method"]
    if m == "projection":
        head = "projection"
    elif m == "baumgarte":
        head = f"Baumgarte i{rec['index']}" + (f" mu={rec['mu']:g}" if "mu" in rec else "")
    else:
        head = f"weighted i{rec['index']} a={rec['a']:g}" + (f" b={rec['b']:g}" if rec["index"] == 1 else "")
    return f"{rec['decomposition']} {head} k={rec['k']}"


def work_precision(entries, datasets: dict, setup: Setup, *, steps=20, repeats=3, warmup_steps=5, provenance=None):
    """CPU time per simulated second against NRMSE for each scheme and stable ``H``.

    ``datasets`` maps ``(decomposition, figure, panel)`` to the panel dataset
    holding the scheme's NRMSE (never recomputed here).  Returns a dataset with
    dims ``(scheme, H)``.
    """
    import xarray as xr

    if not entries:
        raise ParameterError("work_precision needs at least one scheme")
    H = None
    rows = []
    for e in entries:
        ds = datasets[(e["decomposition"], e["figure"], e["panel"])]
        if H is None:
            H = ds["H"].values
        elif not np.array_equal(H, ds["H"].values):
            raise ValueError("all panels must share the same step sizes")
        sel = ds.sel(index=e["index"], k=e["k"])
        err = sel["nrmse"].values
        unstable = sel["unstable"].values.astype(bool)
        per_step = np.full(H.size, np.nan)
        setup_s = np.nan
        for i, h in enumerate(H):
            if unstable[i] or not np.isfinite(err[i]):
                continue  # no error to put the time against
            t = time_macro_steps(
                setup,
                float(h),
                e["method"],
                e["params"],
                e["decomposition"],
                e["k"],
                steps=steps,
                repeats=repeats,
                warmup_steps=warmup_steps,
            )
            per_step[i] = t["seconds_per_step"]
            setup_s = t["setup_seconds"] if not np.isfinite(setup_s) else min(setup_s, t["setup_seconds"])
        rows.append((err, unstable, per_step, setup_s))
    labels = [e["label"] for e in entries]
    costs = [step_cost(e["method"], e["params"], e["decomposition"], e["k"]) for e in entries]
    err = np.array([r[0] for r in rows])
    per_step = np.array([r[2] for r in rows])
    ds = xr.Dataset(
        {
            "nrmse": (
                ("scheme", "H"),
                err,
                {"long_name": "NRMSE of Eq. (72) (from the panel datasets; NaN where unstable)", "units": "1"},
            ),
            "unstable": (("scheme", "H"), np.array([r[1] for r in rows])),
            "cpu_seconds_per_step": (
                ("scheme", "H"),
                per_step,
                {"long_name": "CPU time of one macro step of icosim.macrostep.simulate (min of repeats)", "units": "s"},
            ),
            "cpu_seconds_per_simulated_second": (
                ("scheme", "H"),
                per_step / H[None, :],
                {"long_name": "CPU time per simulated second", "units": "s"},
            ),
            "setup_seconds": (
                ("scheme",),
                np.array([r[3] for r in rows]),
                {"long_name": "CPU time to build the problem (once per run, not per simulated second)", "units": "s"},
            ),
            "subsystem_integrations_per_step": (
                ("scheme",),
                np.array([c["subsystem_integrations"] for c in costs], dtype=np.int32),
                {
                    "long_name": "subsystem integrations per macro step (predictor and corrector of each subsystem; counted)",
                    "units": "1",
                },
            ),
            "coupling_solves_per_step": (
                ("scheme",),
                np.array([c["coupling_solves"] for c in costs], dtype=np.int32),
                {
                    "long_name": "linear solves of coupling conditions per macro step (the method's nonzero-weight solves)",
                    "units": "1",
                },
            ),
            "projections_per_step": (
                ("scheme",),
                np.array([c["projections"] for c in costs], dtype=np.int32),
                {"long_name": "projection steps per macro step", "units": "1"},
            ),
        },
        coords={
            "scheme": ("scheme", np.array(labels, dtype=str)),
            "H": ("H", H, {"long_name": "macro-step size", "units": "s"}),
            "figure": ("scheme", np.array([e["figure"] for e in entries], dtype=str)),
            "method": ("scheme", np.array([e["method"] for e in entries], dtype=str)),
            "decomposition": ("scheme", np.array([e["decomposition"] for e in entries], dtype=str)),
            "index": ("scheme", np.array([e["index"] for e in entries], dtype=np.int32)),
            "k": ("scheme", np.array([e["k"] for e in entries], dtype=np.int32)),
            **{
                name: (
                    "scheme",
                    np.array(
                        [method_attrs(e["method"], **e["params"]).get(name, np.nan) for e in entries], dtype=float
                    ),
                    {"units": PARAM_UNITS[name]},
                )
                for name in ("mu", "beta", "gamma", "a", "b")
            },
        },
    )
    ds.attrs = dict(provenance or {})
    ds.attrs.update(
        timer="time.process_time",
        steps=steps,
        repeats=repeats,
        warmup_steps=warmup_steps,
        timed="icosim.macrostep.simulate: the engine's macro-step loop (predictor, corrector, "
        "projection) of the linear test model; problem set-up excluded (setup_seconds)",
        cost_caveat="the subsystems of the linear test model are integrated exactly (matrix "
        "exponential blocks), so the timed cost is the coupling algorithm's Python overhead and nearly "
        "the same for every scheme: the diagram is close to NRMSE against 1/H. To transfer the "
        "comparison to numerically integrated subsystems, weigh subsystem_integrations_per_step and "
        "coupling_solves_per_step with their cost there.",
        method_parameters_units="mu and beta in s, gamma in s^2, a and b dimensionless",
    )
    return ds


def fastest_schemes(wp, targets) -> list:
    """Per decomposition and target error: schemes ordered by the least CPU time reaching it.

    A scheme reaches ``target`` at the measured step sizes with
    ``nrmse <= target``; its cost is the least CPU time per simulated second
    among those.  Returns dicts ``{decomposition, target, ranking: [(label, seconds, H), ...]}``.
    """
    out = []
    for dec in sorted(set(wp["decomposition"].values.tolist())):
        sub = wp.where(wp["decomposition"] == dec, drop=True)
        for target in targets:
            ranking = []
            for s in range(sub.sizes["scheme"]):
                err = sub["nrmse"].values[s]
                cost = sub["cpu_seconds_per_simulated_second"].values[s]
                ok = np.isfinite(err) & np.isfinite(cost) & (err <= target)
                if ok.any():
                    i = np.flatnonzero(ok)[np.argmin(cost[ok])]
                    ranking.append((str(sub["scheme"].values[s]), float(cost[i]), float(sub["H"].values[i])))
            ranking.sort(key=lambda r: r[1])
            out.append({"decomposition": dec, "target": float(target), "ranking": ranking})
    return out
