"""Messages of ``icosim cosim`` that must say what happened: a unit whose first step fails is a refused row of
``--check``, not a traceback; a scheme the scene cannot use is a scene error naming ``coupling.scheme``; outputs
that are not finite are called so; a quoted number gets the hint it needs; the velocity gap is named with the
position gap; ``initial_coupling`` written by hand off the units' values is warned about, naming those values."""

import json
import os

import pytest
import yaml
from helpers import ROOT

from icosim.cli import main

FMUS = ROOT / "fmus"
pytestmark = [pytest.mark.fmu, pytest.mark.skipif(not hasattr(os, "fork"), reason="the supervised run needs os.fork")]


def body(i, fmu="msd", **start):
    return {"fmu": str(FMUS / fmu), "start": {"m": float(i), "c": 1000.0 / i, "d": 2.0, "x0": 0.1, **start},
            "position": "x", "velocity": "v", "acceleration": "a", "force": "lambda",
            "force_sign": 1 if i == 1 else -1}  # fmt: skip


def scene(tmp_path, body1=None, body2=None, coupling=None, **top):
    data = {"subsystems": {"body1": body1 or body(1), "body2": body2 or body(2)},
            "coupling": {"method": "baumgarte", "index": 1, "mu": 1e-3, "decomposition": "ff", "k": 1, "H": 1e-3,
                         **(coupling or {})},
            "t_end": 0.01, **top}  # fmt: skip
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def check(capsys, path):
    status = main(["cosim", str(path), "--check", "--json"])
    captured = capsys.readouterr()
    return status, (json.loads(captured.out) if captured.out.strip() else None), captured.err.strip()


def rows(report, name):
    return {r["check"]: r for r in next(u for u in report["units"] if u["name"] == name)["findings"]}


def test_a_unit_whose_first_step_fails_is_a_refused_row(capsys, tmp_path):
    path = scene(tmp_path, body1=body(1, "faulty", fault=3, fault_time=0.0))
    status, report, err = check(capsys, path)
    assert status == 2 and report is not None and "Traceback" not in err, err
    step = rows(report, "body1")["step"]
    assert step["verdict"] == "refused"
    assert "unit body1 refused macro step 0 at t = 0 s (doStep returned error)" in step["detail"]
    assert "fault 3" in step["detail"]  # what the unit said
    assert all(r["verdict"] == "pass" for r in rows(report, "body2").values() if r["check"] != "units")
    assert report["refused"]


@pytest.mark.parametrize("scheme", ["gauss-seidel-13", "gauss-seidel-3", "gauss-seidel-11"])
@pytest.mark.parametrize("how", [["--check"], ["--out", "run.nc"]])
def test_a_scheme_that_misnames_the_subsystems_is_a_scene_error(capsys, tmp_path, scheme, how):
    path = scene(tmp_path, coupling={"scheme": scheme})
    status = main(["cosim", str(path), *how[:1], *[str(tmp_path / h) for h in how[1:]]])
    err = capsys.readouterr().err.strip()
    assert status == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"icosim cosim: error: {path}: coupling.scheme: scheme '{scheme}'"), err
    assert "allowed: jacobi, gauss-seidel-12, gauss-seidel-21" in err and "order: [body1, body2]" in err
    assert not (tmp_path / "run.nc").exists()


def test_outputs_that_are_not_finite_are_called_so(capsys, tmp_path):
    path = scene(tmp_path, body1=body(1, "faulty", fault=5, fault_time=0.0))
    status, report, _ = check(capsys, path)
    found = rows(report, "body1")
    assert status == 2
    assert found["outputs"]["verdict"] == "refused"
    assert "its acceleration a is nan after a step with its input at zero" in found["outputs"]["detail"]
    assert "rollback" not in found  # not a failed restore


@pytest.mark.parametrize(
    "text, hint",
    [("2", "'2' is quoted text: write the number without quotes"), ("1.0e6", "write the exponent with its sign")],
)
def test_a_number_read_as_text_gets_the_hint_it_needs(capsys, tmp_path, text, hint):
    path = scene(tmp_path, initial_tolerance=text)
    status, _, err = check(capsys, path)
    assert status == 2 and f"initial_tolerance: '{text}' is not of type 'number'" in err and hint in err, err
    other = "write the exponent" if "quoted" in hint else "quoted text"
    assert other not in err


def test_a_quoted_start_value_gets_the_quotes_hint(capsys, tmp_path):
    path = scene(tmp_path, body1=body(1, m="2"))
    status, report, err = check(capsys, path)
    detail = rows(report, "body1")["open"]["detail"] if report else err
    assert status == 2 and "'2' is quoted text: write the number without quotes" in detail, detail


def test_velocities_are_named_in_the_plural(capsys, tmp_path):
    # index 2 enforces the velocities: body2 starting with 0.5 m/s is a gap
    path = scene(tmp_path, body2=body(2, v0=0.5), coupling={"index": 2})
    status = main(["cosim", str(path), "--out", str(tmp_path / "run.nc")])
    err = capsys.readouterr().err
    assert status == 2 and "the joint's velocities differ at t_start" in err and "velocitys" not in err, err


def test_the_as_is_summary_gives_both_gaps(capsys, tmp_path):
    path = scene(tmp_path, body2=body(2, x0=0.3, v0=0.5), initial="as-is")
    status = main(["cosim", str(path), "--out", str(tmp_path / "run.nc")])
    out = capsys.readouterr().out
    assert status == 0
    assert "joint gap at start 0.2 m, 0.5 m/s (as-is)" in out, out


def test_initial_coupling_off_the_units_is_warned_about(capsys, tmp_path):
    # msd: m1 a = -c1 x0 + lambda, m2 a = -c2 x0 - lambda with equal accelerations at the start:
    # lambda = (c1 m2 - c2 m1) x0 / (m1 + m2) = (1000 * 2 - 500 * 1) 0.1 / 3 = 50 N
    path = scene(tmp_path, initial_coupling=[0.0])
    status = main(["cosim", str(path), "--out", str(tmp_path / "run.nc")])
    err = capsys.readouterr().err
    assert status == 0
    assert "warning:" in err and "initial_coupling: [0] differs" in err and "[50] (computed" in err, err
    assert "first-order" in err
    status, report, _ = check(capsys, path)
    note = next(r for r in report["scene_findings"] if r["check"] == "initial_coupling")
    assert note["verdict"] == "note" and "[50]" in note["detail"]


def test_initial_coupling_that_meets_the_units_is_not_warned_about(capsys, tmp_path):
    path = scene(tmp_path, initial_coupling=[50.0])
    status = main(["cosim", str(path), "--out", str(tmp_path / "run.nc")])
    assert status == 0 and "warning" not in capsys.readouterr().err
