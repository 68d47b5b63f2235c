"""System files written for other masters, read into one :class:`~.description.System`.

* SSP 1.0 and 2.0 (:mod:`.ssp`): an ``.ssp`` archive or an ``.ssd`` with its resources beside it, read with
  pyssp-standard (the SSP reference suite's reader; it validates against the standard's schemas of either version)
  and, for what it does not model (a connection's transformation and unit conversion), the same lxml tree;
* OSP's ``OspSystemStructure.xml`` (:mod:`.osp`), read with the standard library's ElementTree (no maintained
  reader exists outside libcosim's C++) against libcosim's schema.

:func:`read_system` takes either, or a folder holding one; :mod:`.scene` turns a system into a scene (joints from
power bonds) and refuses what the engine cannot run yet, naming it.
"""

from .description import Component, Connection, Connector, System
from .read import find_system_file, is_system_file, read_system

__all__ = [
    "Component",
    "Connection",
    "Connector",
    "System",
    "find_system_file",
    "is_system_file",
    "read_system",
]
