"""The supervisor (icosim.problems.fmu.guard) on real units of fmus/: a call's record lasts exactly as long as its
``with`` block (an exception inside leaves none, so a live child is never stopped for a call that returned; a
call inside another gives the outer one back), a closed unit's slot is taken by the next unit, a job opens each
unit once, and a scene of 200 units run as ``icosim cosim`` runs it has every unit's calls timed and named."""

import os
import time

import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.io.netcdf import open_dataset
from icosim.problems.fmu import guard
from icosim.problems.fmu.exchange import open_fmu_unit
from icosim.problems.fmu.run import fmu_file

FMUS = ROOT / "fmus"
MSD = {"position": "x", "velocity": "v", "acceleration": "a", "force": "lambda"}
pytestmark = [pytest.mark.fmu, pytest.mark.skipif(not hasattr(os, "fork"), reason="the supervised run needs os.fork")]


def msd(label):
    return open_fmu_unit(label, fmu_file(FMUS / "msd"), MSD, {"m": 1.0, "c": 100.0, "d": 1.0, "x0": 0.1})


def supervised(check, call_seconds=0.2):
    """``check()`` in the supervised child; its assertions fail the child (status 1, the traceback on stderr)."""

    def target():
        check()
        return 0

    return guard.supervised(target, call_seconds=call_seconds)


def test_a_call_that_raises_leaves_no_record_and_the_child_is_not_stopped(capfd):
    """An exception inside a call (a refusal raised by the caller) ends its record; the child then works on for
    ten times the call limit and ends normally.  A call inside another gives the outer one back."""

    def check():
        unit = msd("body")
        try:
            with pytest.raises(RuntimeError):
                with guard.call(unit, "fmi2DoStep", 0.25, 3):
                    assert guard.under_way() == ("body", "fmi2DoStep", 0.25, 3)
                    raise RuntimeError("refused")
            assert guard.under_way() is None
            with guard.call(unit, "fmi2DoStep", 0.5, 4):
                with pytest.raises(RuntimeError):
                    with guard.call(unit, "fmi2SetReal", 0.5, 4):
                        assert guard.under_way() == ("body", "fmi2SetReal", 0.5, 4)
                        raise RuntimeError("refused")
                assert guard.under_way() == ("body", "fmi2DoStep", 0.5, 4)
            assert guard.under_way() is None
            unit.step("force", [[1.0], [0.5]], 0.0, 1e-3, step_index=0)  # real calls, each left
            assert guard.under_way() is None
        finally:
            unit.close()
        time.sleep(2.0)  # ten call limits outside any call

    outcome = supervised(check)
    assert (outcome.status, outcome.message) == (0, ""), capfd.readouterr().err


def test_a_closed_units_slot_is_reused():
    def check():
        a, b = msd("a"), msd("b")
        assert (a.index, b.index) == (0, 1)
        a.close()
        assert a.index == -1
        c = msd("c")
        assert c.index == 0  # a's slot
        with guard.call(c, "fmi2GetReal", 0.0):
            assert guard.under_way()[0] == "c"
        for i in range(10):  # opened and closed one after the other: two slots are all they take
            msd(f"d{i}").close()
        assert guard.slots() == 3
        b.close()
        c.close()

    outcome = supervised(check)
    assert (outcome.status, outcome.message) == (0, "")


def test_outside_the_supervisor_nothing_is_recorded():
    unit = msd("body")
    try:
        assert unit.index == -1
        with guard.call(unit, "fmi2DoStep", 0.0, 0):
            assert guard.under_way() is None
    finally:
        unit.close()


def chain_scene(tmp_path, n, last):
    """A chain of ``n`` units (fmus/msd, ``last`` the n-th) joined ff, Baumgarte index 1 under Jacobi."""
    subsystems = {}
    for i in range(1, n + 1):
        start = {"m": 1.0 + (i % 7) / 7, "c": 1000.0, "d": 2.0, "x0": 0.1}
        sub = {"fmu": str(FMUS / "msd"), "start": start} | MSD | {"force_sign": 1}
        subsystems[f"u{i}"] = sub
    subsystems[f"u{n}"] |= last
    data = {"subsystems": subsystems, "joints": [{"between": [f"u{i}", f"u{i + 1}"], "decomposition": "ff"}
            for i in range(1, n)], "t_end": 0.004,
            "coupling": {"method": "baumgarte", "index": 1, "mu": 1e-3, "k": 1, "H": 1e-3, "scheme": "jacobi"}}  # fmt: skip
    path = tmp_path / "chain.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def cosim(capsys, tmp_path, path):
    out = tmp_path / "run.nc"
    status = main(["cosim", str(path), "--out", str(out)])
    return status, capsys.readouterr().err.strip(), out


def faulty(fault):
    start = {"m": 1.0, "c": 1000.0, "d": 2.0, "x0": 0.1, "fault": fault, "fault_time": 0.002}
    return {"fmu": str(FMUS / "faulty"), "start": start}


def test_the_200th_unit_of_a_scene_is_timed_and_named(capsys, tmp_path):
    """200 units open at once in one child: the last one's step that crashes the process is named, as is its step
    that never returns, stopped after the limit; without a fault the run completes with every unit stepped."""
    # the crash first: a unit whose calls are not recorded fails it at once (the hang would never be stopped)
    status, err, out = cosim(capsys, tmp_path, chain_scene(tmp_path, 200, faulty(8)))
    assert status == 2 and "unit u200 crashed the process in fmi2DoStep (SIGSEGV, macro step 3, t = 0.002 s)" in err
    assert not out.exists()
    path = chain_scene(tmp_path, 200, faulty(7))
    # the limit is met by every call that returns, on a loaded machine too (200 units are instantiated in turn)
    data = yaml.safe_load(path.read_text()) | {"limits": {"call_seconds": 3.0}}
    path.write_text(yaml.safe_dump(data))
    status, err, out = cosim(capsys, tmp_path, path)
    assert status == 2 and "unit u200 did not return from fmi2DoStep within 3 s (macro step 3, t = 0.002 s)" in err
    assert not out.exists() and not list(tmp_path.glob(".run.nc*"))
    status, err, out = cosim(capsys, tmp_path, chain_scene(tmp_path, 200, {}))
    assert status == 0, err
    attrs = open_dataset(out).attrs
    assert attrs["status"] == "completed"
    assert all(attrs[f"u{i}_do_step_calls"] >= 4 for i in range(1, 201))  # 4 macro steps each
