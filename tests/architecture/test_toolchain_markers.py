"""The toolchain markers (tests/toolchains.py) in pytest sessions of their own, with and without xdist: a marked
test is skipped where its toolchain is missing, and in CI a marked test skipped where its toolchain is present
fails the session, naming the marker, the test and why it was skipped.

The session runs in a temporary directory on a PATH that holds only the toolchain under test: a fake ``sinfo``
that answers (a cluster), one that fails (a client without a cluster), or none.
"""

import os
import subprocess
import sys

import pytest
from helpers import ROOT

MARKED = """
import pytest

pytestmark = pytest.mark.slurm


def test_runs():
    pass


def test_skipped_for_another_reason():
    pytest.skip("the partition is drained today")
"""

#: Skipped too, but not marked: it lies in a folder named like the marker (a test's keywords hold its folders'
#: names, so only its markers may count).
UNMARKED = """
import pytest


def test_skipped_without_a_marker():
    pytest.skip("nothing to do with the cluster")
"""


def session(tmp_path, *args, sinfo=None, ci=True, require=""):
    """A pytest session on the two files above with the plugin loaded; ``sinfo``: None (no client), "answers" or
    "fails".  Returns the exit status and the output."""
    (tmp_path / "pytest.ini").write_text("[pytest]\nmarkers =\n    slurm: a SLURM cluster\n")
    (tmp_path / "test_marked.py").write_text(MARKED)
    (tmp_path / "slurm").mkdir()
    (tmp_path / "slurm" / "test_unmarked.py").write_text(UNMARKED)
    path = tmp_path / "bin"
    path.mkdir()
    if sinfo:
        (path / "sinfo").write_text(f"#!/bin/sh\nexit {0 if sinfo == 'answers' else 1}\n")
        (path / "sinfo").chmod(0o755)
    env = {k: v for k, v in os.environ.items() if k not in ("CI", "ICOSIM_REQUIRE_TOOLCHAINS") and "PYTEST" not in k}
    env |= {"PATH": str(path), "PYTHONPATH": os.pathsep.join([str(ROOT / "tests"), env.get("PYTHONPATH", "")])}
    env |= {"CI": "true"} if ci else {}
    env |= {"ICOSIM_REQUIRE_TOOLCHAINS": require} if require else {}
    argv = [
        sys.executable,
        "-m",
        "pytest",
        "-p",
        "toolchains",
        "-p",
        "no:cacheprovider",
        "-p",
        "no:benchmark",
        "-rs",
        *args,
    ]
    proc = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    return proc.returncode, proc.stdout + proc.stderr


@pytest.mark.parametrize("workers", ["0", "2"])
def test_a_marked_test_skipped_where_its_toolchain_is_present_fails_ci(tmp_path, workers):
    status, out = session(tmp_path, "-n", workers, sinfo="answers")
    assert status == pytest.ExitCode.TESTS_FAILED, out
    assert "slurm tests skipped in CI" in out and "the slurm toolchain is present, yet 1 test(s)" in out
    assert "test_marked.py::test_skipped_for_another_reason: the partition is drained today" in out
    assert "test_unmarked" not in out.split("slurm tests skipped in CI")[1].split("short test summary")[0]
    assert "1 passed, 2 skipped" in out


def test_outside_ci_the_same_skip_passes(tmp_path):
    status, out = session(tmp_path, sinfo="answers", ci=False)
    assert status == pytest.ExitCode.OK, out
    assert "1 passed, 2 skipped" in out and "skipped in CI" not in out


@pytest.mark.parametrize(
    ("workers", "sinfo", "lacking"),
    [("0", None, "SLURM's sinfo"), ("2", None, "SLURM's sinfo"), ("0", "fails", "a SLURM cluster that answers sinfo")],
)
def test_a_missing_toolchain_skips_its_tests_and_ci_passes(tmp_path, workers, sinfo, lacking):
    status, out = session(tmp_path, "-n", workers, sinfo=sinfo)
    assert status == pytest.ExitCode.OK, out
    assert f"the slurm toolchain is missing: {lacking}" in out
    assert "3 skipped" in out and "skipped in CI" not in out


def test_a_required_toolchain_that_is_missing_fails_its_tests(tmp_path):
    status, out = session(tmp_path, require="slurm")
    assert status == pytest.ExitCode.TESTS_FAILED, out
    assert out.count("the slurm toolchain is missing: SLURM's sinfo (ICOSIM_REQUIRE_TOOLCHAINS requires it)") == 2
    assert "1 skipped, 2 errors" in out


def test_a_misspelt_required_toolchain_stops_the_run(tmp_path):
    status, out = session(tmp_path, require="slurm,chrome")
    assert status == pytest.ExitCode.USAGE_ERROR, out
    assert "ICOSIM_REQUIRE_TOOLCHAINS names ['chrome']" in out
