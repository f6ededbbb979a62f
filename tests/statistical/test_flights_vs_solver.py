"""The flights between collisions at r = 0.25, 1/3, 1/2, 0.75 against the theory of
flight_time.py (McKean's first-passage law with gravity, averaged over the solver's P(0, u)).

- the return speed v given the outgoing speed u of the same flight, the probability of each v bin
  given the u bin, against ``return_speed_bin_probabilities`` with u distributed within its bin
  as u P(0, u), P(0, u) the solver's (the rate of collisions, eq. (collrate));
- the flight-time density per collision on the simulation's T bins against
  ``flight_time_bin_average``;
- the mean and second moment of T per collision against ``mean_flight_time`` and
  ``flight_time_second_moment``, 3 sigma with jackknife errors, and the second moment's z
  pooled over the four r.

Every (u, v) cell and T bin with at least 100 flights is compared: chi^2 per bin and the worst
bin against their sign-flip null distributions at the 1e-3 level.  Power: at every r the
flight-time density scaled by 1.01 is rejected (p < 1e-3) by the same data.  The return-speed
table is less sharp (its cells hold 1e2-1e4 flights; scaled by 1.01 it is rejected at p < 1e-3
at r = 0.25 and 0.75 alone, at p ~ 2e-3 to 4e-3 at r = 1/3 and 1/2), so its power check pools the
four r: shard k of every r flipped together, valid because the runs are independent.  Runs are
shared with test_distribution_vs_solver.py (solver_runs.py); seeds fixed.
"""

import functools
from fractions import Fraction

import numpy as np
import pytest
from solver_runs import MINIMUM_COUNT, SHARDS, assert_agrees, shards

from bouncing_ball import flight_time, solver
from bouncing_ball.estimators import position_moments_summary
from bouncing_ball.solver import solved_outgoing_density
from bouncing_ball.validation import sign_flip_test

RESTITUTIONS = [0.25, Fraction(1, 3), Fraction(1, 2), 0.75]


@functools.cache
def _solution(r):
    return solver.solve_outgoing_speed_density(float(r))


@functools.cache
def _flight_times(r):
    """Each shard's flight-time density in the T bins with >= 100 flights, and the theory's."""
    run = shards(r)
    bins = run[0].flight_time_bins
    counts = np.stack([s.flight_time_counts for s in run])
    usable = (counts.sum(axis=0) >= MINIMUM_COUNT) & np.isfinite(bins.upper) & (bins.lower > 0.0)
    lower, upper = bins.lower[usable], bins.upper[usable]
    flights = np.array([s.flights for s in run], dtype=float)[:, None]
    per_shard = counts[:, usable] / (flights * (upper - lower))
    return per_shard, flight_time.flight_time_bin_average(_solution(r), lower, upper)


@functools.cache
def _return_speeds(r):
    """Each shard's probability of the v bin given the u bin, in every cell of finite bins with
    >= 100 flights, and the theory's."""
    run = shards(r)
    bins = run[0].speed_bins
    counts = np.stack([s.return_speed_counts for s in run])  # (shards, u, v)
    finite = np.isfinite(bins.upper) & (bins.lower > 0.0)
    usable = (counts.sum(axis=0) >= MINIMUM_COUNT) & finite[:, None] & finite[None, :]
    iu, iv = np.nonzero(usable)
    rows = np.unique(iu)
    row_counts = counts.sum(axis=-1)[:, iu]  # every flight of the u bin, v in any bin
    assert np.all(row_counts > 0), "a shard without a flight in a compared u bin"
    per_shard = counts[:, iu, iv] / row_counts
    table = flight_time.return_speed_bin_probabilities(
        _solution(r).outgoing_speed_density,
        bins.lower[rows],
        bins.upper[rows],
        bins.lower,
        bins.upper,
    )
    return per_shard, table[np.searchsorted(rows, iu), iv]


@pytest.fixture(scope="module", params=RESTITUTIONS, ids=str)
def flight_times(request):
    return _flight_times(request.param)


