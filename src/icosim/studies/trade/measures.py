"""What one pendulum run costs and how accurate it is: errors against the reference, drift, CPU, counts.

Every study of the speed-accuracy trade (:mod:`.sweep`, :mod:`.stability_limit`,
:mod:`.tolerance`, :mod:`.adaptive`, :mod:`icosim.studies.trade.work_precision`) describes a run by
the same record (:data:`RECORD`):

* ``error_max`` -- ``max |phi_i - phi_i,ref|`` over ``phi1``, ``phi2`` and the
  run's own solution points (the macro nodes; for a monolithic integrator its
  accepted steps): no interpolation anywhere;
* ``error_rms`` -- the time-weighted RMS of the same errors,
  ``sqrt(int (dphi1^2 + dphi2^2)/2 dt / T)`` by the trapezoidal rule over those
  points (equal weights for equidistant nodes, fair for variable ones);
* ``drift_max`` -- ``max |g_c|`` of the stored states (after any projection),
  ``drift_corrector_max`` the same after the corrector, before projection;
* ``cpu_seconds`` -- :func:`time.process_time` of the macro steps (the
  start-up history excluded), the minimum of ``repeats`` runs when a run is
  cheap (below ``repeat_below`` seconds);
* counts: macro steps, subsystem steps (accepted Radau steps of every link
  integration), right-hand side evaluations (batched calls of a link's
  right-hand side, including those of the finite-difference Jacobians) and
  Jacobian evaluations (of the links' right-hand sides, each one batched
  call), subsystem integrations, rejected Radau steps.

The reference is the monolithic pendulum (:func:`~.reference.reference_solution`)
at the run's own times.
"""

from __future__ import annotations

import math

import numpy as np

from ...engine.methods import make_method
from ...engine.schemes import SCHEMES, get_scheme
from ...errors import ParameterError
from ...problems.pendulum.model import PendulumParameters
from ...problems.pendulum.names import run_name
from ...problems.pendulum.reference import reference_solution
from ...problems.pendulum.runs import RunResult, run_cosimulation

__all__ = ["RECORD", "SCHEMES", "angle_errors", "run_record", "measured_run", "config_label", "check_scheme"]

#: name -> (units, long name) of the per-run record
RECORD = {
    "error_max": ("rad", "max |phi_i - phi_i,ref| over phi1, phi2 and the run's solution points"),
    "error_rms": ("rad", "time-weighted RMS of phi1 - phi1_ref and phi2 - phi2_ref (trapezoidal rule)"),
    "drift_max": ("m", "max |g_c| of the stored states (after any projection)"),
    "drift_corrector_max": ("m", "max |g_c| after the corrector, before any projection"),
    "cpu_seconds": ("s", "CPU seconds of the macro steps (time.process_time; min of repeats for cheap runs)"),
    "n_macro_steps": ("1", "macro steps computed"),
    "n_subsystem_steps": ("1", "accepted Radau steps, summed over every link integration"),
    "n_rhs_evaluations": ("1", "batched evaluations of a link's right-hand side (stages, error estimates, Jacobians)"),
    "n_jacobian_evaluations": ("1", "finite-difference Jacobians of a link's right-hand side"),
    "n_integrations": ("1", "link integrations (a batched call counts once)"),
    "n_rejected": ("1", "rejected Radau steps"),
    "t_last": ("s", "time of the last stored state (end time, or the step before divergence or failure)"),
}


def check_scheme(scheme) -> str:
    """The registered scheme's name (:data:`icosim.engine.schemes.SCHEMES`), checked."""
    try:
        return get_scheme(scheme).name
    except ParameterError as exc:
        raise ParameterError(f"scheme must be one of {', '.join(SCHEMES)}, got {scheme!r}") from exc


def config_label(scheme, method: str, decomposition: str, k: int) -> str:
    """Label of a configuration: ``baumgarte_ff_k1`` (Jacobi), ``baumgarte_ff_k1_gauss-seidel-12`` (another
    scheme), as the runs of Figs. 6-8 are named (:func:`icosim.problems.pendulum.names.run_name`)."""
    return run_name(method, decomposition, int(k), scheme)


