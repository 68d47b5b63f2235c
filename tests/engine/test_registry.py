"""The registry of coupling methods (icosim.engine.methods) and everything that reads it agree."""

import numpy as np
import pytest
import yaml
from helpers import ROOT, validate_config

from icosim.cli import build_parser
from icosim.engine import methods
from icosim.engine.decompositions import DECOMPOSITIONS
from icosim.engine.methods import METHODS, engine_method, get_spec, make_method, parameter_units
from icosim.engine.schema import PLACEHOLDERS, schema_defs, with_registries
from icosim.errors import ParameterError
from icosim.studies.convergence.experiment import dimensional_method, units_description, units_summary
from icosim.studies.stability.panels import method_parameters_units, row_keys

SCHEMAS = ("stability", "convergence", "pendulum")


def _walk(node, path=()):
    """Every (path, mapping) in a YAML document."""
    if isinstance(node, dict):
        yield path, node
        for k, v in node.items():
            yield from _walk(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _walk(v, path + (i,))


@pytest.mark.parametrize("part", SCHEMAS)
def test_schemas_name_no_method_or_parameter_themselves(part):
    """Methods and their parameters reach the schemas only through the placeholders the registry fills."""
    doc = yaml.safe_load((ROOT / "workflow" / "schemas" / f"{part}.schema.yaml").read_text())
    names = set(METHODS) | set(methods.argument_names())
    for path, node in _walk(doc):
        assert not (set(node.get("properties", {})) & names), (part, path)
        assert not (set(map(str, node.get("enum", []))) & set(METHODS)), (part, path)
    used = [name for name in PLACEHOLDERS if name in doc.get("$defs", {})]
    assert used and all(doc["$defs"][name] == {} for name in used)
    filled = with_registries(doc)["$defs"]
    assert all(filled[name] == schema_defs()[name] for name in used)


def test_filled_definitions_are_the_registry():
    defs = schema_defs()
    assert defs["method"]["enum"] == list(METHODS)
    assert set(defs["method_parameters"]["properties"]) == set(methods.argument_names())
    for spec in METHODS.values():
        props = defs["methods_parameters"]["properties"][spec.name]["properties"]
        assert set(props) == set(spec.arguments)
        for p in spec.parameters:  # the schema's bound is the parameter's
            key = "exclusiveMinimum" if p.exclusive_minimum else "minimum"
            assert props[p.name][key] == p.minimum


@pytest.mark.parametrize("part", SCHEMAS)
def test_shipped_configuration_passes_and_unknown_methods_and_parameters_fail(part):
    cfg = yaml.safe_load((ROOT / "config" / f"{part}.yaml").read_text())[part]
    validate_config(cfg, part)
    if part == "pendulum":
        cfg["configurations"][0]["method"] = "nope"
        bad_param = {**cfg, "methods": {**cfg["methods"], "baumgarte": {"index": 1, "nu": 1.0}}}
    else:
        fig = next(iter(cfg["figures"]))
        bad_param = yaml.safe_load(yaml.safe_dump(cfg))
        key = "params" if part == "stability" else "columns"
        bad_param["figures"][fig][key] = {"nu": 1.0} if part == "stability" else [{"nu": 1.0}]
        cfg["figures"][fig]["method"] = "nope"
    with pytest.raises(Exception, match="nope"):
        validate_config(cfg, part)
    with pytest.raises(Exception, match="nu"):
        validate_config(bad_param, part)


def test_make_method_refuses_unknown_names_and_parameters():
    with pytest.raises(ParameterError, match="method must be one of baumgarte, weighted, projection, got 'x'"):
        make_method("x")
    with pytest.raises(ParameterError, match=r"parameter\(s\) mu not used by method 'projection' \(it takes none\)"):
        make_method("projection", mu=1.0)


def test_units_and_scaling_come_from_the_registry():
    assert parameter_units(index=True) == {"mu": "s", "beta": "s", "gamma": "s2", "a": "1", "b": "1", "index": "1"}
    m = dimensional_method("baumgarte", 1e-3, index=1, mu=5e-3)
    assert m.params["beta"] == pytest.approx(10.0) and m.params["gamma"] == pytest.approx(25.0)
    assert dimensional_method("weighted", 1e-3, a=1, b=2).params["b"] == 2.0  # dimensionless: unscaled
    dimensionless = engine_method(make_method("baumgarte", index=1, mu=1e-3), 1e-3)
    assert dimensionless.solves == make_method("baumgarte", beta=2.0, gamma=1.0).solves
    w = make_method("weighted", a=1.0, b=0.0)
    assert engine_method(w, 1e-3).solves == w.solves


def test_attribute_texts_are_the_recorded_ones():
    """The unit descriptions the datasets carry, generated from the registry, are the texts recorded before it."""
    assert method_parameters_units() == (
        "dimensionless (beta_bar = beta/H, gamma_bar = gamma/H^2, mu_bar = mu/H; a, b dimensionless): "
        "the attributes mu, beta, gamma are mu_bar, beta_bar, gamma_bar"
    )
    assert units_description() == (
        "dimensional: mu and beta in s, gamma in s^2 (Baumgarte, Sect. 3.7); a, b dimensionless; "
        "the engine uses beta_bar = beta/H, gamma_bar = gamma/H^2"
    )
    assert units_summary() == "mu and beta in s, gamma in s^2, a and b dimensionless"
    assert row_keys() == ("am21", "alr21", "ali21", "mu", "beta", "gamma", "a", "b")


def test_index_follows_from_the_parameters():
    assert [get_spec("baumgarte").make(beta=b, gamma=g).params["index"] for b, g in ((1, 1), (1, 0), (0, 0))] == [
        1,
        2,
        3,
    ]
    assert [get_spec("weighted").make(a=a, b=b).params["index"] for a, b in ((1, 1), (1, 0), (0, 0))] == [1, 2, 3]
    assert get_spec("weighted").unused(2) == ("b",) and get_spec("baumgarte").unused(3) == ("mu", "beta", "gamma")
    assert get_spec("projection").make().params == {"index": 1}


def test_command_line_offers_the_registry():
    parser = build_parser()
    rho = parser._subparsers._group_actions[0].choices["rho"]
    options = {a.dest: a for a in rho._actions}
    assert tuple(options["method"].choices) == tuple(METHODS)
    assert set(methods.argument_names()) <= set(options)
    assert tuple(options["index"].choices) == (1, 2, 3)


def test_spec_checks_its_own_invariants():
    spec = METHODS["baumgarte"]
    with pytest.raises(ValueError, match="unused_at_index"):
        type(spec)(**{**spec.__dict__, "unused_at_index": {3: ("nu",)}})
    # the decompositions follow from the registry (requires_constraint): a spec cannot name others
    with pytest.raises(TypeError, match="decompositions"):
        type(spec)(**{**spec.__dict__, "decompositions": ("xx",)})
    for requires in (False, True):
        derived = type(spec)(**{**spec.__dict__, "requires_constraint": requires}).decompositions
        expected = [name for name, d in DECOMPOSITIONS.items() if d.has_constraint_condition or not requires]
        assert derived and list(derived) == expected
    with pytest.raises(ValueError, match="already registered"):
        methods.register(spec)
    assert np.isclose(spec.parameter("gamma").engine_value(1e-6, 1e-3), 1.0)
