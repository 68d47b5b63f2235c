"""The chain study's section of the report: what was computed, the largest stable macro steps against the number
of units, the orders against the two-unit case, the place of a heavy or stiff unit, and the part's claims.

Everything shown comes from the datasets the workflow wrote (``results/chains/*.nc``,
:mod:`icosim.studies.chains`) and the claim verdicts; nothing is computed again here.
"""

from __future__ import annotations

from ..verdicts import verdict_counts
from . import html as rp
from .claims import claims_table

__all__ = ["chains_section", "order_rows", "limit_counts"]

esc = rp.escape
_num = rp.number


def limit_counts(stability) -> dict:
    """How many searches ended how (``status`` -> count)."""
    out: dict = {}
    for s in stability["status"].values.ravel().tolist():
        out[str(s)] = out.get(str(s), 0) + 1
    return out


def order_rows(convergence) -> list:
    """One row per convergence curve: N, method, k, scheme, error at the smallest H, order and its status."""
    rows = []
    for n in convergence["n_units"].values.tolist():
        for method in convergence["method"].values.tolist():
            for k in convergence["k"].values.tolist():
                for scheme in convergence["scheme"].values.tolist():
                    sel = {"n_units": n, "method": method, "k": k, "scheme": scheme}
                    err = convergence["error"].sel(sel).values
                    rows.append(
                        [
                            str(n),
                            esc(method),
                            str(k),
                            esc(scheme),
                            _num(err[0]),
                            _num(convergence["order"].sel(sel), ".3f"),
                            esc(str(convergence["order_status"].sel(sel).values)),
                        ]
                    )
    return rows


def chains_section(*, stability, convergence, placement, claims, figures: dict) -> str:
    """The section as an HTML fragment (``id="chains"``); ``figures``: part -> its PNG."""
    n = verdict_counts(claims)
    counts = limit_counts(stability)
    N = ", ".join(str(v) for v in stability["n_units"].values.tolist())
    intro = (
        "<p>Chains of N units joined by rigid joints in a row (docs/chain_study.md), beyond the paper's two. "
        f"Stability: the spectral radius ρ of the whole chain over a geometric scan of H and the largest stable H "
        f"(ρ + its float64 error estimate &lt; 1, bisected to a relative resolution of {stability.attrs['resolution']:g}) "
        f"for N = {esc(N)}; searches: "
        + ", ".join(f"{c} {esc(s)}" for s, c in sorted(counts.items()))
        + ". Convergence: Eq. (72) against the exact monolithic solution over H, the order read off the "
        "smallest-H decade. Placement: one unit of a "
        f"{placement.attrs['n_units']}-unit chain made {esc(placement.attrs['variants'])} at the first, middle or "
        "last place. "
        f"Claims: {n['pass']} pass, {n['fail']} fail, {n['undecided']} undecided.</p>"
    )
    parts = []
    captions = {
        "stability": "Largest stable macro step against the number of units.",
        "convergence": "Eq. (72) error over H; the legend gives each curve's order.",
        "placement": "Largest stable macro step against the place of the changed unit.",
    }
    for part, png in figures.items():
        parts.append(rp.figure(png, esc(captions[part]), alt=f"chain {part}", anchor=rp.figure_anchor("chains", png)))
    orders = rp.table(
        ["N", "method", "k", "scheme", "error at the smallest H", "order", "status"],
        order_rows(convergence),
        raw_columns=tuple(range(7)),
    )
    body = (
        intro
        + "".join(parts)
        + "<h3>Orders over H</h3>"
        + orders
        + "<h3>Claims</h3>"
        + claims_table(claims, part="chains")
    )
    return rp.section("Chains: N units joined in a row", body, "chains")
