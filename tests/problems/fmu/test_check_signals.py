"""``icosim cosim SIGNALSCENE --check`` (icosim.problems.fmu.check_signals) on OMSimulator's DualMassOscillator
units (../shared/outside/omsimulator) coupled by its test's four connections:

* every unit opens and the scene's checks pass; the inputs at ``t_start`` are the outputs that feed them, settled:
  from DualMassOscillator.mo at rest with ``x1 = 0``, ``x2 = 0.5``, the force on mass 1 is ``K2 x2`` and its
  acceleration ``K2 x2 / M1``; exit 0, nothing written;
* at ``k = 2`` by input derivatives, which the Co-Simulation units refuse, each unit's row is refused naming the
  order, and the exit status is 2;
* an algebraic loop (two of the Reference-FMUs' Feedthrough) is the connections' row refused.
"""

from __future__ import annotations

import json

import pytest
from test_drives import K2, M1
from test_signals_outside import dmo_scene, feedthrough_loop_scene

from icosim.cli import main

pytestmark = pytest.mark.outside


def check(capsys, path):
    status = main(["cosim", str(path), "--check", "--json"])
    return status, json.loads(capsys.readouterr().out)


def rows(report):
    return {(u["name"], f["check"]): f for u in report["units"] for f in u["findings"]} | {
        ("scene", f["check"]): f for f in report["scene_findings"]
    }


def test_the_dual_mass_oscillator_s_signal_scene_passes_its_checks(capsys, tmp_path):
    path = dmo_scene(tmp_path, 1e-3, 1.0, k=1)
    status, report = check(capsys, path)
    assert status == 0 and not report["refused"], report
    found = rows(report)
    assert {v["verdict"] for v in found.values()} == {"pass"}
    assert set(found) == {("system1", "open"), ("system2", "open"), ("system2", "record"), ("scene", "connections"),
                          ("scene", "start"), ("scene", "step")}  # fmt: skip
    assert "inputs F; outputs x1, v1, a1" in found[("system1", "open")]["detail"]
    start = dict(part.split(" = ") for part in found[("scene", "start")]["detail"].split(": ", 1)[1].split(", "))
    assert float(start["system2.F -> system1.F"]) == pytest.approx(K2 * 0.5, rel=1e-12)
    assert float(start["system1.a1 -> system2.a1"]) == pytest.approx(K2 * 0.5 / M1, rel=1e-12)
    assert float(start["system1.x1 -> system2.x1"]) == 0.0
    assert list(tmp_path.iterdir()) == [path]  # nothing written


def test_input_derivatives_the_units_refuse_are_their_rows_refused(capsys, tmp_path):
    status, report = check(capsys, dmo_scene(tmp_path, 1e-3, 1.0, k=2, inputs="derivatives"))
    assert status == 2 and report["refused"]
    found = rows(report)
    for name in ("system1", "system2"):
        row = found[(name, "open")]
        assert row["verdict"] == "refused" and row["key"] == f"subsystems.{name}"
        assert "refuses fmi2SetRealInputDerivatives of order 2" in row["detail"] and "coupling.k: 1" in row["detail"]
    assert report["scene_findings"] == []  # no scene check without its units


def test_an_algebraic_loop_is_the_connections_row_refused(capsys, tmp_path):
    status, report = check(capsys, feedthrough_loop_scene(tmp_path))
    assert status == 2
    row = rows(report)[("scene", "connections")]
    assert row["verdict"] == "refused" and "algebraic loop" in row["detail"], row
    assert "a.Float64_continuous_output -> b.Float64_continuous_input" in row["detail"]
