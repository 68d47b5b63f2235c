"""The system, the configurations and one evaluation: what :func:`icosim.advise.advise` is built from.

:class:`TwoMassSystem` (physical units), :class:`Configuration` (method, index, parameters in physical units,
decomposition, k, coupling order), :func:`configurations` (every configuration of the method registry) and
:func:`evaluate` (the spectral radius of one configuration at many H, with the precision policy and a verdict).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..engine import methods as _methods
from ..engine.bounds import check_k
from ..engine.schemes import get_scheme, standard_schemes
from ..engine.spectral.policy import spectral_radius
from ..engine.stages import couples
from ..errors import ParameterError
from ..problems.linear.family import TwoMass
from ..problems.linear.model import PhysicalModel

__all__ = [
    "TwoMassSystem",
    "Configuration",
    "Evaluation",
    "VERDICTS",
    "DEFAULT_K",
    "configurations",
    "index_parameters",
    "evaluate",
]

#: Approximation orders scanned unless others are asked for.
DEFAULT_K = (0, 1, 2)

#: Coupling orders: name -> keyword arguments of :func:`icosim.problems.linear.spectral.spectral_radius`: the Jacobi
#: (parallel) scheme of the paper and Gauss-Seidel (sequential) with subsystem 1 or subsystem 2 first
#: (:mod:`icosim.engine.schemes`); the variants are ranked when asked for.

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

    def family(self, H, decomposition, k: int) -> TwoMass:
        """The points at macro step(s) ``H`` for the spectral analysis (:func:`evaluate`)."""
        return TwoMass(self.model(H), decomposition, k)

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
class Configuration:
    """One co-simulation configuration: method (registry name), index, parameters, decomposition, k and coupling
    scheme (:mod:`icosim.engine.schemes`).

    ``params`` are the method's parameters as the user gives them: physical
    units for parameters that scale with ``H`` (``mu`` in s), or their
    dimensionless form under ``<name>_bar`` (``mu_bar = mu/H``).
    """

    method: str
    index: int
    params: dict
    decomposition: str
    k: int
    scheme: str = "jacobi"

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
        tail = "" if self.scheme == "jacobi" else f" {self.scheme}"
        return f"{head}{f' ({params})' if params else ''} {self.decomposition} k={self.k}{tail}"


def _scaled() -> dict:
    return {name: p for name, p in _methods.parameters().items() if p.scaling}


def index_parameters(spec, index, given: dict) -> dict:
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


def configurations(
    *,
    methods=None,
    decompositions=None,
    k=DEFAULT_K,
    params: dict | None = None,
    schemes=None,
) -> list[Configuration]:
    """Every configuration: each method of the registry (or those named), each index, decomposition and ``k``.

    ``params`` are method parameters by name in physical units (``{"mu": 5e-3, "a": 0.5}``); each
    method takes those it has.  Every configuration is built once here, so a parameter value a method
    refuses is reported (:class:`~icosim.errors.ParameterError`) before any computation.

    >>> len(configurations(schemes=["jacobi"]))  # Baumgarte, weighted: 3 indices x (ff, fd, df); projection: ff, fd, df, dd; k = 0..2
    66
    >>> len(configurations())  # and each with the three schemes that are not variants (Jacobi, Gauss-Seidel 1->2 and 2->1)
    198
    >>> configurations(methods=["weighted"], k=[2])[4].label
    'weighted i1 (a = 1, b = 1) fd k=2 gauss-seidel-12'
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
    ks = sorted({check_k(v) for v in k})
    schemes = list(standard_schemes()) if schemes is None else [get_scheme(s).name for s in schemes]
    out = []
    for name in names:
        spec = _methods.get_spec(name)
        decs = [d for d in spec.decompositions if decompositions is None or d in decompositions]
        for index in spec.indices:
            p = index_parameters(spec, index, params)
            for dec in decs:
                for kk in ks:
                    for scheme in (name for name in schemes if couples(get_scheme(name), dec)):
                        s = Configuration(name, index, p, dec, kk, scheme)
                        s.engine_method(1.0)  # refuses bad values now (e.g. weighted index 1 with b = 0)
                        out.append(s)
    return out


@dataclass
class Evaluation:
    """Spectral radius per H of one configuration, the verdict, and the arithmetic that decided it."""

    H: np.ndarray
    rho: np.ndarray
    err: np.ndarray
    digits: np.ndarray
    verdict: np.ndarray = field(default=None)
    arithmetic: np.ndarray = field(default=None)

    @property
    def stable(self) -> np.ndarray:
        return self.verdict == "stable"


def evaluate(system: TwoMassSystem, configuration: Configuration, H, *, policy="auto", digits=128) -> Evaluation:
    """``rho`` of ``configuration`` at every macro step in ``H`` (``system`` a :class:`TwoMassSystem`, or any object
    whose ``family(H, decomposition, k)`` gives the points, a chain's too): one batched call, or one per H where the engine's
    parameters change with it (a Baumgarte ``mu`` in s).

    The verdict is the precision policy's (:func:`icosim.problems.linear.spectral.spectral_radius`): ``stable``,
    ``unstable`` (float64 trusted, or proven in ball arithmetic), ``marginal`` (the proven enclosure
    contains 1), or ``undecided``: nothing could compute the point, or (policy ``float64``) float64
    could not decide it.
    """
    H = np.atleast_1d(np.asarray(H, dtype=float))
    kw = {"digits": digits, "policy": policy, "scheme": configuration.scheme}
    names = ("rho", "err", "digits", "verdict", "arithmetic")
    c = configuration
    if c.h_dependent:
        parts = [spectral_radius(system.family(h, c.decomposition, c.k), c.engine_method(h), **kw) for h in H]
        rho, err, dig, verdict, arithmetic = (
            np.concatenate([np.atleast_1d(getattr(r, n)) for r in parts]) for n in names
        )
    else:
        r = spectral_radius(system.family(H, c.decomposition, c.k), c.engine_method(), **kw)
        rho, err, dig, verdict, arithmetic = (np.atleast_1d(np.asarray(getattr(r, n))) for n in names)
    if policy == "float64":  # no recheck: what float64 cannot decide stays undecided
        untrusted = ~(np.isfinite(rho) & (np.abs(rho - 1) > err))
        verdict = np.where(untrusted, "undecided", verdict)
    return Evaluation(H, rho, err, dig, verdict.astype(str), arithmetic.astype(str))
