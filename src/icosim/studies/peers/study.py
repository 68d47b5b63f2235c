"""One system of the peers study (:mod:`icosim.studies.peers.config`): every configured run of every master on the
same unit files, timed (:func:`~icosim.studies.peers.timing.measure`), its doStep calls counted and its end
values against the system's reference.  A dataset of the workflow's ``peers`` part, read by its claims
(:mod:`icosim.studies.peers.checks`), figure and report section through :mod:`icosim.studies.peers.fastest`.

* quarter truck: the reference is libcosim's fixed step with the units' ``reference.solver`` (their step
  ``min(h, units.time_step)``) at the ``reference.steps``, extrapolated to ``h = 0`` as a first-order method
  (Richardson: a Jacobi master with a zero-order hold is first order); its error is estimated by the change of
  the last extrapolation.  A run that ends past ``t_end`` (ECCO's last step) is compared with the reference
  carried to its end by the reference's velocity and acceleration (Taylor, second order);
* DualMassOscillator: the exact solution of the units' equations (:class:`~icosim.problems.fmu.dual_mass.DualMass`,
  the parameters read from the units) at each run's end time.

A master that is not installed, cannot run the system's files, fails or diverges is a run with that status and
no error; no run is dropped.
"""

from __future__ import annotations

import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from ...io.dataset import DatasetDict
from ...problems.fmu.dual_mass import DualMass
from ...problems.fmu.errors import SceneError
from . import runners as R
from .config import CANNOT_RUN, SYSTEMS, system_runs, unit_dir
from .masters import available, installed
from .timing import measure

__all__ = ["system_data", "system_dataset", "truck_reference", "QUANTITIES", "MEASURES"]

#: System -> the end values compared with the reference.
QUANTITIES = {"quarter_truck": ("x", "v"), "dual_mass": ("x1", "x2")}
#: System -> what its ``error`` is.
MEASURES = {"quarter_truck": "|x - x_ref| of the chassis's position at the end (m)",
            "dual_mass": "the larger of |x1 - x1_ref| and |x2 - x2_ref| at the end (m)"}  # fmt: skip


def truck_reference(udir: Path, t_end: float, solver: str, time_step: float, steps, tmp: Path) -> dict:
    """libcosim fixed step at ``steps`` (decreasing), the units' ``solver`` at ``min(h, time_step)``: the plain
    end values, the first-order Richardson extrapolations of successive pairs, the last as the reference and the
    change of the last two as its error estimate."""
    h = np.asarray(steps, dtype=float)
    with R.quiet():
        runs = [R.libcosim_truck(R.truck_osp(tmp / f"reference_{n}", float(s), unit_dir=udir, solver=solver,
                                             time_step=min(float(s), time_step)), t_end) for n, s in enumerate(h)]  # fmt: skip
    out: dict = {"steps": h}
    ratio = h[:-1] / h[1:]
    for key in ("x", "v", "a"):
        plain = np.array([r[key] for r in runs])
        rich = (ratio * plain[1:] - plain[:-1]) / (ratio - 1)
        out |= {key: float(rich[-1]), f"{key}_plain": plain, f"{key}_error": float(abs(rich[-1] - rich[-2]))}
    return out


