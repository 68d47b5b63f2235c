"""A unit that hangs or crashes the process is named: the run goes on in a child process that records, in memory
shared with its parent, which unit is in which FMI call since when; the parent stops a call that outlasts its
limit and reports a child that died, naming the unit, the call and the macro step.

:func:`supervised` is what ``icosim cosim`` (and the workflow's FMU jobs) run under; without it the records are
not kept and :func:`enter`/:func:`leave` cost a function call each.  The child's scratch files (the units
unpacked) live in a directory the parent removes however the child ends, and a dataset is renamed into place
only when complete (:func:`icosim.io.netcdf.write_netcdf`), so nothing half-written is left.

Needs ``os.fork`` (Linux, macOS); elsewhere :func:`supervised` runs the target in the process itself.
"""

from __future__ import annotations

import io
import mmap
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "enter",
    "batch",
    "leave",
    "code",
    "register",
    "unregister",
    "scratch_dir",
    "supervised",
    "Outcome",
    "CALL_SECONDS",
]

#: The default limit of one FMI call, in seconds: generous (a unit's doStep may integrate a stiff model).
CALL_SECONDS = 600.0

#: The FMI calls by the names the messages use (``fmi2``/``fmi3`` prefixed by the unit's version).
CALLS = (
    "",
    "instantiate",
    "Get",
    "Set",
    "GetFMUstate",
    "SetFMUstate",
    "DoStep",
    "SetRealInputDerivatives",
    "Terminate",
)
_CODE = {name: i for i, name in enumerate(CALLS)}
_CODE.update(get=_CODE["Get"], set=_CODE["Set"], getFMUstate=_CODE["GetFMUstate"], setFMUstate=_CODE["SetFMUstate"])
_CODE.update(doStep=_CODE["DoStep"], setRealInputDerivatives=_CODE["SetRealInputDerivatives"])

_NAME_BYTES, _MAX_UNITS = 64, 64
#: float64 slots: the number of the call under way (0: none), unit, call, t, macro step, spare, units registered,
#: the last call's number.  A call is timed by the parent from when it first sees its number, so the child writes
#: no clock: a call's record is a few stores into the shared memory (:func:`enter`) and one (:func:`leave`).
_HEADER = 8

_record = None  # a float64 memoryview of the shared memory, in the supervised child only
_shared = None
_units = []  # the labels of the units registered in the supervised child
_scratch = None


def register(unit) -> int:
    """A unit's index in the records (its label and FMI version written where the parent reads them); -1 when
    the process is not supervised or the table is full (its calls are then not named)."""
    if _shared is None or len(_units) >= _MAX_UNITS:
        return -1
    _units.append(unit.label)
    index = len(_units) - 1
    name = f"{'fmi3' if unit.fmi3 else 'fmi2'}:{unit.label}".encode()[: _NAME_BYTES - 1]
    start = _HEADER * 8 + index * _NAME_BYTES
    _shared[start : start + _NAME_BYTES] = name.ljust(_NAME_BYTES, b"\0")
    _record[6] = index + 1
    return index


def unregister(unit):
    """Nothing more is recorded of ``unit`` (its index stays taken: the record may still name it)."""


def enter(index: int, call: str | int, t: float, step: int = -1):
    """Unit ``index`` starts the FMI call ``call`` (a name, or its :func:`code`) at simulated time ``t`` (macro
    step ``step``)."""
    r = _record
    if r is not None and index >= 0:
        r[1] = index
        r[2] = call if call.__class__ is int else _CODE[call]
        r[3] = t
        r[4] = step
        number = r[7] + 1.0
        r[7] = number
        r[0] = number


def batch(index: int, t: float, step: int, calls: int):
    """Unit ``index`` is about to make ``calls`` FMI calls at ``t`` (macro step ``step``), one after the other:
    the record with the unit, time and step written and the calls' numbers taken, and the first number; None
    when not recorded.  The caller of such a batch writes its ``j``-th call's name and number itself, two stores
    (``r[2] = code(name); r[0] = first + j``), and :func:`leave` (``r[0] = 0.0``) after each: a hot path's
    calls recorded without a function call each."""
    r = _record
    if r is None or index < 0:
        return None
    r[1] = index
    r[3] = t
    r[4] = step
    first = r[7] + 1.0
    r[7] = first + (calls - 1)
    return r, first


def code(call: str) -> int:
    """The number :func:`enter` records for the call named ``call`` (a caller may keep it)."""
    return _CODE[call]


def leave():
    """The call returned."""
    r = _record
    if r is not None:
        r[0] = 0.0


def scratch_dir():
    """Where units are unpacked: the supervised run's scratch directory, else the system's (None)."""
    return _scratch


@dataclass
class Outcome:
    """How a supervised run ended: its exit ``status`` and, where the parent stopped it or it died, a ``message``
    naming the unit and the call."""

    status: int
    message: str = ""


