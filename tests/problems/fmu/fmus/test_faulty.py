"""The unit fmus/faulty (fmus/msd failing on purpose) through fmpy's low-level API: without a fault it is msd bit
for bit; each fault shows in the first step at or after fault_time, as described in fmus/README.md, with its
message through the logger under the instance name.  The step that never returns and the crash run in a child
process."""

import math
import signal
import subprocess
import sys
import time

import pytest
from helpers import fmu_instance

pytestmark = pytest.mark.fmu

M, C, D, X0, V0, LAMBDA, X, V, A, XSET, VSET, FAIL_TIME, FAULT_TIME = range(13)  # Real
FAULT = 0  # Integer
H = 1e-3
OK, WARNING, DISCARD, ERROR, FATAL = range(5)


def initialised(tmp_path, fault, messages=None, unit="faulty", fault_time=0.0):
    fmu = fmu_instance(unit, tmp_path / unit, messages)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([X0, V0], [0.01, -0.2])
    if unit == "faulty":
        fmu.setInteger([FAULT], [fault])
        fmu.setReal([FAULT_TIME], [fault_time])
    fmu.exitInitializationMode()
    return fmu


def do_step(fmu, t, h=H):
    """fmi2DoStep's status as it is (fmpy's wrapper raises for discard and worse)."""
    return fmu.dll.fmi2DoStep(fmu.component, t, h, 0)


def steps(fmu, n):
    """n steps under a force with derivatives (a cubic): the status and the outputs after each."""
    out = []
    for j in range(n):
        t = j * H
        fmu.setReal([LAMBDA], [5.0 + 2.0 * t])
        fmu.setRealInputDerivatives([LAMBDA] * 3, [1, 2, 3], [2.0, -40.0, 300.0])
        out.append((do_step(fmu, t), fmu.getReal([X, V, A])))
    return out


def test_without_a_fault_it_is_msd(tmp_path):
    messages = []
    faulty, msd = initialised(tmp_path, 0, messages), initialised(tmp_path, 0, unit="msd")
    got, want = steps(faulty, 5), steps(msd, 5)
    assert got == want and all(status == OK for status, _ in got) and messages == []
    for fmu in (faulty, msd):
        fmu.terminate()
        fmu.freeInstance()


def test_warning_the_step_is_taken(tmp_path):
    messages = []
    fmu, msd = initialised(tmp_path, 1, messages), initialised(tmp_path, 0, unit="msd")
    got, want = steps(fmu, 3), steps(msd, 3)
    assert [status for status, _ in got] == [WARNING] * 3
    assert [outputs for _, outputs in got] == [outputs for _, outputs in want]
    assert [(m.instance, m.status) for m in messages] == [("unit", WARNING)] * 3
    assert messages[0].text == "faulty: a warning in the step from t = 0; the step is taken (fault 1)"
    for f in (fmu, msd):
        f.freeInstance()


@pytest.mark.parametrize(
    ("fault", "status", "text"),
    [
        (2, DISCARD, "step rejected: the unit refuses the step from t = 0.002 (fault 2)"),
        (3, ERROR, "faulty: the step from t = 0.002 failed (fault 3)"),
        (4, FATAL, "faulty: fatal failure in the step from t = 0.002, the instance is lost (fault 4)"),
    ],
)
def test_refused_step_from_fault_time_on(tmp_path, fault, status, text):
    messages = []
    fmu = initialised(tmp_path, fault, messages, fault_time=2 * H)
    assert [do_step(fmu, 0.0), do_step(fmu, H)] == [OK, OK] and messages == []
    before = fmu.getReal([X, V, A])
    assert do_step(fmu, 2 * H) == status
    assert messages == [("unit", status, text)]
    if fault == 2:  # the step is not taken: the unit may be asked for a shorter one
        assert fmu.getReal([X, V, A]) == before
        assert do_step(fmu, 2 * H, H / 2) == DISCARD
    if fault != 4:  # after fmi2Fatal not even fmi2FreeInstance is allowed
        fmu.freeInstance()


