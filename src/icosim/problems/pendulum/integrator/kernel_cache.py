"""numba's disk cache of the compiled integrator (:mod:`icosim.problems.pendulum.integrator.compiled`): kept valid, and filled once.

* numba keys a cached kernel on the time stamp of the file that defines it only, so after an edit of
  a file the kernels inline (``compiled_links.py``, ``compiled_algebra.py``) or take constants from
  (``tableau.py``) it would load the kernels compiled from the old code.  :func:`drop_stale_cache`
  keeps a digest of those files beside the cache (``compiled.sources``) and, when it differs, removes
  the cache files of ``compiled.*``; ``compiled`` calls it before it defines its kernels, and
  ``compiled_step`` likewise for its own (which inline ``compiled.py`` too).
* :func:`gc_paused`: Python's cyclic garbage collector is off while the ``warm_up`` functions compile
  (numba's compiler allocates many short-lived objects; the collections it triggers were 5-10 % of a
  cold compile's CPU, the more the larger the process's heap); nothing compiled changes.
* :func:`compile_record` compiles (or loads) them now and says what it did
  (``compiled_step.compile_kernels``).  The workflow does this once, in one job before the runs
  (``results/pendulum/kernels.json``), since runs that start together on a cold cache (a fresh
  clone) would each compile, about 10 CPU-s.

Only numba's default cache place (``__pycache__`` beside the module) is looked after.
"""

from __future__ import annotations

import contextlib
import gc
import hashlib
import time
from pathlib import Path

__all__ = ["KERNEL_SOURCES", "drop_stale_cache", "gc_paused", "compile_record"]

#: Sources compiled into the kernels of ``compiled.py`` besides itself, relative to its package
#: (:mod:`icosim.problems.pendulum.integrator`).
KERNEL_SOURCES = ("compiled_links.py", "compiled_algebra.py", "tableau.py")


def drop_stale_cache(module: str = "compiled", sources: tuple = KERNEL_SOURCES) -> bool:
    """Remove the cache of ``{module}.*`` if a file in ``sources`` (the files its kernels inline) changed
    since it was written; returns whether it did (also when there was no record yet)."""
    here = Path(__file__)
    root = here.parent
    cache = here.parent / "__pycache__"
    digest = hashlib.sha256(b"".join((root / name).read_bytes() for name in sources)).hexdigest()
    record = cache / f"{module}.sources"
    try:
        if record.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        for path in cache.glob(f"{module}.*.nb[ic]"):
            path.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        record.write_text(digest)
    except OSError:  # a read-only install: numba caches elsewhere or not at all
        pass
    return True


@contextlib.contextmanager
def gc_paused():
    """Python's cyclic garbage collector off inside the block, as it was after it (nested blocks too)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def compile_record(warm_up, kernels: dict) -> dict:
    """Call ``warm_up`` (compile or load ``kernels``, name -> numba dispatcher) and record it: numba's
    version, each kernel's signatures and cache hits and misses in this process, the seconds it took."""
    import numba

    t0, c0 = time.perf_counter(), time.process_time()
    warm_up()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    record = {}
    for name, kernel in kernels.items():
        stats = kernel.stats
        record[name] = {
            "signatures": [str(sig) for sig in kernel.signatures],
            "cache_hits": sum(stats.cache_hits.values()),
            "cache_misses": sum(stats.cache_misses.values()),
        }
    return {"numba": numba.__version__, "kernels": record, "wall_seconds": wall, "cpu_seconds": cpu}
