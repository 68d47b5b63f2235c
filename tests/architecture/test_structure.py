"""The shape of the package: no import cycle, files of one idea, rooms that keep to themselves (the engine
imports only itself and the errors, no study imports another, the report reads the studies through their
data contracts), thin workflow scripts, and library inputs of the rules that follow the real imports."""

import ast
import functools
import json
import subprocess
import sys
from pathlib import Path
from types import MappingProxyType

import pytest
from helpers import ROOT

from icosim.sources import module_closure, module_path, script_closure

SRC = ROOT / "src"
PACKAGE = SRC / "icosim"
SCRIPTS = sorted((ROOT / "workflow" / "scripts").glob("*.py"))
#: Files allowed beyond MAX_LINES, with the reason (one idea that needs the room).
LONG_FILES = {}
MAX_LINES = 450


def _module_name(path):
    rel = path.relative_to(SRC).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


def _imports(path):
    """icosim modules a file imports anywhere (lazy imports included), resolved."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1]) + (f".{node.module}" if node.module else "")
            else:
                base = node.module
            for a in node.names:
                sub = f"{base}.{a.name}"
                out.add(sub if module_path(sub, SRC) else base)
    return {m for m in out if m.split(".")[0] == "icosim" and m != name}


@functools.cache
def _graph():
    """Module -> the icosim modules it imports; parsed once for the tests that read it (none changes it)."""
    return MappingProxyType({_module_name(p): frozenset(_imports(p)) for p in PACKAGE.rglob("*.py")})


def test_no_import_cycle():
    """Every import counts, also one inside a function (the trick that used to hide a cycle)."""
    graph = _graph()
    state = {}

    def visit(node, stack):
        state[node] = "open"
        for nxt in graph.get(node, ()):
            if state.get(nxt) == "open":
                raise AssertionError("import cycle: " + " -> ".join(stack + [node, nxt]))
            if nxt not in state:
                visit(nxt, stack + [node])
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node, [])


#: The package's floors, lowest first: a module imports only its own room and the rooms of lower floors.  Rooms
#: on one floor import nothing of each other (no study another study, no problem another problem), except on
#: the base floor, whose shared modules are listed in the order they may rest on each other.
FLOORS = (
    (
        "base",
        (
            "icosim.errors",
            "icosim.version",
            "icosim.io",
            "icosim.verdicts",
            "icosim.order_fit",
            "icosim.step_limit",
            "icosim.labels",
            "icosim.sources",
            "icosim.job",
        ),
    ),  # fmt: skip
    ("engine", ("icosim.engine",)),
    ("the linear model", ("icosim.problems.linear",)),
    ("problems", ("icosim.problems.pendulum", "icosim.problems.fmu")),
    (
        "studies",
        (
            "icosim.studies.stability",
            "icosim.studies.convergence",
            "icosim.studies.pendulum",
            "icosim.studies.trade",
            "icosim.studies.fmi",
            "icosim.studies.chains",
            "icosim.studies.signals",
            "icosim.studies.peers",
        ),
    ),  # fmt: skip
    ("claims", ("icosim.claims",)),
    ("figures", ("icosim.figures",)),
    ("report and advice", ("icosim.report", "icosim.advise")),
    ("command line", ("icosim.cli",)),
    ("public names", ("icosim",)),
)
#: The studies' data contracts that the report and the figures may read: module -> what they take from it.
#: Each reads datasets or configurations and imports no module of a study that computes.
DATA_CONTRACTS = {
    "icosim.studies.stability.panels": "a panel's configuration: row labels, ratios, grid axes",
    "icosim.studies.convergence.experiment": "the convergence experiment's configuration: setup, step counts, the exact oscillation",
    "icosim.studies.convergence.curves": "panel and work-precision datasets read back as curves and rankings",
    "icosim.studies.trade.conclusions": "the trade datasets read back as the report's rows and counts",
    "icosim.studies.trade.orders": "the order fit above the pendulum's error floor (conclusions apply it)",
    "icosim.studies.peers.fastest": "the peers datasets read back as runs, the fastest per error level and its cost",
}
STUDIES = FLOORS[4][1]


def _room(module, rooms):
    """The room of ``rooms`` (dotted prefixes) that ``module`` lies in (the longest that fits), or None."""
    fits = [r for r in rooms if module == r or module.startswith(r + ".")]
    return max(fits, key=len) if fits else None


def _floor(module):
    """``(floor, position of the room on the floor, room)`` of ``module``."""
    rooms = [(i, j, r) for i, (_, floor) in enumerate(FLOORS) for j, r in enumerate(floor)]
    fits = [(i, j, r) for i, j, r in rooms if module == r or module.startswith(r + ".")]
    return max(fits, key=lambda f: len(f[2])) if fits else None


def test_every_module_lies_on_a_floor():
    assert not [m for m in _graph() if _floor(m) is None]


def test_imports_run_down_the_floors():
    """A module imports its own room and lower floors only; on a floor of rooms, none imports another (the
    base floor's shared modules only those listed before them)."""
    wrong = set()
    for module, imported in _graph().items():
        f, j, room = _floor(module)
        for i in imported:
            fi, ji, other = _floor(i)
            if other == room or fi < f or (fi == f == 0 and ji < j):
                continue
            wrong.add((module, i))
    assert not wrong, sorted(wrong)


def test_the_engine_imports_only_itself_and_the_errors():
    outside = {
        (m, i)
        for m, imported in _graph().items()
        if _room(m, ("icosim.engine",))
        for i in imported
        if not _room(i, ("icosim.engine", "icosim.errors"))
    }
    assert not outside, sorted(outside)


#: The engine's module-level containers and caches, with why they hold no run's state.
ENGINE_MODULE_STATE = {
    "icosim/engine/methods/base.py:UNIT_TEXT": "a constant table: how a unit reads in running text",
    "icosim/engine/schemes.py:SCHEMES": "the registry of schemes, filled at import",
    "icosim/engine/decompositions.py:DECOMPOSITIONS": "the registry of decompositions, filled at import",
    "icosim/engine/backends.py:_EXPM_CACHE": "float64 exponentials by the bytes of their argument (a pure function)",
    "icosim/engine/backends.py:_BALL_EXPM_CACHE": "ball exponentials by precision and the matrix's exact key",
    "icosim/engine/lagrange.py:monomial_coefficients (cache)": "exact Lagrange coefficients by their nodes",
    "icosim/engine/lagrange.py:_weights_at (cache)": "exact Lagrange weights by their nodes and point",
}


def _engine_module_containers():
    """``file:name`` of each module-level name the engine binds to a dict, list or set, or caches with
    functools, and each call of ``id()`` and use of an object's ``__dict__`` anywhere in it."""
    found = set()
    for path in sorted((PACKAGE / "engine").rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        tree = ast.parse(path.read_text())
        for stmt in tree.body:
            value = stmt.value if isinstance(stmt, (ast.Assign, ast.AnnAssign)) else None
            targets = stmt.targets if isinstance(stmt, ast.Assign) else [getattr(stmt, "target", None)]
            mutable = isinstance(value, (ast.Dict, ast.List, ast.Set)) or (
                isinstance(value, ast.Call) and ast.unparse(value.func) in ("dict", "list", "set")
            )
            if mutable:
                found.update(f"{rel}:{t.id}" for t in targets if isinstance(t, ast.Name) and t.id != "__all__")
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and ast.unparse(node.func) == "id":
                found.add(f"{rel}:id() at line {node.lineno}")
            if isinstance(node, ast.Attribute) and node.attr == "__dict__":  # a memo hidden from the class
                found.add(f"{rel}:__dict__ at line {node.lineno}")
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                cached = [ast.unparse(d) for d in node.decorator_list if "cache" in ast.unparse(d)]
                found.update(f"{rel}:{node.name} ({d})" for d in cached if d not in ("cached_property",))
    return found


def test_the_engine_keeps_no_run_state_in_its_modules():
    """Plans, kept Jacobians and their factors belong to the problem that steps with them
    (:class:`icosim.engine.problem.CosimulationProblem`), not to module caches keyed by an object's id: a
    problem used with a second method must never get the first's factors.  What remains at module level is
    the registries (filled at import) and caches of pure functions of values, listed with why."""
    assert _engine_module_containers() == set(ENGINE_MODULE_STATE)


def test_the_report_and_the_figures_read_the_studies_through_their_data_contracts():
    """report/ and figures/ draw what the studies wrote; from a study they import only its data contracts,
    and a data contract imports no other module of a study (so a report never reruns a study's code)."""
    graph = _graph()
    wrong = {
        (m, i)
        for m, imported in graph.items()
        if _room(m, ("icosim.report", "icosim.figures") + tuple(DATA_CONTRACTS))
        for i in imported
        if _room(i, STUDIES) and i not in DATA_CONTRACTS
    }
    assert not wrong, sorted(wrong)
    assert all(m in graph for m in DATA_CONTRACTS)


def _package_imports(path):
    """The packages a file imports as packages: ``from . import x`` and ``from .. import x`` name the package."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level and not node.module:
            parts = package.split(".")
            out.add(".".join(parts[: len(parts) - node.level + 1]))
    return out


def test_no_cycle_through_a_package():
    """Counting ``from . import x`` as an import of the package itself too (it runs the package's
    ``__init__``), no module and no package import each other in a circle: a package's ``__init__`` that
    imports its modules is fine as long as none of them imports the package back."""
    graph = {m: set(i) for m, i in _graph().items()}
    for path in PACKAGE.rglob("*.py"):
        graph[_module_name(path)] |= _package_imports(path) - {_module_name(path)}
    state = {}

    def visit(node, stack):
        state[node] = "open"
        for nxt in graph.get(node, ()):
            if state.get(nxt) == "open":
                raise AssertionError("import cycle: " + " -> ".join(stack + [node, nxt]))
            if nxt not in state:
                visit(nxt, stack + [node])
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node, [])


def test_files_hold_one_idea():
    long = {
        str(p.relative_to(SRC)): n
        for p in PACKAGE.rglob("*.py")
        if (n := len(p.read_text().splitlines())) > MAX_LINES and str(p.relative_to(SRC)) not in LONG_FILES
    }
    assert not long, f"files over {MAX_LINES} lines: {long}"


def test_claims_machinery_knows_no_part():
    imported = _imports(PACKAGE / "verdicts.py")
    assert imported <= {"icosim.errors", "icosim.io.netcdf", "icosim.io.jsonio", "icosim.io.yamlio"}, imported
    assert "<" not in (PACKAGE / "verdicts.py").read_text().split('"""', 2)[2].replace("<=", "")  # no HTML


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.stem)
def test_workflow_scripts_are_thin(script):
    assert len(script.read_text().splitlines()) <= 45


#: What a clean interpreter reports after a script's import statements: the files of the icosim modules loaded.
_REPORT = "sorted(m.__file__ for n, m in sys.modules.items() if n.split('.')[0] == 'icosim')"


def _loaded_files(statements: str) -> list:
    """Files of the icosim modules that ``statements`` load in a fresh interpreter (the source tree's src/)."""
    code = f"{statements}\nimport json, sys\nprint(json.dumps({_REPORT}))"
    env = {"PYTHONPATH": str(SRC), "MPLBACKEND": "Agg", "PATH": "", "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT, env=env)
    return json.loads(out.stdout)


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.stem)
def test_library_inputs_cover_what_a_script_loads(script):
    """The files script_closure lists (a rule's library inputs) are every icosim module its imports load."""
    listed = {p.relative_to(SRC).as_posix() for p in script_closure(script, SRC)}
    tree = ast.parse(script.read_text())
    stmts = [
        ast.unparse(n) for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom)) and "icosim" in ast.unparse(n)
    ]
    loaded = {str(Path(f).resolve().relative_to(SRC.resolve()).as_posix()) for f in _loaded_files("\n".join(stmts))}
    assert loaded <= listed, sorted(loaded - listed)