@pytest.mark.parametrize(("fault", "spoiled"), [(5, A), (6, X)])
def test_spoiled_output_after_the_step(tmp_path, fault, spoiled):
    messages = []
    fmu = initialised(tmp_path, fault, messages, fault_time=H)
    assert do_step(fmu, 0.0) == OK
    assert all(math.isfinite(v) for v in fmu.getReal([X, V, A]))
    assert do_step(fmu, H) == OK
    x, v, a = fmu.getReal([X, V, A])
    if fault == 5:
        assert math.isnan(a) and math.isfinite(x) and math.isfinite(v)
    else:
        assert x == math.inf and math.isfinite(v) and math.isfinite(a)
    assert messages == []
    fmu.freeInstance()


@pytest.mark.parametrize("fault", [0, 9])
def test_restored_state_that_is_not_one(tmp_path, fault):
    """Fault 9: save, step, read, restore, step, read gives positions 1e-6 m apart (the step count survived)."""
    fmu = initialised(tmp_path, fault)
    assert do_step(fmu, 0.0) == OK
    state = fmu.getFMUstate()
    assert do_step(fmu, H) == OK
    first = fmu.getReal([X, V, A])
    fmu.setFMUstate(state)
    assert do_step(fmu, H) == OK
    again = fmu.getReal([X, V, A])
    assert again[1:] == first[1:]
    if fault == 0:
        assert again[0] == first[0]
    else:
        assert again[0] - first[0] == pytest.approx(1e-6, rel=1e-6)
    fmu.freeFMUstate(state)
    fmu.freeInstance()


def test_initialisation_refused(tmp_path):
    messages = []
    with pytest.raises(Exception, match="fmi2ExitInitializationMode failed with status 3"):
        initialised(tmp_path, 10, messages)
    assert messages == [("unit", ERROR, "faulty: initialisation refused: no licence for this unit")]


def test_fault_is_a_fixed_parameter_of_0_to_12(tmp_path):
    messages = []
    fmu = fmu_instance("faulty", tmp_path / "faulty", messages)
    assert fmu.getInteger([FAULT]) == [0] and fmu.getReal([FAULT_TIME]) == [0.0]
    with pytest.raises(Exception, match="status 3"):
        fmu.setInteger([FAULT], [13])
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    with pytest.raises(Exception, match="status 3"):
        fmu.setInteger([FAULT], [3])
    fmu.setReal([FAULT_TIME], [5.0])  # tunable
    assert fmu.getInteger([FAULT]) == [0] and fmu.getReal([FAULT_TIME]) == [5.0]
    assert [m.text for m in messages] == [
        "fmi2SetInteger: fault must be one of 0 to 10",
        "fmi2SetInteger: fault is fixed: it cannot be set after initialisation",
    ]
    fmu.freeInstance()


#: A child process: the unit unpacked in argv[1] with the fault argv[2], one step; its log messages on stdout.
CHILD = r"""
import os, sys
from fmpy.fmi2 import FMU2Slave, defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

def log(env, instance, status, category, message):
    os.write(1, b"log %d %s: %s\n" % (status, instance, message))

cb = fmi2CallbackFunctions()
cb.logger = fmi2CallbackLoggerTYPE(log)
cb.allocateMemory, cb.freeMemory = defaultCallbacks.allocateMemory, defaultCallbacks.freeMemory
fmu = FMU2Slave(guid=sys.argv[3], unzipDirectory=sys.argv[1], modelIdentifier="faulty", instanceName="child")
fmu.instantiate(callbacks=cb)
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.setInteger([0], [int(sys.argv[2])])
fmu.exitInitializationMode()
os.write(1, b"stepping\n")
fmu.doStep(0.0, 1e-3)
os.write(1, b"returned\n")
"""


def child(tmp_path, fault):
    fmu = fmu_instance("faulty", tmp_path / "faulty")  # unpacks the unit
    unzipdir, guid = fmu.unzipDirectory, fmu.guid
    fmu.freeInstance()
    return subprocess.Popen(
        [sys.executable, "-c", CHILD, unzipdir, str(fault), guid], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )


def test_step_that_never_returns(tmp_path):
    proc = child(tmp_path, 7)
    try:
        assert proc.stdout.readline() == b"stepping\n"
        time.sleep(1.0)
        assert proc.poll() is None, "fmi2DoStep returned"
    finally:
        proc.kill()
        out, _ = proc.communicate(timeout=30)
    assert b"returned" not in out


def test_step_that_crashes_the_process(tmp_path):
    proc = child(tmp_path, 8)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGSEGV, err.decode()
    assert out.decode().splitlines() == [
        "stepping",
        f"log {FATAL} child: faulty: the step from t = 0 crashes the process (fault 8)",
    ]
