"""The chain stability search with the bisection's step sizes computed in batches: the same limits as one step
size at a time, every point's ``(rho, error)`` the one it gets alone, and the verdicts on both sides of the limit
proven in ball arithmetic (an independent computation)."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from icosim.engine.spectral.certified import certify_spectral_radius
from icosim.engine.spectral.radius import spectral_radius_float64
from icosim.problems.linear.chain import ChainFamily
from icosim.step_limit import stability_limit
from icosim.studies.chains.config import build_chain, method_of, scheme_name
from icosim.studies.chains.stability import largest_stable_H, rho_over_H, scan_steps

ROOT = Path(__file__).resolve().parents[3]
CFG = yaml.safe_load((ROOT / "config" / "chains.yaml").read_text())["chains"]
SCAN = scan_steps({"min": 1e-3, "max": 1.0, "n": 12})
# (unit, pattern, N, method, k, scheme kind): single masses and segments, a kinematically driven mass (fd at
# N = 2, a block the same at every H), Jacobi and both Gauss-Seidel orders; the last stable up to the cap
CASES = [
    ("mass", "ff", 3, "projection", 0, "jacobi"),
    ("mass", "fd-df", 2, "baumgarte", 1, "jacobi"),
    ("segment", "fd-df", 3, "projection", 0, "gauss-seidel-reverse"),
    ("segment", "ff", 4, "baumgarte", 2, "jacobi"),
    ("mass", "ff", 3, "baumgarte", 1, "gauss-seidel-forward"),
]


def _case(unit, pattern, n, mname, k, kind):
    return build_chain(CFG["units"][unit], pattern, n, 1.0), method_of(CFG["methods"], mname), k, scheme_name(kind, n)


@pytest.mark.parametrize("case", CASES, ids=lambda c: "-".join(map(str, c)))
def test_a_batch_gives_every_point_its_own_rho_and_error_bit_for_bit(case):
    chain, method, k, scheme = _case(*case)
    H = np.geomspace(2e-3, 0.5, 40)  # large enough to be laid out with the batch axis fastest
    rho, err = rho_over_H(chain.with_H(H), method, k, scheme)
    for i in range(0, H.size, 3):
        r, e = rho_over_H(chain.with_H(H[i : i + 1]), method, k, scheme)
        assert (rho[i], err[i]) == (r[0], e[0])  # bitwise
        # alone, the point's draws are those of the estimate with independent draws over a grid
        r0, e0 = spectral_radius_float64(ChainFamily(chain.with_H(H[i : i + 1]), k), method, scheme=scheme)
        assert (r[0], e[0]) == (r0[0], e0[0])
    # the batch in another order: the same numbers per point
    r2, e2 = rho_over_H(chain.with_H(H[::-1].copy()), method, k, scheme)
    np.testing.assert_array_equal(r2[::-1], rho)
    np.testing.assert_array_equal(e2[::-1], err)


@pytest.mark.parametrize("case", CASES, ids=lambda c: "-".join(map(str, c)))
def test_the_batched_bisection_is_the_bisection_one_point_at_a_time(case):
    chain, method, k, scheme = _case(*case)
    one, rho1, err1 = largest_stable_H(chain, method, k, scheme, SCAN, 0.01, ahead=1)
    for ahead in (2, 3):
        many, rho, err = largest_stable_H(chain, method, k, scheme, SCAN, 0.01, ahead=ahead)
        assert (many.H_max, many.H_unstable, many.status) == (one.H_max, one.H_unstable, one.status)
        assert many.evaluations == one.evaluations
        np.testing.assert_array_equal(rho, rho1)
        np.testing.assert_array_equal(err, err1)


def test_stability_limit_checks_the_same_step_sizes_with_a_batched_predicate():
    """Bands and edges placed at random: the batched search checks exactly the step sizes of the plain one,
    and asks the batch for at most the 2^ahead - 1 step sizes of the next halvings at a time."""
    rng = np.random.default_rng(1)
    scan = np.geomspace(1e-3, 1.0, 9)
    for _ in range(40):
        edges = np.sort(rng.uniform(-3.2, 0.2, 4))

        def stable(H, e=edges):
            x = np.log10(H)
            return bool((e[0] <= x < e[1]) or (e[2] <= x < e[3]))

        calls = []

        def batch(Hs, calls=calls, stable=stable):
            calls.append(len(Hs))
            return [stable(H) for H in Hs]

        plain = stability_limit(stable, scan, resolution=0.005)
        for ahead in (1, 2, 4):
            calls.clear()
            lim = stability_limit(None, scan, resolution=0.005, batch=batch, ahead=ahead)
            assert lim.evaluations == plain.evaluations
            assert (lim.H_max, lim.H_unstable, lim.status) == (plain.H_max, plain.H_unstable, plain.status)
            assert all(c <= 2**ahead - 1 for c in calls[1:])


@pytest.mark.parametrize("case", CASES[:2], ids=lambda c: "-".join(map(str, c)))
def test_the_limit_is_proven_stable_and_its_neighbour_above_is_not_stable(case):
    """Ball arithmetic (certify_spectral_radius) at H_max and H_unstable of the batched search: rho < 1 proven at
    H_max; at H_unstable float64 found rho + error >= 1, which the certificate must not contradict by proving
    rho < 1 with a margin float64's estimate would have seen (it proves rho > 1 here)."""
    chain, method, k, scheme = _case(*case)
    lim, _, _ = largest_stable_H(chain, method, k, scheme, SCAN, 0.01)
    assert lim.status == "bisected"
    at = {H: ChainFamily(chain.with_H(H), k) for H in (lim.H_max, lim.H_unstable)}
    assert certify_spectral_radius(at[lim.H_max], method, scheme=scheme).verdict == "stable"
    assert certify_spectral_radius(at[lim.H_unstable], method, scheme=scheme).verdict == "unstable"