@pytest.fixture(scope="module", params=RESTITUTIONS, ids=str)
def return_speeds(request):
    return _return_speeds(request.param)


def test_return_speed_law_agrees(return_speeds):
    """Smallest error rejected: the law scaled by 1.01 at every r (the pooled power test)."""
    per_shard, expected = return_speeds
    assert len(expected) >= 300, "too few populated cells for a meaningful chi^2"
    assert_agrees(per_shard, expected)


def test_flight_time_density_agrees(flight_times):
    """Smallest error rejected: the density scaled by 1.01 (the power test below)."""
    per_shard, expected = flight_times
    error = per_shard.std(axis=0, ddof=1) / np.sqrt(SHARDS)
    assert len(expected) >= 25, "too few populated bins for a meaningful chi^2"
    assert np.median(error / expected) < 0.03, "run too short for a sharp test"
    assert_agrees(per_shard, expected)


def test_flight_time_density_detects_a_one_percent_error(flight_times):
    """The theory's density scaled by 1.01 is rejected by the same shards, p < 1e-3."""
    per_shard, expected = flight_times
    _, p_chi2, _ = sign_flip_test(per_shard - 1.01 * expected)
    assert p_chi2 < 1e-3


def test_return_speed_law_detects_a_one_percent_error_pooled_over_r():
    """The return-speed tables of the four r scaled by 1.01, chi^2 over all their cells."""
    deviations = []
    for r in RESTITUTIONS:
        per_shard, expected = _return_speeds(r)
        deviations.append(per_shard - 1.01 * expected)
    _, p_chi2, _ = sign_flip_test(np.hstack(deviations))
    assert p_chi2 < 1e-3


# the largest relative standard error of each flight-time moment that the test accepts: a
# bias of 4 times this is rejected at one r (z = 4 against the |z| < 3 of the test)
MAX_RELATIVE_ERROR = {"mean_flight_time": 0.004, "flight_time_second_moment": 0.007}
MOMENTS = {
    "mean_flight_time": flight_time.mean_flight_time,
    "flight_time_second_moment": flight_time.flight_time_second_moment,
}


def _moment_z(r, quantity, scale=1.0):
    """z of the simulated moment against the theory's scaled by ``scale``, and the
    relative error."""
    summary = position_moments_summary(shards(r), r, solved_outgoing_density(r)).iloc[0]
    value, error = summary[quantity], summary[f"{quantity}_err"]
    expected = scale * MOMENTS[quantity](_solution(r))
    return (value - expected) / error, error / expected


@pytest.mark.parametrize("r", RESTITUTIONS, ids=str)
@pytest.mark.parametrize("quantity", list(MOMENTS), ids=["mean", "second_moment"])
def test_flight_time_moments_agree(r, quantity):
    """E[T] and E[T^2] per collision within 3 standard errors at each r.  Smallest error
    rejected (z = 4): 1.6% in E[T], 2.8% in E[T^2] (relative errors below MAX_RELATIVE_ERROR,
    asserted); for a smaller error in E[T^2] common to every r, see the pooled test."""
    z, relative_error = _moment_z(r, quantity)
    assert relative_error <= MAX_RELATIVE_ERROR[quantity], "run too short for a sharp test"
    assert abs(z) < 3.0, f"{quantity} at r = {r}: z = {z:.2f}"


def test_flight_time_second_moment_pooled_over_r():
    """E[T^2] per collision at the four r together: the sum of their z over 2 (N(0, 1) for
    independent runs) within 3.  Smallest error rejected: 1% in E[T^2] at every r, checked
    here from the same runs' errors (the theory scaled by 1.01 gives a pooled |z| above 4)."""
    quantity = "flight_time_second_moment"
    pooled = sum(_moment_z(r, quantity)[0] for r in RESTITUTIONS) / np.sqrt(len(RESTITUTIONS))
    assert abs(pooled) < 3.0, f"pooled z = {pooled:.2f}"
    wrong = sum(_moment_z(r, quantity, 1.01)[0] for r in RESTITUTIONS)
    assert abs(wrong / np.sqrt(len(RESTITUTIONS))) > 4.0