def angle_errors(t, phi1, phi2, reference) -> tuple[float, float]:
    """``(error_max, error_rms)`` of the angles against ``reference`` (dict with ``phi1``, ``phi2`` at ``t``)."""
    t = np.asarray(t, float)
    d1 = np.asarray(phi1, float) - np.asarray(reference["phi1"], float)
    d2 = np.asarray(phi2, float) - np.asarray(reference["phi2"], float)
    err_max = float(max(np.max(np.abs(d1)), np.max(np.abs(d2))))
    if t.size < 2 or t[-1] <= t[0]:
        return err_max, math.nan
    sq = 0.5 * (d1 * d1 + d2 * d2)
    integral = float(np.sum(0.5 * (sq[1:] + sq[:-1]) * np.diff(t)))
    return err_max, math.sqrt(integral / (t[-1] - t[0]))


def run_record(result: RunResult, reference) -> dict:
    """The record of a co-simulation run (:data:`RECORD`) with ``status`` and ``reason``; without a
    ``reference`` (None) the errors are NaN."""
    s = result.series
    if reference is None:
        err_max = err_rms = math.nan
    else:
        err_max, err_rms = angle_errors(result.t, s["phi1"], s["phi2"], reference)
    st, jac = result.stats, result.jacobian_stats
    return {
        "status": result.status,
        "reason": result.reason or "",
        "error_max": err_max,
        "error_rms": err_rms,
        "drift_max": float(np.max(np.hypot(s["g_cax"], s["g_cay"]))),
        "drift_corrector_max": float(np.max(np.hypot(s["g_cax_corrector"], s["g_cay_corrector"]))),
        "cpu_seconds": float(result.cpu_seconds),
        "n_macro_steps": int(st["macro_steps"]),
        "n_subsystem_steps": int(st["steps"]),
        "n_rhs_evaluations": int(st["fev"] + jac.get("fev", 0)),
        "n_jacobian_evaluations": int(jac.get("jev", 0)),
        "n_integrations": int(st["integrations"]),
        "n_rejected": int(st["rejected"]),
        "t_last": float(result.t[-1]),
    }


def measured_run(
    settings: dict,
    scheme: str,
    method: str,
    decomposition: str,
    k: int,
    H: float,
    t_end: float,
    *,
    reference: dict | None,
    repeats: int = 1,
    repeat_below: float = 0.0,
    integrator: dict | None = None,
) -> dict:
    """Run one configuration at macro step ``H`` up to ``t_end`` and return its record.

    ``settings`` is the pendulum configuration (``model``, ``methods``,
    ``integrator``, ``sensitivities``, ``corrector``, ``divergence``);
    ``integrator`` overrides its integrator settings; ``reference`` the
    reference integrator (``method``, ``rtol``, ``atol``), or None for a run
    whose errors are not wanted (NaN: no reference is solved).  ``t_end`` is
    rounded up to a whole number of macro steps.  A run cheaper than
    ``repeat_below`` CPU seconds is repeated up to ``repeats`` times in all and
    the least CPU time is kept (the results are identical: the runs are
    deterministic).
    """
    scheme = check_scheme(scheme)
    params = PendulumParameters(**settings["model"])
    m = make_method(method, **settings["methods"][method])
    n = max(1, math.ceil(t_end / H - 1e-9))
    integ = dict(settings["integrator"], **(integrator or {}))

    def run():
        return run_cosimulation(
            params,
            m,
            decomposition,
            int(k),
            H=H,
            t_end=n * H,
            **integ,
            **settings["sensitivities"],
            **settings["corrector"],
            **settings["divergence"],
            scheme=scheme,
        )

    result = run()
    cpu = result.cpu_seconds
    for _ in range(max(1, repeats) - 1):
        if cpu >= repeat_below:
            break
        cpu = min(cpu, run().cpu_seconds)
    result.cpu_seconds = cpu
    ref = None if reference is None else reference_solution(params, result.t, **reference)
    return run_record(result, ref)
