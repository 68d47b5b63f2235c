"""Work-precision: CPU time per simulated second and counted work against the NRMSE.

Each configuration of ``convergence.work_precision.configurations`` (a method, its
parameters, a decomposition and ``k``, with the paper's Jacobi scheme) is timed on the engine's
own macro-step loop (:func:`icosim.engine.run.simulate`) at every stable step
size; the error is read from the panel datasets, never recomputed.  The
subsystems of the linear model are integrated exactly, so the counted work per
macro step (:func:`step_cost`) is what transfers to numerically integrated
subsystems.
"""

from __future__ import annotations

import time

import numpy as np

from ...engine.macrostep import macro_step
from ...engine.methods import get_spec, parameter_units, parameters
from ...engine.run import simulate
from ...errors import ParameterError
from ...problems.linear import exact
from ...problems.linear.problem import LinearCosimulation
from .experiment import Setup, dimensional_method, method_attrs, units_summary
from .panels import effective_params, figure_panels

__all__ = ["time_macro_steps", "step_cost", "resolve_configuration", "work_precision"]


# --------------------------------------------------------------------------- timing
def time_macro_steps(
    setup: Setup,
    H: float,
    method: str,
    params: dict,
    decomposition: str,
    k: int,
    *,
    steps: int = 20,
    repeats: int = 3,
    warmup_steps: int = 5,
) -> dict:
    """CPU time of the co-simulation stepping (:func:`icosim.engine.run.simulate`).

    The problem is built once (its set-up, the subsystem propagators, is timed
    separately: it does not grow with the simulated time); after a warm-up of
    ``warmup_steps``, ``repeats`` runs of ``steps`` macro steps each are timed
    with :func:`time.process_time` and the minimum is kept.  Each macro step of
    the linear model costs the same, so the CPU time per simulated second is
    ``seconds_per_step / H``.
    """
    if steps < 1 or repeats < 1 or warmup_steps < 0:
        raise ParameterError("steps and repeats must be >= 1 and warmup_steps >= 0")
    m = dimensional_method(method, H, **params)
    t0 = time.process_time()
    c = setup.model(H).coefficients()
    problem = LinearCosimulation(c, decomposition, k)
    sol = exact.MonolithicSolution(c, setup.x0, setup.v0 * H)
    state, history = exact.consistent_start(problem, sol)
    setup_seconds = time.process_time() - t0
    if warmup_steps:
        simulate(problem, m, state, history, warmup_steps)
    best = np.inf
    for _ in range(repeats):
        t = time.process_time()
        simulate(problem, m, state, history, steps)
        best = min(best, time.process_time() - t)
    per_step = best / steps
    return {
        "seconds_per_step": per_step,
        "seconds_per_simulated_second": per_step / H,
        "setup_seconds": setup_seconds,
    }


def step_cost(method: str, params: dict, decomposition: str, k: int) -> dict:
    """Work of one macro step, counted on the engine's macro step of the linear model.

    ``subsystem_integrations``: calls of a subsystem integrator (predictor and
    corrector of both subsystems: 4); ``coupling_solves``: linear solves of
    coupling conditions (the method's solves with a nonzero weight: 1 for
    Baumgarte and projection, up to 3 for the weighted multiplier);
    ``projections``: 1 with the projection step.  The sensitivities (Jacobians
    of the coupling conditions) are constant for the linear model and not
    counted; with numerically integrated subsystems they cost extra
    integrations (or are reused).  These counts let the work-precision
    comparison be transferred to subsystems whose integration dominates.
    The problem counts them itself (:attr:`icosim.engine.problem.CosimulationProblem.work`).
    """
    m = dimensional_method(method, 1.0, **params)  # the counts do not depend on H
    problem = LinearCosimulation(Setup().model(1.0e-3).coefficients(), decomposition, k)
    m.check_decomposition(problem.decomposition)
    state = np.zeros((2, 2))
    history = np.zeros((k + 1, problem.n_coupling))
    problem.work.reset()
    macro_step(problem, m, state, history)
    return problem.work.as_dict()


