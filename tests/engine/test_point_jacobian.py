"""The Jacobians of one float64 point through their sparse map in floats (icosim.engine.point_jacobian) against
the general assembly: a macro step of one point and of the same point in a stack of one are the same numbers, bit
for bit, for every kind of joint, method and scheme, scaled or not; the map is refused where an entry is not of
its form, and for stages too large for it."""

import numpy as np
import pytest

from icosim.engine.macrostep import macro_step
from icosim.engine.methods import engine_method, make_method
from icosim.engine.point_jacobian import MAX_ENTRIES, PointJacobian
from icosim.problems.linear.chain import Chain, ChainSegment

H = 1e-3
SEGMENTS = [((1.0,), (1000.0,), (2.0,)), ((2.0,), (500.0,), (1.0,)), ((0.5,), (2000.0,), (0.5,))]
METHODS = [("projection", {}), ("baumgarte", {"index": 1, "mu": 1e-2}), ("weighted", {"index": 1, "a": 1.0, "b": 1.0})]


class _NoMap(dict):
    """A problem's maps of its stages, every one refused: the general assembly for all."""

    def __contains__(self, key):
        return True

    def __getitem__(self, key):
        return None


def _point_and_stack(chain, method, scheme, scale, k=1, seed=0):
    """One macro step of a random point, with the sparse map and with the general assembly alone (the map
    switched off), the levels scaled by ``scale`` as an FMU problem scales them: (state, history, y) of each, the
    second with a leading axis of one, and whether the first took the map."""
    problems = chain.problem(k), chain.problem(k)
    for p in problems:
        p.condition_scale = scale
    problems[1]._point_jacobians = _NoMap()
    rng = np.random.default_rng(seed)
    state = rng.normal(size=(chain.n_segments, 2 * chain.n_masses))
    history = rng.normal(size=(k + 1, problems[0].n_coupling))
    m = engine_method(make_method(method[0], **method[1]), H)
    one = macro_step(problems[0], m, state, history, scheme=scheme)
    stacked = macro_step(problems[1], m, state[None], history[None], scheme=scheme)
    mapped = any(v is not None for v in problems[0]._point_jacobians.values())
    return one, stacked, mapped


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m[0])
@pytest.mark.parametrize("decompositions", [("ff", "ff"), ("ff", "fd"), ("df", "ff"), ("df", "fd")], ids=str)
@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-123", "gauss-seidel-321"])
@pytest.mark.parametrize("scale", [None, (1.0, 0.3, 0.07)], ids=["unscaled", "scaled"])
def test_one_point_equals_a_stack_of_one_bit_for_bit(method, decompositions, scheme, scale):
    chain = Chain(tuple(ChainSegment(*s) for s in SEGMENTS), decompositions, H)
    one, stacked, mapped = _point_and_stack(chain, method, scheme, scale)
    assert mapped
    for a, b in zip(one, stacked):
        assert np.array_equal(a, b[0]), (a, b[0])


def test_a_stage_too_large_for_the_map_takes_the_general_assembly():
    """A 10-unit chain's one Jacobi stage has more entries than MAX_ENTRIES (9 joints by 9 columns on three
    levels): no map, the general assembly, the same numbers; its Gauss-Seidel stages are small: the map."""
    chain = Chain((ChainSegment((1.0,), (1000.0,), (2.0,)),) * 10, ("ff",) * 9, H)
    for scheme, expected in (("jacobi", False), ("gauss-seidel-1.2.3.4.5.6.7.8.9.10", True)):
        one, stacked, mapped = _point_and_stack(chain, METHODS[0], scheme, (1.0, 0.5, 0.25))
        assert mapped is expected
        for x, y in zip(one, stacked):
            assert np.array_equal(x, y[0])


def test_entries_not_of_the_form_are_refused():
    """An entry of three terms, or a coefficient other than +-1, leaves the stage to the general assembly."""

    def general_of(matrix):
        def general(z):
            values = z @ matrix.T  # (stack, entries): one row per entry
            out = {key: np.zeros((len(z), 0, 1)) for key in ("vel", "acc", "force")}
            return {"pos": values[:, :, None], **out}

        return general

    assert PointJacobian.make(general_of(np.array([[1.0, -1.0, 0.0]])), 3) is not None
    assert PointJacobian.make(general_of(np.array([[1.0, -1.0, 1.0]])), 3) is None
    assert PointJacobian.make(general_of(np.array([[2.0, 0.0, 0.0]])), 3) is None
    assert PointJacobian.make(general_of(np.eye(MAX_ENTRIES + 1)), MAX_ENTRIES + 1) is None