def test_stability_claims_do_not_rest_on_the_pendulum_problem():
    files = {p.relative_to(SRC).as_posix() for p in script_closure(ROOT / "workflow/scripts/claims.py", SRC)}
    assert "icosim/studies/stability/checks.py" in files and "icosim/studies/pendulum/checks.py" in files
    assert (
        not {
            "icosim/problems/pendulum/problem.py",
            "icosim/problems/pendulum/runs.py",
            "icosim/studies/convergence/study.py",
        }
        & files
    )
    assert "icosim/problems/pendulum/integrator/compiled.py" not in {
        p.relative_to(SRC).as_posix() for p in module_closure(["icosim.claims.registry"], SRC)
    }


def test_an_edited_module_is_read_again(tmp_path):
    """module_closure parses each file once per version (a cache for Snakemake's start): an edit shows."""
    pkg = tmp_path / "icosim"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "b.py").write_text("")
    (pkg / "c.py").write_text("")
    (pkg / "a.py").write_text("from . import b\n")
    assert [p.name for p in module_closure(["icosim.a"], tmp_path)] == ["__init__.py", "a.py", "b.py"]
    (pkg / "a.py").write_text("from . import b, c\n")
    assert [p.name for p in module_closure(["icosim.a"], tmp_path)] == ["__init__.py", "a.py", "b.py", "c.py"]