# --------------------------------------------------------------------------- work-precision
def resolve_configuration(configuration: dict, figures: dict, k) -> list:
    """Curves of a work-precision configuration: one per decomposition of its figure and per ``k``.

    ``configuration`` names a figure and the column and row parameters as configured
    (e.g. ``{figure: "22", a: 1, b: 1, index: 2}``).
    """
    fig = str(configuration["figure"])
    if fig not in figures:
        raise ParameterError(f"work_precision configuration {configuration}: figure {fig!r} is not configured")
    cfg = figures[fig]
    rest = {key: v for key, v in configuration.items() if key != "figure"}
    col_keys = set().union(*(c.keys() for c in cfg["columns"]))
    col = {key: v for key, v in rest.items() if key in col_keys}
    row = {key: v for key, v in rest.items() if key not in col_keys}
    cols = [c for c in cfg["columns"] if c == col]
    rows = [r for r in cfg["rows"] if r == row]
    if len(cols) != 1 or len(rows) != 1:
        raise ParameterError(
            f"work_precision configuration {configuration}: must match exactly one column of {cfg['columns']} "
            f"and one row of {cfg['rows']} of figure {fig}"
        )
    eff = effective_params(cfg["method"], cols[0], rows[0])
    out = []
    for spec in figure_panels(fig, cfg, k):
        if eff not in spec.rows or spec.scheme != "jacobi":  # the paper's scheme
            continue
        index = spec.indices[spec.rows.index(eff)]
        for kk in spec.k:
            entry = {
                "figure": fig,
                "scheme": spec.scheme,
                "decomposition": spec.decomposition,
                "panel": spec.panel,
                "index": index,
                "k": int(kk),
                "method": cfg["method"],
                "params": dict(eff),
            }
            rec = {**entry, **{n: v for n, v in method_attrs(cfg["method"], **eff).items()}}
            entry["label"] = _configuration_label(rec)
            out.append(entry)
    return out


def _configuration_label(rec) -> str:
    """E.g. ``ff Baumgarte i1 mu=0.005 k=0`` (the registry's short label and label parameters)."""
    spec = get_spec(rec["method"])
    head = spec.short_label + (f" i{rec['index']}" if spec.takes_index else "")
    unused = spec.unused(rec["index"])
    head += "".join(f" {n}={rec[n]:g}" for n in spec.label_parameters if n in rec and n not in unused)
    return f"{rec['decomposition']} {head} k={rec['k']}"


