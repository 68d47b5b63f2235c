"""pythonfmu's interpreter state, released before the process exits.

pythonfmu (0.6.4 to 0.7.0 at least) keeps the state of the Python interpreter its library uses in a global
``std::shared_ptr`` of the library, freed on two paths: the global's C++ destructor (an exit handler registered
when the library is loaded) and the library's destructor function, which calls ``finalizePythonInterpreter``
(it assigns ``nullptr``).  At ``dlclose`` they run in that safe order, but the first pythonfmu library a process
loads is never unloaded (it defines ``STB_GNU_UNIQUE`` symbols of libstdc++, so glibc makes it NODELETE): at exit
the C++ destructor frees the shared_ptr's control block first, then ``finalizePythonInterpreter`` releases it
again and writes into the freed block (glibc aborts, "corrupted double-linked list", when that block sits in one
of its bin lists).  Called while the library is loaded, ``finalizePythonInterpreter`` empties the global, and
both exit paths find nothing to free.  With the interpreter already running the state holds no Python object
(pythonfmu then neither initialises nor finalises Python), no instance uses it, and an instance created later in
the library makes a new one.  :class:`icosim.problems.fmu.units.Unit` calls it when it closes a pythonfmu unit, and an
exit handler for units never closed (docs/fmi.md; ``tools/pythonfmu_exit_repro.py`` reproduces it without
icosim).
"""

from __future__ import annotations

import atexit

__all__ = ["register", "take"]

#: id of a unit -> the teardown of its pythonfmu library, until the unit is closed.
_RELEASES: dict = {}


def register(unit, md, dll):
    """Remember ``finalizePythonInterpreter`` of ``unit``'s library if a pythonfmu exported it (else nothing)."""
    if not (md.generationTool or "").startswith("PythonFMU"):
        return
    release = getattr(dll, "finalizePythonInterpreter", None)
    if release is not None:
        release.argtypes, release.restype = [], None
        _RELEASES[id(unit)] = release


def take(unit):
    """The teardown of ``unit``'s library (None for a unit of another exporter), forgotten here."""
    return _RELEASES.pop(id(unit), None)


@atexit.register
def _release_left_open():
    """Units never closed: their libraries released before the interpreter finalises."""
    while _RELEASES:
        _RELEASES.popitem()[1]()
