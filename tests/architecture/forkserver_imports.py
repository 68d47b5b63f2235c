"""Which icosim modules a few import statements load, each set of statements in a clean interpreter.

:class:`ImportForkServer` starts one interpreter that imports the heavy third-party modules the workflow
scripts load (:data:`PRELOAD`) but no module of icosim, then forks a child for each request: the child
runs the statements and reports the icosim modules in its ``sys.modules``.  Interpreter start and the
third-party imports are paid once, not once per script.  The preloaded modules cannot change which icosim
modules the statements load (icosim never looks at what else is imported); the children see the
environment, working directory and ``sys.path`` a fresh interpreter started as the server would have.
Where ``os.fork`` is missing, or with ``ICOSIM_TEST_IMPORT_FORK=0``, each request starts a fresh
interpreter instead.
"""

import json
import os
import subprocess
import sys
import tempfile

#: Third-party modules that importing the workflow scripts' icosim modules loads (numba for the compiled
#: kernels, matplotlib for the figures); a missing one is skipped.
PRELOAD = (
    "numpy",
    "scipy",
    "yaml",
    "numba",
    "matplotlib.figure",
    "matplotlib.colors",
    "matplotlib.lines",
    "matplotlib.patches",
)

#: What a child reports: the files of the icosim modules loaded (the same expression in both routes).
_REPORT = "sorted(m.__file__ for n, m in sys.modules.items() if n.split('.')[0] == 'icosim')"

#: The server: preloads, checks that it holds no icosim module and runs a single thread (forking is safe),
#: then reads one JSON line per request (the statements) and answers one JSON line per request,
#: ``{"files": [...]}`` or ``{"error": traceback}``, from a child forked for that request.
_SERVER = r"""
import gc, importlib, json, os, sys, threading, traceback
for name in PRELOAD:
    try:
        importlib.import_module(name)
    except ImportError:
        pass
os.environ.clear()  # the one BLAS thread was for the server's numpy: the children see the environment asked for
os.environ.update(CHILD_ENV)
early = sorted(n for n in sys.modules if n.split(".")[0] == "icosim")
assert not early, f"the import fork server loaded icosim modules before forking: {early}"
assert threading.active_count() == 1, "the import fork server must be single-threaded"
gc.freeze()  # the children's collections skip the preloaded objects
for line in sys.stdin:
    statements = json.loads(line)
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: runs the statements, reports, never returns to the loop
        os.close(read_end)
        try:
            exec(compile(statements, "<imports>", "exec"), {"__name__": "__main__"})
            reply = {"files": eval(REPORT)}
        except BaseException:
            reply = {"error": traceback.format_exc()}
        os.write(write_end, json.dumps(reply).encode())
        os._exit(0)
    os.close(write_end)
    with os.fdopen(read_end, "rb") as pipe:
        reply = pipe.read().decode()
    os.waitpid(pid, 0)
    sys.stdout.write((reply or json.dumps({"error": "the child exited without a reply"})) + "\n")
    sys.stdout.flush()
"""


class ImportForkServer:
    """:meth:`loaded_files` of import statements; :meth:`close` ends the server (a fixture's teardown)."""

    def __init__(self, cwd, env):
        self.cwd, self.env = cwd, dict(env)
        self.proc = None
        if hasattr(os, "fork") and os.environ.get("ICOSIM_TEST_IMPORT_FORK", "1") != "0":
            self.stderr = tempfile.TemporaryFile(prefix="icosim-import-server-")
            header = f"PRELOAD = {PRELOAD!r}\nREPORT = {_REPORT!r}\nCHILD_ENV = {self.env!r}\n"
            self.proc = subprocess.Popen(
                [sys.executable, "-c", header + _SERVER],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=self.stderr,
                text=True,
                cwd=cwd,
                env={**self.env, "OPENBLAS_NUM_THREADS": "1"},  # one BLAS thread: no thread left behind by a fork
            )

    def loaded_files(self, statements: str) -> list:
        """Files of the icosim modules loaded after ``statements`` in an interpreter that loaded none."""
        if self.proc is None:
            return self._fresh_interpreter(statements)
        self.proc.stdin.write(json.dumps(statements) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            self.stderr.seek(0)
            raise RuntimeError(f"the import fork server exited:\n{self.stderr.read().decode(errors='replace')}")
        reply = json.loads(line)
        if "error" in reply:
            raise AssertionError(f"the statements failed:\n{statements}\n{reply['error']}")
        return reply["files"]

    def _fresh_interpreter(self, statements):
        code = f"{statements}\nimport json, sys\nprint(json.dumps({_REPORT}))"
        out = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=self.cwd, env=self.env
        )
        return json.loads(out.stdout)

    def close(self):
        """The server reads the end of its requests and exits (killed, by its pid, if it does not)."""
        if self.proc is None:
            return
        self.proc.stdin.close()
        try:
            self.proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.proc.stdout.close()
        self.stderr.close()
