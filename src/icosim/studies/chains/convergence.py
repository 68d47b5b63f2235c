"""Convergence of chains against the two-unit case: the error of Eq. (72) against the exact monolithic solution
over the macro step, and the order read off it, per number of units, method, ``k`` and scheme.

Every run starts from the exact solution (:func:`~icosim.problems.linear.chain.chain_start`: every mass
displaced by ``x0`` at rest, the coupling history the exact coupling variables) and runs over ``t_end``; the
error is Eq. (72)'s normalised root-mean-square error of every mass's position and velocity at every macro
step against :class:`~icosim.problems.linear.chain.ChainSolution`.  The order is read off the smallest-H decade
and counts only where it is asymptotic (:func:`icosim.order_fit.asymptotic_order`).
"""

from __future__ import annotations

import itertools

import numpy as np

from ...engine.run import simulate
from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from ...order_fit import asymptotic_order
from ...problems.linear.chain import ChainSolution, chain_start
from .config import build_chain, method_of, scheme_name

__all__ = ["nrmse", "exact_samples", "run_errors", "convergence_data"]


def nrmse(reference, numerical) -> float:
    """Eq. (72): ``sqrt(sum_j sum_N (ref - num)^2 / sum_j sum_N (ref - mean_N ref)^2)`` over samples (axis 0)
    and variables (axis 1); NaN where the numerical values are not finite."""
    ref, num = np.asarray(reference, dtype=float), np.asarray(numerical, dtype=float)
    if not np.all(np.isfinite(num)):
        return float("nan")
    return float(np.sqrt(np.sum((ref - num) ** 2) / np.sum((ref - ref.mean(axis=0)) ** 2)))


def exact_samples(chain, *, t_end: float, x0: float):
    """The exact solution of ``chain`` (scalar ``H``) from every mass at ``x0`` at rest: the
    :class:`~icosim.problems.linear.chain.ChainSolution` and Eq. (72)'s reference, every mass's position and
    velocity at the macro steps ``1 .. round(t_end / H)`` (``(steps, 2 N n)``).  It rests on neither method, ``k``
    nor scheme: computed once per chain and step size."""
    n_all = chain.n_segments * chain.n_masses
    solution = ChainSolution(chain, np.full(n_all, float(x0)), np.zeros(n_all))
    steps = max(1, int(round(t_end / float(chain.H))))
    exact = solution.state(np.arange(1, steps + 1, dtype=float))
    return solution, np.concatenate([exact["x"], exact["v"]], axis=-1)


def run_errors(chain, method, k: int, scheme: str, exact: list) -> np.ndarray:
    """Eq. (72) of the runs of ``chain`` at each of its ``H`` (an array), in one batched run of as many macro
    steps as the smallest ``H`` takes; each point compared over its own ``round(t_end / H)`` steps.  ``exact``:
    :func:`exact_samples` of each point.  A point that leaves the batched run before its own last step (the
    run stops where any point's state is not finite) is run alone."""
    problem = chain.problem(k)
    starts = [chain_start(problem, solution) for solution, _ in exact]
    state, history = (np.stack([s[i] for s in starts]) for i in (0, 1))
    steps = max(len(ref) for _, ref in exact)
    with np.errstate(all="ignore"):
        traj = simulate(problem, method, state, history, steps, scheme=scheme)
    H, m = np.atleast_1d(chain.H), chain.n_masses
    errors = np.full(H.size, np.nan)
    for j, (solution, ref) in enumerate(exact):
        n = len(ref)
        if len(traj.states) > n:
            S = np.array([s[j] for s in traj.states[1 : n + 1]])
        else:
            alone = solution.chain.problem(k)
            with np.errstate(all="ignore"):
                S = np.array(simulate(alone, method, *chain_start(alone, solution), n, scheme=scheme).states[1:])
        numerical = np.concatenate([S[..., :m].reshape(n, -1), S[..., m:].reshape(n, -1)], axis=-1)
        errors[j] = nrmse(ref, numerical)
    return errors


def convergence_data(cfg: dict, *, command: str = "", log=None) -> DatasetDict:
    """The convergence dataset of ``cfg`` (``config/chains.yaml``'s ``chains``)."""
    cv, methods = cfg["convergence"], cfg["methods"]
    H = np.sort(np.asarray(cv["H"], dtype=float))
    dims = {
        "n_units": list(cv["n_units"]),
        "method": list(cv["methods"]),
        "k": list(cv["k"]),
        "scheme": list(cv["schemes"]),
    }
    shape = tuple(len(v) for v in dims.values())
    error = np.full(shape + (H.size,), np.nan)
    order, spread = np.full(shape, np.nan), np.full(shape, np.nan)
    status = np.full(shape, "", dtype=object)
    chains = {n: build_chain(cfg["units"][cv["unit"]], cv["pattern"], n, H) for n in dims["n_units"]}
    exact = {
        n: [exact_samples(chain.with_H(h), t_end=cv["t_end"], x0=cv["x0"]) for h in H] for n, chain in chains.items()
    }
    for idx in itertools.product(*(range(s) for s in shape)):
        n, mname, k, kind = (dims[d][i] for d, i in zip(dims, idx))
        method, scheme = method_of(methods, mname), scheme_name(kind, n)
        error[idx] = run_errors(chains[n], method, k, scheme, exact[n])
        fit = asymptotic_order(H, error[idx])
        order[idx], spread[idx], status[idx] = fit.order, fit.spread, fit.status
        if log:
            log(f"N={n} {mname} k={k} {kind}: order {fit.order:.3f} ({fit.status})")
    names = list(dims)
    coords = {d: (d, np.array(v)) for d, v in dims.items()}
    coords["H"] = ("H", H, {"units": "s", "long_name": "macro step size"})
    coords["n_units"] = ("n_units", np.array(dims["n_units"]), {"units": "1", "long_name": "number of units N"})
    ds = DatasetDict(
        {
            "error": (
                names + ["H"],
                error,
                {"units": "1", "long_name": "NRMSE of Eq. (72) of every mass's position and velocity"},
            ),
            "order": (names, order, {"units": "1", "long_name": "order over H read off the smallest-H decade"}),
            "order_spread": (
                names,
                spread,
                {"units": "1", "long_name": "largest deviation of a local slope from the order in that decade"},
            ),
            "order_status": (names, status.astype(str), {"long_name": "asymptotic, or why the order is not"}),
        },
        coords=coords,
    )
    ds.attrs.update(provenance_attrs(cfg, title="Chains: convergence against the two-unit case", command=command))
    ds.attrs.update(
        part="chains",
        dataset="convergence",
        unit=cv["unit"],
        pattern=cv["pattern"],
        t_end=float(cv["t_end"]),
        x0=float(cv["x0"]),
    )
    return ds
