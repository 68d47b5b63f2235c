"""A unit that hangs or crashes the process is named: the run goes on in a child process that records, in memory
shared with its parent, which unit is in which FMI call since when; the parent stops a call that outlasts its
limit and reports a child that died, naming the unit, the call and the macro step.

Every FMI call a unit makes is a ``with`` block, :func:`call`: the record is written on entering and cleared on
leaving, whatever happens inside (an exception, a refusal raised by the caller), so no record outlives its call
and a live child is never stopped for a call that returned.  A call made inside another one (a Model Exchange
unit's input written within its integration) restores the outer record when it returns.  A unit takes a slot
when it opens (:func:`register`) and gives it back when it closes (:func:`unregister`; a later unit reuses it);
the slots' labels are written to a file of the scratch directory, which grows with them, so any number of units
may be open in one child.

:func:`supervised` is what ``icosim cosim`` (and the workflow's FMU jobs) run under; without it nothing is
recorded and :func:`call` returns a context manager that does nothing.  The child's scratch files (the units
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
    "call",
    "register",
    "unregister",
    "under_way",
    "slots",
    "scratch_dir",
    "supervised",
    "Outcome",
    "CALLS",
    "CALL_SECONDS",
]

#: The default limit of one FMI call, in seconds: generous (a unit's doStep may integrate a stiff model).
CALL_SECONDS = 600.0

#: The FMI calls a record may name, as the standard names them.
CALLS = (
    "",
    "fmi2Instantiate",
    "fmi3InstantiateCoSimulation",
    "fmi3InstantiateModelExchange",
    "fmi2GetReal",
    "fmi3GetFloat64",
    "fmi2SetReal",
    "fmi3SetFloat64",
    "fmi2GetFMUstate",
    "fmi3GetFMUState",
    "fmi2SetFMUstate",
    "fmi3SetFMUState",
    "fmi2FreeFMUstate",
    "fmi3FreeFMUState",
    "fmi2SetRealInputDerivatives",
    "fmi2GetDirectionalDerivative",
    "fmi2DoStep",
    "fmi3DoStep",
    "fmi2Terminate",
    "fmi3Terminate",
    "fmi2FreeInstance",
    "fmi3FreeInstance",
)
_CODE = {name: float(i) for i, name in enumerate(CALLS)}

#: Bytes of a slot's label in the labels file.
_LABEL_BYTES = 128
#: float64 slots of the shared record: the number of the call under way (0: none), its unit's slot, its call
#: (:data:`CALLS`), t, macro step.  A call is timed by the parent from when it first sees its number, so the child
#: writes no clock: entering a call is a few stores into the shared memory, leaving one.
_RECORD = 5

_record = None  # a float64 memoryview of the shared memory, in the supervised child only
_labels = None  # the file descriptor of the slots' labels, in the supervised child only
_free = []  # the slots given back, reused first
_taken = 0  # the slots ever taken in this child
_number = 0.0  # the last call's number
#: per call under way, innermost last: the record it interrupted (a call inside another), or None
_open = []
_scratch = None


class _Nothing:
    """The context manager of calls that are not recorded."""

    __slots__ = ()

    def __enter__(self):
        return self

    def __exit__(self, kind, value, trace):
        return False


class _Call:
    """The context manager of the call :func:`call` names (one, reused: a call inside it is entered only
    after it, in its block)."""

    __slots__ = ("args",)

    def __enter__(self):
        global _number
        r = _record
        _open.append((r[0], r[1], r[2], r[3], r[4]) if r[0] != 0.0 else None)
        _number = number = _number + 1.0
        r[1], r[2], r[3], r[4] = self.args
        r[0] = number
        return self

    def __exit__(self, kind, value, trace):
        r = _record
        outer = _open.pop()
        if outer is None:
            r[0] = 0.0
        else:  # the outer call again, under its own number: timed from when the parent saw it last
            number, r[1], r[2], r[3], r[4] = outer
            r[0] = number
        return False


_NOTHING = _Nothing()
_CALL = _Call()


def call(unit, name: str, t: float, step: int = -1):
    """The context manager of the FMI call ``name`` (:data:`CALLS`) of ``unit`` at simulated time ``t`` (macro
    step ``step``): ``with guard.call(unit, "fmi2DoStep", t, step): ...``.  Recorded from entering the block to
    leaving it, however it is left; a unit not registered (:func:`register`, its ``index`` -1) or a process not
    supervised records nothing."""
    slot = unit.index
    if slot < 0 or _record is None:
        return _NOTHING
    _CALL.args = (slot, _CODE[name], t, step)
    return _CALL


def under_way():
    """The call recorded now, as ``(unit label, call, t, macro step)``, or None: what the parent would name."""
    if _record is None or _record[0] == 0.0:
        return None
    r = _record
    return _label(_labels, int(r[1])), CALLS[int(r[2])], float(r[3]), int(r[4])


def register(unit) -> int:
    """A slot for ``unit`` in the records (a slot given back first), its label written where the parent reads it;
    -1 when the process is not supervised."""
    global _taken
    if _record is None:
        return -1
    if _free:
        slot = min(_free)
        _free.remove(slot)
    else:
        slot, _taken = _taken, _taken + 1
    label = unit.label.encode()[: _LABEL_BYTES - 1].ljust(_LABEL_BYTES, b"\0")
    os.pwrite(_labels, label, slot * _LABEL_BYTES)
    return slot


def unregister(unit):
    """``unit`` closed: its slot is given back (its label stays until a unit takes the slot) and ``unit.index``
    is -1, so nothing more of it is recorded."""
    slot = getattr(unit, "index", -1)
    if _record is not None and slot >= 0 and slot not in _free:
        _free.append(slot)
    unit.index = -1


def slots() -> int:
    """The slots taken in this child so far, those given back included (at most the units open at once)."""
    return _taken


def scratch_dir():
    """Where units are unpacked: the supervised run's scratch directory, else the system's (None)."""
    return _scratch


def _label(fd, slot) -> str:
    raw = os.pread(fd, _LABEL_BYTES, slot * _LABEL_BYTES)
    return raw.split(b"\0")[0].decode(errors="replace")


@dataclass
class Outcome:
    """How a supervised run ended: its exit ``status`` and, where the parent stopped it or it died, a ``message``
    naming the unit and the call."""

    status: int
    message: str = ""


def _describe(labels_path, record, *, limit=None, signum=None) -> str:
    slot, code, t, step = int(record[1]), int(record[2]), float(record[3]), int(record[4])
    try:
        fd = os.open(labels_path, os.O_RDONLY)
        try:
            label = _label(fd, slot)
        finally:
            os.close(fd)
    except OSError:
        label = f"in slot {slot}"
    name = CALLS[code] if 0 <= code < len(CALLS) else f"call {code}"
    where = f"macro step {step}, t = {t:.12g} s" if step >= 0 else f"t = {t:.12g} s"
    if limit is not None:
        return (
            f"unit {label} did not return from {name} within {limit:g} s ({where}); the run was stopped "
            "(limits.call_seconds in the scene sets the limit)"
        )
    signame = signal.Signals(signum).name if signum in signal.Signals._value2member_map_ else f"signal {signum}"
    return f"unit {label} crashed the process in {name} ({signame}, {where})"


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
    global _record, _labels, _scratch, _taken, _number
    if not hasattr(os, "fork") or _record is not None:
        return Outcome(int(target() or 0))
    shared = mmap.mmap(-1, _RECORD * 8)
    record = memoryview(shared).cast("d")
    scratch = tempfile.mkdtemp(prefix="icosim-run-")
    labels_path = os.path.join(scratch, "units")  # the slots' labels, written by the child as units open
    streams = (sys.stdout, sys.stderr)
    sys.stdout.flush()
    sys.stderr.flush()
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: the run itself
        os.close(read_end)
        _labels = os.open(labels_path, os.O_RDWR | os.O_CREAT, 0o600)
        _record, _scratch, _taken, _number, _free[:], _open[:] = record, scratch, 0, 0.0, [], []
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
                        message = _describe(labels_path, record, signum=signum)
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
                    described = _describe(labels_path, record, limit=call_seconds)
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
