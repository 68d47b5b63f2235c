"""The convergence experiment: physical model, initial conditions, end time, step sizes, methods.

The step sizes are ``H = end_time / N_total`` for whole numbers of macro steps;
method parameters are given in physical units and scaled to the engine's
dimensionless ones by the registry (:mod:`icosim.engine.methods`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...engine.methods import METHODS, UNIT_TEXT, get_spec, parameters
from ...errors import ParameterError
from ...problems.linear.model import PhysicalModel

__all__ = [
    "PAPER_MODEL",
    "Setup",
    "step_counts",
    "oscillation_summary",
    "dimensional_method",
    "method_attrs",
    "units_summary",
    "units_description",
]


#: Physical parameters of the test model in Sect. 3.7.
PAPER_MODEL = {"m1": 1.0, "m2": 2.0, "c1": 1000.0, "c2": 1000.0, "d1": 10.0, "d2": 10.0}


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


def dimensional_method(name: str, H: float, **params):
    """The coupling method at macro step ``H`` from dimensional parameters.

    The parameters are given in physical units as in Sect. 3.7 (their units
    and H scaling are in the registry, :data:`icosim.engine.methods.METHODS`:
    Baumgarte's ``mu``, ``beta`` in s, ``gamma`` in s^2, index 1
    ``beta = 2 mu``, ``gamma = mu^2``) and scaled to the engine's
    dimensionless ones, ``beta_bar = beta / H``, ``gamma_bar = gamma / H^2``
    (``mu_bar = mu / H``).  Dimensionless parameters (the weighted multiplier's
    ``a``, ``b``) are passed as they are.

    >>> dimensional_method("baumgarte", 1e-3, index=1, mu=5e-3).params["beta"]
    10.0
    """
    spec = get_spec(name)
    return spec.make(**spec.engine_params(params, H))


def method_attrs(name: str, **params) -> dict:
    """Method parameters under their command-line names, dimensional (s, s^2) as given."""
    return dict(dimensional_method(name, 1.0, **params).params)


def _unit_groups() -> dict:
    groups = {}
    for name, p in parameters().items():
        groups.setdefault(p.unit, []).append(name)
    return groups


def units_summary() -> str:
    """The units of every method parameter in one phrase, e.g. ``mu and beta in s, ..., a and b dimensionless``."""
    groups = _unit_groups()
    parts = [f"{' and '.join(names)} in {UNIT_TEXT[unit]}" for unit, names in groups.items() if unit != "1"]
    if "1" in groups:
        parts.append(f"{' and '.join(groups['1'])} dimensionless")
    return ", ".join(parts)


def units_description() -> str:
    """The ``method_parameters_units`` attribute of a panel dataset: dimensional, and what the engine uses."""
    groups = _unit_groups()
    dimensional = ", ".join(f"{' and '.join(n)} in {UNIT_TEXT[u]}" for u, n in groups.items() if u != "1")
    owners = [s.label for s in METHODS.values() if any(p.unit != "1" for p in s.parameters)]
    engine = ", ".join(
        f"{n}_bar = {n}/H" + (f"^{p.scaling}" if p.scaling != 1 else "")
        for n, p in parameters().items()
        if p.scaling and not p.shorthand
    )
    return (
        f"dimensional: {dimensional} ({', '.join(owners)}, Sect. 3.7); {', '.join(groups.get('1', []))} "
        f"dimensionless; the engine uses {engine}"
    )