def _runner(system: str, n: int, run: dict, udir: Path, scfg: dict, tmp: Path):
    """``(run(t) -> outcome, the macro step the warm-up rounds to or None)`` of one configured run."""
    spec, master, step = run["spec"], run["master"], run["step"]
    mu = {"index": 1, "mu": float(spec.get("mu_per_H", 10)) * step}
    sens = {"sensitivities": spec.get("sensitivities", "each-step")}
    if system == "quarter_truck":
        solver, ts = scfg["units"]["solver"], float(scfg["units"]["time_step"])
        if master == "libcosim":
            ecco = spec.get("algorithm") == "ecco"
            folder = R.truck_osp(tmp / f"libcosim_{n}", step, unit_dir=udir, algorithm="ecco" if ecco else "fixedStep",
                                 solver=solver, time_step=ts, tolerance=run["tolerance"] if ecco else None)  # fmt: skip
            return (lambda t: R.libcosim_truck(folder, t)), None
        if master == "Ecos":
            return (lambda t: R.ecos_truck(step, t, unit_dir=udir, solver=solver, time_step=ts)), None
        coupling = sens | ({"substeps": int(spec["substeps"])} if "substeps" in spec else {})
        return (lambda t: R.icosim_run(R.truck_scene(tmp, step, int(spec["k"]), t, unit_dir=udir, params=mu,
                                                     solver=solver, time_step=ts, coupling=coupling))), step  # fmt: skip
    if master == "libcosim":
        folder = R.dmo_osp(tmp / f"libcosim_{n}", step, unit_dir=udir)
        return (lambda t: R.libcosim_dmo(folder, t)), None
    if master == "Ecos":
        return (lambda t: R.ecos_dmo(step, t, unit_dir=udir)), None
    if master == "FMPy":
        ssp = R.dmo_ssp(tmp / f"fmpy_{n}.ssp", unit_dir=udir)
        return (lambda t: R.fmpy_dmo(ssp, step, t)), None
    tol = spec.get("tolerance")

    def icosim(t):
        out = R.icosim_run(R.dmo_scene(tmp, "baumgarte", int(spec["k"]), step, t, mu, unit_dir=udir, tolerance=tol,
                                       record=("mass2.s",), coupling=sens))  # fmt: skip
        return out | {"x1": out["x"], "x2": out.get("system2.mass2.s", float("nan"))}

    return icosim, step


def _measured(runner, H, t_end: float, cfg: dict) -> dict:
    """The run's outcome, wall time and timed runs; a failure or divergence is a status, never dropped."""
    try:
        outcome, wall, timed = measure(runner, t_end, int(cfg["repeat"]), float(cfg["budget"]), H,
                                       float(cfg["warmup"]))  # fmt: skip
    except Exception as exc:  # a peer's or a scene's failure is reported by name
        return {"status": f"failed: {type(exc).__name__}: {(str(exc).splitlines() or [''])[0][:400]}"}
    if outcome.get("status", "completed") != "completed":
        return {"status": f"{outcome['status']}: {str(outcome.get('reason', ''))[:200]}", "wall": wall}
    return {**outcome, "status": "completed", "wall": wall, "timed_runs": timed}


def _reference_at(system: str, ref, t: float, t_end: float) -> dict:
    if system == "dual_mass":
        z = ref.exact([t])[0]
        return {"x1": float(z[0]), "x2": float(z[1])}
    dt = t - t_end  # ECCO's last step ends past the stop time
    return {"x": ref["x"] + ref["v"] * dt + 0.5 * ref["a"] * dt**2, "v": ref["v"] + ref["a"] * dt}


def system_data(cfg: dict, system: str, *, root=".") -> DatasetDict:
    """Every run of ``system`` (module docstring); ``cfg``: the part's configuration (``repeat``, ``budget``,
    ``warmup``, ``levels``, ``systems``)."""
    started, load = time.process_time(), os.getloadavg()
    scfg = cfg["systems"][system]
    udir, t_end = unit_dir(scfg, root), float(scfg["t_end"])
    for name in SYSTEMS[system][1]:
        if not (udir / name).is_file():
            raise SceneError(f"peers.systems.{system}.units_dir: no {udir / name} (the other tools' units, "
                             "../shared/outside/README.md)")  # fmt: skip
    versions = installed()
    info: dict = {f"version_{m}": v for m, v in versions.items()}
    rows = []
    with tempfile.TemporaryDirectory(prefix="icosim-peers-") as tmp:
        if system == "dual_mass":
            ref = DualMass.from_units(*(udir / f for f in SYSTEMS[system][1]))
            info |= {"reference": "the exact solution of the units' equations (DualMass.from_units)",
                     **{f"dmo_{k}": v for k, v in vars(ref).items()}}  # fmt: skip
        elif available(versions, "libcosim"):
            r = scfg["reference"]
            ref = truck_reference(udir, t_end, r["solver"], float(scfg["units"]["time_step"]), r["steps"], Path(tmp))
            info |= {"reference": f"libcosim fixed step, units {r['solver']}, extrapolated (Richardson, order 1)",
                     **{f"reference_{k}": ref[k] for k in ("x", "v", "a", "x_error", "v_error")}}  # fmt: skip
        else:
            ref, info["reference"] = None, f"none: libcosim {versions['libcosim']}"
        for n, run in enumerate(system_runs(cfg, system)):
            master = run["master"]
            if not available(versions, master):
                out = {"status": versions[master]}
            elif (system, master) in CANNOT_RUN:
                out = {"status": CANNOT_RUN[(system, master)]}
            else:
                out = _measured(*_runner(system, n, run, udir, scfg, Path(tmp)), t_end, cfg)
            rows.append(run | out)
    for r in rows:
        if r["status"] == "completed" and ref is not None:
            r["reference"] = _reference_at(system, ref, float(r["t"]), t_end)
    info |= {"cpu_seconds": time.process_time() - started, "load_start": list(load), "load_end": list(os.getloadavg()),
             "cpus": os.cpu_count() or 0, "python": platform.python_version()}  # fmt: skip
    return system_dataset(cfg, system, rows, ref, info)


