"""Is my coupled system stable?  Every scheme for one physical two-mass system.

A user brings two subsystems -- masses ``m1, m2`` [kg], stiffnesses ``c1, c2``
[N/m], dampers ``d1, d2`` [N s/m] (overdamped ones included) -- and either a
macro step ``H`` [s] or a range of them.  :func:`advise` answers, for every
registered coupling method (:data:`icosim.methods.METHODS`), each index it can
be formulated at, each decomposition it is defined for and each approximation
order ``k``:

* at one ``H``: the spectral radius ``rho`` of the co-simulation recurrence
  (the precision policy of :func:`icosim.stability.spectral_radius`: float64,
  rechecked at 128 digits where float64 cannot decide) and the verdict;
* over a range ``[H_lo, H_hi]``: where the scheme is stable.  Stability need
  not be monotone in ``H`` (the weighted multiplier at ``k = 2`` is unstable
  for small ``H`` and stable for larger ones), so the range is first scanned
  on a grid of log-spaced ``H``, then every stable/unstable transition between
  neighbouring grid points is refined by bracketing (multisection, each pass
  one batched call) until the bracket is ``rtol`` wide.  The result is the
  stable intervals; the *largest stable H* is the upper end of the last one.
  Intervals narrower than the grid spacing can be missed, and the output says
  so.

The answer is a :class:`pandas.DataFrame`, one row per scheme, stable schemes
ranked first (at one ``H`` by ``rho``: the smaller, the faster a coupling error
decays per macro step; over a range first the schemes stable from the range's
lower end, by how far up they stay stable, then those stable only on higher
intervals, by their largest stable ``H``).  ``df.attrs`` holds the system, its dimensionless parameters
(Eq. 71, or the per-unit-mass coefficients when a subsystem is overdamped) and
the settings.

The dimensionless parameters (Eq. 6, 71) of the two-mass system: with
``m1 = 1, c1 = 100, d1 = 2`` and ``H = 0.01`` s, ``lr1 = -d1 H/(2 m1) = -0.01``
and ``li1 = H sqrt(c1/m1 - (d1/(2 m1))^2)``:

>>> system = TwoMassSystem(m1=1, m2=2, c1=100, c2=200, d1=2, d2=4)
>>> p = system.dimensionless(0.01)
>>> round(p["lr1"], 12), round(p["li1"], 6), p["am21"], p["alr21"], p["ali21"]
(-0.01, 0.099499, 2.0, 1.0, 1.0)

Method parameters are taken in physical units (Baumgarte ``mu`` in s); one
not given is 1 in the paper's dimensionless form (``mu_bar = mu/H = 1``,
``a = b = 1``), as in Figs. 9-15.

Adding a coupling order (Gauss-Seidel) or certified verdicts touches
:data:`COUPLINGS` and :func:`evaluate` only: schemes are enumerated by
:func:`schemes`, every spectral radius is computed by :func:`evaluate`, and the
``verdict`` column is the one place a verdict is stated.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from . import methods as _methods
from .backend import FLOAT64_DIGITS
from .model import ParameterError, PhysicalModel
from .stability import spectral_radius

__all__ = [
    "TwoMassSystem",
    "Scheme",
    "COUPLINGS",
    "schemes",
    "evaluate",
    "stable_intervals",
    "advise",
    "check_settings",
    "advice_records",
    "advice_text",
    "Progress",
    "DEFAULT_K",
    "DEFAULT_SCAN",
    "DEFAULT_RTOL",
]

#: Approximation orders scanned unless others are asked for.
DEFAULT_K = (0, 1, 2)
#: Grid points of the first scan over an H range.
DEFAULT_SCAN = 32
#: Relative width of the bracket at which the refinement of a transition stops.
DEFAULT_RTOL = 1e-6
#: Points per refinement pass of a transition (one batched call each).
_SECTIONS = 8

#: Coupling orders: name -> keyword arguments of :func:`icosim.stability.spectral_radius`.  The Jacobi
#: (parallel) scheme is the engine's; Gauss-Seidel joins here once the engine takes ``scheme=``.
COUPLINGS: dict[str, dict] = {"jacobi": {}}

#: Verdicts of one point: rho <= 1 decided, rho > 1 decided, not decided (failed, or float64 only).
VERDICTS = ("stable", "unstable", "undecided")


@dataclass(frozen=True)
class TwoMassSystem:
    """Two single-mass oscillators (the paper's test model in physical units).

    ``m`` in kg (> 0), ``c`` in N/m and ``d`` in N s/m (>= 0); any damping,
    overdamped included.
    """

    m1: float
    m2: float
    c1: float
    c2: float
    d1: float
    d2: float

    def __post_init__(self):
        for name in ("m1", "m2", "c1", "c2", "d1", "d2"):
            value = getattr(self, name)
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise ParameterError(f"{name} must be a number, got {value!r}") from None
            if not math.isfinite(v):
                raise ParameterError(f"{name} must be a finite number, got {value!r}")
            if name.startswith("m") and not v > 0:
                raise ParameterError(f"{name} must be > 0 (a mass in kg), got {value!r}")
            if not name.startswith("m") and v < 0:
                unit = "N/m" if name.startswith("c") else "N s/m"
                raise ParameterError(f"{name} must be >= 0 (in {unit}), got {value!r}")
            object.__setattr__(self, name, v)

    def as_dict(self) -> dict:
        return {n: getattr(self, n) for n in ("m1", "m2", "c1", "c2", "d1", "d2")}

    def model(self, H) -> PhysicalModel:
        """The engine's physical model at macro step(s) ``H`` (an array broadcasts)."""
        return PhysicalModel(H=np.asarray(H, dtype=float), **self.as_dict())

    @property
    def overdamped(self) -> tuple[bool, bool]:
        """Per subsystem: ``d^2 > 4 m c`` (no real Eq. (71) form; independent of H)."""
        over1, over2 = self.model(1.0).overdamped
        return bool(over1), bool(over2)

    def dimensionless(self, H: float) -> dict:
        """The dimensionless parameters at one ``H``.

        Always the coefficients of Eq. (5)/(6) (``k1 = c1 H^2/m1``, ``delta1 =
        d1 H/m1``, ...); the five parameters of Eq. (71) where they exist, else
        ``None`` with the reason in ``eq71``.
        """
        model = self.model(float(H))
        c = model.coefficients()
        out = {
            "H": float(H),
            **{n: float(getattr(c, n)) for n in ("k1", "delta1", "k2", "delta2", "am21")},
        }
        try:
            tm = model.test_model()
        except ParameterError as exc:
            out.update(dict.fromkeys(("lr1", "li1", "alr21", "ali21")))
            out["eq71"] = str(exc).split(":")[
                0
            ]  # "subsystem 1 is overdamped (d^2 > 4 m c)", or why a ratio is undefined
            return out
        out.update({n: float(getattr(tm, n)) for n in ("lr1", "li1", "alr21", "ali21")})
        out["eq71"] = "ok"
        return out

    def per_second(self) -> dict:
        """``lr1/H`` and ``li1/H`` in 1/s (Eq. 71 scales linearly with H), where they exist."""
        p = self.dimensionless(1.0)
        return {"lr1_per_H": p["lr1"], "li1_per_H": p["li1"]}


@dataclass(frozen=True)
class Scheme:
    """One co-simulation scheme: method (registry name), index, parameters, decomposition, k, coupling order.

    ``params`` are the method's parameters as the user gives them: physical
    units for parameters that scale with ``H`` (``mu`` in s), or their
    dimensionless form under ``<name>_bar`` (``mu_bar = mu/H``).
    """

    method: str
    index: int
    params: dict
    decomposition: str
    k: int
    coupling: str = "jacobi"

    @property
    def spec(self):
        return _methods.get_spec(self.method)

    @property
    def h_dependent(self) -> bool:
        """True if the engine's dimensionless parameters change with H (a parameter given in s or s^2)."""
        return any(name in _scaled() for name in self.params)

    def engine_method(self, H=None):
        """The method with the engine's dimensionless parameters at macro step ``H``."""
        args = {"index": self.index} if self.spec.takes_index else {}
        for name, value in self.params.items():
            if name.endswith("_bar"):
                args[name.removesuffix("_bar")] = value
            elif name in _scaled():
                if H is None:
                    raise ValueError(f"{self.label}: parameter {name} in physical units needs H")
                args[name] = _methods.parameters()[name].engine_value(value, float(H))
            else:
                args[name] = value
        return self.spec.make(**args)

    @property
    def parameter_text(self) -> str:
        units = _methods.parameter_units()
        parts = []
        for name, value in self.params.items():
            if name.endswith("_bar"):
                parts.append(f"{name.removesuffix('_bar')} = {value:g} H")
            else:
                unit = {"s": " s", "s2": " s^2"}.get(units[name], "")
                parts.append(f"{name} = {value:g}{unit}")
        return ", ".join(parts)

    @property
    def label(self) -> str:
        """E.g. ``Baumgarte i1 (mu = 1 H) ff k=2`` (plus the coupling order when not Jacobi)."""
        spec = self.spec
        head = spec.short_label + (f" i{self.index}" if spec.takes_index else "")
        params = self.parameter_text
        tail = "" if self.coupling == "jacobi" else f" {self.coupling}"
        return f"{head}{f' ({params})' if params else ''} {self.decomposition} k={self.k}{tail}"


def _scaled() -> dict:
    return {name: p for name, p in _methods.parameters().items() if p.scaling}


def _index_params(spec, index, given: dict) -> dict:
    """The parameters a method takes at ``index``: its own (shorthand ones replace the rest), not those unused there.

    A parameter not in ``given`` defaults to 1 in dimensionless form (``mu_bar = 1``, ``a = b = 1``).
    """
    unused = set(spec.unused(index))
    own = [p for p in spec.parameters if p.name not in unused]
    if any(p.shorthand for p in own):
        own = [p for p in own if p.shorthand]
    out = {}
    for p in own:
        if p.name in given:
            out[p.name] = float(given[p.name])
        elif p.scaling:
            out[f"{p.name}_bar"] = 1.0
        else:
            out[p.name] = 1.0
    return out


def schemes(
    *,
    methods=None,
    decompositions=None,
    k=DEFAULT_K,
    params: dict | None = None,
    couplings=None,
) -> list[Scheme]:
    """Every scheme: each method of the registry (or those named), each index, decomposition and ``k``.

    ``params`` are method parameters by name in physical units (``{"mu": 5e-3, "a": 0.5}``); each
    method takes those it has.  Every scheme is built once here, so a parameter value a method
    refuses is reported (:class:`~icosim.model.ParameterError`) before any computation.

    >>> len(schemes())  # Baumgarte and weighted: 3 indices x (ff, fd); projection: ff, fd, dd; k = 0, 1, 2
    45
    >>> schemes(methods=["weighted"], k=[2])[1].label
    'weighted i1 (a = 1, b = 1) fd k=2'
    """
    params = dict(params or {})
    names = list(_methods.METHODS) if methods is None else list(methods)
    for name in names:
        _methods.get_spec(name)
    known = set(_methods.parameters())
    unknown = sorted(set(params) - known)
    if unknown:
        raise ParameterError(f"parameter {unknown[0]} is not a method parameter (known: {', '.join(sorted(known))})")
    taken = {n for name in names for n in (p.name for p in _methods.get_spec(name).parameters)}
    unused = sorted(set(params) - taken)
    if unused:
        raise ParameterError(f"{unused[0]} is not used by the methods asked for ({', '.join(names)})")
    ks = sorted({int(v) for v in k})
    if any(v < 0 for v in ks):
        raise ParameterError(f"k must be integers >= 0, got {list(k)}")
    couplings = list(COUPLINGS) if couplings is None else list(couplings)
    for c in couplings:
        if c not in COUPLINGS:
            raise ParameterError(f"coupling must be one of {', '.join(COUPLINGS)}, got {c!r}")
    out = []
    for name in names:
        spec = _methods.get_spec(name)
        decs = [d for d in spec.decompositions if decompositions is None or d in decompositions]
        for index in spec.indices:
            p = _index_params(spec, index, params)
            for dec in decs:
                for kk in ks:
                    for coupling in couplings:
                        s = Scheme(name, index, p, dec, kk, coupling)
                        s.engine_method(1.0)  # refuses bad values now (e.g. weighted index 1 with b = 0)
                        out.append(s)
    return out


@dataclass
class Evaluation:
    """Spectral radius per H of one scheme, with the precision that decided it and the verdict."""

    H: np.ndarray
    rho: np.ndarray
    err: np.ndarray
    digits: np.ndarray
    verdict: np.ndarray = field(default=None)

    @property
    def stable(self) -> np.ndarray:
        return self.verdict == "stable"


def evaluate(system: TwoMassSystem, scheme: Scheme, H, *, policy="auto", digits=128) -> Evaluation:
    """``rho`` of ``scheme`` at every macro step in ``H``: one batched call, or one per H where the engine's
    parameters change with it (a Baumgarte ``mu`` in s).

    The verdict is ``stable`` (``rho <= 1`` decided), ``unstable``, or
    ``undecided``: no precision could compute the point, or (policy
    ``float64``) float64 could not decide it.
    """
    H = np.atleast_1d(np.asarray(H, dtype=float))
    kw = {"digits": digits, "policy": policy, **COUPLINGS[scheme.coupling]}
    if scheme.h_dependent:
        parts = [
            spectral_radius(system.model(h), scheme.engine_method(h), scheme.decomposition, scheme.k, **kw) for h in H
        ]
        rho = np.concatenate([np.atleast_1d(r.rho) for r in parts])
        err = np.concatenate([np.atleast_1d(r.err) for r in parts])
        dig = np.concatenate([np.atleast_1d(r.digits) for r in parts])
        stable = np.concatenate([np.atleast_1d(r.stable) for r in parts])
    else:
        r = spectral_radius(system.model(H), scheme.engine_method(), scheme.decomposition, scheme.k, **kw)
        rho, err, dig, stable = (np.atleast_1d(np.asarray(a)) for a in (r.rho, r.err, r.digits, r.stable))
    untrusted = (dig == FLOAT64_DIGITS) & ~(np.isfinite(rho) & (np.abs(rho - 1) > err))
    undecided = (dig < 0) | ~np.isfinite(rho) | untrusted
    verdict = np.where(undecided, "undecided", np.where(stable, "stable", "unstable"))
    return Evaluation(H, rho, err, dig, verdict)


def _refine(f, lo, hi, stable_lo: bool, rtol: float):
    """Shrink ``[lo, hi]`` (``f(lo)`` stable or not as ``stable_lo``, ``f(hi)`` the opposite) to ``hi/lo - 1 <= rtol``.

    Each pass evaluates ``_SECTIONS - 1`` interior points (log-spaced) in one call and keeps the
    first sub-bracket where the state changes.  Returns ``(lo, hi)`` and the number of passes.
    """
    passes = 0
    while hi / lo - 1 > rtol:
        inner = np.geomspace(lo, hi, _SECTIONS + 1)[1:-1]
        state = f(inner)
        change = np.flatnonzero(state != stable_lo)
        if change.size:
            j = change[0]
            hi = inner[j]
            lo = inner[j - 1] if j > 0 else lo
        else:
            lo = inner[-1]
        passes += 1
    return lo, hi, passes


def stable_intervals(system, scheme, H_lo, H_hi, *, n_scan=DEFAULT_SCAN, rtol=DEFAULT_RTOL, policy="auto", digits=128):
    """Where ``scheme`` is stable on ``[H_lo, H_hi]``: scan, then refine every transition.

    Returns a dict: ``intervals`` (list of ``[lo, hi]``, both ends evaluated stable), ``unstable_above``
    (per interval the evaluated unstable H just above its upper end, None at ``H_hi``), the scan
    (``H``, ``rho``, ``verdict``), and ``n_undecided`` (scan points no precision decided; they count
    as not stable).
    """
    H = np.geomspace(H_lo, H_hi, n_scan)
    H[0], H[-1] = H_lo, H_hi
    ev = evaluate(system, scheme, H, policy=policy, digits=digits)
    ok = ev.stable

    def state(h):
        return evaluate(system, scheme, h, policy=policy, digits=digits).stable

    intervals, above = [], []
    start = H[0] if ok[0] else None
    for i in range(n_scan - 1):
        if ok[i] == ok[i + 1]:
            continue
        lo, hi, _ = _refine(state, H[i], H[i + 1], bool(ok[i]), rtol)
        if ok[i]:  # stable -> unstable: the interval ends at the stable side
            intervals.append([float(start), float(lo)])
            above.append(float(hi))
            start = None
        else:  # unstable -> stable: an interval starts at the stable side
            start = hi
    if start is not None:
        intervals.append([float(start), float(H[-1])])
        above.append(None)
    return {
        "intervals": intervals,
        "unstable_above": above,
        "scan": ev,
        "n_undecided": int(np.sum(ev.verdict == "undecided")),
    }


class Progress:
    """A progress bar on stderr, shown only once a scan has taken more than ``delay`` seconds and only on a terminal.

    >>> import io
    >>> p = Progress(3, stream=io.StringIO()); p(1); p(3); p.close()  # not a terminal: prints nothing
    """

    def __init__(self, total: int, *, label: str = "schemes", stream=None, delay: float = 1.0, width: int = 30):
        self.total, self.label, self.delay, self.width = total, label, delay, width
        self.stream = sys.stderr if stream is None else stream
        self.start = time.perf_counter()
        self.shown = False

    def __call__(self, done: int):
        if time.perf_counter() - self.start < self.delay or not _isatty(self.stream):
            return
        filled = int(self.width * done / max(self.total, 1))
        bar = "#" * filled + "-" * (self.width - filled)
        self.stream.write(f"\r[{bar}] {done}/{self.total} {self.label}")
        self.stream.flush()
        self.shown = True

    def close(self):
        if self.shown:
            self.stream.write("\r" + " " * (self.width + 30) + "\r")
            self.stream.flush()


def _isatty(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def check_settings(H, *, n_scan=DEFAULT_SCAN, rtol=DEFAULT_RTOL, policy="auto") -> np.ndarray:
    """``H`` (one macro step or an increasing range, in s) and the scan settings; returns ``H`` as an array."""
    if policy not in ("auto", "float64"):
        raise ParameterError(f"policy must be 'auto' or 'float64', got {policy!r}")
    H = np.atleast_1d(np.asarray(H, dtype=float))
    if H.size not in (1, 2) or not np.all(np.isfinite(H)) or not np.all(H > 0):
        raise ParameterError(f"H must be one macro step or a range H_LO H_HI, in s (> 0), got {H.tolist()}")
    if H.size == 2 and not H[0] < H[1]:
        raise ParameterError(f"H range must be increasing (H_LO < H_HI), got {H.tolist()}")
    if int(n_scan) != n_scan or n_scan < 2:
        raise ParameterError(f"scan must be an integer >= 2, got {n_scan!r}")
    if not 0 < rtol < 1:
        raise ParameterError(f"rtol must lie in (0, 1), got {rtol!r}")
    return H


def advise(
    system: TwoMassSystem,
    H,
    *,
    scheme_list=None,
    n_scan: int = DEFAULT_SCAN,
    rtol: float = DEFAULT_RTOL,
    policy: str = "auto",
    digits: int = 128,
    progress=None,
):
    """Every scheme of ``scheme_list`` (default :func:`schemes`) for ``system`` at macro step ``H`` or over
    ``H = (H_lo, H_hi)``: a :class:`pandas.DataFrame`, one row per scheme, stable ones ranked first.

    ``progress``, if given, is called with the number of schemes done.

    Columns at one H: ``rank`` (1, 2, ... for stable schemes, else missing), ``scheme``, ``coupling``,
    ``method``, ``index``, ``parameters``, ``decomposition``, ``k``, ``H``, ``rho``, ``rho_float64_error``,
    ``digits``, ``verdict``.  Over a range: ``rank``, the scheme columns, ``H_max`` (largest stable H, missing
    if none), ``H_max_from_lo`` (the largest H such that every H from ``H_lo`` up to it is stable: the
    upper end of a stable interval starting at ``H_lo``; missing if ``H_lo`` is unstable), ``unstable_above`` (the evaluated unstable H just above ``H_max``; missing where ``H_max`` is the
    range's end), ``rho_at_H_max``, ``stable_intervals``, ``verdict`` (``stable`` on the whole range, ``stable
    up to H_max``, ``stable on intervals`` when not monotone, ``unstable`` everywhere, ``undecided``) and
    ``note``.  Where the system has an Eq. (71) form, ``lr1`` and ``li1`` at the row's H.
    """
    H = check_settings(H, n_scan=n_scan, rtol=rtol, policy=policy)
    scheme_list = schemes() if scheme_list is None else list(scheme_list)
    eq71 = system.dimensionless(float(H[-1]))["eq71"] == "ok"
    rows = []
    for n, s in enumerate(scheme_list, start=1):
        base = {
            "scheme": s.label,
            "coupling": s.coupling,
            "method": s.method,
            "index": s.index,
            "parameters": s.parameter_text,
            "method_parameters": dict(s.params),
            "decomposition": s.decomposition,
            "k": s.k,
        }
        if H.size == 1:
            ev = evaluate(system, s, H, policy=policy, digits=digits)
            row = {
                **base,
                "H": float(H[0]),
                "rho": float(ev.rho[0]),
                "rho_float64_error": float(ev.err[0]),
                "digits": int(ev.digits[0]),
                "verdict": str(ev.verdict[0]),
            }
        else:
            row = {**base, **_range_row(system, s, H, n_scan, rtol, policy, digits)}
        row_H = row.get("H", row.get("H_max"))
        if eq71:
            p = system.dimensionless(row_H) if row_H is not None and np.isfinite(row_H) else {}
            row["lr1"], row["li1"] = p.get("lr1"), p.get("li1")
        rows.append(row)
        if progress is not None:
            progress(n)
    df = pd.DataFrame(rows)
    if H.size == 1:
        order = df.assign(_s=df["verdict"] != "stable").sort_values(["_s", "rho"], kind="stable").index
    else:
        # stable from the range's lower end first, by how far up; then stable on higher intervals only
        low = df["H_max_from_lo"].astype(float)
        order = (
            df.assign(
                _a=low.isna(),
                _l=-low.fillna(0.0),
                _h=-df["H_max"].astype(float).fillna(-np.inf),
                _r=df["rho_at_H_max"].astype(float),
            )
            .sort_values(["_a", "_l", "_h", "_r"], kind="stable")
            .index
        )
        df["H_max_from_lo"] = low
        df["H_max"] = df["H_max"].astype(float)
    df = df.loc[order].reset_index(drop=True)
    stable = df["verdict"] == "stable" if H.size == 1 else df["H_max"].notna()
    df.insert(0, "rank", pd.array([i + 1 if s else None for i, s in enumerate(stable)], dtype="Int64"))
    df.attrs.update(
        system=system.as_dict(),
        H=H.tolist(),
        mode="point" if H.size == 1 else "range",
        dimensionless=[system.dimensionless(h) for h in H],
        overdamped=list(system.overdamped),
        per_second=system.per_second() if eq71 else None,
        n_scan=int(n_scan) if H.size == 2 else None,
        rtol=float(rtol) if H.size == 2 else None,
        policy=policy,
        digits=int(digits),
        defaults="those not given are 1 in the paper's dimensionless form (mu_bar = mu/H = 1, a = b = 1)",
    )
    return df


def _range_row(system, s, H, n_scan, rtol, policy, digits) -> dict:
    res = stable_intervals(system, s, H[0], H[1], n_scan=n_scan, rtol=rtol, policy=policy, digits=digits)
    iv, above = res["intervals"], res["unstable_above"]
    notes = []
    if not iv:
        verdict = "undecided" if res["n_undecided"] == n_scan else "unstable"
        H_max = above_max = rho_max = None
        notes.append(f"no stable H among {n_scan} scanned in [{H[0]:.4g}, {H[1]:.4g}] s")
    else:
        H_max, above_max = iv[-1][1], above[-1]
        rho_max = float(evaluate(system, s, H_max, policy=policy, digits=digits).rho[0])
        if len(iv) == 1 and iv[0][0] == H[0]:
            verdict = "stable" if above_max is None else "stable up to H_max"
        else:
            verdict = "stable on intervals"
            notes.append(
                "not monotone in H: stable only on "
                + ", ".join(f"[{lo:.4g}, {hi:.4g}]" for lo, hi in iv)
                + " s; H_max is the upper end of the last stable interval"
            )
        if above_max is None:
            notes.append(f"stable at the range's upper end {H[1]:.4g} s (larger H not scanned)")
    if res["n_undecided"]:
        notes.append(f"{res['n_undecided']} scanned H undecided (counted as not stable)")
    from_lo = iv[0][1] if iv and iv[0][0] == H[0] else None
    return {
        "H_max": H_max,
        "H_max_from_lo": from_lo,
        "unstable_above": above_max,
        "rho_at_H_max": rho_max,
        "stable_intervals": iv,
        "verdict": verdict,
        "note": "; ".join(notes),
    }


# -- output ---------------------------------------------------------------------------------------


def _clean(value, reason: str):
    """A JSON-safe value: non-finite floats become None, with the reason recorded."""
    if isinstance(value, (float, np.floating)):
        return (float(value), None) if math.isfinite(value) else (None, reason)
    if isinstance(value, np.integer):
        return int(value), None
    if value is None or value is pd.NA:
        return None, reason
    return value, None


def advice_records(df) -> dict:
    """The answer as strict JSON-ready data (no NaN or infinity: ``null``, and a ``null_reasons`` entry per row)."""
    reasons = {
        "rank": "not stable",
        "rho": "no precision could compute it",
        "rho_float64_error": "float64 gave no finite value",
        "H_max": "no stable H in the range",
        "H_max_from_lo": "unstable at the range's lower end",
        "unstable_above": "stable up to the range's upper end",
        "rho_at_H_max": "no stable H in the range",
        "lr1": "no Eq. (71) form",
        "li1": "no Eq. (71) form",
    }
    rows = []
    for rec in df.to_dict(orient="records"):
        out, nulls = {}, {}
        for key, value in rec.items():
            v, why = _clean(value, reasons.get(key, "not available"))
            if isinstance(value, float) and key == "rho_float64_error" and not math.isfinite(value):
                why = "float64 could not decide (infinite estimate)"
            out[key] = v
            if v is None and why:
                nulls[key] = why
        if nulls:
            out["null_reasons"] = nulls
        rows.append(out)
    attrs = {k: v for k, v in df.attrs.items()}
    return {**_jsonable(attrs), "schemes": rows}


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    v, _ = _clean(x, "")
    return v


def advice_text(df) -> str:
    """The answer as text: the system, its dimensionless parameters, then the schemes (stable ones ranked first)."""
    a = df.attrs
    s = a["system"]
    lines = [
        f"Two-mass system: m1 = {s['m1']:g} kg, m2 = {s['m2']:g} kg, c1 = {s['c1']:g} N/m, c2 = {s['c2']:g} N/m, "
        f"d1 = {s['d1']:g} N s/m, d2 = {s['d2']:g} N s/m"
    ]
    for p in a["dimensionless"]:
        head = f"at H = {p['H']:g} s: "
        coeff = (
            f"k1 = {p['k1']:.4g}, delta1 = {p['delta1']:.4g}, k2 = {p['k2']:.4g}, delta2 = {p['delta2']:.4g}, "
            f"am21 = {p['am21']:.4g}"
        )
        if p["eq71"] == "ok":
            lines.append(
                f"Eq. (71) {head}lr1 = {p['lr1']:.4g}, li1 = {p['li1']:.4g}, am21 = {p['am21']:.4g}, "
                f"alr21 = {p['alr21']:.4g}, ali21 = {p['ali21']:.4g}  ({coeff})"
            )
        else:
            lines.append(f"Eq. (71) has no real form: {p['eq71']}; coefficients {head}{coeff}")
    if a["per_second"]:
        ps = a["per_second"]
        lines.append(
            f"(lr1 = {ps['lr1_per_H']:.4g} 1/s * H, li1 = {ps['li1_per_H']:.4g} 1/s * H; the ratios do not depend on H)"
        )
    lines.append(f"Method parameters: {a['defaults']}.")
    prec = "float64, rechecked with mpmath at {} digits where float64 cannot decide".format(a["digits"])
    if a["policy"] == "float64":
        prec = "float64 only (points float64 cannot decide are 'undecided')"
    n_stable = int(df["rank"].notna().sum())
    if a["mode"] == "point":
        lines.append(
            f"\n{len(df)} schemes at H = {a['H'][0]:g} s, {n_stable} stable, ranked by rho (smaller: a coupling "
            f"error decays faster per macro step). Precision: {prec}."
        )
        table = df[["rank", "scheme", "rho", "verdict", "digits"]].copy()
        table["rho"] = table["rho"].map(lambda r: f"{r:.6f}" if math.isfinite(r) else "nan")
        table["digits"] = table["digits"].map(
            lambda d: "float64" if d == FLOAT64_DIGITS else f"mp {d}" if d > 0 else "failed"
        )
        table = table.rename(columns={"digits": "decided by"})
    else:
        lo, hi = a["H"]
        lines.append(
            f"\n{len(df)} schemes over H in [{lo:g}, {hi:g}] s, {n_stable} stable somewhere in it, ranked: "
            "first those stable from the range's lower end, by how far up they stay stable, then those stable only "
            "on higher intervals, by their largest stable H. Scan: {a['n_scan']} log-spaced H, then every stable/unstable "
            f"transition bracketed to a relative width of {a['rtol']:g}; stable intervals narrower than the scan "
            f"spacing can be missed. Precision: {prec}."
        )
        table = df[["rank", "scheme", "H_max", "stable_intervals", "verdict"]].copy()
        table["H_max"] = table["H_max"].map(lambda h: "-" if not np.isfinite(h) else f"{h:.6g}")
        table["stable_intervals"] = table["stable_intervals"].map(
            lambda iv: " and ".join(f"[{lo:.4g}, {hi:.4g}]" for lo, hi in iv) or "-"
        )
        table = table.rename(columns={"H_max": "largest stable H [s]", "stable_intervals": "stable for H in [s]"})
        lines.append(
            f"A largest stable H equal to {hi:g} s means stable at the range's upper end (larger H not scanned); "
            "'stable on intervals': not stable at every H below it."
        )
    table["rank"] = table["rank"].map(lambda r: "-" if r is None or r is pd.NA else str(r))
    table = table.astype(str)
    widths = {c: max(len(c), *(len(v) for v in table[c])) for c in table.columns}
    left = {c: (lambda w: lambda v: f"{v:<{w}}")(widths[c]) for c in table.columns}
    lines += [line.rstrip() for line in table.to_string(index=False, justify="left", formatters=left).splitlines()]
    return "\n".join(lines)
