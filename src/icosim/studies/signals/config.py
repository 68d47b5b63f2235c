"""The signal-coupling study as configured (``config/signals.yaml``): its cases, each a coupling setting at every
``k`` of its list, and the scene of one case at one ``H``.  Read when the workflow is parsed: a case whose scene
the scene checks refuse stops the run before any job, naming the case and the key; no unit is opened here.

OMSimulator's DualMassOscillator, coupled two ways:

* ``by: connections`` -- its four signal connections as OMSimulator's own test couples it (``system1.F <-
  system2.F``, ``system2.{x1, v1, a1} <- system1.{x1, v1, a1}``), with the case's ``k``, ``scheme`` (``order``
  for Gauss-Seidel) and, where given, ``implicit``;
* ``by: joint`` -- mass 1 and System2's driven point held together by a joint (decomposition fd: System1
  force-driven by ``F``, System2 driven by ``x1``, ``v1``, ``a1``), coupled by the case's ``method`` and
  ``params``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from ...problems.fmu.errors import SceneError

__all__ = ["CONNECTIONS", "study_cases", "case_label", "scene_data", "check_cases", "unit_paths", "BY"]

#: OMSimulator's four connections of the DualMassOscillator, as (source, output, target, input).
CONNECTIONS = [("system2", "F", "system1", "F")] + [("system1", v, "system2", v) for v in ("x1", "v1", "a1")]
#: How a case couples the units.
BY = ("connections", "joint")
_SIGNAL_KEYS = ("scheme", "order", "implicit")


def _scheme_name(case: dict) -> str:
    if case.get("scheme", "jacobi") != "gauss-seidel":
        return case.get("scheme", "jacobi")
    order = case.get("order") or []
    return "gauss-seidel-" + "".join(str(name)[-1] for name in order)


def case_label(case: dict) -> str:
    """``connections_jacobi_k0``, ``connections_gauss-seidel-21_k1``, ``joint_baumgarte_fd_k2`` (``_implicit``
    appended where the case is implicit)."""
    if case["by"] == "joint":
        label = f"joint_{case['method']}_fd_k{case['k']}"
        scheme = case.get("scheme", "jacobi")
        label += "" if scheme == "jacobi" else f"_{scheme}"
    else:
        label = f"connections_{_scheme_name(case)}_k{case['k']}"
    return label + ("_implicit" if case.get("implicit") else "")


def unit_paths(cfg: dict, root=".") -> dict:
    """Unit name -> its ``.fmu`` (``units_dir`` / ``units``, relative to ``root`` unless absolute), absolute."""
    base = Path(root).resolve() / Path(cfg["units_dir"])
    return {name: (base / file).resolve() for name, file in cfg["units"].items()}


def study_cases(cfg: dict) -> dict:
    """Case label -> the case at one ``k``: ``by``, ``k``, ``H`` (sorted), ``growth_H``, and the coupling keys of
    its kind; every ``H`` divides ``t_end``."""
    out = {}
    for n, case in enumerate(cfg["cases"]):
        for k in case["k"]:
            one = {key: value for key, value in case.items() if key not in ("k", "H", "growth_H")}
            one |= {"k": int(k), "H": sorted(float(h) for h in case["H"])}
            one["growth_H"] = sorted(float(h) for h in case.get("growth_H", []))
            if one["by"] == "joint" and (one["growth_H"] or any(key in case for key in ("order", "implicit"))):
                raise SceneError(f"signals.cases[{n}]: growth_H, order and implicit belong to cases by connections "
                                 "(the joint's spectral radius is not predicted for System2's drive)")  # fmt: skip
            for h in one["H"]:
                steps = cfg["t_end"] / h
                if abs(steps - round(steps)) > 1e-6 * steps:
                    raise SceneError(f"signals.cases[{n}]: H = {h:g} s does not divide t_end = {cfg['t_end']:g} s")
            label = case_label(one)
            if label in out:
                raise SceneError(f"signals.cases[{n}]: case {label} is configured twice")
            out[label] = one
    return out


def scene_data(cfg: dict, case: dict, H: float, t_end: float, *, root=".") -> dict:
    """The scene of ``case`` at the step ``H`` to ``t_end`` on the configured units (Model Exchange, the
    configured tolerance), ``system2.mass2.s`` recorded."""
    paths = unit_paths(cfg, root)
    me = {"interface": "model-exchange", "tolerance": float(cfg["tolerance"])}
    starts = {name: dict(cfg["start"].get(name, {})) for name in paths}
    if case["by"] == "connections":
        coupling = {"k": case["k"], "H": float(H)} | {key: case[key] for key in _SIGNAL_KEYS if key in case}
        return {
            "subsystems": {
                "system1": {"fmu": str(paths["system1"]), **me, "start": starts["system1"]},
                "system2": {"fmu": str(paths["system2"]), **me, "start": starts["system2"], "record": ["mass2.s"]},
            },
            "connections": [{"from": f"{a}.{y}", "to": f"{b}.{u}"} for a, y, b, u in CONNECTIONS],
            "coupling": coupling,
            "t_end": float(t_end),
        }
    coupling = {"method": case["method"], "decomposition": "fd", "k": case["k"], "H": float(H), "perturbation": 1.0,
                "scheme": case.get("scheme", "jacobi"), **dict(case.get("params", {}))}  # fmt: skip
    return {
        "subsystems": {
            "system1": {"fmu": str(paths["system1"]), **me, "start": starts["system1"], "position": "x1",
                        "velocity": "v1", "acceleration": "a1", "force": "F", "force_sign": 1},
            "system2": {"fmu": str(paths["system2"]), **me, "start": starts["system2"], "position_input": "x1",
                        "velocity_input": "v1", "acceleration_input": "a1", "reaction_force": "F", "force_sign": 1,
                        "record": ["mass2.s"]},
        },
        "coupling": coupling,
        "t_end": float(t_end),
    }  # fmt: skip


def write_scene(directory, data: dict, name: str) -> Path:
    """``data`` as ``<directory>/<name>.yaml``."""
    import yaml

    path = Path(directory) / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def check_cases(cfg: dict) -> dict:
    """:func:`study_cases`, each case's scene at its first ``H`` checked by the scene checks: a refused key names
    the case.  No unit is opened, nor needed: the scenes name empty stand-ins of the units (the job checks the
    units themselves, and names one that is missing)."""
    from ...problems.fmu.scene import load_scene

    cases = study_cases(cfg)
    with tempfile.TemporaryDirectory(prefix="icosim-signals-") as tmp:
        for file in cfg["units"].values():
            (Path(tmp) / Path(file).name).touch()
        stand_in = {**cfg, "units_dir": tmp, "units": {n: Path(f).name for n, f in cfg["units"].items()}}
        for label, case in cases.items():
            try:
                load_scene(write_scene(tmp, scene_data(stand_in, case, case["H"][0], cfg["t_end"]), label))
            except SceneError as exc:
                raise SceneError(f"signals.cases: {label}: {str(exc).split(': ', 1)[-1]}") from None
    return cases
