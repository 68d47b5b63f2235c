"""A new coupling scheme or decomposition is a registry entry plus its own rule code.

A toy decomposition (a second displacement/force split under another name) and a toy scheme (a
sequential scheme, subsystem 1 first, under another name) are registered here, in the test, through
:func:`icosim.engine.decompositions.register` and :func:`icosim.engine.schemes.register` alone.  Nothing
in the package names them, yet the configuration schemas, the command line's choices, the engine and
the workflow's DAG take them; the engine's numbers equal those of the entries they copy.
"""

import json
from dataclasses import dataclass

import pytest
import yaml
from helpers import ROOT, copy_workflow, scheduled, snakemake, validate_config

from icosim.cli import main
from icosim.engine import decompositions, schemes
from icosim.engine.decompositions import Decomposition
from icosim.engine.schemes import GaussSeidel

DECOMPOSITION = "toy-split"
SCHEME = "toy-sequential"


@dataclass(frozen=True, init=False, repr=False)
class ToySequential(GaussSeidel):
    """Subsystem 1 first, as Gauss-Seidel 1->2, under its own name."""

    def __init__(self):
        super().__init__(first=1)

    @property
    def name(self) -> str:
        return SCHEME

    @property
    def label(self) -> str:
        return "Toy sequential"


TOY_DECOMPOSITION = Decomposition(
    DECOMPOSITION, ("kinematic", "force"), (1, 0), ("lambda_c", "a_tilde_2"), "toy displacement/force"
)

# the same registration, as a module the workflow's copy imports before its rules
REGISTRATION = f"""
from dataclasses import dataclass
from icosim.engine import decompositions, schemes
from icosim.engine.decompositions import Decomposition
from icosim.engine.schemes import GaussSeidel


@dataclass(frozen=True, init=False, repr=False)
class ToySequential(GaussSeidel):
    def __init__(self):
        super().__init__(first=1)

    @property
    def name(self):
        return {SCHEME!r}

    @property
    def label(self):
        return "Toy sequential"


decompositions.register(Decomposition({DECOMPOSITION!r}, ("kinematic", "force"), (1, 0), ("lambda_c", "a_tilde_2"),
                                      "toy displacement/force"))
schemes.register(ToySequential())
"""


@pytest.fixture
def toys():
    decompositions.register(TOY_DECOMPOSITION)
    schemes.register(ToySequential())
    yield
    del decompositions.DECOMPOSITIONS[DECOMPOSITION]  # the registries as they were
    del schemes.SCHEMES[SCHEME]


def _figure(cfg):
    return {**cfg["figures"]["13"], "title": "toy", "decomposition": DECOMPOSITION, "schemes": [SCHEME, "jacobi"]}


def test_no_file_of_the_package_names_the_toys():
    for path in (ROOT / "src").rglob("*.py"):
        text = path.read_text()
        assert DECOMPOSITION not in text and SCHEME not in text, path


def test_schema_takes_the_toys_only_when_registered(toys):
    cfg = yaml.safe_load((ROOT / "config" / "stability.yaml").read_text())["stability"]
    cfg["figures"]["toy"] = _figure(cfg)
    validate_config(cfg, "stability")
    del decompositions.DECOMPOSITIONS[DECOMPOSITION]
    try:
        with pytest.raises(Exception, match=DECOMPOSITION):
            validate_config(cfg, "stability")
    finally:
        decompositions.register(TOY_DECOMPOSITION)


def test_command_line_choices_and_numbers(toys, capsys):
    def rho(decomposition, scheme):
        argv = ["rho", "--method", "weighted", "--a", "1", "--b", "1", "--decomposition", decomposition]
        argv += ["--k", "1", "--scheme", scheme, "--lr1", "-0.4", "--li1", "1.1", "--am21", "3"]
        argv += ["--alr21", "0.5", "--ali21", "2", "--json"]
        assert main(argv) == 0
        return json.loads(capsys.readouterr().out)

    toy, original = rho(DECOMPOSITION, SCHEME), rho("df", "gauss-seidel-12")
    assert toy["decomposition"] == DECOMPOSITION and toy["scheme"] == SCHEME
    assert toy["rho"] == original["rho"] and toy["verdict"] == original["verdict"]  # the same code path
    with pytest.raises(SystemExit):
        main(["rho", "--help"])
    assert DECOMPOSITION in capsys.readouterr().out


def test_without_registration_the_command_line_refuses_them(capsys):
    with pytest.raises(SystemExit):
        main(["rho", "--method", "projection", "--decomposition", DECOMPOSITION, "--k", "0"])
    err = capsys.readouterr().err
    assert "argument --decomposition" in err and "ff, fd, df, dd" in err.replace("'", "")


def test_the_dag_schedules_a_figure_with_the_toys(tmp_path):
    wf = copy_workflow(tmp_path)
    (wf / "toy_registry.py").write_text(REGISTRATION)
    snakefile = (wf / "Snakefile").read_text()
    (wf / "Snakefile").write_text(f"import sys\nsys.path.insert(0, {str(wf)!r})\nimport toy_registry\n\n{snakefile}")
    cfg_path = wf / "config" / "stability.yaml"
    cfg = yaml.safe_load(cfg_path.read_text())
    cfg["stability"]["figures"]["toy"] = _figure(cfg["stability"])
    cfg_path.write_text(yaml.safe_dump(cfg))
    proc = snakemake(wf, "-n", "results/stability/figures/figtoy_toy-sequential.png")
    panels = scheduled(proc, "stability_panels_figtoy")
    assert "results/stability/figtoy/toy-sequential/r1_k0_full.nc" in panels
    assert "results/stability/figtoy/jacobi/r4_k2_zoom.nc" in panels
    assert scheduled(proc, "stability_figure_figtoy")
