"""The precision policy: float64 first, proofs where float64 cannot decide.

Every point is first computed in float64 with an error estimate
(:mod:`icosim.engine.spectral.radius`).  A point is *trusted* if its float64 result
is finite and ``|rho - 1|`` exceeds that estimate; its verdict is then
``stable`` or ``unstable`` from float64 -- a good heuristic, not a bound.
Certified in ball arithmetic (:mod:`icosim.engine.spectral.certified`, a proven
enclosure of ``rho``) are

* every point float64 cannot decide (not trusted),
* every point whose float64 ``rho`` lies within ``band`` of 1 (default 1e-6),
* a seeded random *audit* sample of the rest (default 1 %), which checks the
  float64 verdicts: a certified verdict that differs from float64's is counted
  as *overturned* (and the certified one stands).

Verdicts, with no tolerance conventions: ``stable`` (proven ``rho < 1``, or
float64 trusted), ``unstable`` (proven ``rho > 1``, or float64 trusted),
``marginal`` (the proven enclosure still contains 1 at the precision cap, e.g.
``rho = 1`` exactly on the undamped axis), ``undecided`` (nothing could be
computed for the point; the grid goes on).  The result records per point which
arithmetic decided it.

The origin of the parameter plane (a free mass: a Jordan block at 1) is marginal:

>>> from icosim import TestModel, make_method
>>> from icosim.problems.linear.family import TwoMass
>>> res = spectral_radius(TwoMass(TestModel(0.0, 0.0), "ff", k=0), make_method("projection"))
>>> str(res.verdict), str(res.arithmetic), bool(res.certified), res.n_high_precision
('marginal', 'ball', True, 1)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING

import numpy as np

from ...errors import NotFiniteError, ParameterError, PointTimeout, PrecisionCapError
from ..backends import FLOAT64_DIGITS
from ..bounds import MAX_BITS_LIMIT, MAX_SECONDS, time_budget
from ..schemes import JACOBI, Scheme, get_scheme
from .batched import certify_spectral_radii
from .certified import DEFAULT_BITS, MAX_BITS, SpectralCertificate
from .radius import spectral_radius_float64, spectral_radius_mp

if TYPE_CHECKING:
    from ..methods.base import CouplingMethod
    from .family import LinearFamily

__all__ = [
    "spectral_radius",
    "StabilityResult",
    "Certification",
    "POLICIES",
    "VERDICTS",
    "ARITHMETICS",
    "REASONS",
    "reason_code",
]

#: ``auto``: float64, certify what it cannot decide (and the band and the audit); ``float64``: no
#: recheck; ``certify``: every point certified; ``mp``: every point with mpmath at ``digits``.
POLICIES = ("auto", "float64", "certify", "mp")
#: Per-point verdicts.
VERDICTS = ("stable", "unstable", "marginal", "undecided")
#: What decided a point.
ARITHMETICS = ("float64", "ball", "mpmath", "none")
#: Why a point is undecided (``none`` for decided points): a derived quantity not finite in float64, a precision
#: beyond a cap (guard digits), the time budget, any other error, or a ball amplification matrix that is not finite
#: at the largest precision (the coupling's linear system singular at the point, or every digit lost).
REASONS = ("none", "overflow", "precision_cap", "timeout", "error", "not_finite")


@dataclass(frozen=True)
class Certification:
    """Which float64 points are certified besides the untrusted ones, and the ball precision.

    ``band``: certify every point with ``|rho - 1| < band``; ``audit``: the
    share of the remaining points certified at random (``seed``); ``bits`` and
    ``max_bits``: the ball arithmetic's first and largest working precision;
    ``point_seconds``: the wall-time budget of one point's recheck (past it the
    point is undecided, reason ``timeout``; 0: none).
    """

    band: float = 1e-6
    audit: float = 0.01
    seed: int = 0
    bits: int = DEFAULT_BITS
    max_bits: int = MAX_BITS
    point_seconds: float = 60.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ParameterError(f"certify.{f.name} must be a number, got {value!r}")
        if int(self.seed) != self.seed or self.seed < 0:
            raise ParameterError(f"certify.seed must be an integer >= 0, got {self.seed!r}")
        if not (np.isfinite(self.band) and self.band >= 0):
            raise ParameterError(f"certify.band must be a finite number >= 0, got {self.band!r}")
        if not (0 <= self.audit <= 1):
            raise ParameterError(f"certify.audit must lie in [0, 1], got {self.audit!r}")
        if int(self.bits) != self.bits or self.bits < 53:
            raise ParameterError(f"certify.bits must be an integer >= 53, got {self.bits!r}")
        if int(self.max_bits) != self.max_bits or not self.bits <= self.max_bits <= MAX_BITS_LIMIT:
            raise ParameterError(
                f"certify.max_bits must be an integer in bits = {self.bits}..{MAX_BITS_LIMIT}, got {self.max_bits!r}"
            )
        if not (0 <= self.point_seconds <= MAX_SECONDS):
            raise ParameterError(
                f"certify.point_seconds must be a number in 0..{MAX_SECONDS:g}, got {self.point_seconds!r}"
            )

    @classmethod
    def from_dict(cls, d: dict | None) -> Certification:
        d = dict(d or {})
        unknown = sorted(set(d) - {f.name for f in fields(cls)})
        if unknown:
            raise ParameterError(f"certify: unknown key(s) {unknown}; allowed: {[f.name for f in fields(cls)]}")
        return cls(**d)


@dataclass
class StabilityResult:
    """Per point: spectral radius, verdict, what decided it, and the proof where there is one.

    ``rho`` is the float64 value where float64 decided, else a value inside
    the proven enclosure ``[rho_lower, rho_upper]`` (NaN outside certified
    points); ``verdict`` and ``arithmetic`` hold names from :data:`VERDICTS`
    and :data:`ARITHMETICS`; ``float64_verdict`` is float64's own verdict on
    the points it trusted ('' elsewhere); ``digits`` the decimal digits of the
    arithmetic that decided (15 for float64; for balls ``bits * log10 2``).
    ``seconds`` and ``cpu_seconds`` split the cost (``float64``, ``certify``,
    ``mp``).  ``reason`` says in words why a point is undecided (or what
    float64 could not do), ``reason_code`` classifies it (:data:`REASONS`).
    """

    rho: np.ndarray
    err: np.ndarray
    digits: np.ndarray
    verdict: np.ndarray
    arithmetic: np.ndarray
    rho_lower: np.ndarray
    rho_upper: np.ndarray
    bits: np.ndarray
    audited: np.ndarray
    float64_verdict: np.ndarray
    reason: np.ndarray
    reason_code: np.ndarray
    seconds: dict = field(default_factory=dict)
    cpu_seconds: dict = field(default_factory=dict)

    @property
    def stable(self) -> np.ndarray:
        """Stable verdicts (proven or float64): marginal and undecided points are not."""
        return self.verdict == "stable"

    @property
    def certified(self) -> np.ndarray:
        """Points whose verdict rests on a proven enclosure (ball arithmetic): stable, unstable or marginal."""
        return (self.arithmetic == "ball") & (self.verdict != "undecided")

    @property
    def overturned(self) -> np.ndarray:
        """Points float64 trusted whose certified verdict is the opposite one."""
        proven = np.isin(self.verdict, ("stable", "unstable")) & self.certified
        return proven & (self.float64_verdict != "") & (self.float64_verdict != self.verdict)

    @property
    def n_high_precision(self) -> int:
        """Points decided by an arithmetic other than float64 (ball or mpmath)."""
        return int(np.sum(np.isin(self.arithmetic, ("ball", "mpmath"))))

    @property
    def n_failed(self) -> int:
        """Points nothing could decide (``undecided``)."""
        return int(np.sum(self.verdict == "undecided"))


def spectral_radius(
    family: LinearFamily,
    method: CouplingMethod,
    *,
    digits: int = 128,
    policy: str = "auto",
    certification: Certification | dict | None = None,
    scheme: str | Scheme = JACOBI,
) -> StabilityResult:
    """Spectral radius and stability verdict at every point of ``family`` with the precision policy.

    Parameters
    ----------
    family : the points (:class:`~icosim.engine.spectral.family.LinearFamily`; the two-mass model's:
        :func:`icosim.problems.linear.spectral.spectral_radius` takes its parameters).
    scheme : the coupling scheme (:mod:`icosim.engine.schemes`; default Jacobi), used by every arithmetic.
    policy : one of :data:`POLICIES` (module docstring).
    digits : mpmath digits of the ``mp`` policy.
    certification : :class:`Certification` settings (or a mapping of them).

    One point that cannot be computed gets the verdict ``undecided`` and its
    ``reason``; the grid goes on.
    """
    if policy not in POLICIES:
        raise ValueError(f"policy must be one of {', '.join(POLICIES)}, got {policy!r}")
    scheme = get_scheme(scheme)
    cert_settings = (
        certification if isinstance(certification, Certification) else Certification.from_dict(certification)
    )
    shape = family.shape
    out = _empty(shape)
    t0, c0 = time.perf_counter(), time.process_time()
    # derived quantities (k = lr^2 + li^2, ...) that overflow float64: undecided, nothing is computed there
    overflow = family.overflowing()
    out["reason"][overflow] = family.overflow_reason
    out["reason_code"][overflow] = "overflow"
    if policy == "mp":
        todo_ball = np.zeros(shape, dtype=bool)
        todo_mp = ~overflow
    else:
        rho, err = _float64_isolated(family, overflow, method, out, scheme)
        out["rho"], out["err"] = rho, err
        trusted = np.isfinite(rho) & (np.abs(rho - 1) > err)
        if policy == "float64":  # no recheck: float64's verdict on every finite point
            trusted = np.isfinite(rho)
        f64 = np.where(rho <= 1, "stable", "unstable")
        out["verdict"] = np.where(trusted, f64, "undecided").astype(object)
        out["float64_verdict"] = np.where(trusted, f64, "").astype(object)
        out["arithmetic"] = np.where(trusted, "float64", "none").astype(object)
        out["digits"] = np.where(trusted, FLOAT64_DIGITS, -1)
        why = np.where(np.isfinite(rho), "float64 cannot decide", "float64 not finite")
        out["reason"] = np.where(trusted | overflow, out["reason"], why).astype(object)
        todo_mp = np.zeros(shape, dtype=bool)
        if policy == "float64":
            todo_ball = np.zeros(shape, dtype=bool)
        elif policy == "certify":
            todo_ball = ~overflow
        else:
            rng = np.random.default_rng(cert_settings.seed)
            audit = trusted & (rng.random(shape) < cert_settings.audit)
            near = trusted & (np.abs(rho - 1) < cert_settings.band)
            out["audited"] = audit | near
            todo_ball = (~trusted | near | audit) & ~overflow
    t1, c1 = time.perf_counter(), time.process_time()
    todo = [idx for idx in np.ndindex(shape) if todo_ball[idx]]
    # the points are certified together (batched ball arithmetic, every certificate as if alone), one point's
    # failure leaves only that point undecided
    certificates = certify_spectral_radii(
        [family.point(idx) for idx in todo],
        method,
        bits=cert_settings.bits,
        max_bits=cert_settings.max_bits,
        point_seconds=cert_settings.point_seconds,
        scheme=scheme,
    )
    for idx, c in zip(todo, certificates):
        if isinstance(c, BaseException):
            _undecided(out, idx, c)
        else:
            _store(out, idx, c)
    t2, c2 = time.perf_counter(), time.process_time()
    for idx in np.ndindex(shape):
        if not todo_mp[idx]:
            continue
        try:
            with time_budget(cert_settings.point_seconds):
                r = spectral_radius_mp(family.point(idx), method, digits, scheme=scheme)
        except Exception as exc:  # one point's failure must not abort a grid
            _undecided(out, idx, exc)
            continue
        # an eigenvalue of a Jordan block is computed only to about half the digits: no verdict closer to 1
        half = 10.0 ** -(digits // 2)
        out["rho"][idx], out["digits"][idx], out["arithmetic"][idx] = float(r), digits, "mpmath"
        out["verdict"][idx] = "stable" if r < 1 - half else "unstable" if r > 1 + half else "marginal"
    t3, c3 = time.perf_counter(), time.process_time()
    return StabilityResult(
        **{k: (v.astype(str) if v.dtype == object else v) for k, v in out.items()},
        seconds={"float64": t1 - t0, "certify": t2 - t1, "mp": t3 - t2},
        cpu_seconds={"float64": c1 - c0, "certify": c2 - c1, "mp": c3 - c2},
    )


def _float64_isolated(
    family: LinearFamily, overflow: np.ndarray, method: CouplingMethod, out: dict, scheme: str | Scheme = JACOBI
) -> tuple[np.ndarray, np.ndarray]:
    """The float64 pass over the grid in one call; if it raises, point by point, each failure undecided alone."""
    shape = family.shape
    try:
        rho, err = spectral_radius_float64(family.safe(overflow), method, scheme=scheme)  # no overflow inside
        return np.where(overflow, np.nan, rho), np.where(overflow, np.inf, err)
    except Exception:  # noqa: BLE001 -- find the point(s) responsible; the others keep their values
        rho, err = np.full(shape, np.nan), np.full(shape, np.inf)
        for idx in np.ndindex(shape):
            if overflow[idx]:
                continue
            try:
                r, e = spectral_radius_float64(family.point(idx), method, scheme=scheme)
                rho[idx], err[idx] = float(r), float(e)
            except Exception as exc:  # noqa: BLE001
                _undecided(out, idx, exc)
        return rho, err


def reason_code(exc: BaseException) -> str:
    """The :data:`REASONS` code of the exception that left a point undecided."""
    if isinstance(exc, PointTimeout):
        return "timeout"
    if isinstance(exc, PrecisionCapError):
        return "precision_cap"
    return "overflow" if isinstance(exc, (OverflowError, NotFiniteError)) else "error"


def _undecided(out: dict, idx: tuple[int, ...], exc: BaseException) -> None:
    """One point undecided by ``exc``: nothing of an earlier pass stands (an audited float64 value included)."""
    out["verdict"][idx], out["reason"][idx] = "undecided", f"{type(exc).__name__}: {exc}"
    out["reason_code"][idx] = reason_code(exc)
    out["rho"][idx], out["digits"][idx], out["arithmetic"][idx] = np.nan, -1, "none"


def _empty(shape: tuple[int, ...]) -> dict:
    return {
        "rho": np.full(shape, np.nan),
        "err": np.full(shape, np.inf),
        "digits": np.full(shape, -1, dtype=int),
        "verdict": np.full(shape, "undecided", dtype=object),
        "arithmetic": np.full(shape, "none", dtype=object),
        "rho_lower": np.full(shape, np.nan),
        "rho_upper": np.full(shape, np.nan),
        "bits": np.zeros(shape, dtype=int),
        "audited": np.zeros(shape, dtype=bool),
        "float64_verdict": np.full(shape, "", dtype=object),
        "reason": np.full(shape, "", dtype=object),
        "reason_code": np.full(shape, "none", dtype=object),
    }


def _store(out: dict, idx: tuple[int, ...], c: SpectralCertificate) -> None:
    """One certificate into the result arrays (bounds rounded outward to float64)."""
    if c.verdict == "undecided":  # the ball arithmetic lost every digit at the cap: nothing is known
        out["verdict"][idx], out["rho"][idx], out["digits"][idx] = "undecided", np.nan, -1
        out["reason"][idx], out["reason_code"][idx] = c.reason, c.cause or "precision_cap"
        out["arithmetic"][idx] = "none"
        return
    lower = float(c.rho_lower)
    lower = np.nextafter(lower, -np.inf) if lower > c.rho_lower else lower
    upper = np.inf if c.rho_upper is None else float(c.rho_upper)
    upper = np.nextafter(upper, np.inf) if upper < (c.rho_upper or 0) else upper
    out["rho_lower"][idx], out["rho_upper"][idx] = lower, upper
    if out["float64_verdict"][idx] != c.verdict or not lower <= out["rho"][idx] <= upper:
        # float64 did not decide, or the proof contradicts its verdict or its value: a value inside the enclosure
        out["rho"][idx] = lower if not np.isfinite(upper) else (lower + upper) / 2
    out["verdict"][idx], out["arithmetic"][idx], out["bits"][idx] = c.verdict, "ball", c.bits
    out["reason_code"][idx] = "none"  # decided (a float64 failure before it is only its reason to be certified)
    out["digits"][idx] = int(c.bits * np.log10(2))
    out["reason"][idx] = c.reason
