"""The paper's claims as data, checked against result datasets.

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.core`                the generic machinery: claims, selectors, check
                            kinds, verdicts, their JSON and TSV (knows no part)
:mod:`.registry`            the table of every part's check kinds, and the
                            claims functions bound to it
==========================  ===================================================

Each study defines its check kinds in its own ``checks`` module; only the registry
imports them.  The package imports none of its modules.
"""
