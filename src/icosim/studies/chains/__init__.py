"""The chain study (``docs/chain_study.md``): N units joined by rigid joints in a row, beyond the paper's two.

``config`` (the study as configured, checked before any work), ``stability`` (rho over H and the largest stable
H against the number of units), ``convergence`` (errors and orders against the two-unit case), ``placement``
(where a heavy or stiff unit sits), ``checks`` (the check kinds of ``config/claims/chains.yaml``).
"""
