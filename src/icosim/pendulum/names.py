"""Names of the pendulum's runs, stored series and coupling variables (see docs/pendulum.md)."""

from __future__ import annotations

__all__ = ["COUPLING_VARIABLES", "VARIABLES", "run_name"]


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


# -- datasets, summary and claims ------------------------------------------------------
def run_name(method: str, decomposition: str, k: int) -> str:
    """File stem of a run: ``{method}_{decomposition}_k{k}``."""
    return f"{method}_{decomposition}_k{k}"
