"""The peers study as configured (``config/peers.yaml``): per system, its series -- one master with its fixed
settings over a list of macro steps (or, for libcosim's ECCO, of tolerances) -- expanded into the runs of the
system's job.  Read when the workflow is parsed: a master, a key or a value the study does not know stops the run
before any job, naming the system, the series and the allowed values.

The systems:

* ``quarter_truck`` -- OSP's quarter truck (``Chassis.fmu``, ``Wheel.fmu``, ``OspSystemStructure.xml`` in
  ``units_dir``): the chassis's position at ``t_end`` against libcosim's fixed step with the units' RK4,
  extrapolated (``reference``); the units' solver and its step as ``units`` say (the file's: Euler at 1e-5 s);
* ``dual_mass`` -- OMSimulator's DualMassOscillator (System1 and System2 in ``units_dir``): the larger error of
  x1 and x2 at ``t_end`` against the exact solution of the units' equations; the peers run the units'
  co-simulation, icosim their Model Exchange.

The masters: ``libcosim`` (``algorithm: fixed-step`` over ``steps``, or ``ecco`` over ``tolerances`` from the
initial ``step``; ECCO on the quarter truck only, whose file declares the power bond it controls), ``Ecos`` and
``FMPy`` (fixed step over ``steps``), ``icosim`` (Baumgarte index 1 with ``mu = mu_per_H * H``, ``k``, and on the
quarter truck ``substeps``, on the DualMassOscillator the integrator's ``tolerance``; ``sensitivities`` either).
"""

from __future__ import annotations

from pathlib import Path

from ...problems.fmu.errors import SceneError

__all__ = ["SYSTEMS", "MASTERS", "CANNOT_RUN", "system_runs", "check_config", "unit_dir", "series_label"]

#: System -> its title and the unit files its ``units_dir`` must hold.
SYSTEMS = {
    "quarter_truck": ("OSP's quarter truck", ("Chassis.fmu", "Wheel.fmu", "OspSystemStructure.xml")),
    "dual_mass": ("OMSimulator's DualMassOscillator", ("DualMassOscillator.System1.fmu",
                                                        "DualMassOscillator.System2.fmu")),
}  # fmt: skip
#: Master -> the keys of its series (``master`` and the varied list apart), per system.
MASTERS = {
    "libcosim": {"quarter_truck": ("algorithm", "step"), "dual_mass": ("algorithm",)},
    "Ecos": {"quarter_truck": (), "dual_mass": ()},
    "FMPy": {"quarter_truck": (), "dual_mass": ()},
    "icosim": {"quarter_truck": ("k", "substeps", "sensitivities", "mu_per_H"),
               "dual_mass": ("k", "tolerance", "sensitivities", "mu_per_H")},
}  # fmt: skip
#: (system, master) -> why the master cannot run the system's files: a row with this reason, never a silent gap.
CANNOT_RUN = {
    ("quarter_truck", "FMPy"): (
        "not run: simulate_ssp sets Real, Integer and Boolean values only, and the file sets the units' String "
        "solverType; with the units' default solver they would be other units"
    ),
}
_ALGORITHMS = ("fixed-step", "ecco")
_SENSITIVITIES = ("each-step", "first-step")


def unit_dir(system_cfg: dict, root=".") -> Path:
    """The system's ``units_dir`` (relative to ``root`` unless absolute), absolute."""
    return (Path(root).resolve() / Path(system_cfg["units_dir"])).resolve()


def series_label(master: str, series: dict) -> str:
    """A series in words: ``libcosim, fixed step``, ``icosim, Baumgarte 1, k = 1, 4 sub-steps, first-step``."""
    if master == "libcosim" and series.get("algorithm") == "ecco":
        return f"libcosim, ECCO from h = {series['step']:g}"
    if master != "icosim":
        return f"{master}, fixed step"
    label = f"icosim, Baumgarte 1 (mu = {series.get('mu_per_H', 10):g} H), k = {series['k']}"
    if "substeps" in series:
        label += f", {series['substeps']} sub-steps"
    if "tolerance" in series:
        label += f", integrator tolerance {series['tolerance']:g}"
    return label + f", {series.get('sensitivities', 'each-step')} sensitivities"


