"""FMUs built from source: a unit directory (``modelDescription.xml`` and ``sources/``) zipped into an ``.fmu``
whose platform binary fmpy's CMake project compiles, once per content (a cache keyed by the SHA-256 of the files).

A unit directory of ``fmus/`` may share code with the others: the files of the sibling directory
``common/``, and the ``sources/`` of the sibling units its ``uses.txt`` names, are copied into its ``sources/``
before the build (``fmus/README.md``).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import zipfile
from pathlib import Path

from .errors import FmuError

__all__ = ["build_unit", "cache_dir", "is_source_dir", "unit_files"]


def cache_dir() -> Path:
    """Where built units go: ``$ICOSIM_FMU_CACHE``, else ``$XDG_CACHE_HOME/icosim/fmus`` (``~/.cache`` by default)."""
    if os.environ.get("ICOSIM_FMU_CACHE"):
        return Path(os.environ["ICOSIM_FMU_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "icosim" / "fmus"


def is_source_dir(path) -> bool:
    """Is ``path`` a unit's source: a directory (a ``modelDescription.xml`` beside ``sources/``) or a pythonfmu
    script (``.py``)?"""
    path = Path(path)
    if path.is_file() and path.suffix == ".py":
        return True
    return path.is_dir() and (path / "modelDescription.xml").is_file() and (path / "sources").is_dir()


def unit_files(source: Path) -> dict[str, Path]:
    """Archive name -> file of the unit built from ``source`` (the shared ``common/`` files under ``sources/``)."""
    files = {"modelDescription.xml": source / "modelDescription.xml"}
    common = source.parent / "common"
    uses = source / "uses.txt"  # sibling units whose sources this one shares (an FMI 3.0 twin of a unit)
    shared = [source.parent / name / "sources" for name in uses.read_text().split()] if uses.is_file() else []
    for folder in ([common] if common.is_dir() else []) + shared + [source / "sources"]:
        for f in sorted(folder.iterdir()):
            if f.is_file():
                files[f"sources/{f.name}"] = f
    return files


def build_unit(source, cache=None) -> Path:
    """The ``.fmu`` built from the unit directory ``source`` (compiled on first use, then taken from the cache).

    Raises :class:`~icosim.problems.fmu.errors.FmuError` naming the unit when fmpy, CMake or the compiler is missing or the
    build fails (the compiler's last lines in the message).
    """
    import fmpy

    source = Path(source).resolve()
    if source.suffix == ".py":
        return _build_python(source, Path(cache) if cache is not None else cache_dir())
    files = unit_files(source)
    digest = hashlib.sha256(f"fmpy {fmpy.__version__} {fmpy.platform}".encode())
    for name, f in files.items():
        digest.update(name.encode() + b"\0" + f.read_bytes() + b"\0")
    out_dir = Path(cache) if cache is not None else cache_dir()
    target = out_dir / f"{source.name}-{digest.hexdigest()[:16]}.fmu"
    if target.is_file():
        return target
    if shutil.which("cmake") is None:
        raise FmuError(f"{source}: building the unit needs CMake and a C compiler (cmake not found)")
    with tempfile.TemporaryDirectory(prefix="icosim-fmu-") as tmp:
        unzipdir, build_dir = Path(tmp) / "unit", Path(tmp) / "build"
        for name, f in files.items():
            (unzipdir / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(f, unzipdir / name)
        build_dir.mkdir()
        _compile(source, unzipdir, build_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        part = target.with_name(target.name + f".{os.getpid()}.part")
        with zipfile.ZipFile(part, "w", zipfile.ZIP_DEFLATED) as zf:
            for f in sorted(unzipdir.rglob("*")):
                if f.is_file():
                    zf.write(f, f.relative_to(unzipdir).as_posix())
        os.replace(part, target)
    return target


def _compile(source: Path, unzipdir: Path, build_dir: Path):
    """fmpy's CMake project (``fmpy.build``) configured for the unit, run quietly."""
    import fmpy
    from fmpy.build import create_cmake_settings

    try:
        create_cmake_settings(unzipdir, build_dir)
    except Exception as exc:  # fmpy reports a bad model description with plain exceptions
        raise FmuError(f"{source}: cannot configure the build: {exc}") from None
    project = Path(fmpy.__file__).parent / "c-code"
    for cmd in (
        ["cmake", "-S", str(project), "-B", str(build_dir)],
        ["cmake", "--build", str(build_dir), "--target", "install", "--config", "Release"],
    ):
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            tail = " | ".join((run.stderr or run.stdout).strip().splitlines()[-5:])
            raise FmuError(f"{source}: building the unit failed ({' '.join(cmd[:2])}): {tail}")


def _build_python(script: Path, out_dir: Path) -> Path:
    """A pythonfmu script exported as an FMU that can save and restore its state (``--handle-state``)."""
    try:
        import pythonfmu
        from pythonfmu.builder import FmuBuilder
    except ImportError:
        raise FmuError(f"{script}: exporting a Python unit needs pythonfmu (pip install 'icosim[fmi]')") from None
    digest = hashlib.sha256(f"pythonfmu {pythonfmu.__version__}\0".encode() + script.read_bytes()).hexdigest()
    target = out_dir / f"{script.stem}-{digest[:16]}.fmu"
    if target.is_file():
        return target
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="icosim-pythonfmu-") as tmp:
        try:
            built = FmuBuilder.build_FMU(script, dest=tmp, canGetAndSetFMUstate=True)
        except Exception as exc:
            raise FmuError(f"{script}: pythonfmu could not export it: {exc}") from None
        part = target.with_name(target.name + f".{os.getpid()}.part")
        shutil.copyfile(built, part)
        os.replace(part, target)
    return target
