"""The FMU part of the workflow as configured (``config/fmi.yaml``): its scenes, the units they need, the order
cases.  Read when the workflow is parsed: a scene file that fails its schema stops the run before any job,
naming the file and the key; no unit is loaded or built here.
"""

from __future__ import annotations

from pathlib import Path

from ...problems.fmu.build import is_source_dir, unit_files
from ...problems.fmu.errors import SceneError

__all__ = ["scene_files", "scene_units", "unit_sources", "unit_inputs", "order_cases", "case_label"]


def case_label(case: dict) -> str:
    """``projection_ff_k2``, ``baumgarte_ff_k1`` (the scheme appended unless Jacobi)."""
    label = f"{case['method']}_{case['decomposition']}_k{case['k']}"
    return label + ("" if case.get("scheme", "jacobi") == "jacobi" else f"_{case['scheme']}")


def scene_files(cfg: dict, root) -> dict:
    """Scene name -> its file (relative to ``root``), each read and checked against the scene schema."""
    from ...io.yamlio import load_yaml
    from ...problems.fmu.scene import _validate

    root = Path(root)
    out = {}
    for name in cfg["scenes"]:
        path = Path(cfg["scene_dir"]) / f"{name}.yaml"
        if not (root / path).is_file():
            raise SceneError(f"fmi.scenes: {name}: no scene file {path}")
        _validate(path, load_yaml((root / path).read_text()))
        out[name] = str(path)
    return out


def scene_units(scene_path, root) -> list:
    """The unit sources a scene names (source directories and pythonfmu scripts), relative to ``root``."""
    from ...io.yamlio import load_yaml

    root = Path(root).resolve()
    scene_path = root / scene_path
    data = load_yaml(scene_path.read_text())
    out = []
    for sub in data["subsystems"].values():
        source = (scene_path.parent / sub["fmu"]).resolve()
        if source.suffix != ".fmu":
            out.append(str(source.relative_to(root)))
    return out


def unit_sources(cfg: dict, root) -> list:
    """Every unit source the configured scenes and order cases need (``units_dir``'s ``msd`` and
    ``msd_kinematic`` for the orders), sorted, relative to ``root``."""
    sources = {str(Path(cfg["units_dir"]) / name) for name in ("msd", "msd_kinematic")}
    for path in scene_files(cfg, root).values():
        sources.update(scene_units(path, root))
    return sorted(sources)


def unit_inputs(sources, root) -> list:
    """The files a build of ``sources`` reads (shared ``common/`` files included), relative to ``root``;
    sources missing on disk contribute none (the build job names them)."""
    root = Path(root).resolve()
    files = set()
    for source in sources:
        path = root / source
        if path.suffix == ".py" and path.is_file():
            files.add(source)
        elif is_source_dir(path):
            files.update(str(f.resolve().relative_to(root)) for f in unit_files(path).values())
    return sorted(files)


def order_cases(cfg: dict) -> dict:
    """Case label -> ``{method, decomposition, k, scheme, params, H}``, one per configured case and ``k``."""
    orders = cfg["orders"]
    out = {}
    for case in orders["cases"]:
        for k in case["k"]:
            one = {
                "method": case["method"],
                "decomposition": case["decomposition"],
                "k": int(k),
                "scheme": case.get("scheme", "jacobi"),
                "params": dict(case.get("params", {})),
                "H": [float(h) for h in case["H"]],
            }
            for h in one["H"]:
                steps = orders["t_end"] / h
                if abs(steps - round(steps)) > 1e-6 * steps:
                    raise SceneError(f"fmi.orders: H = {h:g} s does not divide t_end = {orders['t_end']:g} s")
            label = case_label(one)
            if label in out:
                raise SceneError(f"fmi.orders: case {label} is configured twice")
            out[label] = one
    return out
