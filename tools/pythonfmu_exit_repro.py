"""pythonfmu's double release at process exit, without icosim: fmpy and pythonfmu only (Linux).

A trivial pythonfmu slave is exported, then each run is a fresh process that loads it with fmpy, instantiates
it, steps it, frees it (``fmi2FreeInstance``, then fmpy's ``dlclose``) and exits.  pythonfmu (0.6.4 to 0.7.0 at
least) keeps its interpreter state in a global ``std::shared_ptr<PyState>`` of the library.  The library stays
loaded (glibc makes it NODELETE: it defines ``STB_GNU_UNIQUE`` symbols of libstdc++), so at ``exit`` the global's
C++ destructor (registered with ``__cxa_atexit`` when the library was loaded) frees the control block, and then
``_dl_fini`` calls the library's destructor function, ``finalizePythonInterpreter``, whose ``pyState = nullptr``
releases the freed block once more (a write into freed memory, every run).  glibc reports it only when the freed
block sits in one of its bin lists ("corrupted double-linked list", "free(): corrupted unsorted chunks");
valgrind's memcheck reports it in every run.  ``--release`` calls ``finalizePythonInterpreter`` before freeing
the instance (icosim's workaround, icosim.problems.fmu.pythonfmu): both exit paths then find nothing to free.

    python tools/pythonfmu_exit_repro.py [--runs N] [--valgrind] [--release]

prints, over N runs: the runs with a non-zero exit status, with "corrupted" in stderr, and (``--valgrind``) with
an invalid access by ``finalizePythonInterpreter``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

SLAVE = """
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class slave(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.x = 0.0
        self.register_variable(Real("x", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.x += step_size
        return True
"""


def child(fmu: str, release: bool) -> None:
    """One process: load, instantiate, step, free, exit."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(fmu)
    unzipdir = extract(fmu, unzipdir=tempfile.mkdtemp())
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier)
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 0.1)
    s.terminate()
    if release:
        s.dll.finalizePythonInterpreter()  # pythonfmu's own teardown, while the library is loaded
    s.freeInstance()  # fmi2FreeInstance, then dlclose (the library stays mapped: NODELETE)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--valgrind", action="store_true", help="each run under valgrind's memcheck")
    parser.add_argument("--release", action="store_true", help="call finalizePythonInterpreter before freeing")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child, args.release)
        return
    from pythonfmu.builder import FmuBuilder

    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "slave.py"
        script.write_text(SLAVE)
        fmu = str(FmuBuilder.build_FMU(script, dest=tmp))
        failed = corrupted = invalid = 0
        for i in range(args.runs):
            log = Path(tmp) / f"memcheck.{i}.log"
            cmd = [sys.executable, __file__, "--child", fmu] + (["--release"] if args.release else [])
            if args.valgrind:
                cmd = ["valgrind", "--undef-value-errors=no", f"--log-file={log}"] + cmd
            env = {**os.environ, "PYTHONMALLOC": "malloc"} if args.valgrind else None
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
            failed += proc.returncode != 0
            corrupted += "corrupted" in proc.stderr
            invalid += args.valgrind and "finalizePythonInterpreter" in log.read_text()
        print(f"runs {args.runs}: exit status not 0 in {failed}, 'corrupted' in {corrupted}", end="")
        print(f", invalid access by finalizePythonInterpreter in {invalid}" if args.valgrind else "")


if __name__ == "__main__":
    main()
