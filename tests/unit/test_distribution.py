"""The equilibrium distribution at any r (bouncing_ball.distribution), computed from the solver's
P(0, v), against the exact r = 1/2, 1/3 solutions (exact.py).  The checks at other r (the
solver's Ito time averages, the moment identities of P(x, v)) are in test_distribution_any_r.py."""

import warnings
from fractions import Fraction

import numpy as np
import pytest
from distribution_support import build
from scipy import integrate

from bouncing_ball import distribution, exact

EXACT = [Fraction(1, 2), Fraction(1, 3)]
# the checks at any r (0.15, 0.25, 0.6, 0.75, 0.9) are in test_distribution_any_r.py: each r
# costs a 3-12 s build of w(F)


@pytest.fixture(scope="module")
def built():
    """(solution, WeightFunction) per r, built once per session (distribution_support.build)."""
    return build


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_weight_function_matches_the_exact_one(r, built):
    """w(F) of eq. (weightfunc) from the solver's P(0, v) against eq. (weightfunc2), F in [1e-3, 1e3]
    (the interpolant) and at a few F directly."""
    solution, weight = built(r)
    forces = np.geomspace(1e-3, 1e3, 41)
    expected = np.log(exact.weight_function(forces, r))
    assert np.max(np.abs(weight.log(forces) - expected)) < 1e-8
    direct = distribution.log_weight_function(np.array([0.01, 30.0]), solution)
    assert np.max(np.abs(direct - np.log(exact.weight_function([0.01, 30.0], r)))) < 1e-8


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_position_density_and_speed_squared_match_the_exact_ones(r, built):
    """P(x) of eq. (P(x)1) against eq. (P(x)2), and <v^2>_x of eq. (moment2), x in [1e-3, 100]."""
    _, weight = built(r)
    x = np.geomspace(1e-3, 100.0, 11)
    px = distribution.position_density(x, weight)
    assert np.max(np.abs(px / exact.position_density(x, r) - 1.0)) < 1e-8
    v2 = distribution.mean_speed_squared_given_position(x, weight)
    assert np.max(np.abs(v2 / exact.mean_speed_squared_given_position(x, r) - 1.0)) < 1e-8


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_bin_averages_match_the_exact_ones(r, built):
    _, weight = built(r)
    lo = np.array([0.0, 1e-3, 0.5, 10.0, 40.0])
    hi = np.array([1e-3, 0.01, 0.6, 12.0, 80.0])
    for ours, theirs in [
        (distribution.position_bin_average, exact.position_bin_average),
        (
            distribution.speed_squared_given_position_bin_average,
            exact.speed_squared_given_position_bin_average,
        ),
    ]:
        assert np.max(np.abs(ours(lo, hi, weight) / theirs(lo, hi, r) - 1.0)) < 1e-8


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_distribution_matches_the_exact_one(r, built):
    """P(x, v) by the F integral of eq. (fpsol) with the computed w against exact.distribution."""
    solution, weight = built(r)
    x, v = np.meshgrid([1e-3, 0.1, 1.0, 10.0], [-4.0, -0.5, 0.0, 0.5, 4.0], indexing="ij")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        ours = distribution.distribution(x, v, weight, solution)
        theirs = exact.distribution(x, v, r)
    assert np.max(np.abs(ours / theirs - 1.0)) < 1e-8
    # x = 0: the solver's P(0, v) and eq. (bc)
    at_wall = distribution.distribution(0.0, np.array([-2.0, 0.7]), weight, solution)
    assert np.allclose(at_wall, exact.distribution(0.0, np.array([-2.0, 0.7]), r), rtol=1e-9)


def test_tables(built):
    solution, weight = built(Fraction(1, 2))
    positions = distribution.position_table(weight, np.geomspace(1e-3, 1e3, 7))
    assert list(positions.columns) == ["x", "px", "v2_given_x"]
    assert np.all(np.diff(positions["px"]) < 0.0)
    forces = distribution.weight_table(weight, np.geomspace(1e-4, 1e6, 5))
    assert list(forces.columns) == ["F", "w", "log_w"]
    assert np.all(np.isfinite(forces["log_w"]))
    table, worst = distribution.distribution_table(weight, solution, [0.0, 1.0], [-1.0, 1.0])
    assert len(table) == 4 and worst < 1e-8


def test_asymptotic_exponents_at_one_half(built):
    """The measured large-x form of P(x) at r = 1/2 is the paper's x^(-1/4) exp(-(2x/3)^(1/2))."""
    _, weight = built(Fraction(1, 2))
    measured = distribution.measured_exponents(weight)
    assert measured["large_x_rate"] == pytest.approx(np.sqrt(2.0 / 3.0), rel=1e-4)
    assert measured["large_x_power"] == pytest.approx(-0.25, abs=2e-3)