def work_precision(entries, datasets: dict, setup: Setup, *, steps=20, repeats=3, warmup_steps=5, provenance=None):
    """CPU time per simulated second against NRMSE for each configuration and stable ``H``.

    ``datasets`` maps ``(scheme, decomposition, figure, panel)`` to the panel dataset
    holding the configuration's NRMSE (never recomputed here).  Returns a dataset with
    dims ``(configuration, H)``.
    """
    import xarray as xr

    if not entries:
        raise ParameterError("work_precision needs at least one configuration")
    H = None
    rows = []
    for e in entries:
        ds = datasets[(e["scheme"], e["decomposition"], e["figure"], e["panel"])]
        if H is None:
            H = ds["H"].values
        elif not np.array_equal(H, ds["H"].values):
            raise ValueError("all panels must share the same step sizes")
        sel = ds.sel(index=e["index"], k=e["k"])
        err = sel["nrmse"].values
        unstable = sel["unstable"].values.astype(bool)
        per_step = np.full(H.size, np.nan)
        setup_s = np.nan
        for i, h in enumerate(H):
            if unstable[i] or not np.isfinite(err[i]):
                continue  # no error to put the time against
            t = time_macro_steps(
                setup,
                float(h),
                e["method"],
                e["params"],
                e["decomposition"],
                e["k"],
                steps=steps,
                repeats=repeats,
                warmup_steps=warmup_steps,
            )
            per_step[i] = t["seconds_per_step"]
            setup_s = t["setup_seconds"] if not np.isfinite(setup_s) else min(setup_s, t["setup_seconds"])
        rows.append((err, unstable, per_step, setup_s))
    labels = [e["label"] for e in entries]
    units = parameter_units(index=True)
    costs = [step_cost(e["method"], e["params"], e["decomposition"], e["k"]) for e in entries]
    err = np.array([r[0] for r in rows])
    per_step = np.array([r[2] for r in rows])
    ds = xr.Dataset(
        {
            "nrmse": (
                ("configuration", "H"),
                err,
                {"long_name": "NRMSE of Eq. (72) (from the panel datasets; NaN where unstable)", "units": "1"},
            ),
            "unstable": (("configuration", "H"), np.array([r[1] for r in rows])),
            "cpu_seconds_per_step": (
                ("configuration", "H"),
                per_step,
                {
                    "long_name": "CPU time of one macro step of icosim.engine.run.simulate (min of repeats)",
                    "units": "s",
                },
            ),
            "cpu_seconds_per_simulated_second": (
                ("configuration", "H"),
                per_step / H[None, :],
                {"long_name": "CPU time per simulated second", "units": "s"},
            ),
            "setup_seconds": (
                ("configuration",),
                np.array([r[3] for r in rows]),
                {"long_name": "CPU time to build the problem (once per run, not per simulated second)", "units": "s"},
            ),
            "subsystem_integrations_per_step": (
                ("configuration",),
                np.array([c["subsystem_integrations"] for c in costs], dtype=np.int32),
                {
                    "long_name": "subsystem integrations per macro step (predictor and corrector of each subsystem; counted)",
                    "units": "1",
                },
            ),
            "coupling_solves_per_step": (
                ("configuration",),
                np.array([c["coupling_solves"] for c in costs], dtype=np.int32),
                {
                    "long_name": "linear solves of coupling conditions per macro step (the method's nonzero-weight solves)",
                    "units": "1",
                },
            ),
            "projections_per_step": (
                ("configuration",),
                np.array([c["projections"] for c in costs], dtype=np.int32),
                {"long_name": "projection steps per macro step", "units": "1"},
            ),
        },
        coords={
            "configuration": ("configuration", np.array(labels, dtype=str)),
            "H": ("H", H, {"long_name": "macro-step size", "units": "s"}),
            "figure": ("configuration", np.array([e["figure"] for e in entries], dtype=str)),
            "method": ("configuration", np.array([e["method"] for e in entries], dtype=str)),
            "decomposition": ("configuration", np.array([e["decomposition"] for e in entries], dtype=str)),
            "index": ("configuration", np.array([e["index"] for e in entries], dtype=np.int32)),
            "k": ("configuration", np.array([e["k"] for e in entries], dtype=np.int32)),
            **{
                name: (
                    "configuration",
                    np.array(
                        [method_attrs(e["method"], **e["params"]).get(name, np.nan) for e in entries], dtype=float
                    ),
                    {"units": units[name]},
                )
                for name in parameters()
            },
        },
    )
    ds.attrs = dict(provenance or {})
    ds.attrs.update(
        timer="time.process_time",
        steps=steps,
        repeats=repeats,
        warmup_steps=warmup_steps,
        timed="icosim.engine.run.simulate: the engine's macro-step loop (predictor, corrector, "
        "projection) of the linear test model; problem set-up excluded (setup_seconds)",
        cost_caveat="the subsystems of the linear test model are integrated exactly (matrix "
        "exponential blocks), so the timed cost is the coupling algorithm's Python overhead and nearly "
        "the same for every configuration: the diagram is close to NRMSE against 1/H. To transfer the "
        "comparison to numerically integrated subsystems, weigh subsystem_integrations_per_step and "
        "coupling_solves_per_step with their cost there.",
        method_parameters_units=units_summary(),
    )
    return ds