def test_a_missing_module_is_an_error_naming_it_and_who_wants_it(tmp_path):
    """A closure that skipped a module it was asked for, or one a module imports, would vouch for less than it
    says (a rule's library digest without the module)."""
    pkg = tmp_path / "icosim"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from . import gone\n")
    (pkg / "b.py").write_text("import icosim.gone\n")
    with pytest.raises(ModuleNotFoundError, match=r"no module icosim\.missing under .* \(asked for\)"):
        module_closure(["icosim.missing"], tmp_path)
    with pytest.raises(ModuleNotFoundError, match=r"no module icosim\.gone under .* \(imported by icosim\.b\)"):
        module_closure(["icosim.b"], tmp_path)
    # ``from . import name``: a name that is no module is an attribute of the package, not a missing module
    assert [p.name for p in module_closure(["icosim.a"], tmp_path)] == ["__init__.py", "a.py"]


def test_the_library_digest_follows_paths_and_contents_not_time_stamps(tmp_path):
    """A rule's `library` parameter: the same files give the same digest wherever the checkout is; an
    edit, another file or a renamed one gives another; a touch does not."""
    import hashlib
    import os

    from icosim.sources import library_digest

    def tree(root, texts):
        for name, text in texts.items():
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            (root / name).write_text(text)
        return root

    a = tree(tmp_path / "a", {"icosim/x.py": "x = 1\n", "icosim/y.py": "y = 2\n"})
    b = tree(tmp_path / "b", {"icosim/x.py": "x = 1\n", "icosim/y.py": "y = 2\n"})
    names = ["icosim/y.py", "icosim/x.py"]
    expected = hashlib.sha256()
    for name in sorted(names):
        expected.update(name.encode() + b"\0" + hashlib.sha256((a / name).read_bytes()).hexdigest().encode())
    assert library_digest(names, a) == library_digest(names[::-1], b) == expected.hexdigest()
    os.utime(a / "icosim/x.py", ns=(1, 1))
    assert library_digest(names, a) == expected.hexdigest()
    (a / "icosim/x.py").write_text("x = 3\n")
    assert library_digest(names, a) != expected.hexdigest()
    assert library_digest(["icosim/x.py"], b) != library_digest(names, b)
    (b / "icosim/z.py").write_text("y = 2\n")
    assert library_digest(["icosim/x.py", "icosim/z.py"], b) != library_digest(names, b)


