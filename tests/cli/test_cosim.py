"""``icosim cosim``: the shipped example scenes run; the dataset holds the trajectory, the scene and the units'
provenance and counters; ``--json`` prints a summary."""

import json

import numpy as np
import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.io.netcdf import open_dataset
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_scene import SignalScene

pytestmark = pytest.mark.fmu

SCENES = sorted((ROOT / "config" / "scenes").glob("*.yaml"))


@pytest.fixture(autouse=True, scope="module")
def scene_schema_checker():
    """Scene files are checked with jsonschema (the fmi extra)."""
    return pytest.importorskip("jsonschema", reason="scene files are checked with jsonschema (the fmi extra)")


@pytest.fixture(autouse=True)
def fmu_cache(monkeypatch):
    monkeypatch.setenv("ICOSIM_FMU_CACHE", str(ROOT / "build" / "fmus"))


def shortened(scene, tmp_path, steps=40):
    """The scene with absolute unit (or system file) paths and ``steps`` macro steps."""
    data = yaml.safe_load(scene.read_text())
    if "system" in data:
        data["system"] = str((scene.parent / data["system"]).resolve())
    for sub in data["subsystems"].values():
        if "fmu" in sub:
            sub["fmu"] = str((scene.parent / sub["fmu"]).resolve())
    data["t_end"] = data.get("t_start", 0.0) + steps * data["coupling"]["H"]
    path = tmp_path / scene.name
    path.write_text(yaml.safe_dump(data))
    return path


def test_the_examples_are_there():
    assert {
        "two_mass_ff.yaml",
        "two_mass_fd.yaml",
        "two_mass_dd.yaml",
        "two_mass_python.yaml",
        "chain3.yaml",
        "chain10.yaml",
    } <= {p.name for p in SCENES}


@pytest.mark.parametrize("scene", SCENES, ids=lambda p: p.stem)
def test_example_scene_is_valid_and_runs(capsys, tmp_path, scene):
    load_scene(scene)  # the file as shipped (its relative paths) passes every check
    assert main(["cosim", str(scene), "--check", "--json"]) == 0  # and every unit's
    report = json.loads(capsys.readouterr().out)
    assert not report["refused"] and len(report["units"]) == len(load_scene(scene).names)
    out = tmp_path / "run.nc"
    assert main(["cosim", str(shortened(scene, tmp_path)), "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    ds = open_dataset(out)
    assert summary["status"] == "completed" and ds.attrs["status"] == "completed"
    if isinstance(load_scene(scene), SignalScene):  # <unit>.<variable>(time) for each connected, recorded one
        implicit = load_scene(scene).coupling["implicit"]
        assert ds.sizes["time"] == 41 and ds.attrs["coupling"] == ("implicit" if implicit else "explicit")
        assert all(np.all(np.isfinite(ds[v].values)) for v in ds.data_vars) and len(ds.data_vars) >= 2
        return
    assert summary["macro_steps"] == 40
    assert np.all(np.isfinite(ds["position"].values))
    gap = np.abs(ds["joint_gap" if "joint" in ds.dims else "gap"].values)
    if scene.stem == "two_mass_unstable":  # unstable by design (rho = 1.13 per macro step): the gap grows
        assert gap[-5:].max() > 10 * gap[1:6].max()
    else:
        assert gap.max() < 1e-3  # the joint holds (to the method's drift)


def test_dataset_contents(capsys, tmp_path):
    scene = shortened(ROOT / "config" / "scenes" / "two_mass_ff.yaml", tmp_path, steps=25)
    out = tmp_path / "run.nc"
    assert main(["cosim", str(scene), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "completed: 25 macro steps" in text and "6 doStep calls per macro step" in text
    ds = open_dataset(out)
    assert list(ds["subsystem"].values) == ["body1", "body2"]
    assert ds["position"].dims == ("subsystem", "time") and ds["velocity"].dims == ("subsystem", "time")
    assert ds["multiplier"].dims == ("time",) and ds["gap"].dims == ("time",)
    assert ds.sizes["time"] == 26
    np.testing.assert_allclose(ds["time"].values, np.arange(26) * 1e-3)
    np.testing.assert_array_equal(ds["gap"], ds["position"][0] - ds["position"][1])
    assert json.loads(ds.attrs["scene_json"])["coupling"]["method"] == "projection"
    for name in ("body1", "body2"):
        assert ds.attrs[f"{name}_model_name"] == "msd"
        assert ds.attrs[f"{name}_guid"] == "{8c4e810f-3df3-4a00-8276-176fa3c9f001}"
        assert ds.attrs[f"{name}_fmi_version"] == "2.0"
        assert ds.attrs[f"{name}_generation_tool"].startswith("icosim fmus/")
        assert ds.attrs[f"{name}_do_step_calls"] == 6 * 25 // 2
        # start, corrector, projection: a predictor corrected in the same stage ends at its corrector's state, unsaved
        assert ds.attrs[f"{name}_states_saved"] == 1 + 2 * 25
        assert ds.attrs[f"{name}_states_restored"] == 2 * 25
    assert ds.attrs["do_step_calls"] == 150 and ds.attrs["wall_time_s"] > 0


def test_a_diverging_scene_is_written_with_its_status(capsys, tmp_path):
    """Weighted multiplier, fd, k = 2, Gauss-Seidel 1->2 at H = 1 ms is violently unstable: the run stops where
    the state passes the divergence bound, says at which step, exits with status 1, and the dataset says so."""
    data = yaml.safe_load((ROOT / "config" / "scenes" / "two_mass_fd.yaml").read_text())
    data["coupling"] = {"method": "weighted", "index": 1, "a": 1.0, "b": 1.0, "decomposition": "fd", "k": 2}
    data["coupling"] |= {"scheme": "gauss-seidel-12", "H": 1e-3, "perturbation": 1.0}
    for sub in data["subsystems"].values():
        sub["fmu"] = str((ROOT / "config" / "scenes" / sub["fmu"]).resolve())
    path = tmp_path / "diverging.yaml"
    path.write_text(yaml.safe_dump(data | {"t_end": 0.5}))
    out = tmp_path / "run.nc"
    assert main(["cosim", str(path), "--out", str(out), "--json"]) == 1
    summary = json.loads(capsys.readouterr().out)
    n = summary["diverged_at"]
    assert summary["status"] == "diverged" and f"diverged at macro step {n} " in summary["reason"]
    assert "|state| > 1.1e+10" in summary["reason"] and summary["macro_steps"] == n - 1
    ds = open_dataset(out)
    assert ds.attrs["status"] == "diverged" and ds.attrs["diverged_at"] == n and ds.sizes["time"] == n


def test_fmpy_is_imported_only_when_a_scene_runs():
    import subprocess
    import sys

    code = (
        "import sys, icosim.cli, icosim.problems.fmu.scene, icosim.problems.fmu.run, icosim.problems.fmu.predict; "
        "icosim.cli.build_parser(); print('fmpy' in sys.modules, 'pythonfmu' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.split() == ["False", "False"]


def test_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["cosim", "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert "--predict" in text and "--out RUN.nc" in text and "SCENE.yaml" in text
