"""The shape of tests/: folders that mirror the package's rooms, one basename per test file, and marked modules
that never skip while they are imported (their skips would hide from the toolchain check, tests/toolchains.py)."""

import ast

from helpers import ROOT
from toolchains import TOOLCHAINS

TESTS = ROOT / "tests"
PACKAGE = ROOT / "src" / "icosim"
#: Test folders that are no room of the package, with what they hold.
BEYOND_THE_PACKAGE = {
    "workflow": "the Snakemake side: dry runs, real runs, the SLURM profile, faults and recovery, a job's process",
    "tools": "the tools of tools/",
    "architecture": "the shape of the package and of its tests, the toolchain markers",
    "problems/fmu/fmus": "the test units of fmus/, each through fmpy's low-level API",
}
TEST_FILES = sorted(TESTS.rglob("test_*.py"))


def test_every_test_lies_in_a_folder_that_mirrors_a_room_of_the_package():
    folders = {path.parent.relative_to(TESTS).as_posix() for path in TEST_FILES}
    assert "." not in folders, "a test file at the top of tests/: it belongs in the folder of its room"
    stray = {f for f in folders if not (PACKAGE / f).is_dir() and f not in BEYOND_THE_PACKAGE}
    assert not stray, f"test folders with no room of src/icosim/ of that name: {sorted(stray)}"


def test_test_basenames_are_unique_and_the_folders_no_packages():
    """The folders are put on sys.path one by one (pytest's default import mode): a module is known by its
    basename, so two files of one name would shadow each other; a package would change their names."""
    names = [path.name for path in TEST_FILES]
    assert len(names) == len(set(names)), sorted({n for n in names if names.count(n) > 1})
    assert not list(TESTS.rglob("__init__.py"))


def _marks_a_toolchain(tree):
    return any(
        isinstance(node, ast.Attribute) and node.attr in TOOLCHAINS and ast.unparse(node.value) == "pytest.mark"
        for node in ast.walk(tree)
    )


def _skips_at_import(tree):
    """Calls of pytest.skip or pytest.importorskip among the module's own statements (not in a function)."""
    calls = []
    for stmt in tree.body:
        if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            continue
        for node in ast.walk(stmt):
            if isinstance(node, ast.Call) and ast.unparse(node.func) in ("pytest.skip", "pytest.importorskip"):
                calls.append(f"line {node.lineno}: {ast.unparse(node.func)}")
    return calls


def test_a_module_with_toolchain_markers_does_not_skip_while_it_is_imported():
    """A module skipped at import reports no test, so CI could not tell that its marked tests were skipped:
    such a skip belongs in a fixture or the test."""
    trees = {path.relative_to(TESTS).as_posix(): ast.parse(path.read_text()) for path in TEST_FILES}
    wrong = {name: _skips_at_import(tree) for name, tree in trees.items() if _marks_a_toolchain(tree)}
    assert not {name: calls for name, calls in wrong.items() if calls}
    assert sum(map(_marks_a_toolchain, trees.values())) > 10  # the check sees the markers
