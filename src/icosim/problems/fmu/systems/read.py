"""Which reader a file needs: an ``.ssp`` or ``.ssd`` (SSP), an ``OspSystemStructure.xml`` (OSP), or a folder
holding one of them."""

from __future__ import annotations

from pathlib import Path

from ..errors import SceneError
from .description import System

__all__ = ["is_system_file", "find_system_file", "read_system"]

OSP_NAME = "OspSystemStructure.xml"


def is_system_file(path) -> bool:
    """Is ``path`` a system file or a folder holding one (not a scene)?"""
    path = Path(path)
    if path.is_dir():
        return (path / OSP_NAME).exists() or (path / "SystemStructure.ssd").exists()
    return path.suffix in (".ssp", ".ssd") or _is_osp(path)


def _is_osp(path) -> bool:
    """libcosim's names: ``OspSystemStructure.xml``, and in its tests ``OspSystemStructure_<case>.xml``."""
    return path.suffix == ".xml" and (path.name.startswith("OspSystemStructure") or path.name.endswith(OSP_NAME))


def find_system_file(path) -> Path:
    """The system file itself: ``path``, or the one its folder holds (refused where it holds both kinds)."""
    path = Path(path)
    if not path.exists():
        raise SceneError(f"{path}: no such system file")
    if not path.is_dir():
        return path
    found = [p for p in (path / OSP_NAME, path / "SystemStructure.ssd") if p.exists()]
    if len(found) != 1:
        held = " and ".join(p.name for p in found) or "neither"
        raise SceneError(
            f"{path}: a system folder holds {OSP_NAME} or SystemStructure.ssd, one of them; it holds {held}"
        )
    return found[0]


def read_system(path) -> System:
    """Read the system a file (or a folder) holds."""
    path = find_system_file(path)
    if path.suffix in (".ssp", ".ssd"):
        from .ssp import read_ssp

        return read_ssp(path)
    if _is_osp(path):
        from .osp import read_osp

        return read_osp(path)
    raise SceneError(f"{path}: not a system file (allowed: .ssp, .ssd, {OSP_NAME}, or a folder holding one)")
