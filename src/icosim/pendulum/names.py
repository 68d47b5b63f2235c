"""Names of the pendulum's runs, stored series and coupling variables (see docs/pendulum.md)."""

from __future__ import annotations

from ..engine.schemes import get_scheme

__all__ = ["COUPLING_VARIABLES", "TRADE_FIGURE_DATASETS", "VARIABLES", "run_name"]


#: Names of the coupling variables per decomposition.
COUPLING_VARIABLES = {
    "ff": ("lambda_cax", "lambda_cay"),
    "fd": ("lambda_cax", "lambda_cay", "a_tilde_x", "a_tilde_y"),
    "dd": ("a_tilde_x", "a_tilde_y"),
}


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
    """File stem of a run: ``{method}_{decomposition}_k{k}`` (Jacobi), with ``_gs12``/``_gs21`` for Gauss-Seidel.

    >>> run_name("weighted", "fd", 2), run_name("projection", "dd", 0, "gauss-seidel-21")
    ('weighted_fd_k2', 'projection_dd_k0_gs21')
    """
    suffix = get_scheme(scheme).suffix
    return f"{method}_{decomposition}_k{k}" + (f"_{suffix}" if suffix else "")