def _interface(system: str, master: str) -> str:
    """The units' interface a master runs: icosim the DualMassOscillator's Model Exchange (it cannot roll back
    their co-simulation step), every other run the co-simulation units."""
    return "model exchange" if (system, master) == ("dual_mass", "icosim") else "co-simulation"


def _series_runs(system: str, n: int, series: dict) -> list[dict]:
    where = f"peers.systems.{system}.series[{n}]"
    master = series.get("master")
    if master not in MASTERS:
        raise SceneError(f"{where}.master: {master!r}; allowed: {', '.join(MASTERS)}")
    allowed = MASTERS[master][system]
    ecco = master == "libcosim" and series.get("algorithm", "fixed-step") == "ecco"
    varied = "tolerances" if ecco else "steps"
    unknown = sorted(set(series) - {"master", varied, *allowed})
    if unknown:
        raise SceneError(f"{where}: unknown key {unknown[0]!r} for {master} on {system}; allowed: "
                         f"{', '.join(('master', varied, *allowed))}")  # fmt: skip
    if master == "libcosim" and series.get("algorithm", "fixed-step") not in _ALGORITHMS:
        raise SceneError(f"{where}.algorithm: {series['algorithm']!r}; allowed: {', '.join(_ALGORITHMS)}")
    if ecco and system != "quarter_truck":
        raise SceneError(f"{where}.algorithm: ecco runs on quarter_truck only (its file declares the power bond)")
    if ecco and "step" not in series:
        raise SceneError(f"{where}.step: required with algorithm ecco (the initial macro step)")
    if series.get("sensitivities", "each-step") not in _SENSITIVITIES:
        raise SceneError(f"{where}.sensitivities: {series['sensitivities']!r}; allowed: {', '.join(_SENSITIVITIES)}")
    if master == "icosim" and not isinstance(series.get("k"), int):
        raise SceneError(f"{where}.k: required, an integer >= 0")
    values = series.get(varied)
    if not isinstance(values, list) or not values or not all(isinstance(v, (int, float)) and v > 0 for v in values):
        raise SceneError(f"{where}.{varied}: a non-empty list of numbers > 0")
    label = series_label(master, series)
    runs = []
    for value in values:
        name = f"tolerance {value:g}" if ecco else f"{'H' if master == 'icosim' else 'h'} = {value:g}"
        step = float(series["step"]) if ecco else float(value)
        runs.append({"master": master, "series": label, "setting": f"{label}, {name}", "step": step,
                     "tolerance": float(value) if ecco else float("nan"), "interface": _interface(system, master),
                     "spec": dict(series)})  # fmt: skip
    return runs


def system_runs(cfg: dict, system: str) -> list[dict]:
    """The runs of ``system`` in the configured order: ``master``, ``series`` (its label), ``setting`` (the
    run's label), ``step`` (the macro step, ECCO's initial one), ``tolerance`` (ECCO's, else NaN), ``interface``
    (of the units it runs), ``spec``."""
    if system not in SYSTEMS:
        raise SceneError(f"peers.systems: {system!r}; allowed: {', '.join(SYSTEMS)}")
    runs = [r for n, s in enumerate(cfg["systems"][system]["series"]) for r in _series_runs(system, n, s)]
    t_end = float(cfg["systems"][system]["t_end"])
    seen = set()
    for r in runs:
        steps = t_end / r["step"]
        if r["tolerance"] != r["tolerance"] and abs(steps - round(steps)) > 1e-6 * steps:
            raise SceneError(f"peers.systems.{system}: {r['setting']}: the step does not divide t_end = {t_end:g} s")
        if r["setting"] in seen:
            raise SceneError(f"peers.systems.{system}.series: the run {r['setting']!r} is configured twice")
        seen.add(r["setting"])
    return runs


def check_config(cfg: dict) -> dict:
    """System -> its runs (:func:`system_runs`), every system checked; no unit is opened."""
    return {system: system_runs(cfg, system) for system in cfg["systems"]}
