"""The workflow's FMU part: the scenes run on their units and checked against the built-in models.

==========================  ===========================================================
module                      holds
==========================  ===========================================================
:mod:`.validation`          a scene against its built-in model, its prediction and the
                            growth measured; the supervised job of one scene
:mod:`.orders`              the linear study's orders of convergence on the units
:mod:`.checks`              the check kinds of its claims
:mod:`.config`              its configuration, checked before any job
==========================  ===========================================================

The package imports none of its modules.
"""
