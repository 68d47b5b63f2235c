"""The error estimate and the PI step-size controller of adaptive macro steps.

**Error estimate.**  The predictor extrapolates the coupling variables with a
polynomial of degree ``k`` (Eq. 9); the corrector computes them from the
coupling conditions.  Their difference ``e_c - e_p`` is the extrapolation
error: for exact samples of a smooth ``e(t)`` on equidistant nodes it is
``H^(k+1) e^(k+1)(T_N)`` to leading order (the Lagrange remainder at
``tau = 1`` with nodes ``0, -1, ..., -k``: ``prod (1 + j) / (k+1)! = 1``), so the
estimate scales like ``H^(k+1)`` (:func:`pc_estimate`, tested against that
constant).  Its norm is ``max_j |e_c,j - e_p,j| / (tol (1 + |e_c,j|))`` (the
coupling variables in the problem's units; SI for the pendulum: N and m/s^2).

**Controller.**  A PI controller (:class:`StepController`; Gustafsson's
controller as given by Hairer & Wanner, *Solving ODEs I*, Sect. IV.2, Eq. 2.43c)
with step rejection: ``H_new = H * safety * err^(-beta1/p) * err_prev^(beta2/p)``
with ``p = k + 1``, limited to ``[fac_min, fac_max] H`` and to
``[H_min, H_max]``; no growth right after a rejection; a rejected step is
retried with ``H * max(fac_min, safety * err^(-1/p))``.  How the two drive a
run: :mod:`icosim.engine.control.driver`.  The estimate measures accuracy, not
stability: where the step a tolerance asks for lies beyond the macro step's
stability limit, the mode that grows there raises the estimate and the
controller holds the steps about that limit, whatever the tolerance (the error
is then smaller than the tolerance asks; docs/fmi.md, "Controlled macro steps").

**Power residual (ECCO).**  For a power bond -- a joint whose two sides
exchange a force and a velocity -- energy conservation says that the power one
side receives is the power the other gives: ``f_a . v_a + f_b . v_b = 0`` with
``f`` the coupling force on each side and ``v`` its velocity at the joint.  Its
residual at a communication point, times the step, is the energy residual
``E_j = |f_a . v_a + f_b . v_b| H`` of bond ``j``; Sadjina et al. (2016/2019,
"Energy conservation and power bonds in co-simulations") size the steps by it
(ECCO).  :func:`power_residual_estimate` is its norm as libcosim computes it
(``ecco_algorithm.cpp``): ``sqrt(mean_j (E_j / (atol + rtol max_j E_j))^2)``.
ECCO's PI controller ``H_new = H * safety * err^-(k_I + k_P) * err_prev^k_P``
is :class:`StepController` with ``order = 1``, ``beta1 = k_I + k_P`` and
``beta2 = k_P`` (:func:`ecco_controller`).

The estimates a controlled run may use are :data:`ESTIMATES`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from ...errors import ParameterError

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["ESTIMATES", "StepController", "ecco_controller", "pc_estimate", "power_residual_estimate"]


@dataclass(frozen=True)
class StepController:
    """PI step-size controller with rejection, for an error estimate that scales like ``H^order``.

    >>> c = StepController(order=2, H_max=1.0)
    >>> c.accepts(0.5), c.accepts(2.0), c.accepts(float("nan"))
    (True, False, False)
    >>> round(c.after_reject(0.1, 4.0), 15)  # 0.1 * 0.9 * 4^(-1/2)
    0.045
    >>> c.after_accept(0.1, 0.0, None)  # an error of zero: the largest growth
    0.2
    """

    order: int
    safety: float = 0.9
    fac_min: float = 0.2
    fac_max: float = 2.0
    beta1: float = 0.7
    beta2: float = 0.4
    H_min: float = 1e-6
    H_max: float = math.inf

    def __post_init__(self) -> None:
        if not (isinstance(self.order, int) and self.order >= 1):
            raise ParameterError(f"controller order must be an integer >= 1, got {self.order!r}")
        if not (0 < self.safety <= 1 and 0 < self.fac_min < 1 < self.fac_max):
            raise ParameterError("controller needs 0 < safety <= 1 and 0 < fac_min < 1 < fac_max")
        if not (self.beta1 > 0 and self.beta2 >= 0):
            raise ParameterError("controller needs beta1 > 0 and beta2 >= 0")
        if not (0 < self.H_min < self.H_max):
            raise ParameterError(f"controller needs 0 < H_min < H_max, got {self.H_min!r}, {self.H_max!r}")

    @staticmethod
    def accepts(err: float) -> bool:
        """A step is accepted when its error norm is at most 1 (never when it is not a number)."""
        return bool(err <= 1.0)

    def _clip(self, H: float) -> float:
        return min(max(H, self.H_min), self.H_max)

    def after_accept(self, H: float, err: float, err_prev: float | None, *, after_reject: bool = False) -> float:
        """Size of the next step after an accepted one with error ``err`` (the step before: ``err_prev``)."""
        p = self.order
        if err <= 0:
            fac = self.fac_max
        else:
            fac = self.safety * err ** (-self.beta1 / p)
            if err_prev is not None and self.beta2 > 0:
                fac *= max(err_prev, 1e-4) ** (self.beta2 / p)
        fac = min(max(fac, self.fac_min), self.fac_max)
        if after_reject:
            fac = min(fac, 1.0)
        return self._clip(H * fac)

    def after_reject(self, H: float, err: float) -> float:
        """Size of the retry after a rejected step with error ``err`` (inf or NaN: the largest cut)."""
        fac = self.safety * err ** (-1.0 / self.order) if math.isfinite(err) else self.fac_min
        return max(H * min(max(fac, self.fac_min), self.safety), self.H_min)


def pc_estimate(e_corrected: npt.ArrayLike, e_predicted: npt.ArrayLike, tol: float) -> float:
    """Norm of the predictor-corrector difference: ``max |e_c - e_p| / (tol (1 + |e_c|))``."""
    e_c = np.asarray(e_corrected, float)
    d = np.abs(e_c - np.asarray(e_predicted, float))
    return float(np.max(d / (tol * (1.0 + np.abs(e_c)))))


def power_residual_estimate(residuals: npt.ArrayLike, H: float, absolute: float, relative: float) -> float:
    """ECCO's error norm of power residuals ``r_j`` (W) over a step ``H``: the energy residuals ``E_j = |r_j| H``
    scaled as libcosim scales them, ``sqrt(mean_j (E_j / (absolute + relative max_j E_j))^2)`` (``absolute`` in J).

    >>> power_residual_estimate([2.0, -1.0], 0.5, 0.5, 0.0)  # E = 1, 0.5 against 0.5 J
    1.5811388300841898
    """
    E = np.abs(np.asarray(residuals, float)) * float(H)
    level = float(np.max(E))
    return float(np.sqrt(np.mean((E / (absolute + relative * level)) ** 2)))


def ecco_controller(
    *,
    safety: float,
    fac_min: float,
    fac_max: float,
    proportional_gain: float,
    integral_gain: float,
    H_min: float,
    H_max: float,
) -> StepController:
    """ECCO's PI controller (``safety * err^-(k_I + k_P) * err_prev^k_P``, the factor limited to
    ``[fac_min, fac_max]``) as a :class:`StepController` of order 1.

    >>> c = ecco_controller(safety=0.99, fac_min=0.2, fac_max=1.5, proportional_gain=0.2, integral_gain=0.15,
    ...                     H_min=1e-5, H_max=1e-2)
    >>> (c.order, c.beta1, c.beta2)
    (1, 0.35, 0.2)
    >>> round(c.after_accept(1e-4, 0.5, 0.8), 12) == round(1e-4 * 0.99 * 0.5 ** -0.35 * 0.8**0.2, 12)
    True
    """
    return StepController(
        order=1,
        safety=safety,
        fac_min=fac_min,
        fac_max=fac_max,
        beta1=integral_gain + proportional_gain,
        beta2=proportional_gain,
        H_min=H_min,
        H_max=H_max,
    )


#: The error estimates of a controlled run: name -> what it measures (read-only).
ESTIMATES = MappingProxyType(
    {
        "predictor-corrector": "the corrector's coupling variables against the predictor's (pc_estimate), "
        "of order k + 1 in H",
        "power-residual": "ECCO's: the power residual of each joint at the step's end times H (power_residual_estimate)",
    }
)
