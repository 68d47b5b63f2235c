"""The toolchain markers: tests that need a C compiler, CMake and fmpy (``fmu``), a SLURM cluster (``slurm``),
headless Chromium (``browser``) or the units and systems of other tools in ``../shared/outside`` (``outside``), with
the other masters run on them (``peers``: libcosim and Ecos as well; a test marked ``peers`` is not marked
``outside`` too: in CI a skip counts against every marker of a test).  A pytest plugin, loaded by tests/conftest.py.

A marked test runs where its toolchain is present and is skipped where it is not, with a reason naming what is
missing.  ``ICOSIM_REQUIRE_TOOLCHAINS`` (marker names, comma-separated) makes a missing toolchain fail those tests
instead: CI names the toolchains it installs.

In CI (``CI=true``) a skip must not hide a test the machine could run: when a marker's toolchain is present and
any of its tests was skipped all the same, for whatever reason (a ``skipif``, a ``pytest.skip`` or
``pytest.importorskip`` in the test or its fixtures), the session fails, naming the marker and the tests.  Under
pytest-xdist the workers skip and label their reports with the test's toolchain markers; the controller, which
receives every report, counts the skips and decides.  A module skipped while it is imported reports no test at
all, so a marked module never skips at import (tests/architecture/test_test_folders.py checks it).
"""

from __future__ import annotations

import functools
import importlib.util
import os
import shutil
import subprocess
from pathlib import Path

import pytest


def _fmu_missing() -> list[str]:
    missing = []
    if not (shutil.which("cc") or shutil.which("gcc")):
        missing.append("a C compiler (cc or gcc)")
    if not shutil.which("cmake"):
        missing.append("CMake")
    if importlib.util.find_spec("fmpy") is None:
        missing.append("fmpy (the fmi extra)")
    return missing


def _slurm_missing() -> list[str]:
    if not shutil.which("sinfo"):
        return ["SLURM's sinfo"]
    try:
        answered = subprocess.run(["sinfo", "-h"], capture_output=True, timeout=10).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        answered = False
    return [] if answered else ["a SLURM cluster that answers sinfo"]


def _browser_missing() -> list[str]:
    from icosim.report.browser import find_chromium  # the report's own search: the executable it would run

    return [] if find_chromium() else ["Chromium on PATH (Debian: apt-get install chromium)"]


#: Units and systems exported by other tools (their origin and licences: its README), beside the project's root.
OUTSIDE = Path(__file__).resolve().parents[1].parent / "shared" / "outside"


def _outside_missing() -> list[str]:
    missing = [] if (OUTSIDE / "README.md").is_file() else [f"the other tools' units in {OUTSIDE}"]
    if importlib.util.find_spec("fmpy") is None:
        missing.append("fmpy (the fmi extra)")
    return missing


def _peers_missing() -> list[str]:
    """The outside units and fmpy, and each peer package, importable (Ecos loads TBB's shared library on import)."""
    from icosim.studies.peers.masters import PEER_PACKAGES  # the plugin loads before icosim is needed

    missing = _outside_missing()
    for package, master in PEER_PACKAGES.items():
        try:
            importlib.import_module(package)
        except (ImportError, OSError) as exc:
            missing.append(f"{master} ({package}, the peers extra: {exc})")
    return missing


#: Marker -> what its toolchain lacks on this machine (an empty list: present).
TOOLCHAINS = {"fmu": _fmu_missing, "slurm": _slurm_missing, "browser": _browser_missing, "outside": _outside_missing,
              "peers": _peers_missing}  # fmt: skip
REQUIRE = "ICOSIM_REQUIRE_TOOLCHAINS"


@functools.cache
def missing(marker: str) -> tuple[str, ...]:
    """What the toolchain of ``marker`` lacks, looked up once per process (``sinfo`` may take seconds)."""
    return tuple(TOOLCHAINS[marker]())


def required() -> set[str]:
    names = set(os.environ.get(REQUIRE, "").replace(",", " ").split())
    unknown = names - set(TOOLCHAINS)
    if unknown:
        raise pytest.UsageError(f"{REQUIRE} names {sorted(unknown)}; the toolchain markers are {sorted(TOOLCHAINS)}")
    return names


def in_ci() -> bool:
    return os.environ.get("CI", "").lower() in ("1", "true", "yes")


def toolchain_markers(item: pytest.Item) -> list[str]:
    """The toolchain markers of a test (its own, its class's or its module's ``pytestmark``).  Markers only: a
    test's keywords also hold its folders' names, and tests/problems/fmu/ is a folder called ``fmu``."""
    return [name for name in TOOLCHAINS if item.get_closest_marker(name) is not None]


def pytest_configure(config: pytest.Config) -> None:
    required()  # a misspelt name stops the run at once
    if not hasattr(config, "workerinput"):  # the controller (or a run without xdist) sees every report
        config.pluginmanager.register(SkipsInCI(), "toolchain-skips-in-ci")


def _lacking(name: str) -> str:
    return f"the {name} toolchain is missing: {', '.join(missing(name))}"


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """A skip marker on each test whose toolchain is missing (reported at the test's own line)."""
    for item in items:
        for name in toolchain_markers(item):
            if missing(name) and name not in required():
                item.add_marker(pytest.mark.skip(reason=_lacking(name)))


@pytest.hookimpl(tryfirst=True)  # before the test's fixtures are set up (they may build units)
def pytest_runtest_setup(item: pytest.Item) -> None:
    for name in toolchain_markers(item):
        if missing(name) and name in required():
            pytest.fail(f"{_lacking(name)} ({REQUIRE} requires it)", pytrace=False)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    report = yield
    names = toolchain_markers(item)
    if names:
        report.toolchain_markers = names  # an attribute of the report travels with it from an xdist worker
    return report


class SkipsInCI:
    """The skipped tests of each toolchain marker, and the session's failure in CI where the toolchain is
    present."""

    def __init__(self) -> None:
        self.skipped: dict[str, list[tuple[str, str]]] = {}
        self.failing: dict[str, list[tuple[str, str]]] = {}

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        if not report.skipped or hasattr(report, "wasxfail"):  # an expected failure ran; it is no skip
            return
        reason = report.longrepr[2] if isinstance(report.longrepr, (tuple, list)) else str(report.longrepr)
        for name in getattr(report, "toolchain_markers", ()):
            self.skipped.setdefault(name, []).append((report.nodeid, reason.removeprefix("Skipped: ")))

    def pytest_sessionfinish(self, session: pytest.Session) -> None:
        if not in_ci():
            return
        self.failing = {name: tests for name, tests in self.skipped.items() if not missing(name)}
        if self.failing and session.exitstatus == pytest.ExitCode.OK:
            session.exitstatus = pytest.ExitCode.TESTS_FAILED

    def pytest_terminal_summary(self, terminalreporter) -> None:
        for name, tests in self.failing.items():
            terminalreporter.section(f"{name} tests skipped in CI", sep="=", red=True, bold=True)
            terminalreporter.line(
                f"the {name} toolchain is present, yet {len(tests)} test(s) marked {name} were skipped; "
                "CI=true fails the session:",
                red=True,
            )
            for nodeid, reason in tests:
                terminalreporter.line(f"  {nodeid}: {reason}")
