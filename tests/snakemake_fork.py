"""The test suite's Snakemake processes, forked from one that has imported Snakemake.

A speed trick of the tests alone: the workflow tests start some sixty Snakemake processes, and each would
import Snakemake and its plugins again (half of a dry run's CPU time).  :class:`SnakemakeForkServer` imports
them once and forks a child per run that is the ``snakemake`` command.  ``ICOSIM_TEST_SNAKEMAKE_FORK=0``
switches it off (:func:`helpers.snakemake` then runs the command); ``docs/benchmarks.md`` has what it saves.
"""

import atexit
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
if not Path(SNAKEMAKE).exists():
    SNAKEMAKE = shutil.which("snakemake") or "snakemake"


#: Modules besides Snakemake's own that every parse of the workflow imports (none of icosim): the fork
#: server imports them once, not each Snakemake process (about 0.1 CPU-s of each).
PRELOAD = (
    "smart_open",
    "jsonschema",
    "fastjsonschema",
    "nbformat",
    "requests",
    "yte",
    "argparse_dataclass",
    "platformdirs",
    "graphlib",
    "packaging.version",
    "snakemake.profiles",
    "snakemake.storage",
)

#: The fork server: imports Snakemake and :data:`PRELOAD` (about half of the CPU time of a dry run of this
#: workflow), then
#: for each request forks a child that is the ``snakemake`` command -- ``sys.exit(snakemake.cli.main())``
#: with the request's argv, working directory, environment and stdout/stderr files, exiting as that
#: script exits (atexit handlers, flushed streams).  It imports nothing of icosim: the Snakefile of the
#: copy imports the copy's src/ as it would in a new process.  Single-threaded, so forking is safe.
FORK_SERVER = r"""
import json, os, sys
sys.path[0] = os.path.dirname(SNAKEMAKE)  # as the console script: its own directory, not the cwd
import snakemake.api, snakemake.cli, snakemake.dag, snakemake.persistence, snakemake.script, snakemake.utils
import snakemake.scheduling.job_scheduler, snakemake.workflow
from snakemake_interface_executor_plugins.registry import ExecutorPluginRegistry
from snakemake_interface_logger_plugins.registry import LoggerPluginRegistry
from snakemake_interface_report_plugins.registry import ReportPluginRegistry
from snakemake_interface_storage_plugins.registry import StoragePluginRegistry
ExecutorPluginRegistry().get_plugin("local"), LoggerPluginRegistry(), ReportPluginRegistry(), StoragePluginRegistry()
import importlib
for name in PRELOAD:  # what parsing the workflow imports later (Snakemake's source cache, schema validation)
    try:
        importlib.import_module(name)
    except ImportError:
        pass
import gc, threading
assert threading.active_count() == 1, "the fork server must be single-threaded"
gc.freeze()  # the children's collections skip what the server imported: fewer pages copied on write
requests, replies = os.fdopen(0, "r"), os.fdopen(os.dup(1), "w")
for line in requests:
    req = json.loads(line)
    pid = os.fork()
    if pid == 0:  # the child: never returns to the loop
        try:
            requests.close(), replies.close()
            os.chdir(req["cwd"])
            os.environ.clear()
            os.environ.update(req["env"])
            null = os.open(os.devnull, os.O_RDONLY)
            os.dup2(null, 0)
            for fd, path in ((1, req["stdout"]), (2, req["stderr"])):
                os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644), fd)
            sys.argv = list(req["argv"])
        except BaseException:
            os._exit(121)
        sys.exit(snakemake.cli.main())
    replies.write(f"{pid}\n")
    replies.flush()
    _, status = os.waitpid(pid, 0)
    replies.write(f"{os.waitstatus_to_exitcode(status)}\n")
    replies.flush()
"""


class SnakemakeForkServer:
    """One fork server per test process, started at the first call (see ``FORK_SERVER``)."""

    _instance = None

    @classmethod
    def get(cls):
        if cls._instance is None or cls._instance.proc.poll() is not None:
            cls._instance = cls()
        return cls._instance

    def __init__(self):
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
        code = f"SNAKEMAKE = {SNAKEMAKE!r}\nPRELOAD = {PRELOAD!r}\n{FORK_SERVER}"
        self.proc = subprocess.Popen(
            [sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env, bufsize=1
        )
        self.buffer = b""
        self.tmp = Path(tempfile.mkdtemp(prefix="snakemake-fork-"))
        atexit.register(self.close)

    def close(self):
        """End of the test process: the server reads the end of its requests and exits."""
        self.proc.stdin.close()
        self.proc.wait(timeout=60)
        shutil.rmtree(self.tmp, ignore_errors=True)

    def run(self, argv, cwd, env, timeout):
        out, err = self.tmp / "stdout", self.tmp / "stderr"
        req = {"argv": argv, "cwd": str(cwd), "env": env, "stdout": str(out), "stderr": str(err)}
        self.proc.stdin.write(json.dumps(req) + "\n")
        self.proc.stdin.flush()
        pid = int(self._readline(None))
        try:
            returncode = int(self._readline(timeout))
        except subprocess.TimeoutExpired:
            os.kill(pid, signal.SIGKILL)
            self._readline(None)
            raise subprocess.TimeoutExpired(argv, timeout) from None
        return subprocess.CompletedProcess(argv, returncode, out.read_text(), err.read_text())

    def _readline(self, timeout):
        """A line of the server's replies (its stdout, read unbuffered so that select sees what is left)."""
        fd = self.proc.stdout.fileno()
        deadline = None if timeout is None else time.monotonic() + timeout
        while b"\n" not in self.buffer:
            wait = None if deadline is None else max(0.0, deadline - time.monotonic())
            if not select.select([fd], [], [], wait)[0]:
                raise subprocess.TimeoutExpired("snakemake", timeout)
            chunk = os.read(fd, 4096)
            if not chunk:
                raise RuntimeError("the Snakemake fork server exited")
            self.buffer += chunk
        line, self.buffer = self.buffer.split(b"\n", 1)
        return line.decode()
