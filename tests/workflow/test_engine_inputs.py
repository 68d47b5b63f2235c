"""The engine that the workflow's numerical jobs must rest on (``ENGINE`` in workflow/rules/common.smk): modules
that exist, whose files every such job's library digest covers."""

import ast
import re

from helpers import ROOT

from icosim.sources import module_closure, script_closure

COMMON = ROOT / "workflow" / "rules" / "common.smk"
SRC = ROOT / "src"


def _engine_modules():
    """The module names ``ENGINE = lib(...)`` gives, as the rule file spells them."""
    match = re.search(r"^ENGINE = lib\((.*)\)$", COMMON.read_text(), re.MULTILINE)
    assert match, f"{COMMON.name} defines no ENGINE = lib(...)"
    return [f"icosim.{name}" for name in ast.literal_eval(f"({match.group(1)},)")]


def test_the_engine_names_modules_that_exist():
    names = _engine_modules()
    files = {p.relative_to(SRC).as_posix() for p in module_closure(names, SRC)}  # a missing one raises
    for name in names:
        stem = name.replace(".", "/")
        assert f"{stem}.py" in files or f"{stem}/__init__.py" in files, name
    assert {"icosim/engine/macrostep.py", "icosim/problems/linear/problem.py"} <= files


def test_every_numerical_job_rests_on_the_whole_engine():
    """The scripts of the rules whose library is ``engine_library``: their closures hold every ENGINE file."""
    engine = set(module_closure(_engine_modules(), SRC))
    rules = "\n".join(p.read_text() for p in (ROOT / "workflow" / "rules").glob("*.smk"))
    scripts = sorted(set(re.findall(r'engine_library\("(\w+)"\)', rules)))
    assert len(scripts) > 5
    for script in scripts:
        assert engine <= set(script_closure(ROOT / "workflow" / "scripts" / f"{script}.py", SRC)), script
