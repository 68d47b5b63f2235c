"""``--chain FILE`` of ``icosim rho`` and ``icosim advise``: a chain of linear oscillator segments joined by rigid
joints, read from a YAML file (:func:`icosim.advise.chains.read_chain`), in place of the two subsystems.

With ``--chain`` the two-unit arguments (``--decomposition``, ``--lr1`` ... for ``rho``; ``--m1`` ... and
``--decompositions`` for ``advise``) do not apply: the units and the joints' decompositions come from the file,
and giving them too is an error naming them.  The chain takes the macro step ``--H`` in s.  Bad input (a missing
file, a bad key, an unknown scheme, an order missing a unit) exits with status 2 naming the argument or the key,
before any work.
"""

from __future__ import annotations

from ..errors import ParameterError

__all__ = ["run", "run_rho", "run_advise"]


def _given(args, names) -> list[str]:
    return [f"--{n}" for n in names if getattr(args, n, None) is not None]


def _chain(args, parser, two_unit):
    """The chain of ``--chain`` after refusing the two-unit arguments given with it."""
    from ..advise.chains import read_chain

    if given := _given(args, two_unit):
        parser.error(
            f"argument --chain: not allowed with {', '.join(given)} (the units and the joints' decompositions "
            "come from the chain file)"
        )
    try:
        return read_chain(args.chain)
    except ParameterError as exc:
        parser.error(f"argument --chain: {exc}")


def _scheme(text, chain, parser, argument="--scheme"):
    from ..advise.chains import chain_scheme

    try:
        return chain_scheme(text, chain)
    except ParameterError as exc:
        parser.error(f"argument {argument}: {exc}")


def run(args, parser) -> int:
    """The command of ``args`` with ``--chain`` (``icosim`` dispatches here when it is given)."""
    if args.command == "rho":
        return run_rho(args, parser)
    from .advise import advise_parameters

    params = {name: getattr(args, name) for name in advise_parameters() if getattr(args, name) is not None}
    return run_advise(args, parser, params)


def run_rho(args, parser) -> int:
    """``icosim rho --chain FILE``: the chain's spectral radius at ``--H``, its verdict proven as the two-unit
    command's (:func:`icosim.cli.rho.family_answer`)."""
    import numpy as np

    from ..io.jsonio import dumps
    from ..problems.linear.chain import ChainFamily
    from .rho import MODEL_NAMES, _argument_message, _method_from_args, family_answer, precision, rho_text

    chain = _chain(args, parser, ("decomposition",) + MODEL_NAMES)
    if args.H is None:
        parser.error("the following arguments are required with --chain: --H")
    if not args.H > 0:
        parser.error(f"argument --H: must be a macro step in s (> 0), got {args.H!r}")
    scheme = _scheme(args.scheme, chain, parser)
    family = ChainFamily(chain.with_H(args.H), args.k)
    try:
        method = _method_from_args(args)
    except ParameterError as exc:
        parser.error(_argument_message(str(exc)))
    try:
        family.check(method, scheme)
    except ParameterError as exc:  # a method not defined for a joint's decomposition, an order not served
        parser.error(f"argument --method/--scheme: {exc} (the chain's joints: {', '.join(chain.decompositions)})")
    if np.any(family.overflowing()):
        parser.error(f"argument --H: {family.overflow_reason}")
    answer = family_answer(family, method, lambda: family, scheme=scheme, **precision(args))
    result = {
        **answer,
        "method": method.name,
        "chain": args.chain,
        "joints": list(chain.decompositions),
        "units": chain.n_segments,
        "H": args.H,
        "k": args.k,
        "scheme": scheme.name,
        "method_parameters": method.params,
    }
    print(dumps(result) if args.json else rho_text(answer, show_enclosure=args.certify, scheme=scheme))
    return 0


def run_advise(args, parser, params: dict) -> int:
    """``icosim advise --chain FILE``: every configuration of the chain ranked (:func:`icosim.advise.chains.advise_chain`),
    those the engine refuses listed with the reason."""
    from ..advise import DEFAULT_K
    from ..advise.chains import advise_chain, chain_advice_text, chain_configurations
    from .advise import print_advice, scan_settings
    from .arguments import fail

    chain = _chain(args, parser, ("m1", "m2", "c1", "c2", "d1", "d2", "decompositions"))
    for text in args.schemes or ():
        _scheme(text, chain, parser, "--schemes")
    try:
        settings = scan_settings(args)
        configuration_list, refused = chain_configurations(
            chain, methods=args.methods, k=args.k or DEFAULT_K, params=params, schemes=args.schemes
        )
    except ParameterError as exc:
        fail(parser, str(exc))

    def compute(bar):
        return advise_chain(
            chain, args.H, configuration_list=configuration_list, refused=refused, progress=bar, **settings
        )

    return print_advice(args, len(configuration_list), compute, chain_advice_text)
