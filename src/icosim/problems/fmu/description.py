"""A unit's model description, read the way fmpy reads it, and the kind of unit a scene can couple as
co-simulation: FMI 2.0 or 3.0 co-simulation that saves and restores its state (model exchange:
:mod:`icosim.problems.fmu.exchange`)."""

from __future__ import annotations

import zipfile
from pathlib import Path

from .errors import FmuError

__all__ = ["read_description", "check_kind", "STATE_REASON"]

#: Why a unit must save and restore its state: every scheme integrates a unit more than once over a macro step.
STATE_REASON = (
    "every coupling scheme integrates a unit more than once from the same macro-step start (predictor, the "
    "perturbed steps of the sensitivities, corrector), which needs fmi2GetFMUstate/fmi2SetFMUstate"
)


def read_description(label: str, path: Path):
    """The unit's model description (fmpy) and the problems fmpy's validation finds in it (a list; exporters get
    details wrong that do not touch what a scene uses, e.g. an Integer output declared continuous), or
    :class:`FmuError` naming ``label`` and the file when it cannot be read at all."""
    from fmpy import read_model_description
    from fmpy.model_description import ValidationError

    path = Path(path)
    if path.is_dir():
        raise FmuError(
            f"{label}: {path} is a directory but not a unit's source (a modelDescription.xml beside sources/) "
            "nor an unpacked FMU; name the .fmu file or the unit's source directory"
        )
    if not path.is_file():
        raise FmuError(f"{label}: FMU file {path} does not exist")
    if not zipfile.is_zipfile(path):
        raise FmuError(f"{label}: {path} is not an FMU (not a ZIP archive)")
    try:
        return read_model_description(str(path), validate=True), []
    except ValidationError as exc:
        problems = [" ".join(str(p).split()) for p in exc.problems]
    except Exception as exc:  # fmpy raises plain exceptions for unreadable descriptions
        problems, first = None, " ".join(str(exc).split()[:40]) or type(exc).__name__
    if problems is not None:
        try:
            return read_model_description(str(path), validate=False), problems
        except Exception as exc:
            first = " ".join(str(exc).split()[:40]) or type(exc).__name__
    raise FmuError(f"{label}: {path} has no readable modelDescription.xml ({first})") from None


def check_kind(label: str, path: Path, md, *, saves_state: bool = True):
    """Refuse a unit that is not an FMI 2.0/3.0 co-simulation unit that saves and restores its state (without
    ``saves_state``: a co-simulation unit, stepped forward only)."""
    if md.fmiVersion not in ("2.0",) and not md.fmiVersion.startswith("3."):
        raise FmuError(f"{label}: {path} is FMI {md.fmiVersion}; FMI 2.0 or 3.0 co-simulation units are supported")
    if md.coSimulation is None:
        kinds = [k for k, present in (("model exchange", md.modelExchange), ("scheduled execution",
                 getattr(md, "scheduledExecution", None))) if present is not None]  # fmt: skip
        has = " and ".join(kinds) or "no interface"
        raise FmuError(
            f"{label}: {path} offers {has} only (no <CoSimulation> in its modelDescription.xml); as "
            "co-simulation a unit brings its own solver"
            + ("; use interface: model-exchange (or auto)" if md.modelExchange is not None else "")
        )
    if saves_state and not md.coSimulation.canGetAndSetFMUstate:
        flag = "canGetAndSetFMUState" if md.fmiVersion.startswith("3.") else "canGetAndSetFMUstate"
        other = "; its model exchange leaves the state with icosim: use interface: model-exchange (or auto)"
        raise FmuError(f"{label}: {path} declares {flag}=false; {STATE_REASON}{other if md.modelExchange else ''}")
