"""The check kinds of every part in one table, and the claims functions bound to it.

Each part defines its kinds in its own ``checks`` module; this registry imports
them all (as scipy's ``solve_ivp`` keeps its ``METHODS`` table), so the generic
machinery in :mod:`icosim.verdicts` needs to import no part and no part needs to
register itself.

===========================================  ==========================================================
module                                       check kinds
===========================================  ==========================================================
:mod:`icosim.studies.stability.checks`       ``stable_fraction``, ``compare``, ``trend``, ``pointwise``
:mod:`icosim.studies.convergence.checks`     ``convergence_order``
:mod:`icosim.studies.pendulum.checks`        ``pendulum_stability``
:mod:`icosim.studies.fmi.checks`             ``fmi_bound``, ``fmi_orders``
:mod:`icosim.studies.chains.checks`          ``chain_two_unit``, ``chain_order``, ``chain_trend``, ``chain_placement``
:mod:`icosim.studies.signals.checks`         ``signals_order``, ``signals_growth``, ``signals_ratio``
:mod:`icosim.studies.peers.checks`           ``peers_order``, ``peers_agree``
===========================================  ==========================================================

>>> sorted(CHECKS)
['chain_order', 'chain_placement', 'chain_trend', 'chain_two_unit', 'compare', 'convergence_order', 'fmi_bound', 'fmi_orders', 'peers_agree', 'peers_order', 'pendulum_stability', 'pointwise', 'signals_growth', 'signals_order', 'signals_ratio', 'stable_fraction', 'trend']
"""

from __future__ import annotations

from .. import verdicts as _claims
from ..studies.chains import checks as _chains
from ..studies.convergence import checks as _convergence
from ..studies.fmi import checks as _fmi
from ..studies.peers import checks as _peers
from ..studies.pendulum import checks as _pendulum
from ..studies.signals import checks as _signals
from ..studies.stability import checks as _stability
from ..verdicts import Claim, Verdict

__all__ = ["CHECKS", "DEFAULTS", "parse_claims", "load_claims", "evaluate_claim", "evaluate", "describe_claim"]

#: check kind -> :class:`icosim.verdicts.CheckKind`, for every part.
CHECKS = {**_stability.CHECKS, **_convergence.CHECKS, **_pendulum.CHECKS, **_fmi.CHECKS, **_chains.CHECKS,
          **_signals.CHECKS, **_peers.CHECKS}  # fmt: skip

#: A claim is about the paper's coupling scheme, Jacobi, unless a selector names another.
DEFAULTS = {"scheme": "jacobi"}


def parse_claims(items, *, where: str = "claims") -> list[Claim]:
    """:func:`icosim.verdicts.parse_claims` with every part's check kinds."""
    return _claims.parse_claims(items, CHECKS, where=where)


def load_claims(path, key: str = "claims") -> list[Claim]:
    """:func:`icosim.verdicts.load_claims` with every part's check kinds."""
    return _claims.load_claims(path, CHECKS, key=key)


def evaluate_claim(claim: Claim, datasets) -> Verdict:
    return _claims.evaluate_claim(claim, datasets, CHECKS, DEFAULTS)


def evaluate(claims, datasets) -> list[Verdict]:
    """One :class:`~icosim.verdicts.Verdict` per claim, with every part's check kinds and :data:`DEFAULTS`."""
    return _claims.evaluate(claims, datasets, CHECKS, DEFAULTS)


def describe_claim(claim: Claim) -> dict:
    """:func:`icosim.verdicts.describe_claim` with every part's check kinds."""
    return _claims.describe_claim(claim, CHECKS)
