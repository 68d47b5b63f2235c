"""Names of the pendulum's runs, stored series and coupling variables (see docs/pendulum.md)."""

from __future__ import annotations

from ...engine.decompositions import get_decomposition
from ...engine.schemes import get_scheme

__all__ = ["coupling_variables", "TRADE_FIGURE_DATASETS", "VARIABLES", "run_name"]

#: The joint's two components of each kind of coupling variable: the joint force or the joint acceleration.
_JOINT = {"force": ("lambda_cax", "lambda_cay"), "acceleration": ("a_tilde_x", "a_tilde_y")}


def coupling_variables(decomposition) -> tuple[str, ...]:
    """Names of the pendulum's coupling variables for a decomposition: two per coupling variable of the
    decomposition (:class:`icosim.engine.decompositions.Decomposition`), its x and y components.

    >>> coupling_variables("fd")
    ('lambda_cax', 'lambda_cay', 'a_tilde_x', 'a_tilde_y')
    """
    dec = get_decomposition(decomposition)
    return tuple(name for j in range(dec.n_coupling) for name in _JOINT[dec.variable_kind(j)])


#: Time series of every dataset: name -> (units, long name).
VARIABLES = {
    "phi1": ("rad", "angle of link 1"),
    "phi2": ("rad", "angle of link 2"),
    "g_cax": ("m", "joint constraint g_cax = (x_S1 + l1/2 cos phi1) - (x_S2 - l2/2 cos phi2)"),
    "g_cay": ("m", "joint constraint g_cay = (y_S1 + l1/2 sin phi1) - (y_S2 - l2/2 sin phi2)"),
    "lambda_cax": ("N", "joint force of link 1 on link 2, x"),
    "lambda_cay": ("N", "joint force of link 1 on link 2, y"),
}


#: The speed-accuracy figures (icosim.figures.pendulum_trade.TRADE_FIGURES): name -> the datasets
#: it draws, as stems under results/pendulum/, in the figure function's argument order.
TRADE_FIGURE_DATASETS = {
    "work_precision": ("work_precision", "adaptive"),
    "error_over_H": ("work_precision",),
    "stability_limit": ("stability_limit",),
    "tolerance": ("tolerance",),
    "adaptive": ("adaptive",),
}


# -- datasets, summary and claims ------------------------------------------------------
def run_name(method: str, decomposition: str, k: int, scheme="jacobi") -> str:
    """Name of a run: ``{method}_{decomposition}_k{k}`` (Jacobi, the paper's), with the scheme's name added otherwise.

    >>> run_name("weighted", "fd", 2), run_name("projection", "dd", 0, "gauss-seidel-21")
    ('weighted_fd_k2', 'projection_dd_k0_gauss-seidel-21')
    """
    name = get_scheme(scheme).name
    return f"{method}_{decomposition}_k{k}" + ("" if name == "jacobi" else f"_{name}")