def system_dataset(cfg: dict, system: str, rows: list, ref, info: dict) -> DatasetDict:
    """The dataset of one system from its runs: each row the configured run (:func:`~.config.system_runs`) with
    ``status`` and, where it completed, ``t``, the end values of :data:`QUANTITIES`, ``reference`` (their reference
    at ``t``), ``wall``, ``timed_runs``, ``do_steps``, ``macro_steps``, ``check_steps``; ``ref`` the quarter
    truck's reference (:func:`truck_reference`) or None; ``info`` attributes (``cpu_seconds``, ``load_start``,
    ``load_end``, ``reference``, ``version_<master>``, ...).  The errors are computed here, from the end values."""
    from ...io.netcdf import provenance_attrs

    nan = float("nan")
    q = QUANTITIES[system]

    def col(key, default=nan):
        return np.array([float(r.get(key, default)) for r in rows], dtype=float)

    data = {key: ("run", np.array([str(r[key]) for r in rows], dtype=str)) for key in
            ("master", "series", "setting", "status", "interface")}  # fmt: skip
    data |= {
        "step": ("run", col("step"), {"units": "s", "long_name": "macro step (ECCO: its initial one)"}),
        "tolerance": ("run", col("tolerance"), {"long_name": "ECCO's relative and absolute tolerance"}),
        "t": ("run", col("t"), {"units": "s", "long_name": "time the run ended at"}),
        "wall": ("run", col("wall"), {"units": "s", "long_name": "minimum wall time of the timed runs"}),
        "timed_runs": ("run", col("timed_runs"), {"long_name": "timed runs after the warm-up"}),
        "do_steps": ("run", col("do_steps"), {"long_name": "doStep calls summed over the units"}),
        "macro_steps": ("run", np.array([float(r.get("macro_steps", r.get("do_steps", nan) / 2)) for r in rows])),
        "check_steps": ("run", col("check_steps", 0.0), {"long_name": "icosim's checks' probing doSteps"}),
    }
    for name in q:
        end, refs = col(name), np.array([r["reference"][name] if "reference" in r else nan for r in rows])
        data[f"end_{name}"] = ("run", end, {"long_name": f"{name} at the end of the run"})
        data[f"reference_{name}"] = ("run", refs, {"long_name": f"the reference's {name} at the run's end"})
        data[f"error_{name}"] = ("run", np.abs(end - refs))
    errors = np.array([data[f"error_{name}"][1] for name in q])
    measure = errors[0] if system == "quarter_truck" else np.max(errors, axis=0)
    data["error"] = ("run", measure, {"units": "m", "long_name": MEASURES[system]})
    coords = {"run": ("run", np.arange(len(rows)))}
    if system == "quarter_truck" and ref is not None:
        coords["reference_step"] = ("reference_step", ref["steps"], {"units": "s"})
        data |= {f"reference_plain_{k}": ("reference_step", ref[f"{k}_plain"]) for k in ("x", "v", "a")}
    ds = DatasetDict(data, coords=coords)
    scfg = cfg["systems"][system]
    config = {key: cfg[key] for key in ("repeat", "budget", "warmup", "levels")} | {"system": scfg}
    attrs = provenance_attrs(config, title=f"peers: {SYSTEMS[system][0]}")
    attrs.update(part="peers", dataset="system", system=system, system_title=SYSTEMS[system][0],
                 measure=MEASURES[system], t_end=float(scfg["t_end"]), levels=[float(v) for v in cfg["levels"]],
                 repeat=int(cfg["repeat"]), budget=float(cfg["budget"]), warmup=float(cfg["warmup"]), **info)  # fmt: skip
    ds.attrs.update(attrs)
    return ds
