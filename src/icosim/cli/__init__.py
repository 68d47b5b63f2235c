"""The ``icosim`` command: one module per sub-command, its parser beside its logic.

==========================  ===================================================
sub-command                 module
==========================  ===================================================
``icosim rho``              :mod:`.rho`: the spectral radius of one parameter
                            point, its verdict proven in ball arithmetic
``icosim advise``           :mod:`.advise`: every configuration for a two-mass
                            system, stable or not, up to which macro step
``icosim map``              :mod:`.map`: a stability map as PNG, PDF and NetCDF
``icosim cosim``            :mod:`.cosim`: an FMU scene run with a coupling method
``rho``/``advise --chain``  :mod:`.chain`: the same answers for a chain of
                            linear oscillator segments read from a YAML file
==========================  ===================================================

:mod:`.arguments` holds the argument types they share, so that every command takes and
refuses numbers alike.  Negative values may follow their option with a space, also in
exponent notation (``--lr1 -1e-3``).  Bad input -- including input beyond a limit of
:mod:`icosim.engine.bounds` -- is reported as ``icosim <command>: error: argument --<name>: ...``,
with exit status 2, before any work and without a traceback.  The library's messages name
parameters (``mu``); the commands attribute them to the option (``argument --mu: ...``).
"""

from __future__ import annotations

import argparse
import sys

from . import advise, chain, cosim, rho
from . import map as map_

__all__ = ["main", "build_parser", "COMMANDS"]

#: Sub-command name -> its module (``add_parser(sub)``, ``run(args, parser)``), in the order of ``--help``.
COMMANDS = {"rho": rho, "advise": advise, "map": map_, "cosim": cosim}


def build_parser() -> argparse.ArgumentParser:
    from ..version import package_version

    parser = argparse.ArgumentParser(
        prog="icosim",
        description="Implicit co-simulation methods with algebraic constraints (Schweizer et al.).",
    )
    parser.add_argument("--version", action="version", version=f"icosim {package_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    parser.set_defaults(subparser=None)
    for command in COMMANDS.values():
        command.add_parser(sub)
    return parser


def _negative_values_attached(argv, parser) -> list:
    """``--lr1 -1e-3`` as ``--lr1=-1e-3``.

    argparse reads a token that starts with ``-`` as an option unless it looks
    like a plain negative number (``-1``, ``-.5``); exponent notation is not
    covered.  A token after an option that takes a value is joined to it when
    it parses as a number, so users can type numbers as they write them.
    """
    # options that take exactly one value (flags such as --json have nargs = 0)
    argv = list(argv)
    # the command's own options only: another command may take the same option with several values
    takes_value = {
        opt for action in _all_actions(parser, argv) if action.nargs is None for opt in action.option_strings
    }
    out, i = [], 0
    while i < len(argv):
        tok = argv[i]
        if tok in takes_value and i + 1 < len(argv) and argv[i + 1].startswith("-") and _is_number(argv[i + 1]):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
            continue
        out.append(tok)
        i += 1
    return out


def _all_actions(parser, argv=()):
    for action in parser._actions:
        yield action
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                if name in argv[:1]:
                    yield from _all_actions(sub)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def main(argv=None) -> int:
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else argv
    args = parser.parse_args(_negative_values_attached(argv, parser))
    try:
        # ``--chain FILE`` (rho, advise): a chain in place of the two subsystems (:mod:`.chain`)
        command = chain if getattr(args, "chain", None) is not None else COMMANDS[args.command]
        return command.run(args, args.subparser)
    except KeyboardInterrupt:
        # files are written whole or not at all (renamed into place when complete): say so, no traceback
        print(f"icosim {args.command}: interrupted; no output file was left half-written", file=sys.stderr)
        return 130