def test_the_imports_kept_across_processes_follow_the_text(tmp_path):
    """What a source imports is kept by its text in the user's cache (Snakemake reads the workflow in
    every process): a second process parses nothing, an edited file is parsed again, a broken cache
    file is ignored."""
    pkg = tmp_path / "tree" / "icosim"
    pkg.mkdir(parents=True)
    for name, text in (("__init__.py", ""), ("b.py", ""), ("c.py", ""), ("a.py", "from . import b\n")):
        (pkg / name).write_text(text)
    env = {"PYTHONPATH": str(SRC), "PATH": "", "XDG_CACHE_HOME": str(tmp_path / "cache")}

    def closure(parse_allowed=True):
        code = (
            "import ast, json, sys\n"
            "from icosim.sources import module_closure\n"
            + ("" if parse_allowed else "ast.parse = None\n")
            + f"print(json.dumps([p.name for p in module_closure(['icosim.a'], {str(tmp_path / 'tree')!r})]))"
        )
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
        return json.loads(out.stdout) if out.returncode == 0 else "failed"

    assert closure() == ["__init__.py", "a.py", "b.py"]
    assert closure(parse_allowed=False) == ["__init__.py", "a.py", "b.py"]
    (pkg / "a.py").write_text("from . import b, c\n")
    assert closure(parse_allowed=False) == "failed"  # a new text is parsed, never looked up by its name
    assert closure() == ["__init__.py", "a.py", "b.py", "c.py"]
    (cache_file,) = (tmp_path / "cache" / "icosim").glob("source-imports-*.json")
    cache_file.write_text("{broken")
    (pkg / "a.py").write_text("from . import c\n")
    assert closure() == ["__init__.py", "a.py", "c.py"]


def _loaded_after(statement: str, modules) -> list:
    """Which of ``modules`` a fresh interpreter has loaded after ``statement``."""
    code = f"import sys; {statement}; print(sorted(set({sorted(modules)!r}) & set(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        env={"PYTHONPATH": str(SRC), "PATH": ""},
    )
    return json.loads(out.stdout.replace("'", '"'))


def test_importing_the_spectral_radius_stays_light():
    assert _loaded_after("import icosim.engine.spectral", {"xarray", "matplotlib"}) == []


def _type_checking_imports(path):
    """``{name: module}`` imported under ``if TYPE_CHECKING:`` in ``path`` (relative module names)."""
    tree = ast.parse(path.read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for stmt in node.body:
                out.update({alias.name: "." * stmt.level + stmt.module for alias in stmt.names})
    return out


def test_the_package_loads_its_public_names_lazily_and_lists_them_for_the_workflow():
    """icosim's public names: one table for the lazy loader, the same names under TYPE_CHECKING
    (what icosim.sources reads, so every job importing icosim keeps the whole engine as input)."""
    import icosim

    assert _type_checking_imports(SRC / "icosim" / "__init__.py") == icosim._LAZY
    assert set(icosim._LAZY) == set(icosim.__all__)
    assert all(getattr(icosim, name) is not None for name in icosim.__all__)
    engine = {
        "icosim/problems/linear/problem.py",
        "icosim/engine/spectral/__init__.py",
        "icosim/engine/methods/__init__.py",
    }
    assert engine <= {p.relative_to(SRC).as_posix() for p in module_closure(["icosim.problems.pendulum.names"], SRC)}
    assert _loaded_after("import icosim.studies.trade.measures", {"scipy.linalg", "mpmath"}) == []
