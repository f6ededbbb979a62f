"""The return-law prediction of P(0, v) (``estimators.return_law_prediction``) against the
exact solutions: fed the exact equilibrium's outgoing speeds, it gives back the exact
collisions per speed bin, eq. (inteq) being the balance it rests on."""

import dataclasses
from fractions import Fraction

import numpy as np
import pytest
from scipy import integrate

from bouncing_ball import exact
from bouncing_ball.bins import LogBins
from bouncing_ball.estimators import return_law_prediction
from bouncing_ball.settings import ShardSettings, return_law_speed_bins
from bouncing_ball.tallies import ShardTallies

# speed bins (and so the fine bins of the return-law control) that hold the collisions of
# both exact r to rounding, as the bins that follow r do (scales)
SETTINGS = ShardSettings(
    shard_time=1.0,
    equilibration_time=0.0,
    criterion_c=3,
    min_step_divisor=10,
    max_steps=100,
    speed_bins=LogBins(1e-10, 1e3, 10),
)
# the rate of collisions is int u P(0, u) du, eq. (collrate); scaled up to counts
SCALE = 1e12


def _collision_rate(density, lower, upper):
    """int u P(0, u) du over each bin (an underflow bin from 1e-14, an overflow to 1e4)."""
    lower, upper = np.maximum(lower, 1e-14), np.minimum(upper, 1e4)
    nodes, weights = np.polynomial.legendre.leggauss(8)
    half = 0.5 * np.log(upper / lower)[:, None]
    u = np.exp(half * nodes + 0.5 * np.log(upper * lower)[:, None])
    return np.sum(u * u * density(u) * half * weights, axis=1)


def _equilibrium_shard(density):
    """A shard whose fine outgoing-speed counts are the equilibrium's expectation."""
    fine = return_law_speed_bins(SETTINGS.speed_bins)
    counts = SCALE * _collision_rate(density, fine.lower, fine.upper)
    empty = ShardTallies.from_loop(SETTINGS, ShardTallies.loop_arrays(SETTINGS))
    return dataclasses.replace(empty, return_law_speed_counts=counts)


@pytest.mark.parametrize("r", exact.EXACT_RESTITUTIONS, ids=str)
def test_equilibrium_outgoing_speeds_predict_the_exact_bins(r):
    """Between v = 1e-3 and 10 every speed bin's prediction is the exact rate of eq. (P(0,v))
    to 1e-6 relative (the quadratures' accuracy; a wrong r or kernel is off by percents)."""

    def density(u):
        return exact.outgoing_speed_density(u, r)

    predicted = return_law_prediction([_equilibrium_shard(density)], float(r), density)[0]
    bins = SETTINGS.speed_bins
    expected = SCALE * np.array(
        [
            integrate.quad(lambda u: u * density(np.array([u]))[0], a, b, epsrel=1e-12)[0]
            for a, b in zip(bins.lower, np.minimum(bins.upper, 1e4))
        ]
    )
    centre = np.sqrt(bins.lower * bins.upper)
    inside = (centre > 1e-3) & (centre < 10.0)
    np.testing.assert_allclose(predicted[inside], expected[inside], rtol=1e-6)


def test_another_restitution_predicts_other_bins():
    """The prediction is sharp: the r = 1/2 equilibrium's speeds pushed through the law with
    r = 0.45 miss the r = 1/2 bins by more than 1% somewhere in 1e-3 < v < 10."""
    r = Fraction(1, 2)

    def density(u):
        return exact.outgoing_speed_density(u, r)

    shard = _equilibrium_shard(density)
    right = return_law_prediction([shard], 0.5, density)[0]
    wrong = return_law_prediction([shard], 0.45, density)[0]
    bins = SETTINGS.speed_bins
    centre = np.sqrt(bins.lower * bins.upper)
    inside = (centre > 1e-3) & (centre < 10.0)
    assert np.max(np.abs(wrong[inside] / right[inside] - 1.0)) > 0.01


def test_no_collisions_predict_none():
    empty = ShardTallies.from_loop(SETTINGS, ShardTallies.loop_arrays(SETTINGS))
    prediction = return_law_prediction([empty, empty], 0.5, lambda u: np.ones_like(u))
    assert prediction.shape == (2, SETTINGS.speed_bins.n + 2) and not prediction.any()


@pytest.mark.parametrize("r", exact.EXACT_RESTITUTIONS, ids=str)
def test_equilibrium_outgoing_speeds_predict_the_flight_moments(r):
    """Fed the exact equilibrium's outgoing speeds, the flight-law prediction gives the mean
    time between collisions 1 / I of eq. (xandDeltax) (3 at r = 1/2, 4/3 at r = 1/3) and
    the solver's <T^2>, per flight, to 1e-6 (a wrong E[T | u] is off by percents)."""
    from bouncing_ball import flight_time, solver
    from bouncing_ball.estimators import flight_law_prediction

    def density(u):
        return exact.outgoing_speed_density(u, r)

    shard = _equilibrium_shard(density)
    flights = shard.return_law_speed_counts.sum()
    mean, second = flight_law_prediction([shard], density)[0] / flights
    rate = exact.position_moments(r)["collision_rate"]
    assert mean == pytest.approx(1.0 / rate, rel=1e-6)
    solution = solver.solve_outgoing_speed_density(r)
    assert second == pytest.approx(flight_time.flight_time_second_moment(solution), rel=1e-6)


def _shards_with_speeds(density, scales):
    """Shards of unit time whose outgoing speeds (fine and coarse bins) are the equilibrium's
    expected counts times ``scales`` (one shard each), rounded."""
    from bouncing_ball.tallies import SCALAR_INDEX

    fine, coarse = return_law_speed_bins(SETTINGS.speed_bins), SETTINGS.speed_bins
    shards = []
    for scale in scales:
        arrays = ShardTallies.loop_arrays(SETTINGS)
        arrays["scalars"][SCALAR_INDEX["time"]] = 1.0
        arrays["speed_counts"][:] = np.round(
            scale * 1e6 * _collision_rate(density, coarse.lower, coarse.upper)
        )
        shard = ShardTallies.from_loop(SETTINGS, arrays)
        fine_counts = np.round(scale * 1e6 * _collision_rate(density, fine.lower, fine.upper))
        shards.append(dataclasses.replace(shard, return_law_speed_counts=fine_counts))
    return shards


def test_the_return_law_control_uses_the_density_the_caller_passes():
    """outgoing_speed_histogram solves nothing: its controlled column is the return-law control
    of the P(0, u) passed in (here the exact one of r = 1/2), NaN without it, and r must come
    parsed."""
    from bouncing_ball.estimators import outgoing_speed_histogram

    half = Fraction(1, 2)

    def density(u):
        return exact.outgoing_speed_density(u, half)

    shards = _shards_with_speeds(density, [1.0, 1.01, 0.99, 1.02, 0.98])
    given = outgoing_speed_histogram(shards, half, density)
    by_hand = outgoing_speed_histogram(
        shards, return_law=return_law_prediction(shards, 0.5, density)
    )
    np.testing.assert_array_equal(given.p0v_controlled, by_hand.p0v_controlled)
    assert np.isfinite(given.p0v_controlled[given["count"] > 0]).all()
    assert np.isnan(outgoing_speed_histogram(shards, half).p0v_controlled).all()
    with pytest.raises(TypeError, match="restitution: give r as parsed"):
        outgoing_speed_histogram(shards, "1/2", density)
    with pytest.raises(ValueError, match="restitution"):
        outgoing_speed_histogram(shards, None, density)