def _describe(shared, record, *, limit=None, signum=None) -> str:
    index, code, t, step = int(record[1]), int(record[2]), float(record[3]), int(record[4])
    start = _HEADER * 8 + index * _NAME_BYTES
    raw = bytes(shared[start : start + _NAME_BYTES]).split(b"\0")[0].decode(errors="replace")
    version, _, label = raw.partition(":")
    call = f"{version}{CALLS[code]}" if code and CALLS[code] != "instantiate" else "fmi2Instantiate"
    if code == _CODE["instantiate"] and version == "fmi3":
        call = "fmi3InstantiateCoSimulation"
    where = f"macro step {step}, t = {t:.12g} s" if step >= 0 else f"t = {t:.12g} s"
    if limit is not None:
        return (
            f"unit {label} did not return from {call} within {limit:g} s ({where}); the run was stopped "
            "(limits.call_seconds in the scene sets the limit)"
        )
    name = signal.Signals(signum).name if signum in signal.Signals._value2member_map_ else f"signal {signum}"
    return f"unit {label} crashed the process in {call} ({name}, {where})"


def _has_fd(stream) -> bool:
    try:
        stream.fileno()
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        return False
    return True


def _drain(fd, chunks):
    while True:
        data = os.read(fd, 1 << 16)
        if not data:
            return
        chunks.append(data)


def supervised(target, *, call_seconds: float = CALL_SECONDS, leftovers=()) -> Outcome:
    """Run ``target()`` (returning an exit status) in a child process under watch.

    A call of a unit that outlasts ``call_seconds`` gets the child killed; a child that dies of a signal is
    reported with the unit and call it was in.  Either way ``leftovers`` (paths or glob patterns of files the
    target may have been writing, e.g. the ``.*.part`` temporaries of a dataset) and the scratch directory are
    removed, and the outcome's status is 2 with the message.  Otherwise the child's own status is returned.
    """
    global _record, _shared, _scratch
    if not hasattr(os, "fork") or _record is not None:
        return Outcome(int(target() or 0))
    size = _HEADER * 8 + _MAX_UNITS * _NAME_BYTES
    shared = mmap.mmap(-1, size)
    record = memoryview(shared).cast("d")
    scratch = tempfile.mkdtemp(prefix="icosim-run-")
    streams = (sys.stdout, sys.stderr)
    sys.stdout.flush()
    sys.stderr.flush()
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: the run itself
        os.close(read_end)
        _shared, _record, _scratch, _units[:] = shared, record, scratch, []
        # streams without a file descriptor of their own (captured in memory) are sent to the parent at the end
        buffered = [not _has_fd(s) for s in streams]
        if buffered[0]:
            sys.stdout = io.StringIO()
        if buffered[1]:
            sys.stderr = io.StringIO()
        status = 1
        try:
            status = int(target() or 0)
        except SystemExit as exc:
            status = exc.code if isinstance(exc.code, int) else 1
        except BaseException:
            traceback.print_exc()
        finally:
            texts = [sys.stdout.getvalue() if buffered[0] else "", sys.stderr.getvalue() if buffered[1] else ""]
            sys.stdout.flush()
            sys.stderr.flush()
            payload = "\0".join(texts).encode()
            view = memoryview(payload)
            while view:
                view = view[os.write(write_end, view) :]
            os.close(write_end)
        os._exit(status)
    os.close(write_end)
    chunks = []
    reader = threading.Thread(target=_drain, args=(read_end, chunks), daemon=True)
    reader.start()
    message, status = "", None
    seen, since = -1.0, 0.0  # the number of the call last seen active, and when it was first seen
    try:
        pause = 0.001
        while True:
            done, wait_status = os.waitpid(pid, os.WNOHANG)
            if done:
                if os.WIFSIGNALED(wait_status):
                    signum = os.WTERMSIG(wait_status)
                    if record[0] != 0.0:
                        message = _describe(shared, record, signum=signum)
                    else:
                        message = f"the run process died of {signal.Signals(signum).name} outside any unit call"
                    status = 2
                else:
                    status = os.WEXITSTATUS(wait_status)
                break
            number = record[0]
            if number != 0.0:
                now = time.monotonic()
                if number != seen:
                    seen, since = number, now
                elif now - since > call_seconds:
                    described = _describe(shared, record, limit=call_seconds)
                    os.kill(pid, signal.SIGKILL)
                    os.waitpid(pid, 0)
                    message, status = described, 2
                    break
            time.sleep(pause)
            pause = min(2 * pause, 0.05, call_seconds / 20)
    except BaseException:  # the parent interrupted (Ctrl-C): the child goes with it
        try:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        except OSError:
            pass
        raise
    finally:
        reader.join()
        os.close(read_end)
        shutil.rmtree(scratch, ignore_errors=True)
        record.release()
        shared.close()
    texts = b"".join(chunks).decode(errors="replace").split("\0")
    for stream, text in zip(streams, texts + ["", ""]):
        if text:
            stream.write(text)
            stream.flush()
    if message:
        for item in leftovers:
            item = Path(item)
            for path in item.parent.glob(item.name):
                path.unlink(missing_ok=True)
    return Outcome(status, message)
